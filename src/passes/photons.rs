//! The photon passes: init, traverse (one pipeline per work-group size, and one per size for max-level), stats, dense emission, the two-interface
//! trace or the exact transport's waves, and the splat. They share one binding layout
//! (glsl/common/photon_bindings.glsl).

use crate::bvh::BvhLayout;
use crate::gpu_types::{
    DenseEmitPush, IndirectCommand, InitPush, SplatCollapsePush, StatsPush, TracePush, TransportPush, TraversePush,
    WavePush,
};
use crate::settings::Metric;
use crate::shaders::{self, consts::*};
use crate::vk::pipeline::LazyPipeline;
use crate::vk::{
    Blend, Buffer, ColorTarget, Device, GraphicsDesc, Image, Pipeline, Raster, Sampler, Target, Tracker, Use, VkResult,
};
use ash::vk;
use std::sync::Arc;

/// glsl/wave.comp's specialization constants (src/shader_consts.rs): `WAVE_PRIMARY`, `WAVE_DIFFERENTIAL`,
/// `WAVE_MEDIA`, `WAVE_COLOR`, `WAVE_SPECTRAL` and `WAVE_SUBGROUPS` (`subgroups`).
/// A CPU driver runs both sides of every branch, so each wave compiles only the code it runs.
fn wave_spec(variant: usize, subgroups: u32) -> [(u32, u32); 6] {
    [
        (WAVE_PRIMARY_ID, (variant & 1) as u32),
        (WAVE_DIFFERENTIAL_ID, (variant >> 1 & 1) as u32),
        (WAVE_MEDIA_ID, (variant >> 2 & 1) as u32),
        (WAVE_COLOR_ID, (variant >> 3 & 1) as u32),
        (WAVE_SPECTRAL_ID, (variant >> 4 & 1) as u32),
        (WAVE_SUBGROUPS_ID, subgroups),
    ]
}

/// A wave pipeline's name in messages and timings: its layout and specialization.
fn wave_name(layout: &str, spec: &[(u32, u32); 6]) -> String {
    let [(_, primary), (_, diff), (_, media), (_, color), (_, spectral), _] = *spec;
    format!(
        "transport wave {}{}{}{}{} ({layout} BVH nodes)",
        if primary != 0 { "0" } else { "k > 0" },
        if diff != 0 { ", ray differentials" } else { "" },
        if media != 0 { ", media" } else { "" },
        if color != 0 { ", color" } else { "" },
        if spectral != 0 { ", spectral" } else { "" },
    )
}

/// What a queue entry of exact transport holds besides its ray ([`crate::settings::ResolvedSettings::ray_vec4s`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WaveRays {
    /// Ray differentials (`--footprint differential`).
    pub differential: bool,
    /// The ray's medium and volumes (the scene has absorbing or overlapping media).
    pub media: bool,
    /// The ray's color, in its medium word (color photons; only with `media`).
    pub color: bool,
    /// The ray's wavelength, its photon's (spectral photons).
    pub spectral: bool,
}

/// The most subgroups a work group of `LINEAR_WG` invocations can have on a device whose least subgroup size is
/// `min_subgroup_size`.
fn wave_subgroups(min_subgroup_size: u32) -> u32 {
    LINEAR_WG.div_ceil(min_subgroup_size.max(1))
}

// glsl/wave.comp counts a work group's children inside glass, outside it and its records in three 10-bit fields of
// one word: each at most two per invocation.
const _: () = assert!(2 * LINEAR_WG < 1 << 10);

/// One BVH layout's wave pipelines, every specialization ([`wave_spec`]).
fn wave_variants(device: &Arc<Device>, layout: &str, spv: &'static shaders::Spv) -> [LazyPipeline; 32] {
    std::array::from_fn(|k| {
        let spec = wave_spec(k, wave_subgroups(device.info.min_subgroup_size));
        LazyPipeline::compute_specialized(device, &wave_name(layout, &spec), spv.words(), &spec)
    })
}

