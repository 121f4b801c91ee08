//! One frame, in its fixed pass order, with the barriers that join the passes. The steps are those of
//! docs/design.md "Pipeline", with the same numbers:
//!
//! 1. light-view g-buffers: refractor front and back (photon view), receivers with the shadow map as their depth
//!    (receiver view)
//! 2. coverage pyramid
//! 3. photons: dense emission, or adaptive init → traverse × levels → stats, in batches
//! 4. transport: each batch's photons traced to the receivers (exact transport's waves, or the two-interface
//!    trace)
//! 5. splat: each batch's landings into the caustic flux map (compute, or vkCmdDrawIndirect)
//! 6. resolve: flux → caustic irradiance
//! 7. eye view: the receivers' g-buffer, shaded in compute under each light (radiance, caustics, direct);
//!    refractor front and back
//! 8. composite: the glass (BVH-traced eye rays, or deferred refraction) and tone mapping
//!
//! Steps 3 to 5 repeat per batch. With no refractor in the light, steps 2-6 are not recorded at all. GPU-driven
//! traversal records every level with vkCmdDispatchIndirect from arguments that the stats shader wrote; the
//! CPU-driven baseline submits after each level, reads the count back, and records the next dispatch directly.

use crate::error::AppResult;
use crate::gpu_types::{FrameData, TransportState, TraversalState};
use crate::passes::composite::CompositeInputs;
use crate::passes::coverage::CoverageInputs;
use crate::passes::eye::{EyeGbuffer, EyeInputs};
use crate::passes::geometry::GeometryTarget;
use crate::passes::photons::{init_mode, stats_mode, PhotonBindings, TraverseShape};
use crate::passes::Passes;
use crate::renderer::{Aov, AovData, FrameReport, FrameSlot, LightReport, Renderer, Views};
use crate::scene::view::CameraView;
use crate::scene_gpu::SceneBuffers;
use crate::settings::{Driven, Method, ResolvedSettings, Splat, Transport};
use crate::shaders::consts::*;
use crate::targets::{ReceiverTargets, Targets, CANARY, DEBUG_ROWS, PHOTON_GUARD};
use crate::vk::{Access, Barriers, Buffer, Device, Image, Recorder, Sampler, SubmitSync, Timestamps, VkResult};
use ash::vk;
use std::time::Instant;

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

/// Stage label of the CPU-driven traversal's host round trips (GPU idle while the host reads and records).
pub const HOST_ROUNDTRIP: &str = "host_roundtrip";

/// Extra commands appended to the frame's last command buffer (the viewer's blit to the swapchain).
pub type Finish<'a> = &'a mut dyn FnMut(&Device, vk::CommandBuffer, &Targets);

/// Everything a frame reads, borrowed for its recording.
struct Ctx<'a> {
    d: &'a Device,
    p: &'a Passes,
    sb: &'a SceneBuffers,
    nearest: &'a Sampler,
    linear: &'a Sampler,
    t: &'a Targets,
    /// The current light's receiver maps and uniforms.
    r: &'a ReceiverTargets,
    ubo: &'a Buffer,
    /// This frame-in-flight slot's readback buffer.
    readback: &'a Buffer,
    light: usize,
    /// Index of this (light, color channel) pass, and its channel among the light's (0 for a gray frame).
    pass: usize,
    channel: usize,
    s: &'a ResolvedSettings,
    /// A viewer preview: one eye sample per pixel, glass by two-surface deferred refraction.
    preview: bool,
    data: &'a FrameData,
    /// The records are splatted by the compute pass into the flux texels (else drawn as points).
    compute_splat: bool,
    /// The compute splat gathers a work group's taps in shared memory first.
    tiled_splat: bool,
    /// The frame reads back the caustics or direct AOV, so the eye view writes them (else only the radiance).
    eye_aovs: bool,
}

/// The mutable side of a frame: the command buffer being recorded (the CPU-driven path submits mid-frame), the
/// timestamps and the report.
struct Rec<'a> {
    recorder: &'a mut Recorder,
    ts: &'a mut Timestamps,
    cmd: vk::CommandBuffer,
    report: FrameReport,
    record_time: f64,
    mark: Instant,
}

impl Rec<'_> {
    /// Submit what is recorded, wait for it, and start a new command buffer (CPU-driven traversal only).
    fn roundtrip(&mut self) -> VkResult<()> {
        self.ts.mark(self.cmd, HOST_ROUNDTRIP);
        self.record_time += self.mark.elapsed().as_secs_f64();
        self.recorder.submit_and_wait()?;
        self.report.host_readbacks += 1;
        self.mark = Instant::now();
        self.cmd = self.recorder.begin()?;
        Ok(())
    }
}

/// A frame submitted and not read back yet (see [`Renderer::submit_frame_at`]).
pub(crate) struct Pending {
    slot: usize,
    report: FrameReport,
    start: Instant,
    /// Index of the frame's first eye-view interval (the per-light sums stop there).
    lights_end: usize,
    /// The AOV its readback copies, if any.
    aov: Option<Aov>,
    /// Its caustic inputs (see [`Renderer::caustic_key`]).
    key: String,
    /// The settings it was recorded with (the readback layout and what to read depend on them).
    settings: ResolvedSettings,
}

impl Renderer {
    /// Render one frame headless and read back `aov`.
    pub fn render(&mut self, camera: &CameraView, aov: Option<Aov>) -> AppResult<(FrameReport, Option<AovData>)> {
        self.render_frame(camera, aov, None, &SubmitSync::default())
    }

    /// Progressive refinement: render this frame at `level` when it is below the chosen one (the settings keep
    /// the chosen level). Every such frame is a complete, flux-correct frame at its own level.
    pub fn render_frame_at(
        &mut self,
        level: u32,
        preview: bool,
        camera: &CameraView,
        aov: Option<Aov>,
        finish: Option<Finish>,
        sync: &SubmitSync,
    ) -> AppResult<(FrameReport, Option<AovData>)> {
        self.finish_frames()?;
        self.submit_frame_at(level, preview, camera, aov, finish, sync)?;
        let pending = self.pending.pop_back().expect("the frame just submitted");
        self.complete(pending)
    }

