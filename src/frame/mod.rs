//! One frame as data flow: [`record_frame`] records the pipeline's steps in order over resources it borrows, and
//! never sees the renderer. Each step declares how it uses its images and buffers to the frame's
//! [`Tracker`](crate::vk::Tracker), which emits the barriers (no step names what came before it). The steps are
//! those of docs/design.md "Pipeline", with the same numbers, after the scene update (when objects moved since the
//! last frame: their world-space vertices placed from object space, and the BVH's instance records written):
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

pub(crate) mod deposit;
mod photons;
pub mod report;
mod steps;

use crate::gpu_types::FrameData;
use crate::passes::composite::LightMaps;
use crate::passes::Passes;
use crate::scene::view::LightView;
use crate::scene_gpu::SceneBuffers;
use crate::settings::{ResolvedSettings, Splat};
use crate::targets::{ReceiverTargets, Targets};
use crate::vk::{Access, Buffer, Device, Recorder, Sampler, Timestamps, Tracker, VkResult};
use ash::vk;
use deposit::Step;
pub use report::{Aov, AovData, DebugPhoton, FrameReport, LightReport, SceneUpdateReport, SlotVerdict};
use std::time::Instant;

/// Stage label of the CPU-driven traversal's host round trips (GPU idle while the host reads and records).
pub const HOST_ROUNDTRIP: &str = "host_roundtrip";

/// What a frame records with, borrowed: the device, the pipelines, the scene on the GPU, the samplers and the
/// targets, with the frame-in-flight slot whose uniforms and readback buffer it uses.
pub(crate) struct FrameResources<'a> {
    pub device: &'a Device,
    pub passes: &'a Passes,
    pub scene: &'a SceneBuffers,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
    pub targets: &'a Targets,
    pub slot: usize,
}

/// The objects that moved since the last frame: the scene update (before step 1) places their vertices and writes the
/// BVH's instance records.
#[derive(Default)]
pub(crate) struct SceneUpdate {
    /// Per moved object: its transform and ranges in the scene's buffers.
    pub moves: Vec<crate::gpu_types::SceneUpdatePush>,
    /// Every instance record, when the BVH is built and an object moved.
    pub instances: Option<Vec<crate::bvh::GpuInstance>>,
    /// Simulated water surfaces put back at rest (ranges of `SceneBuffers::heights`: first float, count), then
    /// stepped to the frame's time (drops and steps, in order), before they are displaced.
    pub water_rest: Vec<(u32, u32)>,
    pub water_steps: Vec<crate::gpu_types::WaterStepPush>,
    /// Water displaced to the frame's time: raster vertices (after `moves`), and BVH triangles.
    pub water_vertices: Vec<crate::gpu_types::WaterPush>,
    pub water_triangles: Vec<crate::gpu_types::WaterPush>,
    /// Every morphing object's weights at the frame's time (written before the morphs), when one is morphed.
    pub morph_weights: Option<Vec<f32>>,
    /// Morphing objects weighted to the frame's time: raster vertices (after `moves`), and BVH triangles.
    pub morph_vertices: Vec<crate::gpu_types::MorphPush>,
    pub morph_triangles: Vec<crate::gpu_types::MorphPush>,
    /// The deforming meshes' BVHs to refit (after their triangles), one height of one mesh each, and how many
    /// meshes; then their wide nodes, one height of one mesh each, when the wide layout is on the GPU.
    pub refits: Vec<crate::gpu_types::RefitPush>,
    pub wide_refits: Vec<crate::gpu_types::RefitPush>,
    pub refit_meshes: u32,
}

impl SceneUpdate {
    fn is_empty(&self) -> bool {
        self.moves.is_empty()
            && self.instances.is_none()
            && self.water_rest.is_empty()
            && self.water_steps.is_empty()
            && self.water_vertices.is_empty()
            && self.water_triangles.is_empty()
            && self.morph_vertices.is_empty()
            && self.morph_triangles.is_empty()
            && self.refits.is_empty()
    }
}