/// A compute splat's pipelines, per `SPLAT_COLOR`: gray records, records with an RGB tint, records with a
/// wavelength.
fn splat_variants(device: &Arc<Device>, name: &str, spv: &'static [u32]) -> [LazyPipeline; 3] {
    [SPLAT_GRAY, SPLAT_TINT, SPLAT_WAVELENGTH].map(|color| {
        let name = format!("{name}{}", ["", ", color", ", spectral"][color as usize]);
        LazyPipeline::compute_specialized(device, &name, spv, &[(SPLAT_COLOR_ID, color)])
    })
}

/// The index of a wave's pipeline among its layout's variants ([`wave_spec`]).
fn wave_variant(primary: bool, rays: WaveRays) -> usize {
    primary as usize
        | (rays.differential as usize) << 1
        | (rays.media as usize) << 2
        | (rays.color as usize) << 3
        | (rays.spectral as usize) << 4
}

/// The bytes of one indirect command ([`IndirectCommand`]).
pub const COMMAND_BYTES: u64 = std::mem::size_of::<IndirectCommand>() as u64;
/// Byte offsets of the indirect commands (`IndirectBuf` in photon_bindings.glsl, by the same constants).
pub const TRACE_OFFSET: u64 = COMMAND_BYTES * INDIRECT_TRACE as u64;
pub const DRAW_OFFSET: u64 = COMMAND_BYTES * INDIRECT_DRAW as u64;
/// Exact transport: the current wave's dispatch.
pub const WAVE_OFFSET: u64 = COMMAND_BYTES * INDIRECT_WAVE as u64;
/// The compute splat's dispatch over the draw's records.
pub const SPLAT_OFFSET: u64 = COMMAND_BYTES * INDIRECT_SPLAT as u64;
pub const INDIRECT_BYTES: u64 = COMMAND_BYTES * INDIRECT_COMMANDS as u64;

pub struct PhotonBindings<'a> {
    pub ubo: &'a Buffer,
    pub state: &'a Buffer,
    pub photons: &'a Buffer,
    pub indirect: &'a Buffer,
    pub coverage: &'a Buffer,
    pub front: &'a Image,
    pub front_aux: &'a Image,
    pub back: &'a Image,
    pub recv: &'a Image,
    pub debug: &'a Buffer,
    pub splats: &'a Buffer,
    pub sampler: &'a Sampler,
    pub transport: &'a Buffer,
    pub queues: [&'a Buffer; 2],
    pub bvh: &'a crate::scene_gpu::BvhBuffers,
    pub flux_texels: &'a Buffer,
    pub splat_tints: &'a Buffer,
    /// The eye deposit: the receivers seen from the eye, and the flux per eye sample.
    pub eye_geo: &'a Image,
    pub eye_flux: &'a Buffer,
}