    /// Record and submit a frame, and wait for its results; `finish` appends commands to its last command buffer
    /// and `sync` gives that submission its semaphores.
    pub fn render_frame(
        &mut self,
        camera: &CameraView,
        aov: Option<Aov>,
        finish: Option<Finish>,
        sync: &SubmitSync,
    ) -> AppResult<(FrameReport, Option<AovData>)> {
        let level = self.config.level;
        self.render_frame_at(level, false, camera, aov, finish, sync)
    }

    /// The frame-in-flight slot the next frame takes. When every slot is in flight, this first waits for the
    /// oldest frame, the last to use that slot, and keeps its report for [`Renderer::take_completed`]. The viewer
    /// calls it before acquiring a swapchain image with that slot's semaphore.
    pub fn next_slot(&mut self) -> AppResult<usize> {
        while self.pending.len() >= self.frames_in_flight() {
            let oldest = self.pending.pop_front().expect("a frame in flight");
            let (report, _) = self.complete(oldest)?;
            self.completed.push(report);
        }
        Ok((self.submitted % self.frames_in_flight() as u64) as usize)
    }

    /// Wait for every frame in flight and keep their reports for [`Renderer::take_completed`].
    pub fn finish_frames(&mut self) -> AppResult<()> {
        while let Some(oldest) = self.pending.pop_front() {
            let (report, _) = self.complete(oldest)?;
            self.completed.push(report);
        }
        Ok(())
    }

    /// The reports of the frames completed since the last call, oldest first.
    pub fn take_completed(&mut self) -> Vec<FrameReport> {
        std::mem::take(&mut self.completed)
    }

    /// Record and submit a frame at `level` (see [`Renderer::render_frame_at`]) without waiting for it: its report
    /// comes later from [`Renderer::take_completed`], once a later frame needs its slot or
    /// [`Renderer::finish_frames`] is called.
    pub fn submit_frame_at(
        &mut self,
        level: u32,
        preview: bool,
        camera: &CameraView,
        aov: Option<Aov>,
        finish: Option<Finish>,
        sync: &SubmitSync,
    ) -> AppResult<()> {
        let chosen = self.config.level;
        self.config.level = level.min(chosen);
        let out = self.submit(preview, camera, aov, finish, sync);
        self.config.level = chosen;
        out
    }

    fn submit(
        &mut self,
        preview: bool,
        camera: &CameraView,
        aov: Option<Aov>,
        finish: Option<Finish>,
        sync: &SubmitSync,
    ) -> AppResult<()> {
        let start = Instant::now();
        let slot = self.next_slot()?;
        // The caustics and direct AOVs are point samples at the pixel centers; the beauty is supersampled.
        let aa = match aov {
            Some(Aov::Caustics) | Some(Aov::Direct) => 1,
            _ if preview => 1,
            _ => self.config.aa,
        };
        self.ensure_targets(camera.width, camera.height, aa)?;
        let nl = self.scene.lights.len();
        // Color: 3 passes per light (red, green, blue) when some glass disperses or absorbs unequally, else 1.
        let nc = self.scene.color_channels();
        let views = (0..nl).map(|i| Views::new(&self.scene, &self.config, camera, i)).collect::<AppResult<Vec<_>>>()?;
        // Reuse by dependency: the light-view stages, the photons and the caustic map depend on the lights, the
        // geometry and materials, and the settings, not on the camera or the output size. When none of those
        // changed since the last frame submitted, only the eye and composite passes are recorded (the queue runs
        // frames in order, so a frame in flight that computes the maps finishes them before this one reads them).
        let key = self.caustic_key();
        let self_level = self.config.level;
        let reused = self.reuse && self.last_caustic.as_ref().is_some_and(|(k, _)| *k == key);
        let (data, slots) = {
            let t = self.targets.as_ref().expect("targets");
            let channel = |c: usize| if nc == 1 { 0 } else { c as u32 + 1 };
            let data: Vec<FrameData> =
                (0..nl * nc).map(|p| self.frame_data(&views[p / nc], t, p / nc, channel(p % nc))).collect();
            (data, self.batch_slots(t.photon.capacity))
        };
        // Reuse of the whole eye view: same caustic inputs, same uniforms (camera, views, exposure, sky), same
        // kernels and targets. Only for frames that read back no eye AOV other than the composite's outputs.
        let eye_key = {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            key.hash(&mut h);
            bytemuck::cast_slice::<FrameData, u8>(&data).hash(&mut h);
            (preview, self.targets_generation).hash(&mut h);
            h.finish()
        };
        let eye_reused =
            reused && matches!(aov, None | Some(Aov::Beauty) | Some(Aov::BeautyHdr)) && self.last_eye == Some(eye_key);
        self.last_eye = Some(eye_key);
        let Renderer {
            device,
            passes,
            scene_buffers,
            nearest,
            linear,
            slots: frame_slots,
            targets,
            config: settings,
            ..
        } = self;
        let FrameSlot { recorder, timestamps } = &mut frame_slots[slot];
        let targets = targets.as_mut().expect("targets");
        for (ubo, d) in targets.ubos[slot].iter_mut().zip(&data) {
            ubo.write(0, std::slice::from_ref(d))?;
        }
        let splat = settings.splat;
        let compute_splat = splat.is_compute() && targets.receivers[0].flux.format == vk::Format::R32_SFLOAT;
        let tiled_splat = splat == Splat::Tiled;
        let eye_aovs = matches!(aov, Some(Aov::Caustics) | Some(Aov::Direct));
        let targets = &*targets;
        let readback = &targets.readbacks[slot];
        // Pass `p`: light p / nc, channel p % nc.
        let ctx = |p: usize| Ctx {
            d: device,
            p: passes,
            sb: scene_buffers,
            nearest,
            linear,
            t: targets,
            r: &targets.receivers[p / nc],
            ubo: &targets.ubos[slot][p],
            readback,
            light: p / nc,
            pass: p,
            channel: p % nc,
            s: settings,
            preview,
            data: &data[p],
            compute_splat,
            tiled_splat,
            eye_aovs,
        };
        let cmd = recorder.begin()?;
        let mut rec = Rec {
            recorder,
            ts: timestamps,
            cmd,
            report: FrameReport::default(),
            record_time: 0.0,
            mark: Instant::now(),
        };
        rec.report.caustics = views[0].photon.is_some();
        rec.report.compute_splat = compute_splat;
        rec.report.photon_view = views[0].photon;
        rec.report.reused = reused;
        rec.report.level = self_level;
        rec.report.preview = preview;
        rec.ts.reset(rec.cmd);
        // The lights' state copies and the AOV readback write disjoint ranges of the readback buffer.
        ctx(0).barrier(rec.cmd, |b| {
            b.buffer(readback, &[Access::FrameStart], &[Access::TransferDst]);
        });
        for pass in 0..nl * nc {
            let c = ctx(pass);
            let first_segment = rec.ts.len();
            let caustics = views[c.light].photon.is_some();
            let first_channel = c.channel == 0;
            if reused {
                if first_channel {
                    c.reuse_caustics(&mut rec);
                }
            } else {
                c.light_gbuffers(&mut rec, caustics, first_channel);
                if caustics {
                    c.coverage(&mut rec);
                    c.photons(&mut rec, slots)?;
                    c.resolve(&mut rec);
                    c.copy_light_state(&mut rec);
                } else if first_channel {
                    c.clear_irradiance(&mut rec);
                }
            }
            rec.report.lights.push(LightReport {
                light: c.light,
                // The pass's channel code, as its uniforms give it to the shaders.
                channel: c.data.transport[3] & 0xff,
                caustics,
                first_segment,
                ..Default::default()
            });
        }
        let c0 = ctx(0);
        rec.report.eye_reused = eye_reused;
        // The lights' own stages end where the eye view starts.
        let lights_end = rec.ts.len();
        if eye_reused {
            // The beauty and HDR images are the last frame's, left as transfer sources by its composite.
            rec.ts.mark(rec.cmd, "eye_reused");
        } else {
            rec.ts.mark(rec.cmd, "eye.receivers");
            for light in 0..nl {
                ctx(light * nc).eye_receivers(&mut rec);
            }
            rec.ts.mark(rec.cmd, "eye.refractors");
            c0.eye_refractors(&mut rec);
            c0.composite(&mut rec);
        }
        rec.ts.mark(rec.cmd, "readback");
        let aov_image = c0.readback(&mut rec, aov);
        if let Some(f) = finish {
            f(c0.d, rec.cmd, c0.t);
        }
        rec.ts.mark(rec.cmd, "");
        rec.record_time += rec.mark.elapsed().as_secs_f64();
        rec.recorder.submit_with(sync)?;
        let mut report = rec.report;
        report.record_ms = rec.record_time * 1e3;
        if !reused {
            // The maps this frame computes serve the next frames with the same inputs; its traversal and transport
            // state join them once it completes.
            self.last_caustic = Some((key.clone(), report.lights.clone()));
        }
        self.submitted += 1;
        let settings = self.config.clone();
        self.pending.push_back(Pending { slot, report, start, lights_end, aov: aov_image, key, settings });
        Ok(())
    }