/// What a frame records: the decisions made before recording (by the renderer, from its inputs).
pub(crate) struct FramePlan<'a> {
    /// The scene update: the objects that moved.
    pub scene_update: &'a SceneUpdate,
    /// The settings at this frame's level.
    pub settings: &'a ResolvedSettings,
    /// The uniforms of each pass (light-major: one per light and color channel), already written to the slot's
    /// uniform buffers.
    pub data: &'a [FrameData],
    /// Per light view: whether a refractor lies in its light (its caustic stages run).
    pub caustics: &'a [bool],
    /// Per light view: its light and cube face.
    pub emitters: &'a [crate::renderer::Emitter],
    /// Color passes per light: 1, or 3 when some glass needs color and the photons cannot carry it.
    pub channels: usize,
    /// The first light's photon view (for the report).
    pub photon_view: Option<LightView>,
    /// The caustic maps of the last frame serve this one: steps 1 to 6 are not recorded.
    pub reused: bool,
    /// The eye view of the last frame serves this one too: steps 7 and 8 are not recorded.
    pub eye_reused: bool,
    /// The deposits the frame's landings go to, in the order they try them (a subset of
    /// [`deposit::DEPOSITS`]): the light maps, and the eye deposit where it runs (docs/design.md "The eye deposit").
    pub deposits: &'a [deposit::Deposit],
    /// Clear the frame-scoped deposits' stores before the lights' passes (else they add to them, or they are kept).
    pub clear_deposits: bool,
    /// A preview: one eye sample per pixel (glass traced as in a still, at the preview's resolution).
    pub preview: bool,
    /// The AOV to copy to the readback buffer.
    pub aov: Option<Aov>,
    /// GPU-driven batching: the batch slots to record.
    pub batch_slots: u32,
    /// The rest of an earlier frame's batches: that frame ran out of batch slots with tiles left on the GPU's stack.
    pub continuation: Option<Continuation<'a>>,
}

/// A frame that finishes the batches of the frame before it: the passes it names restore their traversal and
/// transport state from that frame's readback buffer (the stack of tiles left, the counts and the energy account
/// so far), trace the remaining tiles into a cleared flux map, and add its irradiance to the pass's map; the other
/// passes' maps are kept as they are.
#[derive(Clone, Copy, Debug)]
pub struct Continuation<'a> {
    /// Per pass: whether it continues.
    pub passes: &'a [bool],
    /// The frame-in-flight slot whose readback buffer holds the earlier frame's states.
    pub from_slot: usize,
}

impl FrameReport {
    /// What the frame's report knows before it is recorded: its plan.
    fn start(&mut self, plan: &FramePlan, compute_splat: bool) {
        self.caustics = plan.caustics.first().copied().unwrap_or(false);
        self.compute_splat = compute_splat;
        self.photon_view = plan.photon_view;
        self.reused = plan.reused;
        self.level = plan.settings.level;
        self.preview = plan.preview;
    }
}

impl FramePlan<'_> {
    /// Whether the frame composites the beauty image: every frame but one that reads back the caustics or direct
    /// AOV.
    pub fn beauty(&self) -> bool {
        !matches!(self.aov, Some(Aov::Caustics) | Some(Aov::Direct))
    }

    fn lights(&self) -> usize {
        self.caustics.len()
    }
}

/// The mutable side of a frame: the command buffer being recorded (the CPU-driven path submits mid-frame), the
/// access tracker, the timestamps and the report.
pub(crate) struct Rec<'a> {
    /// None when the frame records into a command buffer the host owns (then it cannot submit mid-frame).
    pub recorder: Option<&'a mut Recorder>,
    pub ts: &'a mut Timestamps,
    pub sync: &'a mut Tracker,
    pub cmd: vk::CommandBuffer,
    pub report: FrameReport,
    pub record_time: f64,
    pub mark: Instant,
}