impl PhotonBindings<'_> {
    /// The photon stage's one declaration: each binding of the shared layout, with the resource it binds and its
    /// strongest use by any of the stage's compute passes. Each pass binds the whole list; its pipeline declares
    /// of it what its SPIR-V accesses, a binding its shaders only read as a read, one they do not declare not at
    /// all (src/vk/uses.rs), so each dispatch is ordered after the passes whose writes it reads (counts, queues,
    /// arguments) and no more. Which pass writes what: the test `the_photon_passes_write_what_their_table_says`.
    /// A variant whose layout reads a buffer through texels declares that read.
    fn uses(&self) -> [Use<'_>; PB_COUNT as usize] {
        let bvh = self.bvh;
        crate::vk::pipeline::ordered([
            (PB_FRAME, Use::Uniform(self.ubo)),
            (PB_STATE, Use::Write(self.state)),
            (PB_PHOTONS, Use::Write(self.photons)),
            (PB_INDIRECT, Use::Indirect(self.indirect)),
            (PB_COVERAGE, Use::Read(self.coverage)),
            (PB_FRONT, Use::Sampled(self.front, self.sampler)),
            (PB_FRONT_AUX, Use::Sampled(self.front_aux, self.sampler)),
            (PB_BACK, Use::Sampled(self.back, self.sampler)),
            (PB_RECEIVERS, Use::Sampled(self.recv, self.sampler)),
            (PB_DEBUG, Use::Write(self.debug)),
            (PB_SPLATS, Use::Write(self.splats)),
            (PB_TRANSPORT, Use::Write(self.transport)),
            (PB_RAYS_IN, Use::Write(self.queues[0])),
            (PB_RAYS_OUT, Use::Write(self.queues[1])),
            (PB_BVH_PAIR, Use::Read(&bvh.pair_nodes)),
            (PB_BVH_TRIS, Use::Read(&bvh.triangles)),
            (PB_BVH_NORMALS, Use::Read(&bvh.normals)),
            (PB_BVH_INSTANCES, Use::Read(&bvh.instances)),
            (PB_BVH_SINGLE, Use::Read(&bvh.single_nodes)),
            (PB_FLUX_TEXELS, Use::Write(self.flux_texels)),
            (PB_BVH_THREADED, Use::Read(&bvh.threaded_nodes)),
            (PB_BVH_WIDE, Use::Read(&bvh.wide_nodes)),
            (PB_BVH_WIDE_PRIMS, Use::Read(&bvh.wide_prims)),
            (PB_SPLAT_TINTS, Use::Write(self.splat_tints)),
            (PB_EYE, Use::Sampled(self.eye_geo, self.sampler)),
            (PB_EYE_FLUX, Use::Write(self.eye_flux)),
        ])
    }

    /// The raster splat's uses of the same layout: its vertex shader reads the records, its draw the arguments;
    /// the rest it leaves alone.
    fn raster_splat_uses(&self) -> [Use<'_>; PB_COUNT as usize] {
        let mut uses = self.uses().map(Use::unused);
        uses[PB_FRAME as usize] = Use::Uniform(self.ubo);
        uses[PB_INDIRECT as usize] = Use::Indirect(self.indirect);
        uses[PB_SPLATS as usize] = Use::Read(self.splats);
        uses
    }
}

/// Modes of init.comp (src/shader_consts.rs).
pub mod init_mode {
    pub use crate::shaders::consts::{INIT_BATCH as BATCH, INIT_DENSE as DENSE, INIT_FRAME as FRAME};
}

/// Modes of stats.comp (src/shader_consts.rs).
pub mod stats_mode {
    pub use crate::shaders::consts::{STATS_COMMIT as COMMIT, STATS_DENSE as DENSE, STATS_LEVEL as LEVEL};
}

/// Modes of transport.comp (src/shader_consts.rs).
pub mod transport_mode {
    pub use crate::shaders::consts::{
        TRANSPORT_AFTER_WAVE as AFTER_WAVE, TRANSPORT_BEGIN_ADAPTIVE as BEGIN_ADAPTIVE,
        TRANSPORT_BEGIN_DENSE as BEGIN_DENSE, TRANSPORT_COMMIT as COMMIT,
    };
}

pub struct PhotonPasses {
    device: Arc<Device>,
    init: Pipeline,
    /// Per BVH layout the checks walk (pair, wide), per metric (indexed by `Metric::code`), per work-group side:
    /// max-level (TRAVERSE_MAX_LEVEL: no metric code, the last level fused into the one before), max-error and
    /// flux-error (TRAVERSE_METRIC: that metric's code only).
    traverse: [[Vec<(u32, LazyPipeline)>; 3]; 2],
    /// Per layout, max-error's and flux-error's 8x8 traversal with four lanes per candidate (TRAVERSE_COOP).
    traverse_coop: [[LazyPipeline; 2]; 2],
    stats: Pipeline,
    dense_emit: LazyPipeline,
    trace: LazyPipeline,
    /// Exact transport's waves, per BVH layout (pair, single, threaded, wide) and per specialization
    /// ([`wave_spec`]): wave 0 or a bounce wave, with or without ray differentials, with or without the rays'
    /// media, their color, their wavelength.
    waves: [[LazyPipeline; 32]; 4],
    transport: LazyPipeline,
    splat: LazyPipeline,
    /// None when the device has no float atomics on buffers. Per `SPLAT_COLOR`: gray records, records with an RGB
    /// tint, records with a wavelength.
    splat_compute: Option<[LazyPipeline; 3]>,
    /// The same with a work group's taps gathered in shared memory first (SPLAT_TILED).
    splat_compute_tiled: Option<[LazyPipeline; 3]>,
    /// Adds a coarse level of the flux texels into the one below it (glsl/splat_collapse.comp).
    splat_collapse: LazyPipeline,
}