    /// Wait for a submitted frame and read its timings, its traversal and transport state and its AOV.
    fn complete(&mut self, p: Pending) -> AppResult<(FrameReport, Option<AovData>)> {
        let FrameSlot { recorder, timestamps } = &mut self.slots[p.slot];
        recorder.wait()?;
        let mut report = p.report;
        report.frame_ms = p.start.elapsed().as_secs_f64() * 1e3;
        report.segments = timestamps.resolve()?;
        if timestamps.overflowed() {
            log::warn!("more stages than timestamp queries: the per-stage GPU times of this frame are truncated");
        }
        report.stages = crate::vk::query::sum_by_label(&report.segments);
        report.substages = crate::vk::query::sum_by_sublabel(&report.segments);
        report.gpu_ms = report.stages.iter().filter(|(l, _)| *l != HOST_ROUNDTRIP).map(|(_, ms)| ms).sum();
        // Each light's light-side stages: the timed intervals from its first mark to the next light's.
        let ends: Vec<usize> =
            report.lights.iter().skip(1).map(|l| l.first_segment).chain(std::iter::once(p.lights_end)).collect();
        for (l, end) in report.lights.iter_mut().zip(ends) {
            l.gpu_ms = report
                .segments
                .get(l.first_segment..end.min(report.segments.len()))
                .unwrap_or(&[])
                .iter()
                .filter(|(label, _, _)| *label != HOST_ROUNDTRIP)
                .map(|(_, _, ms)| ms)
                .sum();
        }
        let t = self.targets.as_ref().expect("targets");
        let readback = &t.readbacks[p.slot];
        let cached = self.last_caustic.as_mut().filter(|(k, _)| *k == p.key);
        if report.reused {
            // The frame that computed the maps completed before this one: its states are known.
            if let Some((_, lights)) = cached {
                for (l, c) in report.lights.iter_mut().zip(lights.iter()) {
                    l.state = c.state;
                    l.transport = c.transport;
                }
            }
        } else {
            read_results(t, readback, &p.settings, &mut report)?;
            if let Some((_, lights)) = cached {
                *lights = report.lights.clone();
            }
        }
        report.state = report.lights[0].state;
        report.transport = report.lights[0].transport;
        let img = read_aov(t, readback, &p.settings, p.aov)?;
        Ok((report, img))
    }
}