impl Rec<'_> {
    /// Submit what is recorded, wait for it, and start a new command buffer (CPU-driven traversal only).
    fn roundtrip(&mut self) -> VkResult<()> {
        let Some(recorder) = self.recorder.as_mut() else {
            return Err(crate::vk::VkError::Unsupported(
                "CPU-driven traversal submits mid-frame; it cannot record into a host's command buffer".into(),
            ));
        };
        self.ts.mark(self.cmd, HOST_ROUNDTRIP);
        self.record_time += self.mark.elapsed().as_secs_f64();
        recorder.submit_and_wait()?;
        self.report.host_readbacks += 1;
        self.mark = Instant::now();
        self.cmd = recorder.begin()?;
        Ok(())
    }

    /// Emit the barriers the declared accesses need.
    fn flush(&mut self, d: &Device) {
        self.sync.flush(d, self.cmd);
    }
}

/// One pass of the frame's light-side steps (a light, in one color channel), with everything its steps read.
struct Ctx<'a> {
    d: &'a Device,
    p: &'a Passes,
    sb: &'a SceneBuffers,
    nearest: &'a Sampler,
    linear: &'a Sampler,
    t: &'a Targets,
    /// The current light's receiver maps.
    r: &'a ReceiverTargets,
    ubo: &'a Buffer,
    /// This frame-in-flight slot's readback buffer.
    readback: &'a Buffer,
    light: usize,
    /// Index of this (light, color channel) pass, and its channel among the light's (0 for a gray frame).
    pass: usize,
    channel: usize,
    s: &'a ResolvedSettings,
    data: &'a FrameData,
    /// The records are splatted by the compute pass into the flux texels (else drawn as points).
    compute_splat: bool,
    /// The compute splat gathers a work group's taps in shared memory first.
    tiled_splat: bool,
    /// The resolve reads the compute splat's flux texels through their texel view and adds the first coarse level
    /// itself, so that level's collapse and the copy into the flux image are not recorded (else it samples the
    /// flux image).
    resolve_texels: bool,
    /// The frame reads back the caustics or direct AOV, so the eye view writes them (else only the radiance).
    eye_aovs: bool,
}

/// The scene update, before step 1: place the moved objects' vertices in world space and deform the deforming ones
/// (compute), write the BVH's instance records (transfer), and refit the deformed BVHs (compute). Each pass declares
/// its uses as it binds them, and each transfer its accesses; the passes that read the results (the rasterizer's
/// vertex and index reads, the traversals' reads of the BVH) declare theirs.
fn scene_update(res: &FrameResources, up: &SceneUpdate, rec: &mut Rec) -> VkResult<()> {
    if up.is_empty() {
        return Ok(());
    }
    let (d, sb, update) = (res.device, res.scene, &res.passes.scene_update);
    if let Some(weights) = &up.morph_weights {
        rec.ts.mark(rec.cmd, "scene_update.weights");
        rec.sync.buffer(&sb.morph_weights, &[Access::TransferDst]);
        rec.flush(d);
        update.write(rec.cmd, &sb.morph_weights, weights);
    }
    if !up.water_rest.is_empty() || !up.water_steps.is_empty() {
        rec.ts.mark(rec.cmd, "scene_update.water_steps");
        if !up.water_rest.is_empty() {
            rec.sync.buffer(&sb.heights, &[Access::TransferDst]);
            rec.flush(d);
            update.water_rest(rec.cmd, sb, &up.water_rest);
        }
        for job in &up.water_steps {
            update.water_step(rec.cmd, rec.sync, sb, job)?;
        }
    }
    rec.ts.mark(rec.cmd, "scene_update.vertices");
    let world = (&sb.vertices, &sb.indices);
    update.place(rec.cmd, rec.sync, (&sb.object_vertices, &sb.object_indices), world, &up.moves)?;
    // A moved deforming object's vertices were just placed at rest: the deformation overwrites them.
    update.water_vertices(rec.cmd, rec.sync, sb, &up.water_vertices)?;
    update.morph_vertices(rec.cmd, rec.sync, sb, &up.morph_vertices)?;
    if let Some(records) = &up.instances {
        rec.ts.mark(rec.cmd, "scene_update.instances");
        rec.sync.buffer(&sb.bvh.instances, &[Access::TransferDst]);
        rec.flush(d);
        update.write(rec.cmd, &sb.bvh.instances, records);
    }
    if !up.water_triangles.is_empty() || !up.morph_triangles.is_empty() || !up.refits.is_empty() {
        // Marked before the barrier, not after it: lavapipe takes a timestamp's time at its next flush, so a mark
        // between a barrier and a dispatch would charge the dispatch to the stage before it.
        rec.ts.mark(rec.cmd, "scene_update.triangles");
        update.water_triangles(rec.cmd, rec.sync, sb, &up.water_triangles)?;
        update.morph_triangles(rec.cmd, rec.sync, sb, &up.morph_triangles)?;
        rec.ts.mark(rec.cmd, "scene_update.refit");
        // One height per dispatch, each after the one below (its boxes are read).
        for job in &up.refits {
            update.refit(rec.cmd, rec.sync, sb, job)?;
        }
        for job in &up.wide_refits {
            update.refit_wide(rec.cmd, rec.sync, sb, job)?;
        }
    }
    Ok(())
}