/// How traversal runs: the work-group side its dispatches count candidates in
/// ([`crate::settings::Settings::traverse_dispatch_wg`]), the metric, whether the checks are cooperative,
/// and whether exact transport's checks walk the wide BVH layout (where the waves do) instead of the pair layout.
#[derive(Clone, Copy, Debug)]
pub struct TraverseShape {
    pub wg: u32,
    pub metric: Metric,
    pub coop: bool,
    pub wide: bool,
}

impl PhotonPasses {
    /// `flux_format`: the caustic flux map's format (R32F where it can be blended).
    pub fn new(device: &Arc<Device>, flux_format: vk::Format) -> VkResult<Self> {
        let compute = |name: &str, spv: &[u32]| Pipeline::compute(device, name, spv);
        let lazy = |name: &str, spv: &'static [u32]| LazyPipeline::compute(device, name, spv);
        // One traversal pipeline per BVH layout the checks walk (pair; wide: texel reads), metric (llvmpipe pays
        // for code a metric never takes) and work-group side.
        let sides = [1u32, 2, 4, 8, 16];
        // Each layout index: 0 pair, 1 wide.
        let layout_name = |l: usize| ["", ", wide BVH"][l];
        let variant = |metric: Metric, l: usize, spv: [&'static Spv; 5]| -> Vec<(u32, LazyPipeline)> {
            sides
                .iter()
                .zip(spv)
                .map(|(&s, spv)| {
                    let name = format!("traverse {metric:?} {s}x{s}{}", layout_name(l));
                    (s, LazyPipeline::compute(device, &name, spv.words()))
                })
                .collect()
        };
        use shaders::*;
        let traverse_layout = |l: usize| {
            let pick = |pair: &'static Spv, w: &'static Spv| if l > 0 { w } else { pair };
            [
                variant(
                    Metric::MaxLevel,
                    l,
                    [
                        pick(TRAVERSE_COMP_MAX_LEVEL_WG1, TRAVERSE_COMP_MAX_LEVEL_WG1_WIDE),
                        pick(TRAVERSE_COMP_MAX_LEVEL_WG2, TRAVERSE_COMP_MAX_LEVEL_WG2_WIDE),
                        pick(TRAVERSE_COMP_MAX_LEVEL_WG4, TRAVERSE_COMP_MAX_LEVEL_WG4_WIDE),
                        pick(TRAVERSE_COMP_MAX_LEVEL_WG8, TRAVERSE_COMP_MAX_LEVEL_WG8_WIDE),
                        pick(TRAVERSE_COMP_MAX_LEVEL_WG16, TRAVERSE_COMP_MAX_LEVEL_WG16_WIDE),
                    ],
                ),
                variant(
                    Metric::MaxError,
                    l,
                    [
                        pick(TRAVERSE_COMP_MAX_ERROR_WG1, TRAVERSE_COMP_MAX_ERROR_WG1_WIDE),
                        pick(TRAVERSE_COMP_MAX_ERROR_WG2, TRAVERSE_COMP_MAX_ERROR_WG2_WIDE),
                        pick(TRAVERSE_COMP_MAX_ERROR_WG4, TRAVERSE_COMP_MAX_ERROR_WG4_WIDE),
                        pick(TRAVERSE_COMP_MAX_ERROR_WG8, TRAVERSE_COMP_MAX_ERROR_WG8_WIDE),
                        pick(TRAVERSE_COMP_MAX_ERROR_WG16, TRAVERSE_COMP_MAX_ERROR_WG16_WIDE),
                    ],
                ),
                variant(
                    Metric::FluxError,
                    l,
                    [
                        pick(TRAVERSE_COMP_FLUX_ERROR_WG1, TRAVERSE_COMP_FLUX_ERROR_WG1_WIDE),
                        pick(TRAVERSE_COMP_FLUX_ERROR_WG2, TRAVERSE_COMP_FLUX_ERROR_WG2_WIDE),
                        pick(TRAVERSE_COMP_FLUX_ERROR_WG4, TRAVERSE_COMP_FLUX_ERROR_WG4_WIDE),
                        pick(TRAVERSE_COMP_FLUX_ERROR_WG8, TRAVERSE_COMP_FLUX_ERROR_WG8_WIDE),
                        pick(TRAVERSE_COMP_FLUX_ERROR_WG16, TRAVERSE_COMP_FLUX_ERROR_WG16_WIDE),
                    ],
                ),
            ]
        };
        let traverse = [traverse_layout(0), traverse_layout(1)];
        let splat = {
            let device = device.clone();
            LazyPipeline::new(move || {
                Pipeline::graphics(
                    &device,
                    "splat",
                    &GraphicsDesc {
                        vertex: shaders::SPLAT_VERT.words(),
                        fragment: shaders::SPLAT_FRAG.words(),
                        vertex_attributes: &[],
                        vertex_stride: 0,
                        topology: vk::PrimitiveTopology::POINT_LIST,
                        cull: vk::CullModeFlags::NONE,
                        depth: None,
                        colors: &[ColorTarget { format: flux_format, blend: Blend::Additive }],
                    },
                )
            })
        };
        let coop = |metric: &str, pair: &'static Spv, wide: &'static Spv, l: usize| {
            let spv = if l > 0 { wide } else { pair };
            let name = format!("traverse {metric} 8x8, four lanes a candidate{}", layout_name(l));
            LazyPipeline::compute(device, &name, spv.words())
        };
        let traverse_coop = [0, 1].map(|l| {
            [
                coop("MaxError", TRAVERSE_COMP_MAX_ERROR_COOP, TRAVERSE_COMP_MAX_ERROR_COOP_WIDE, l),
                coop("FluxError", TRAVERSE_COMP_FLUX_ERROR_COOP, TRAVERSE_COMP_FLUX_ERROR_COOP_WIDE, l),
            ]
        });
        let atomics = device.info.float_atomic_add;
        let splat_color = |name: &str, spv: &'static [u32]| splat_variants(device, name, spv);
        Ok(PhotonPasses {
            device: device.clone(),
            init: compute("init", shaders::INIT_COMP.words())?,
            traverse,
            traverse_coop,
            stats: compute("stats", shaders::STATS_COMP.words())?,
            dense_emit: lazy("dense emit", shaders::DENSE_EMIT_COMP.words()),
            trace: lazy("photon trace", shaders::TRACE_COMP.words()),
            waves: [
                ("pair", WAVE_COMP),
                ("single-box", WAVE_COMP_SINGLE),
                ("threaded", WAVE_COMP_THREADED),
                ("wide", WAVE_COMP_WIDE),
            ]
            .map(|(layout, spv)| wave_variants(device, layout, spv)),
            transport: lazy("transport state", shaders::TRANSPORT_COMP.words()),
            splat_compute: atomics.then(|| splat_color("compute splat", shaders::SPLAT_COMP.words())),
            splat_compute_tiled: atomics
                .then(|| splat_color("compute splat (tiled)", shaders::SPLAT_COMP_TILED.words())),
            splat_collapse: lazy("splat levels collapse", shaders::SPLAT_COLLAPSE_COMP.words()),
            splat,
        })
    }