impl Ctx<'_> {
    fn barrier(&self, cmd: vk::CommandBuffer, f: impl FnOnce(&mut Barriers)) {
        let mut b = Barriers::new();
        f(&mut b);
        b.flush(self.d, cmd);
    }

    /// The splat's debug dump: off, or from which level.
    fn debug(&self) -> Option<u32> {
        (self.s.debug_photons > 0).then_some(self.s.debug_min_level)
    }

    /// How this frame's traversal runs (work-group side as its dispatches count candidates, metric, cooperative
    /// checks); both the GPU- and the CPU-driven loop use it.
    fn traverse_shape(&self) -> TraverseShape {
        TraverseShape { wg: self.s.traverse_dispatch_wg(), metric: self.s.metric, coop: self.s.coop_traversal() }
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
        }
    }

    /// Step 1: light-view g-buffers.
    /// `receivers`: also the receiver g-buffer and the shadow map (a light's first color pass draws them).
    fn light_gbuffers(&self, rec: &mut Rec, caustics: bool, receivers: bool) {
        let (t, cmd, g) = (self.t, rec.cmd, &self.p.geometry);
        rec.ts.mark(cmd, "light_gbuffer.front");
        let start = [Access::FrameStart];
        self.barrier(cmd, |b| {
            for img in [&t.light.front, &t.light.front_aux, &t.light.back] {
                b.image(img, &start, &[Access::ColorAttachment]);
            }
            b.image(&t.light.depth, &start, &[Access::DepthAttachment]);
            if receivers {
                b.image(&self.r.geo, &start, &[Access::ColorAttachment]);
                b.image(&self.r.shadow, &start, &[Access::DepthAttachment]);
            }
        });
        let photon_view = &self.data.photon_view;
        let receiver_view = &self.data.receiver_view;
        if caustics {
            // The IOR buffer is drawn only when the refractors' IORs differ (else the shaders read the uniform).
            let ior = self.sb.shared_ior.is_none().then_some(&t.light.front_aux);
            g.record_front(cmd, self.sb, &t.light.front, ior, &t.light.depth, photon_view);
            // Exact transport reads only the front buffer (coverage); the back surface is the two-interface
            // trace's.
            if self.s.transport == Transport::TwoInterface {
                rec.ts.mark(cmd, "light_gbuffer.back");
                // The depth buffer is reused (cleared) by the back-face pass.
                self.barrier(cmd, |b| {
                    b.image(&t.light.depth, &[Access::DepthAttachment], &[Access::DepthAttachment]);
                });
                let back = GeometryTarget {
                    colors: &[&t.light.back],
                    depth: &t.light.depth,
                    view: photon_view,
                    ranges: &[self.sb.refractors],
                };
                g.record(cmd, &g.back, self.sb, &back);
            }
        }
        if receivers {
            // The receivers' g-buffer and the shadow map, in one pass.
            rec.ts.mark(cmd, "light_gbuffer.receivers");
            g.record_receivers(cmd, self.sb, &self.r.geo, &self.r.shadow, receiver_view);
        }
        let sampled = [Access::ComputeSampled, Access::VertexSampled, Access::FragmentSampled];
        self.barrier(cmd, |b| {
            if caustics {
                for img in [&t.light.front, &t.light.front_aux, &t.light.back] {
                    b.image(img, &[Access::ColorAttachment], &sampled);
                }
            }
            if receivers {
                b.image(&self.r.geo, &[Access::ColorAttachment], &sampled);
                let eye_read = [Access::FragmentSampled, Access::ComputeSampled];
                b.image(&self.r.shadow, &[Access::DepthAttachment], &eye_read);
            }
        });
    }

    /// A frame that reuses the caustic map, the receiver g-buffer and the shadow map of the last one: order this
    /// frame's reads after the last frame's (the images keep their layouts).
    fn reuse_caustics(&self, rec: &mut Rec) {
        let cmd = rec.cmd;
        rec.ts.mark(cmd, "reused");
        let sampled = [Access::ComputeSampled, Access::VertexSampled, Access::FragmentSampled];
        self.barrier(cmd, |b| {
            b.image(&self.r.geo, &sampled, &sampled);
            let eye_read = [Access::FragmentSampled, Access::ComputeSampled];
            b.image(&self.r.shadow, &eye_read, &eye_read);
            b.image(&self.r.irradiance, &eye_read, &eye_read);
        });
    }

    /// Step 2: the coverage pyramid.
    fn coverage(&self, rec: &mut Rec) {
        let (t, cmd) = (self.t, rec.cmd);
        rec.ts.mark(cmd, "coverage");
        self.barrier(cmd, |b| {
            b.buffer(&t.photon.coverage, &[Access::FrameStart], &[Access::ComputeWrite]);
        });
        let mips = self.s.gbuffer_level() + 1;
        let inputs = CoverageInputs {
            ubo: self.ubo,
            coverage: &t.photon.coverage,
            front: &t.light.front,
            recv: &self.r.geo,
            sampler: self.nearest,
            mips,
        };
        self.p.coverage.record(cmd, &inputs);
        self.barrier(cmd, |b| {
            b.buffer(&t.photon.coverage, &[Access::ComputeWrite], &[Access::ComputeRead]);
        });
    }

    /// Step 3: photons, in batches; each batch's photons are traced (step 4) and splatted (step 5) into the
    /// caustic flux map.
    fn photons(&self, rec: &mut Rec, slots: u32) -> VkResult<()> {
        let (t, d) = (self.t, self.d);
        let cmd = rec.cmd;
        rec.ts.mark(cmd, "photon_init");
        let debug = self.s.debug_photons > 0;
        self.barrier(cmd, |b| {
            for buf in [&t.photon.state, &t.photon.photons, &t.photon.indirect, &t.photon.debug, &t.photon.transport] {
                b.buffer(buf, &[Access::FrameStart], &[Access::TransferDst]);
            }
            if self.compute_splat {
                b.buffer(&self.r.flux_texels, &[Access::FrameStart], &[Access::TransferDst]);
            } else {
                b.image(&self.r.flux, &[Access::FrameStart], &[Access::ColorAttachment]);
            }
        });
        unsafe {
            if self.compute_splat {
                d.cmd_fill_buffer(cmd, self.r.flux_texels.raw, 0, vk::WHOLE_SIZE, 0);
            }
            d.cmd_fill_buffer(cmd, t.photon.state.raw, 0, vk::WHOLE_SIZE, 0);
            d.cmd_fill_buffer(cmd, t.photon.transport.raw, 0, vk::WHOLE_SIZE, 0);
            // Header (count, capacity) and rows: disjoint ranges, so the two transfers need no barrier between them.
            d.cmd_update_buffer(cmd, t.photon.debug.raw, 0, bytemuck::bytes_of(&[0u32, self.s.debug_photons, 0, 0]));
            d.cmd_fill_buffer(cmd, t.photon.debug.raw, 16, vk::WHOLE_SIZE, 0);
            if debug {
                // Canary after the capacity: a shader writing past its photon budget would overwrite it.
                let cap = 8 * t.photon.capacity as u64;
                d.cmd_fill_buffer(cmd, t.photon.photons.raw, cap, 8 * PHOTON_GUARD as u64, CANARY);
            }
        }
        let all = [Access::ComputeWrite, Access::IndirectRead];
        self.barrier(cmd, |b| {
            for buf in [&t.photon.state, &t.photon.photons, &t.photon.indirect] {
                b.buffer(buf, &[Access::TransferDst], &all);
            }
            b.buffer(&t.photon.debug, &[Access::TransferDst], &[Access::ComputeWrite]);
            b.buffer(&t.photon.transport, &[Access::TransferDst], &[Access::ComputeWrite]);
            b.buffer(&t.photon.splats, &[Access::FrameStart], &[Access::ComputeWrite]);
            if self.compute_splat {
                b.buffer(&self.r.flux_texels, &[Access::TransferDst], &[Access::ComputeWrite]);
            }
            for q in &t.photon.queues {
                b.buffer(q, &[Access::FrameStart], &[Access::ComputeWrite]);
            }
        });
        match self.s.method {
            Method::Dense => self.dense(rec),
            Method::Adaptive => match self.s.driven {
                Driven::Gpu => {
                    self.adaptive_gpu(rec, slots);
                    Ok(())
                }
                Driven::Cpu => self.adaptive_cpu(rec),
            },
        }?;
        let cmd = rec.cmd;
        if self.compute_splat {
            self.copy_flux_texels(cmd);
        }
        self.barrier(cmd, |b| {
            if self.compute_splat {
                b.image(&self.r.flux, &[Access::TransferDst], &[Access::ComputeSampled]);
            } else {
                b.image(&self.r.flux, &[Access::ColorAttachment], &[Access::ComputeSampled]);
            }
            b.buffer(&t.photon.state, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.buffer(&t.photon.debug, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.buffer(&t.photon.photons, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.buffer(&t.photon.transport, &[Access::ComputeWrite], &[Access::TransferSrc]);
        });
        Ok(())
    }

    /// The compute splat's flux texels → the flux image the resolve samples.
    fn copy_flux_texels(&self, cmd: vk::CommandBuffer) {
        let img = &self.r.flux;
        self.barrier(cmd, |b| {
            b.buffer(&self.r.flux_texels, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.image(img, &[Access::FrameStart], &[Access::TransferDst]);
        });
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
                cmd,
                self.r.flux_texels.raw,
                img.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &[region],
            )
        };
    }

    /// Barriers between one batch's splat and the next batch's compute passes.
    fn after_splat(&self, cmd: vk::CommandBuffer) {
        let t = self.t;
        self.barrier(cmd, |b| {
            if self.compute_splat {
                b.buffer(&self.r.flux_texels, &[Access::ComputeWrite], &[Access::ComputeWrite]);
                b.buffer(&t.photon.splats, &[Access::ComputeRead], &[Access::ComputeWrite]);
            } else {
                b.image(&self.r.flux, &[Access::ColorAttachment], &[Access::ColorAttachment]);
                b.buffer(&t.photon.splats, &[Access::VertexRead], &[Access::ComputeWrite]);
            }
            // The trace read the photons and the indirect arguments, the splat read the records and the draw.
            b.buffer(&t.photon.photons, &[Access::ComputeRead], &[Access::ComputeWrite]);
            // Exact transport's commit read the traversal state; the next batch's init writes it.
            b.buffer(&t.photon.state, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            b.buffer(
                &t.photon.indirect,
                &[Access::ComputeRead, Access::IndirectRead],
                &[Access::ComputeWrite, Access::IndirectRead],
            );
        });
    }

    /// Steps 4 and 5 for one batch: trace its emitted photons (compute, dispatched indirectly), then splat them.
    /// `commit`: adaptive traversal's last stats pass, which commits or splits the batch. Under two-interface
    /// transport it ran already; under exact transport it runs after the waves, which may abort the batch.
    fn trace_and_splat(&self, rec: &mut Rec, clear: bool, commit: bool) {
        let t = self.t;
        let (cmd, b, ph) = (rec.cmd, self.bindings(), &self.p.photons);
        self.compute_to_compute(cmd);
        if self.s.transport == Transport::Exact {
            self.exact_transport(rec, commit);
        } else {
            rec.ts.mark(cmd, "photon_trace");
            ph.trace(cmd, &b, self.debug());
        }
        let reader = if self.compute_splat { Access::ComputeRead } else { Access::VertexRead };
        self.barrier(cmd, |b| {
            b.buffer(&t.photon.splats, &[Access::ComputeWrite], &[reader]);
            // The compute splat reads its record range from the draw command as well as dispatching from it.
            b.buffer(&t.photon.indirect, &[Access::ComputeWrite], &[Access::IndirectRead, Access::ComputeRead]);
        });
        rec.ts.mark(cmd, "splat");
        if self.compute_splat {
            ph.splat_compute(cmd, &b, self.tiled_splat);
        } else {
            ph.splat(cmd, &b, &self.r.flux, clear);
        }
    }

    /// Compute → compute on the traversal buffers (and the indirect arguments just written).
    fn compute_to_compute(&self, cmd: vk::CommandBuffer) {
        let t = self.t;
        let next = [Access::ComputeWrite, Access::IndirectRead];
        self.barrier(cmd, |b| {
            b.buffer(&t.photon.state, &[Access::ComputeWrite], &next);
            b.buffer(&t.photon.photons, &[Access::ComputeWrite], &next);
            b.buffer(&t.photon.indirect, &[Access::ComputeWrite], &next);
            if self.s.transport == Transport::Exact {
                b.buffer(&t.photon.transport, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            }
        });
    }

    /// Exact transport of the batch's emitted photons, in waves (docs/design.md step 4): every wave is one
    /// vkCmdDispatchIndirect whose arguments the transport pass wrote from the previous wave's appends. The host
    /// records MAX_INTERACTIONS + 1 waves; those after the queue empties dispatch zero work groups.
    fn exact_transport(&self, rec: &mut Rec, commit: bool) {
        use crate::passes::photons::transport_mode as tm;
        let (t, cmd, b, ph) = (self.t, rec.cmd, self.bindings(), &self.p.photons);
        let adaptive = self.s.method == Method::Adaptive;
        let may_abort = adaptive && self.s.batching;
        let step = |b: &mut Barriers| {
            let next = [Access::ComputeWrite, Access::IndirectRead];
            b.buffer(&t.photon.transport, &[Access::ComputeWrite], &next);
            b.buffer(&t.photon.indirect, &[Access::ComputeWrite, Access::IndirectRead], &next);
            b.buffer(&t.photon.state, &[Access::ComputeWrite], &next);
            b.buffer(&t.photon.splats, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            for q in &t.photon.queues {
                b.buffer(q, &[Access::ComputeWrite], &[Access::ComputeWrite]);
            }
        };
        rec.ts.mark(cmd, "transport_primary");
        ph.transport(cmd, &b, if adaptive { tm::BEGIN_ADAPTIVE } else { tm::BEGIN_DENSE }, may_abort, 0);
        for wave in 0..=MAX_INTERACTIONS {
            self.barrier(cmd, step);
            if wave >= 1 {
                rec.ts.mark(cmd, WAVE_LABELS[wave as usize - 1]);
            }
            ph.wave(cmd, &b, wave, may_abort, self.s.bvh_layout);
            self.barrier(cmd, step);
            ph.transport(cmd, &b, tm::AFTER_WAVE, may_abort, wave + 1);
        }
        self.barrier(cmd, step);
        rec.ts.mark(cmd, "stats");
        if commit {
            ph.stats(cmd, &b, self.s.level, stats_mode::COMMIT, self.s.traverse_dispatch_wg());
            self.barrier(cmd, step);
        }
        ph.transport(cmd, &b, tm::COMMIT, may_abort, 0);
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
            let cmd = rec.cmd;
            let row0 = band * rows;
            rec.ts.mark(cmd, "photon_init");
            ph.init(cmd, &b, init_mode::DENSE, self.s.traverse_wg);
            self.compute_to_compute(cmd);
            rec.ts.mark(cmd, "dense_emit");
            ph.dense_emit(cmd, &b, self.s.level, row0, rows.min(n - row0));
            self.compute_to_compute(cmd);
            rec.ts.mark(cmd, "stats");
            ph.stats(cmd, &b, self.s.level, stats_mode::DENSE, self.s.traverse_wg);
            self.trace_and_splat(rec, band == 0, false);
            if band + 1 < bands {
                self.after_splat(cmd);
            }
        }
        Ok(())
    }

    /// GPU-driven adaptive traversal: a fixed command sequence per batch slot, every dispatch and draw indirect.
    fn adaptive_gpu(&self, rec: &mut Rec, slots: u32) {
        let b = self.bindings();
        let ph = &self.p.photons;
        let shape = self.traverse_shape();
        let wg = shape.wg;
        let cmd = rec.cmd;
        let exact = self.s.transport == Transport::Exact;
        ph.init(cmd, &b, init_mode::FRAME, wg);
        self.compute_to_compute(cmd);
        rec.report.batch_slots = slots;
        for slot in 0..slots {
            rec.ts.mark(cmd, "photon_init");
            ph.init(cmd, &b, init_mode::BATCH, wg);
            self.compute_to_compute(cmd);
            for level in 0..=self.s.level {
                rec.ts.mark(cmd, TRAVERSE_LABELS[level as usize]);
                ph.traverse_indirect(cmd, &b, level, shape);
                self.compute_to_compute(cmd);
                rec.ts.mark(cmd, "stats");
                let mode = if level == self.s.level && !exact { stats_mode::COMMIT } else { stats_mode::LEVEL };
                ph.stats(cmd, &b, level, mode, wg);
                self.compute_to_compute(cmd);
            }
            self.trace_and_splat(rec, slot == 0, exact);
            if slot + 1 < slots {
                self.after_splat(cmd);
            }
        }
    }

    /// Copy the traversal state to the readback buffer (and make it visible to the host after the submit).
    fn copy_state(&self, cmd: vk::CommandBuffer) {
        let t = self.t;
        self.barrier(cmd, |b| {
            b.buffer(&t.photon.state, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.buffer(self.readback, &[Access::FrameStart], &[Access::TransferDst]);
        });
        let size = std::mem::size_of::<TraversalState>() as u64;
        unsafe {
            self.d.cmd_copy_buffer(
                cmd,
                t.photon.state.raw,
                self.readback.raw,
                &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size }],
            )
        };
        self.barrier(cmd, |b| {
            b.buffer(self.readback, &[Access::TransferDst], &[Access::HostRead]);
            b.buffer(&t.photon.state, &[Access::TransferSrc], &[Access::ComputeWrite]);
        });
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
        ph.init(rec.cmd, &b, init_mode::FRAME, wg);
        self.compute_to_compute(rec.cmd);
        let mut first = true;
        let mut batches = 0;
        loop {
            rec.ts.mark(rec.cmd, "photon_init");
            ph.init(rec.cmd, &b, init_mode::BATCH, wg);
            self.copy_state(rec.cmd);
            rec.roundtrip()?;
            let mut st = self.read_state()?;
            if st.start_level >= MAX_LEVELS {
                break;
            }
            batches += 1;
            for level in st.start_level..=self.s.level {
                let cmd = rec.cmd;
                self.compute_to_compute(cmd);
                rec.ts.mark(cmd, TRAVERSE_LABELS[level as usize]);
                if st.aborted == 0 {
                    ph.traverse_direct(cmd, &b, level, st.read_count, shape);
                }
                self.compute_to_compute(cmd);
                rec.ts.mark(cmd, "stats");
                let last = level == self.s.level;
                let commit = last && self.s.transport == Transport::TwoInterface;
                ph.stats(cmd, &b, level, if commit { stats_mode::COMMIT } else { stats_mode::LEVEL }, wg);
                if !last {
                    self.copy_state(cmd);
                    rec.roundtrip()?;
                    st = self.read_state()?;
                }
            }
            self.trace_and_splat(rec, first, self.s.transport == Transport::Exact);
            self.after_splat(rec.cmd);
            first = false;
        }
        rec.report.batch_slots = batches;
        if first && !self.compute_splat {
            // No batch at all: the flux map still needs clearing (the compute splat's texels were cleared).
            let cmd = rec.cmd;
            crate::passes::begin_rendering(self.d, cmd, self.r.flux.extent, &[&self.r.flux], true, None);
            unsafe { self.d.cmd_end_rendering(cmd) };
        }
        // The last barrier left the buffers ready for compute; restore what `photons` expects.
        let t = self.t;
        self.barrier(rec.cmd, |b| {
            b.buffer(&t.photon.state, &[Access::ComputeWrite, Access::TransferSrc], &[Access::ComputeWrite]);
        });
        Ok(())
    }

    /// Step 6: caustic flux → irradiance.
    fn resolve(&self, rec: &mut Rec) {
        let cmd = rec.cmd;
        rec.ts.mark(cmd, "resolve");
        // A light's later color passes write their channel and keep the earlier ones.
        let earlier = [Access::FragmentSampled, Access::ComputeSampled];
        let from: &[Access] = if self.channel == 0 { &[Access::FrameStart] } else { &earlier };
        self.barrier(cmd, |b| {
            b.image(&self.r.irradiance, from, &[Access::ComputeWrite]);
        });
        self.p.resolve.record(cmd, self.ubo, &self.r.flux, &self.r.geo, &self.r.irradiance, self.nearest);
        self.barrier(cmd, |b| {
            b.image(&self.r.irradiance, &[Access::ComputeWrite], &[Access::FragmentSampled, Access::ComputeSampled]);
        });
    }

    /// No refractor: the irradiance map is zero (no caustic pass is recorded).
    fn clear_irradiance(&self, rec: &mut Rec) {
        let cmd = rec.cmd;
        let img = &self.r.irradiance;
        self.barrier(cmd, |b| {
            b.image(img, &[Access::FrameStart], &[Access::TransferDst]);
        });
        unsafe {
            self.d.cmd_clear_color_image(
                cmd,
                img.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &vk::ClearColorValue { float32: [0.0; 4] },
                &[img.range()],
            )
        };
        self.barrier(cmd, |b| {
            b.image(img, &[Access::TransferDst], &[Access::FragmentSampled, Access::ComputeSampled]);
        });
    }

    /// Step 7a: the eye view of the receivers under this light: the first light draws their eye g-buffer, then
    /// each light's shading writes (the first) or adds to (the others) the radiance, and the caustics and direct
    /// AOVs when the frame reads one back, so the AOVs are the sums over lights.
    fn eye_receivers(&self, rec: &mut Rec) {
        let (t, cmd) = (self.t, rec.cmd);
        let e = &t.eye;
        let first = self.light == 0;
        let out: &[&Image] = if self.eye_aovs { &[&e.radiance, &e.caustics, &e.direct] } else { &[&e.radiance] };
        let g = EyeGbuffer { geo: &e.recv, albedo: &e.albedo, depth: &e.depth };
        if first {
            // The g-buffer does not depend on the light: drawn once, before the first light's shading.
            self.barrier(cmd, |b| {
                b.image(&e.recv, &[Access::FrameStart], &[Access::ColorAttachment]);
                b.image(&e.albedo, &[Access::FrameStart], &[Access::ColorAttachment]);
                b.image(&e.depth, &[Access::FrameStart], &[Access::DepthAttachment]);
            });
            self.p.eye.record_gbuffer(cmd, self.sb, &self.data.camera, &g);
            rec.ts.mark(cmd, "eye.shade");
        }
        self.barrier(cmd, |b| {
            if first {
                b.image(&e.recv, &[Access::ColorAttachment], &[Access::ComputeSampled]);
                b.image(&e.albedo, &[Access::ColorAttachment], &[Access::ComputeSampled]);
            }
            for img in out {
                // A further light reads what the last one wrote, pixel by pixel.
                let from = if first { Access::FrameStart } else { Access::ComputeWrite };
                b.image(img, &[from], &[Access::ComputeWrite]);
            }
        });
        let inputs = EyeInputs {
            ubo: self.ubo,
            shadow: &self.r.shadow,
            irradiance: &self.r.irradiance,
            recv: &self.r.geo,
            nearest: self.nearest,
            linear: self.linear,
        };
        self.p.eye.record_shade(cmd, &inputs, &g, out, !first);
    }

    /// Step 7b: the eye view of the refractors: front and back g-buffers for the composite.
    fn eye_refractors(&self, rec: &mut Rec) {
        let (t, cmd) = (self.t, rec.cmd);
        let e = &t.eye;
        let g = &self.p.geometry;
        let cam = &self.data.camera;
        // The exact composite traces the glass through the BVH: it needs only where the front surface is.
        let exact = self.exact_eye();
        self.barrier(cmd, |b| {
            b.image(&e.front, &[Access::FrameStart], &[Access::ColorAttachment]);
            if !exact {
                for img in [&e.front_aux, &e.back] {
                    b.image(img, &[Access::FrameStart], &[Access::ColorAttachment]);
                }
            }
            b.image(&e.refr_depth, &[Access::FrameStart], &[Access::DepthAttachment]);
        });
        let ior = (!exact && self.sb.shared_ior.is_none()).then_some(&e.front_aux);
        g.record_front(cmd, self.sb, &e.front, ior, &e.refr_depth, cam);
        if exact {
            return;
        }
        self.barrier(cmd, |b| {
            b.image(&e.refr_depth, &[Access::DepthAttachment], &[Access::DepthAttachment]);
        });
        g.record(
            cmd,
            &g.back,
            self.sb,
            &GeometryTarget { colors: &[&e.back], depth: &e.refr_depth, view: cam, ranges: &[self.sb.refractors] },
        );
    }

    /// The composite traces eye rays through the BVH (exact transport, full-quality frames); else it refracts
    /// through the eye's front and back buffers.
    fn exact_eye(&self) -> bool {
        self.s.transport == Transport::Exact && !self.preview
    }

    /// Step 8: the glass (eye rays through the BVH, or deferred refraction), supersample resolve, tone mapping.
    fn composite(&self, rec: &mut Rec) {
        let (t, cmd) = (self.t, rec.cmd);
        let e = &t.eye;
        rec.ts.mark(cmd, "composite");
        self.barrier(cmd, |b| {
            b.image(&e.radiance, &[Access::ComputeWrite], &[Access::ComputeSampled]);
            b.image(&e.front, &[Access::ColorAttachment], &[Access::ComputeSampled]);
            // Bound but not read by the exact composite, which draws neither.
            let from = if self.exact_eye() { Access::FrameStart } else { Access::ColorAttachment };
            for img in [&e.front_aux, &e.back] {
                b.image(img, &[from], &[Access::ComputeSampled]);
            }
            b.image(&e.beauty, &[Access::FrameStart], &[Access::ComputeWrite]);
            b.image(&e.hdr, &[Access::FrameStart], &[Access::ComputeWrite]);
        });
        self.p.composite.record(
            cmd,
            &CompositeInputs {
                ubo: self.ubo,
                radiance: &e.radiance,
                front: &e.front,
                front_aux: &e.front_aux,
                back: &e.back,
                beauty: &e.beauty,
                hdr: &e.hdr,
                shadow: &self.r.shadow,
                irradiance: &self.r.irradiance,
                recv: &self.r.geo,
                bvh: &self.sb.bvh,
                nearest: self.nearest,
                linear: self.linear,
                exact: self.exact_eye(),
            },
        );
        self.barrier(cmd, |b| {
            b.image(&e.beauty, &[Access::ComputeWrite], &[Access::TransferSrc]);
            b.image(&e.hdr, &[Access::ComputeWrite], &[Access::TransferSrc]);
        });
    }

    /// Copy the requested AOV, the traversal state, the debug dump and the guard to the readback buffer.
    fn readback(&self, rec: &mut Rec, aov: Option<Aov>) -> Option<Aov> {
        let (t, cmd, d) = (self.t, rec.cmd, self.d);
        let layout = Targets::readback_layout(self.s, 16 * t.width as u64 * t.height as u64);
        let image: Option<&Image> = aov.map(|a| match a {
            Aov::Beauty => &t.eye.beauty,
            Aov::BeautyHdr => &t.eye.hdr,
            Aov::Caustics => &t.eye.caustics,
            Aov::Direct => &t.eye.direct,
        });
        self.barrier(cmd, |b| {
            // After the lights' state copies (copy_light_state): write-after-write on other ranges of the buffer.
            b.buffer(self.readback, &[Access::TransferDst], &[Access::TransferDst]);
            if let Some(img) = image {
                // The composite's outputs are already transfer sources.
                if !std::ptr::eq(img, &t.eye.beauty) && !std::ptr::eq(img, &t.eye.hdr) {
                    b.image(img, &[Access::ComputeWrite], &[Access::TransferSrc]);
                }
            }
        });
        unsafe {
            if let Some(img) = image {
                let region = vk::BufferImageCopy::default()
                    .buffer_offset(layout.aov)
                    .image_subresource(vk::ImageSubresourceLayers {
                        aspect_mask: vk::ImageAspectFlags::COLOR,
                        mip_level: 0,
                        base_array_layer: 0,
                        layer_count: 1,
                    })
                    .image_extent(vk::Extent3D { width: t.width, height: t.height, depth: 1 });
                d.cmd_copy_image_to_buffer(
                    cmd,
                    img.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    self.readback.raw,
                    &[region],
                );
            }
        }
        self.barrier(cmd, |b| {
            b.buffer(self.readback, &[Access::TransferDst], &[Access::HostRead]);
        });
        aov
    }

    /// Copy this light's traversal and transport state (and, for the first light, the debug dump and the guard)
    /// to its slot of the readback buffer, before the next light's photons reset them.
    fn copy_light_state(&self, rec: &mut Rec) {
        let (t, cmd, d) = (self.t, rec.cmd, self.d);
        let layout = Targets::readback_layout(self.s, 16 * t.width as u64 * t.height as u64);
        let i = self.pass as u64;
        let state = std::mem::size_of::<TraversalState>() as u64;
        let transport = std::mem::size_of::<TransportState>() as u64;
        unsafe {
            let copies = [vk::BufferCopy { src_offset: 0, dst_offset: layout.state + i * state, size: state }];
            d.cmd_copy_buffer(cmd, t.photon.state.raw, self.readback.raw, &copies);
            let copies =
                [vk::BufferCopy { src_offset: 0, dst_offset: layout.transport + i * transport, size: transport }];
            d.cmd_copy_buffer(cmd, t.photon.transport.raw, self.readback.raw, &copies);
            if self.s.debug_photons > 0 && self.pass == 0 {
                let debug = 16 + 16 * DEBUG_ROWS * self.s.debug_photons as u64;
                d.cmd_copy_buffer(
                    cmd,
                    t.photon.debug.raw,
                    self.readback.raw,
                    &[vk::BufferCopy { src_offset: 0, dst_offset: layout.debug, size: debug }],
                );
                let guard = vk::BufferCopy {
                    src_offset: 8 * t.photon.capacity as u64,
                    dst_offset: layout.guard,
                    size: 8 * PHOTON_GUARD as u64,
                };
                d.cmd_copy_buffer(cmd, t.photon.photons.raw, self.readback.raw, &[guard]);
            }
        }
    }
}

/// Each light's state from the readback buffer (lights that ran their caustic stages this frame).
fn read_results(t: &Targets, readback: &Buffer, s: &ResolvedSettings, report: &mut FrameReport) -> AppResult<()> {
    let layout = Targets::readback_layout(s, 16 * t.width as u64 * t.height as u64);
    if report.reused {
        return Ok(());
    }
    for (i, l) in report.lights.iter_mut().enumerate() {
        if !l.caustics {
            continue;
        }
        let i = i as u64;
        let st =
            readback.read::<TraversalState>(layout.state + i * std::mem::size_of::<TraversalState>() as u64, 1)?[0];
        l.state = Some(st);
        if s.transport == Transport::Exact {
            let at = layout.transport + i * std::mem::size_of::<TransportState>() as u64;
            l.transport = Some(readback.read::<TransportState>(at, 1)?[0]);
        }
    }
    if let Some(st) = report.lights[0].state {
        report.unfinished_tiles = if s.method == Method::Adaptive { st.stack_size } else { 0 };
    }
    if report.lights[0].caustics && s.debug_photons > 0 {
        let header = readback.read::<[u32; 4]>(layout.debug, 1)?[0];
        let n = header[0].min(s.debug_photons) as usize;
        report.debug_rows = readback.read::<[u32; 4]>(layout.debug + 16, n * DEBUG_ROWS as usize)?;
        let guard = readback.read::<u32>(layout.guard, 2 * PHOTON_GUARD as usize)?;
        report.guard_intact = Some(guard.iter().all(|&w| w == CANARY));
    }
    Ok(())
}

fn read_aov(t: &Targets, readback: &Buffer, s: &ResolvedSettings, aov: Option<Aov>) -> AppResult<Option<AovData>> {
    let layout = Targets::readback_layout(s, 16 * t.width as u64 * t.height as u64);
    let n = (t.width * t.height) as usize;
    Ok(match aov {
        None => None,
        Some(Aov::Beauty) => {
            Some(AovData::Rgba8 { width: t.width, height: t.height, rgba: readback.read::<u8>(layout.aov, 4 * n)? })
        }
        Some(_) => {
            Some(AovData::Float { width: t.width, height: t.height, rgba: readback.read::<[f32; 4]>(layout.aov, n)? })
        }
    })
}
