//! Steps 3 to 5: the photons (dense emission, or adaptive traversal GPU- or CPU-driven), in batches, each traced
//! (exact transport's waves, or the two-interface trace) and splatted into the caustic flux map.

use super::{Ctx, Rec};
use crate::bvh::BvhLayout;
use crate::gpu_types::{TransportState, TraversalState};
use crate::passes::photons::{init_mode, stats_mode, PhotonBindings, TraverseShape, WaveRays};
use crate::settings::{CarriedColor, Driven, Footprint, Method, Transport};
use crate::shaders::consts::*;
use crate::targets::{Targets, CANARY, PHOTON_GUARD};
use crate::vk::{Access, VkResult};
use ash::vk;
use std::mem::size_of;

/// Exact transport's waves after the first, as sub-stages of `transport_bounces` (index: wave - 1), so that a
/// profile shows where the bounces' time goes: the early waves carry most rays, the late ones a long tail.
const WAVE_LABELS: [&str; MAX_INTERACTIONS as usize] = [
    "transport_bounces.wave_01",
    "transport_bounces.wave_02",
    "transport_bounces.wave_03",
    "transport_bounces.wave_04",
    "transport_bounces.wave_05",
    "transport_bounces.wave_06",
    "transport_bounces.wave_07",
    "transport_bounces.wave_08",
    "transport_bounces.wave_09",
    "transport_bounces.wave_10",
    "transport_bounces.wave_11",
    "transport_bounces.wave_12",
    "transport_bounces.wave_13",
    "transport_bounces.wave_14",
    "transport_bounces.wave_15",
    "transport_bounces.wave_16",
    "transport_bounces.wave_17",
    "transport_bounces.wave_18",
    "transport_bounces.wave_19",
    "transport_bounces.wave_20",
    "transport_bounces.wave_21",
    "transport_bounces.wave_22",
    "transport_bounces.wave_23",
    "transport_bounces.wave_24",
    "transport_bounces.wave_25",
    "transport_bounces.wave_26",
    "transport_bounces.wave_27",
    "transport_bounces.wave_28",
    "transport_bounces.wave_29",
    "transport_bounces.wave_30",
    "transport_bounces.wave_31",
    "transport_bounces.wave_32",
];

const TRAVERSE_LABELS: [&str; MAX_LEVELS as usize] = [
    "traverse_L0",
    "traverse_L1",
    "traverse_L2",
    "traverse_L3",
    "traverse_L4",
    "traverse_L5",
    "traverse_L6",
    "traverse_L7",
    "traverse_L8",
    "traverse_L9",
    "traverse_L10",
    "traverse_L11",
    "traverse_L12",
    "traverse_L13",
    "traverse_L14",
    "traverse_L15",
    "traverse_L16",
];