/// Record one frame into `rec`: the steps in order, every barrier from the declared accesses. Returns the index of
/// the frame's first eye-view interval (the per-light sums of GPU time stop there) and the AOV its readback holds.
pub(crate) fn record_frame(res: &FrameResources, plan: &FramePlan, rec: &mut Rec) -> VkResult<(usize, Option<Aov>)> {
    let s = plan.settings;
    let t = res.targets;
    let nc = plan.channels;
    let compute_splat = s.splat.is_compute() && t.receivers[0].flux.format == vk::Format::R32_SFLOAT;
    let readback = &t.readbacks[res.slot];
    let ctx = |p: usize| Ctx {
        d: res.device,
        p: res.passes,
        sb: res.scene,
        nearest: res.nearest,
        linear: res.linear,
        t,
        r: &t.receivers[p / nc],
        ubo: &t.ubos[res.slot][p],
        readback,
        light: p / nc,
        pass: p,
        channel: p % nc,
        s,
        data: &plan.data[p],
        compute_splat,
        tiled_splat: s.splat == Splat::Tiled,
        resolve_texels: compute_splat && t.receivers[p / nc].flux_texels.texels != vk::BufferView::null(),
        eye_aovs: matches!(plan.aov, Some(Aov::Caustics) | Some(Aov::Direct)),
    };
    rec.report.start(plan, compute_splat);
    rec.ts.reset(rec.cmd);
    scene_update(res, plan.scene_update, rec)?;
    // The lights' state copies and the AOV readback write disjoint ranges of the readback buffer.
    rec.sync.buffer(readback, &[Access::TransferDst]);
    let mut lights_end = None;
    for step in deposit::order(plan.deposits, plan.clear_deposits, !plan.reused, !plan.eye_reused) {
        match step {
            Step::Clear(d) => ctx(0).clear_deposit(rec, d),
            Step::EyeGbuffer => {
                rec.ts.mark(rec.cmd, "eye.receivers");
                ctx(0).eye_gbuffer(rec)?;
            }
            Step::LightViews => light_views(plan, &ctx, rec)?,
            Step::EyeView { gbuffer } => {
                // The lights' own stages end where the eye view starts.
                lights_end = Some(rec.ts.len());
                eye_view(plan, &ctx, rec, gbuffer)?;
            }
        }
    }
    rec.report.eye_reused = plan.eye_reused;
    let lights_end = lights_end.unwrap_or_else(|| rec.ts.len());
    let c0 = ctx(0);
    if plan.eye_reused {
        // The beauty and HDR images are the last frame's, left as transfer sources by its composite.
        rec.ts.mark(rec.cmd, "eye_reused");
    }
    rec.ts.mark(rec.cmd, "readback");
    let aov = c0.readback(rec, plan.aov);
    Ok((lights_end, aov))
}