    /// The traversal pipeline of `metric` with work groups of `wg`×`wg` (8×8 for a side not built); `coop`: the
    /// cooperative checks' 8x8 pipeline of max-error or flux-error, whose groups take 4x4 candidates (`wg` is 4).
    fn traverse_pipeline(&self, shape: TraverseShape) -> VkResult<&Pipeline> {
        let layout = shape.wide as usize;
        let wg = shape.wg;
        match (shape.coop, shape.metric) {
            (true, Metric::MaxError) => return self.traverse_coop[layout][0].get(),
            (true, Metric::FluxError) => return self.traverse_coop[layout][1].get(),
            _ => {}
        }
        let list = &self.traverse[layout][shape.metric.code() as usize];
        list.iter().find(|(s, _)| *s == wg).map(|(_, p)| p).unwrap_or(&list[3].1).get()
    }

    pub fn init(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        mode: u32,
        wg: u32,
    ) -> VkResult<()> {
        self.init.bind_uses(cmd, sync, &b.uses())?;
        self.init.push(cmd, &InitPush { mode, wg_side: wg });
        unsafe { self.device.cmd_dispatch(cmd, 1, 1, 1) };
        Ok(())
    }

    /// One traversal level, launched with vkCmdDispatchIndirect from the GPU-written arguments.
    pub fn traverse_indirect(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        level: u32,
        shape: TraverseShape,
    ) -> VkResult<()> {
        let p = self.traverse_pipeline(shape)?;
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &TraversePush { level, wg_side: shape.wg });
        unsafe { self.device.cmd_dispatch_indirect(cmd, b.indirect.raw, COMMAND_BYTES * level as u64) };
        Ok(())
    }

    /// One traversal level with host-computed work groups (the CPU-driven baseline).
    pub fn traverse_direct(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        level: u32,
        count: u32,
        shape: TraverseShape,
    ) -> VkResult<()> {
        let (wg, p) = (shape.wg, self.traverse_pipeline(shape)?);
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &TraversePush { level, wg_side: wg });
        let groups = count.div_ceil(wg * wg);
        if groups > 0 {
            let gx = groups.min(65535);
            unsafe { self.device.cmd_dispatch(cmd, gx, groups.div_ceil(gx), 1) };
        }
        Ok(())
    }

    pub fn stats(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        level: u32,
        mode: u32,
        wg: u32,
    ) -> VkResult<()> {
        self.stats.bind_uses(cmd, sync, &b.uses())?;
        self.stats.push(cmd, &StatsPush { level, mode, wg_side: wg });
        unsafe { self.device.cmd_dispatch(cmd, 1, 1, 1) };
        Ok(())
    }

    /// Emit every covered cell of rows [row0, row0 + rows) of the level's grid.
    pub fn dense_emit(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        level: u32,
        row0: u32,
        rows: u32,
    ) -> VkResult<()> {
        let p = self.dense_emit.get()?;
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &DenseEmitPush { level, row0, rows });
        let n = LEVEL0_RES << level;
        unsafe { self.device.cmd_dispatch(cmd, n.div_ceil(TILE_WG), rows.div_ceil(TILE_WG), 1) };
        Ok(())
    }

    /// Trace the emitted photons into splat records, dispatched indirectly. `debug`: dump the traced photons of
    /// level `debug` or deeper into the debug buffer.
    pub fn trace(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        debug: Option<u32>,
    ) -> VkResult<()> {
        let p = self.trace.get()?;
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &TracePush { debug: debug.is_some() as u32, debug_min_level: debug.unwrap_or(0) });
        unsafe { self.device.cmd_dispatch_indirect(cmd, b.indirect.raw, TRACE_OFFSET) };
        Ok(())
    }

    /// Exact transport's bookkeeping (`transport_mode`); `may_abort`: the batch is split on overflow; `next_wave`:
    /// after a wave, the index of the wave it prepares (0 otherwise).
    #[allow(clippy::too_many_arguments)]
    pub fn transport(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        mode: u32,
        may_abort: bool,
        next_wave: u32,
    ) -> VkResult<()> {
        let p = self.transport.get()?;
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &TransportPush { mode, may_abort: may_abort as u32, next_wave });
        unsafe { self.device.cmd_dispatch(cmd, 1, 1, 1) };
        Ok(())
    }

    /// One wave of exact transport, dispatched indirectly from the arguments the transport pass wrote.
    /// `rays`: what the rays carry besides themselves.
    #[allow(clippy::too_many_arguments)]
    pub fn wave(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        wave: u32,
        may_abort: bool,
        layout: BvhLayout,
        rays: WaveRays,
    ) -> VkResult<()> {
        let l = match layout {
            // The settings resolve `auto`; pair is its fallback.
            BvhLayout::Pair | BvhLayout::Auto => 0,
            BvhLayout::Single => 1,
            BvhLayout::Threaded => 2,
            BvhLayout::Wide => 3,
        };
        let p = self.waves[l][wave_variant(wave == 0, rays)].get()?;
        // Wave k reads the queue wave k - 1 appended to and appends to the other.
        let mut uses = b.uses();
        if wave % 2 == 1 {
            uses.swap(PB_RAYS_IN as usize, PB_RAYS_OUT as usize);
        }
        p.bind_uses(cmd, sync, &uses)?;
        p.push(cmd, &WavePush { may_abort: may_abort as u32 });
        unsafe { self.device.cmd_dispatch_indirect(cmd, b.indirect.raw, WAVE_OFFSET) };
        Ok(())
    }

    /// Splat the records into the flux texels with a compute pass dispatched indirectly (float atomics). Settings
    /// resolve `--splat` to raster on a device without them, so the pipeline exists whenever this is called.
    /// `color`: what the records carry of their color (`SPLAT_COLOR`), into the texels' three planes.
    pub fn splat_compute(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        tiled: bool,
        color: crate::settings::CarriedColor,
    ) -> VkResult<()> {
        let p = if tiled { &self.splat_compute_tiled } else { &self.splat_compute };
        let Some(p) = p.as_ref() else { return Ok(()) };
        let p = p[color.splat_code() as usize].get()?;
        p.bind_uses(cmd, sync, &b.uses())?;
        unsafe { self.device.cmd_dispatch_indirect(cmd, b.indirect.raw, SPLAT_OFFSET) };
        Ok(())
    }

    /// Add coarse level `level` of the flux texels of a `res`² map into the level below it, in each of the
    /// texels' `planes`.
    pub fn splat_collapse(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        level: u32,
        res: u32,
        planes: u32,
    ) -> VkResult<()> {
        let p = self.splat_collapse.get()?;
        p.bind_uses(cmd, sync, &b.uses())?;
        p.push(cmd, &SplatCollapsePush { level });
        let groups = (res >> (level - 1)).div_ceil(TILE_WG);
        unsafe { self.device.cmd_dispatch(cmd, groups, groups, planes) };
        Ok(())
    }

    /// Splat the traced photons into the caustic flux map with vkCmdDrawIndirect. `clear`: clear the map first
    /// (the frame's first batch), else add to it.
    pub fn splat(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        flux: &Image,
        clear: bool,
    ) -> VkResult<()> {
        let target = if clear { Target::Clear(flux) } else { Target::Load(flux) };
        self.raster_splat(cmd, sync, b, target, true)
    }

    /// Clear the caustic flux map (a frame whose traversal emitted no batch).
    pub fn clear_flux(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        flux: &Image,
    ) -> VkResult<()> {
        self.raster_splat(cmd, sync, b, Target::Clear(flux), false)
    }

    fn raster_splat(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        b: &PhotonBindings,
        flux: Target,
        draw: bool,
    ) -> VkResult<()> {
        let p = self.splat.get()?;
        let uses = b.raster_splat_uses();
        let raster = Raster { colors: &[flux], depth: None, vertices: None, indices: None, uses: &uses };
        p.begin_raster(cmd, sync, &raster)?;
        if draw {
            unsafe { self.device.cmd_draw_indirect(cmd, b.indirect.raw, DRAW_OFFSET, 1, COMMAND_BYTES as u32) };
        }
        raster.end(&self.device, cmd);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The photon stage's passes share one list of uses (`PhotonBindings::uses`), each declaring what its SPIR-V
    /// writes as a write and the rest as reads (src/vk/uses.rs). This table is what each writes, so that a reader
    /// sees it, and a shader that starts writing something else changes it.
    #[test]
    fn the_photon_passes_write_what_their_table_says() {
        let desc = crate::vk::ContextDesc { validation: true, ..crate::vk::ContextDesc::from_env() };
        let device = crate::vk::Context::headless(&desc).expect("a Vulkan device").device;
        let p = PhotonPasses::new(&device, vk::Format::R32_SFLOAT).expect("the photon passes");
        let names: std::collections::HashMap<u32, &str> = [
            (PB_STATE, "state"),
            (PB_PHOTONS, "photons"),
            (PB_INDIRECT, "indirect"),
            (PB_DEBUG, "debug"),
            (PB_SPLATS, "splats"),
            (PB_TRANSPORT, "transport"),
            (PB_RAYS_IN, "rays_in"),
            (PB_RAYS_OUT, "rays_out"),
            (PB_FLUX_TEXELS, "flux_texels"),
            (PB_SPLAT_TINTS, "splat_tints"),
            (PB_EYE_FLUX, "eye_flux"),
        ]
        .into_iter()
        .collect();
        let writes = |pipeline: &Pipeline| -> Vec<&str> {
            pipeline.writes().iter().map(|b| names.get(b).copied().unwrap_or("?")).collect()
        };
        let wave = |k: usize| p.waves[3][k].get().expect("wave");
        let splat = |s: &Option<[LazyPipeline; 3]>| s.as_ref().map(|s| writes(s[1].get().expect("splat")));
        let got = [
            ("init", writes(&p.init)),
            ("traverse", writes(p.traverse[1][2][3].1.get().expect("traverse"))),
            ("stats", writes(&p.stats)),
            ("dense emit", writes(p.dense_emit.get().expect("dense emit"))),
            ("trace", writes(p.trace.get().expect("trace"))),
            ("transport", writes(p.transport.get().expect("transport"))),
            ("wave 0", writes(wave(wave_variant(true, WaveRays::default())))),
            ("bounce wave", writes(wave(wave_variant(false, WaveRays::default())))),
            ("splat", splat(&p.splat_compute).unwrap_or_default()),
            ("splat tiled", splat(&p.splat_compute_tiled).unwrap_or_default()),
            ("collapse", writes(p.splat_collapse.get().expect("collapse"))),
        ];
        let table: [(&str, &[&str]); 11] = [
            ("init", &["state", "photons", "indirect"]),
            ("traverse", &["state", "photons"]),
            ("stats", &["state", "indirect"]),
            ("dense emit", &["state", "photons"]),
            ("trace", &["debug", "splats"]),
            ("transport", &["indirect", "transport"]),
            ("wave 0", &["state", "splats", "transport", "rays_out", "splat_tints"]),
            ("bounce wave", &["state", "splats", "transport", "rays_out", "splat_tints"]),
            ("splat", &["flux_texels", "eye_flux"]),
            ("splat tiled", &["flux_texels", "eye_flux"]),
            ("collapse", &["flux_texels"]),
        ];
        let atomics = device.info.float_atomic_add;
        for ((name, w), (expected_name, expected)) in got.iter().zip(table) {
            let expected: &[&str] = if name.starts_with("splat") && !atomics { &[] } else { expected };
            assert_eq!((*name, w.as_slice()), (expected_name, expected));
        }
        assert_eq!(crate::vk::validation_message_count(), 0);
    }

    #[test]
    fn wave_subgroups_cover_every_subgroup_size() {
        // A pipeline may run with any subgroup size from the device's least up: a work group of LINEAR_WG
        // invocations then has LINEAR_WG / size subgroups (at least one), and the wave's loop over them, bounded by
        // wave_subgroups(least), must reach the last.
        let sizes = [1, 4, 8, 16, 32, 64, 128];
        for least in sizes {
            let bound = wave_subgroups(least);
            assert!((1..=LINEAR_WG).contains(&bound), "least {least}: bound {bound}");
            for size in sizes.into_iter().filter(|&s| s >= least) {
                let subgroups = LINEAR_WG.div_ceil(size);
                assert!(subgroups <= bound, "least {least}, size {size}: {subgroups} subgroups > {bound}");
            }
        }
        assert_eq!(wave_subgroups(8), 8, "lavapipe's SIMD groups of 8 lanes");
    }
}