impl Ctx<'_> {
    /// The splat's debug dump: off, or from which level.
    fn debug(&self) -> Option<u32> {
        (self.s.debug_photons > 0).then_some(self.s.debug_min_level)
    }

    /// How this frame's traversal runs (work-group side as its dispatches count candidates, metric, cooperative
    /// checks); both the GPU- and the CPU-driven loop use it.
    fn traverse_shape(&self) -> TraverseShape {
        TraverseShape {
            wg: self.s.traverse_dispatch_wg(),
            metric: self.s.metric,
            coop: self.s.coop_traversal(),
            wide: self.s.transport == Transport::Exact && self.s.bvh_layout == BvhLayout::Wide,
        }
    }

    fn bindings(&self) -> PhotonBindings<'_> {
        let t = self.t;
        PhotonBindings {
            ubo: self.ubo,
            state: &t.photon.state,
            photons: &t.photon.photons,
            indirect: &t.photon.indirect,
            coverage: &t.photon.coverage,
            front: &t.light.front,
            front_aux: &t.light.front_aux,
            back: &t.light.back,
            recv: &self.r.geo,
            debug: &t.photon.debug,
            splats: &t.photon.splats,
            sampler: self.nearest,
            transport: &t.photon.transport,
            queues: [&t.photon.queues[0], &t.photon.queues[1]],
            bvh: &self.sb.bvh,
            flux_texels: &self.r.flux_texels,
            splat_tints: &t.photon.splat_tints,
            eye_geo: &t.eye.recv,
            eye_flux: &t.eye.flux,
        }
    }

    /// Step 3: photons, in batches; each batch's photons are traced (step 4) and splatted (step 5) into the
    /// caustic flux map. `continue_from`: the slot whose readback buffer holds this pass's state from the frame
    /// before, whose remaining tiles these batches trace (see [`super::Continuation`]).
    pub(super) fn photons(&self, rec: &mut Rec, slots: u32, continue_from: Option<usize>) -> VkResult<()> {
        let (t, d) = (self.t, self.d);
        rec.ts.mark(rec.cmd, "photon_init");
        let debug = self.s.debug_photons > 0;
        for buf in [&t.photon.state, &t.photon.photons, &t.photon.indirect, &t.photon.debug, &t.photon.transport] {
            rec.sync.buffer(buf, &[Access::TransferDst]);
        }
        // The compute splat's flux texels are cleared here (the raster splat's first batch clears its flux map).
        if self.compute_splat {
            rec.sync.buffer(&self.r.flux_texels, &[Access::TransferDst]);
        }
        let from = continue_from.map(|slot| &t.readbacks[slot]);
        if let Some(from) = from {
            rec.sync.buffer(from, &[Access::TransferSrc]);
        }
        rec.flush(d);
        let cmd = rec.cmd;
        unsafe {
            if self.compute_splat {
                d.cmd_fill_buffer(cmd, self.r.flux_texels.raw, 0, vk::WHOLE_SIZE, 0);
            }
            match from {
                // The state the frame before left: its stack of tiles, its counts and its energy account.
                Some(from) => {
                    let layout = Targets::readback_layout(self.s, 16 * t.width as u64 * t.height as u64);
                    let i = self.pass as u64;
                    let (state, transport) = (size_of::<TraversalState>() as u64, size_of::<TransportState>() as u64);
                    let copy = |dst: &crate::vk::Buffer, at: u64, size: u64| {
                        let region = vk::BufferCopy { src_offset: at, dst_offset: 0, size };
                        d.cmd_copy_buffer(cmd, from.raw, dst.raw, &[region]);
                    };
                    copy(&t.photon.state, layout.state + i * state, state);
                    copy(&t.photon.transport, layout.transport + i * transport, transport);
                }
                None => {
                    d.cmd_fill_buffer(cmd, t.photon.state.raw, 0, vk::WHOLE_SIZE, 0);
                    d.cmd_fill_buffer(cmd, t.photon.transport.raw, 0, vk::WHOLE_SIZE, 0);
                }
            }
            // Header (count, capacity) and rows: disjoint ranges, so the two transfers need no barrier between them.
            // A continuation appends to the dump the frame before left (tests dump the photons of one light).
            if from.is_none() {
                d.cmd_update_buffer(
                    cmd,
                    t.photon.debug.raw,
                    0,
                    bytemuck::bytes_of(&[0u32, self.s.debug_photons, 0, 0]),
                );
                d.cmd_fill_buffer(cmd, t.photon.debug.raw, 16, vk::WHOLE_SIZE, 0);
            }
            if debug {
                // Canary after the capacity: a shader writing past its photon budget would overwrite it.
                let cap = 8 * t.photon.capacity as u64;
                d.cmd_fill_buffer(cmd, t.photon.photons.raw, cap, 8 * PHOTON_GUARD as u64, CANARY);
            }
        }
        // Each photon pass declares its uses as it binds them (PhotonBindings::uses).
        match self.s.method {
            Method::Dense => self.dense(rec),
            Method::Adaptive => match self.s.driven {
                Driven::Gpu => self.adaptive_gpu(rec, slots, continue_from.is_none()),
                Driven::Cpu => self.adaptive_cpu(rec),
            },
        }?;
        if self.compute_splat {
            self.collapse_splat_levels(rec)?;
            if !self.resolve_texels {
                self.copy_flux_texels(rec);
            }
        }
        Ok(())
    }

    /// Differential footprints: the compute splat put its wide tents in the flux texels' coarse levels; add each
    /// into the one below it, coarsest first (glsl/splat_collapse.comp). Timed with the splat. Where the resolve
    /// reads the texels, it adds level 1 into level 0 itself.
    fn collapse_splat_levels(&self, rec: &mut Rec) -> VkResult<()> {
        if self.s.footprint != crate::settings::Footprint::Differential {
            return Ok(());
        }
        let res = self.s.caustic_res;
        rec.ts.mark(rec.cmd, "splat");
        let b = self.bindings();
        let finest = if self.resolve_texels { 2 } else { 1 };
        let planes = crate::targets::flux_planes(self.s) as u32;
        for level in (finest..=crate::targets::splat_levels(res)).rev() {
            self.p.photons.splat_collapse(rec.cmd, rec.sync, &b, level, res, planes)?;
        }
        Ok(())
    }

    /// The compute splat's flux texels → the flux image the resolve samples.
    fn copy_flux_texels(&self, rec: &mut Rec) {
        let img = &self.r.flux;
        rec.sync.buffer(&self.r.flux_texels, &[Access::TransferSrc]);
        rec.sync.discard(img, &[Access::TransferDst]);
        rec.flush(self.d);
        let region = vk::BufferImageCopy::default()
            .image_subresource(vk::ImageSubresourceLayers {
                aspect_mask: vk::ImageAspectFlags::COLOR,
                mip_level: 0,
                base_array_layer: 0,
                layer_count: 1,
            })
            .image_extent(vk::Extent3D { width: img.extent.width, height: img.extent.height, depth: 1 });
        unsafe {
            self.d.cmd_copy_buffer_to_image(
                rec.cmd,
                self.r.flux_texels.raw,
                img.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Steps 4 and 5 for one batch: trace its emitted photons (compute, dispatched indirectly), then splat them.
    /// `commit`: adaptive traversal's last stats pass, which commits or splits the batch. Under two-interface
    /// transport it ran already; under exact transport it runs after the waves, which may abort the batch.
    fn trace_and_splat(&self, rec: &mut Rec, clear: bool, commit: bool) -> VkResult<()> {
        let (b, ph) = (self.bindings(), &self.p.photons);
        // Each mark goes before the barrier that opens its stage: lavapipe takes a timestamp's time at its next
        // flush, so a mark between a barrier and a dispatch would charge the dispatch to the stage before it.
        let exact = self.s.transport == Transport::Exact;
        rec.ts.mark(rec.cmd, if exact { "transport_primary" } else { "photon_trace" });
        if exact {
            self.exact_transport(rec, commit)?;
        } else {
            ph.trace(rec.cmd, rec.sync, &b, self.debug())?;
        }
        rec.ts.mark(rec.cmd, "splat");
        if self.compute_splat {
            ph.splat_compute(rec.cmd, rec.sync, &b, self.tiled_splat, self.s.carried_color)
        } else {
            ph.splat(rec.cmd, rec.sync, &b, &self.r.flux, clear)
        }
    }

    /// Exact transport of the batch's emitted photons, in waves (docs/design.md step 4): every wave is one
    /// vkCmdDispatchIndirect whose arguments the transport pass wrote from the previous wave's appends. The host
    /// records MAX_INTERACTIONS + 1 waves; those after the queue empties dispatch zero work groups.
    fn exact_transport(&self, rec: &mut Rec, commit: bool) -> VkResult<()> {
        use crate::passes::photons::transport_mode as tm;
        let (b, ph) = (self.bindings(), &self.p.photons);
        let adaptive = self.s.method == Method::Adaptive;
        let may_abort = adaptive && self.s.batching;
        let begin = if adaptive { tm::BEGIN_ADAPTIVE } else { tm::BEGIN_DENSE };
        ph.transport(rec.cmd, rec.sync, &b, begin, may_abort, 0)?;
        for wave in 0..=MAX_INTERACTIONS {
            if wave >= 1 {
                rec.ts.mark(rec.cmd, WAVE_LABELS[wave as usize - 1]);
            }
            let rays = WaveRays {
                differential: self.s.footprint == Footprint::Differential,
                media: self.s.media,
                color: self.s.carried_color == CarriedColor::Tint,
                spectral: self.s.carried_color == CarriedColor::Wavelength,
            };
            ph.wave(rec.cmd, rec.sync, &b, wave, may_abort, self.s.bvh_layout, rays)?;
            ph.transport(rec.cmd, rec.sync, &b, tm::AFTER_WAVE, may_abort, wave + 1)?;
        }
        rec.ts.mark(rec.cmd, "stats");
        if commit {
            ph.stats(rec.cmd, rec.sync, &b, self.s.level, stats_mode::COMMIT, self.s.traverse_dispatch_wg())?;
        }
        ph.transport(rec.cmd, rec.sync, &b, tm::COMMIT, may_abort, 0)
    }

    fn dense(&self, rec: &mut Rec) -> VkResult<()> {
        let b = self.bindings();
        let ph = &self.p.photons;
        let n = LEVEL0_RES << self.s.level;
        // Bands of rows sized so that even a fully covered band fits the photon buffer (and, under exact
        // transport, half a ray queue).
        let per_band = self.s.batch_photons(self.t.photon.capacity);
        let rows = (per_band / n).clamp(1, n).min(65535 * TILE_WG);
        let bands = n.div_ceil(rows);
        rec.report.batch_slots = bands;
        for band in 0..bands {
            let row0 = band * rows;
            rec.ts.mark(rec.cmd, "photon_init");
            ph.init(rec.cmd, rec.sync, &b, init_mode::DENSE, self.s.traverse_wg)?;
            rec.ts.mark(rec.cmd, "dense_emit");
            ph.dense_emit(rec.cmd, rec.sync, &b, self.s.level, row0, rows.min(n - row0))?;
            rec.ts.mark(rec.cmd, "stats");
            ph.stats(rec.cmd, rec.sync, &b, self.s.level, stats_mode::DENSE, self.s.traverse_wg)?;
            self.trace_and_splat(rec, band == 0, false)?;
        }
        Ok(())
    }

    /// GPU-driven adaptive traversal: a fixed command sequence per batch slot, every dispatch and draw indirect.
    /// `fresh`: the frame's first batches (else a continuation's, from the restored stack of tiles).
    fn adaptive_gpu(&self, rec: &mut Rec, slots: u32, fresh: bool) -> VkResult<()> {
        let b = self.bindings();
        let ph = &self.p.photons;
        let shape = self.traverse_shape();
        let wg = shape.wg;
        let exact = self.s.transport == Transport::Exact;
        if fresh {
            ph.init(rec.cmd, rec.sync, &b, init_mode::FRAME, wg)?;
        }
        rec.report.batch_slots = slots;
        for slot in 0..slots {
            rec.ts.mark(rec.cmd, "photon_init");
            ph.init(rec.cmd, rec.sync, &b, init_mode::BATCH, wg)?;
            for level in 0..=self.s.level {
                rec.ts.mark(rec.cmd, TRAVERSE_LABELS[level as usize]);
                ph.traverse_indirect(rec.cmd, rec.sync, &b, level, shape)?;
                rec.ts.mark(rec.cmd, "stats");
                let mode = if level == self.s.level && !exact { stats_mode::COMMIT } else { stats_mode::LEVEL };
                ph.stats(rec.cmd, rec.sync, &b, level, mode, wg)?;
            }
            self.trace_and_splat(rec, slot == 0, exact)?;
        }
        Ok(())
    }

    /// Copy the traversal state to the readback buffer, for the host after the submit.
    fn copy_state(&self, rec: &mut Rec) {
        let t = self.t;
        rec.sync.buffer(&t.photon.state, &[Access::TransferSrc]);
        rec.sync.buffer(self.readback, &[Access::TransferDst]);
        rec.flush(self.d);
        let size = std::mem::size_of::<TraversalState>() as u64;
        unsafe {
            self.d.cmd_copy_buffer(
                rec.cmd,
                t.photon.state.raw,
                self.readback.raw,
                &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size }],
            )
        };
        rec.sync.buffer(self.readback, &[Access::HostRead]);
        rec.flush(self.d);
    }

    fn read_state(&self) -> VkResult<TraversalState> {
        Ok(self.readback.read::<TraversalState>(0, 1)?[0])
    }

    /// The CPU-driven baseline: the host reads the state back after init and after each level, and records the
    /// next traversal dispatch with host-computed work groups.
    fn adaptive_cpu(&self, rec: &mut Rec) -> VkResult<()> {
        let b = self.bindings();
        let ph = &self.p.photons;
        let shape = self.traverse_shape();
        let wg = shape.wg;
        ph.init(rec.cmd, rec.sync, &b, init_mode::FRAME, wg)?;
        let mut first = true;
        let mut batches = 0;
        loop {
            rec.ts.mark(rec.cmd, "photon_init");
            ph.init(rec.cmd, rec.sync, &b, init_mode::BATCH, wg)?;
            self.copy_state(rec);
            rec.roundtrip()?;
            let mut st = self.read_state()?;
            if st.start_level >= MAX_LEVELS {
                break;
            }
            batches += 1;
            for level in st.start_level..=self.s.level {
                rec.ts.mark(rec.cmd, TRAVERSE_LABELS[level as usize]);
                if st.aborted == 0 {
                    ph.traverse_direct(rec.cmd, rec.sync, &b, level, st.read_count, shape)?;
                }
                rec.ts.mark(rec.cmd, "stats");
                let last = level == self.s.level;
                let commit = last && self.s.transport == Transport::TwoInterface;
                ph.stats(
                    rec.cmd,
                    rec.sync,
                    &b,
                    level,
                    if commit { stats_mode::COMMIT } else { stats_mode::LEVEL },
                    wg,
                )?;
                if !last {
                    self.copy_state(rec);
                    rec.roundtrip()?;
                    st = self.read_state()?;
                }
            }
            self.trace_and_splat(rec, first, self.s.transport == Transport::Exact)?;
            first = false;
        }
        rec.report.batch_slots = batches;
        if first && !self.compute_splat {
            // No batch at all: the flux map still needs clearing (the compute splat's texels were cleared).
            ph.clear_flux(rec.cmd, rec.sync, &b, &self.r.flux)?;
        }
        Ok(())
    }
}