/// Steps 1 to 6 for every light view and color channel (or their reuse, or a continuation's remaining batches).
fn light_views<'a>(plan: &FramePlan, ctx: &impl Fn(usize) -> Ctx<'a>, rec: &mut Rec) -> VkResult<()> {
    let nc = plan.channels;
    for pass in 0..plan.lights() * nc {
        let c = ctx(pass);
        let first_segment = rec.ts.len();
        let caustics = plan.caustics[c.light];
        let first_channel = c.channel == 0;
        if let Some(cont) = plan.continuation {
            if cont.passes[pass] {
                c.light_gbuffers(rec, caustics, first_channel)?;
                c.coverage(rec)?;
                c.photons(rec, plan.batch_slots, Some(cont.from_slot))?;
                c.resolve(rec, true)?;
                c.copy_light_state(rec);
            } else if first_channel {
                c.reuse_caustics(rec);
            }
        } else if plan.reused {
            if first_channel {
                c.reuse_caustics(rec);
            }
        } else {
            c.light_gbuffers(rec, caustics, first_channel)?;
            if caustics {
                c.coverage(rec)?;
                c.photons(rec, plan.batch_slots, None)?;
                c.resolve(rec, false)?;
                c.copy_light_state(rec);
            } else if first_channel {
                c.clear_irradiance(rec);
            }
        }
        rec.report.lights.push(LightReport {
            light: plan.emitters[c.light].light,
            face: plan.emitters[c.light].face,
            // The pass's channel code, as its uniforms give it to the shaders.
            channel: c.data.pass.channel,
            caustics,
            first_segment,
            ..Default::default()
        });
    }
    Ok(())
}

/// Step 7 and 8: the eye view (drawing the receivers' eye g-buffer when `gbuffer`: no deposit drew it before the
/// photons), the glass and the composite.
fn eye_view<'a>(plan: &FramePlan, ctx: &impl Fn(usize) -> Ctx<'a>, rec: &mut Rec, gbuffer: bool) -> VkResult<()> {
    let nc = plan.channels;
    let c0 = ctx(0);
    if gbuffer {
        rec.ts.mark(rec.cmd, "eye.receivers");
    }
    for light in 0..plan.lights() {
        ctx(light * nc).eye_receivers(rec, gbuffer)?;
    }
    rec.ts.mark(rec.cmd, "eye.refractors");
    // A frame that reads back the caustics or direct AOV (the receivers' shading writes them) needs neither
    // the glass nor the beauty: its refractor buffers, glass passes and composite are not recorded (their
    // timestamps mark empty stages), and the renderer lets no later frame reuse its eye view.
    if plan.beauty() {
        c0.eye_refractors(rec)?;
        if c0.exact_eye() {
            // One glass pass for up to GLASS_LIGHTS lights (a fourth adds a pass): the trace runs once per
            // pass, each receiver it reaches shaded with the pass's lights.
            let lights: Vec<usize> = (0..plan.lights()).collect();
            for (k, group) in lights.chunks(crate::shaders::consts::GLASS_LIGHTS as usize).enumerate() {
                let more: Vec<LightMaps> = group[1..]
                    .iter()
                    .map(|&l| {
                        let c = ctx(l * nc);
                        LightMaps { ubo: c.ubo, shadow: &c.r.shadow, irradiance: &c.r.irradiance, recv: &c.r.geo }
                    })
                    .collect();
                ctx(group[0] * nc).eye_glass(rec, &more, k > 0)?;
            }
        }
        c0.composite(rec)?;
    } else {
        rec.ts.mark(rec.cmd, "composite");
    }
    Ok(())
}
