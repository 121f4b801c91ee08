//! The renderer: pipelines, the scene on the GPU, the views of the current frame, and its targets. One call of
//! [`Renderer::render`] records and submits a whole frame (src/frame.rs) and reports what happened.

use crate::error::{AppError, AppResult};
use crate::gpu_types::{FrameData, GpuView, TraversalState};
use crate::passes::Passes;
use crate::scene::view::{CameraView, LightView, Window};
use crate::scene::{Camera, LightKind, Material, Scene, MAX_LIGHTS};
use crate::scene_gpu::SceneBuffers;
use crate::settings::{Footprint, Method, ResolvedSettings, Settings, Transport};
use crate::shaders::consts::*;
use crate::targets::Targets;
use crate::vk::{Device, Recorder, Sampler, Timestamps, VkResult};
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// The light views of a frame and the eye camera.
#[derive(Clone, Copy, Debug)]
pub struct Views {
    /// Fitted to the refractors; None when there is nothing to refract (no dielectric, or none in the cone).
    pub photon: Option<LightView>,
    /// Over the receivers: caustic map, receiver g-buffer and shadow map.
    pub receiver: LightView,
    pub camera: CameraView,
}

impl Views {
    /// The views of light `index`.
    pub fn new(scene: &Scene, settings: &ResolvedSettings, camera: &CameraView, index: usize) -> AppResult<Views> {
        let light = &scene.lights[index];
        let all = || scene.objects.iter().flat_map(|o| o.mesh.positions.iter().copied());
        let refr = || scene.refractors().flat_map(|o| o.mesh.positions.iter().copied());
        let recv = || scene.receivers().flat_map(|o| o.mesh.positions.iter().copied());
        let behind = |o: &&crate::scene::Object| {
            o.mesh
                .positions
                .iter()
                .any(|p| (*p - light.position).dot((light.target - light.position).normalize()) <= 1e-4)
        };
        if light.kind == LightKind::Spot {
            if let Some(o) = scene.refractors().find(behind) {
                return Err(AppError::BadInput(format!(
                    "{}: object `{}` reaches behind the spot light's plane; a spot light must see every refractor in front of it",
                    scene.path.display(),
                    o.name
                )));
            }
        }
        if light.kind == LightKind::Point {
            if let Some(o) = scene.objects.iter().find(behind) {
                return Err(AppError::BadInput(format!(
                    "{}: object `{}` reaches behind the plane through point light {index} facing its target; its shadow and caustic maps are one frustum, so every object must lie in front of that plane (move the light or its `target`)",
                    scene.path.display(),
                    o.name
                )));
            }
        }
        let photon = if scene.has_refractors() {
            LightView::fit(light, refr(), refr(), settings.gbuffer_side(), 1.0)
        } else {
            None
        };
        let receiver = LightView::fit(light, recv(), all(), settings.caustic_res, 1.0)
            .or_else(|| LightView::fit(light, all(), all(), settings.caustic_res, 1.0))
            .unwrap_or_else(|| {
                let mut v = LightView::fit(light, std::iter::once(light.target), all(), settings.caustic_res, 1.0)
                    .expect("the light's target lies on its axis");
                v.window = Window { x0: -1.0, y0: -1.0, w: 2.0 };
                v
            });
        Ok(Views { photon, receiver, camera: *camera })
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aov {
    Beauty,
    /// The beauty image before exposure and tone mapping: linear radiance, W/(m²·sr) (written as EXR).
    BeautyHdr,
    Caustics,
    Direct,
}

impl std::str::FromStr for Aov {
    type Err = AppError;
    fn from_str(s: &str) -> AppResult<Aov> {
        match s {
            "beauty" => Ok(Aov::Beauty),
            "caustics" => Ok(Aov::Caustics),
            "direct" => Ok(Aov::Direct),
            _ => Err(AppError::BadInput(format!("--aov `{s}`: expected beauty, caustics or direct"))),
        }
    }
}

/// One pass of a frame: one light, in one color channel (or the only, gray one).
#[derive(Clone, Debug, Default)]
pub struct LightReport {
    /// The light's index in the scene.
    pub light: usize,
    /// 0: the gray pass; 1, 2, 3: red, green, blue.
    pub channel: u32,
    /// Whether this light's caustic stages ran (a refractor lies in its light).
    pub caustics: bool,
    /// Its traversal state and exact transport's account (kept from the last frame when reused).
    pub state: Option<TraversalState>,
    pub transport: Option<crate::gpu_types::TransportState>,
    /// GPU ms of its light-side stages (light view, coverage, photons, resolve); its eye shading is in `eye`.
    pub gpu_ms: f64,
    /// Index of its first timed interval in the frame's segments.
    pub first_segment: usize,
}

/// What one frame did, read back after it completed.
#[derive(Clone, Debug, Default)]
pub struct FrameReport {
    /// GPU milliseconds per stage, in order (intervals with the same label summed).
    pub stages: Vec<(&'static str, f64)>,
    /// GPU milliseconds of the parts of a stage timed on their own (`light_gbuffer.front`, ...), in order.
    pub substages: Vec<(&'static str, f64)>,
    /// Every timed interval: (label, start ms from the frame's first timestamp, duration ms).
    pub segments: Vec<(&'static str, f64, f64)>,
    /// Sum of the stages (excluding host round trips of the CPU-driven traversal).
    pub gpu_ms: f64,
    /// Wall-clock time from the start of recording until the results were available.
    pub frame_ms: f64,
    /// CPU time spent recording commands.
    pub record_ms: f64,
    /// Whether the caustic passes were recorded (the scene has a refractor inside the light).
    pub caustics: bool,
    /// Whether the records were splatted by the compute pass (else drawn as points).
    pub compute_splat: bool,
    /// The light-view stages, the photons and the caustic map were reused from the last frame (nothing they
    /// depend on changed); only the eye and composite passes ran.
    pub reused: bool,
    /// The photon level this frame rendered (below the chosen one while the viewer refines progressively).
    pub level: u32,
    /// A viewer preview: one eye sample per pixel, glass by two-surface deferred refraction.
    pub preview: bool,
    /// Nothing the eye view depends on changed since the last frame (camera, lights, settings, the caustic map):
    /// its beauty image was presented again, and no eye or composite pass was recorded.
    pub eye_reused: bool,
    /// The light view of the photon grid (None without caustic passes).
    pub photon_view: Option<LightView>,
    pub state: Option<TraversalState>,
    /// Exact transport's wave counts and energy account.
    pub transport: Option<crate::gpu_types::TransportState>,
    pub host_readbacks: u32,
    /// Each pass (light-major; one per light, or three with color), in order (`state` and `transport` above are
    /// the first pass's).
    pub lights: Vec<LightReport>,
    /// Batch slots recorded (GPU-driven adaptive) or bands (dense).
    pub batch_slots: u32,
    /// Tiles still pending when the frame ended (GPU-driven batching ran out of slots).
    pub unfinished_tiles: u32,
    /// Debug photon dump: 3 rows per photon (see photon_bindings.glsl).
    pub debug_rows: Vec<[u32; 4]>,
    /// Debug runs: whether the photon buffer's guard region kept its canary.
    pub guard_intact: Option<bool>,
}

/// Whether a frame traversed every tile (see [`Renderer::adapt_batch_slots`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SlotVerdict {
    Complete,
    /// Tiles were left over; the next frame records more slots.
    Incomplete,
    /// Tiles were left over with the most slots a frame records (`MAX_BATCHES`): raise the photon budget.
    OutOfSlots,
}

/// A float or 8-bit image read back from the GPU.
pub enum AovData {
    Float { width: u32, height: u32, rgba: Vec<[f32; 4]> },
    Rgba8 { width: u32, height: u32, rgba: Vec<u8> },
}

pub struct Renderer {
    pub device: Arc<Device>,
    pub passes: Passes,
    pub scene: Scene,
    pub scene_buffers: SceneBuffers,
    pub nearest: Sampler,
    pub linear: Sampler,
    /// One-off uploads (scene buffers).
    pub recorder: Recorder,
    /// Each frame in flight's command buffer, fence and timestamp queries.
    pub(crate) slots: Vec<FrameSlot>,
    /// Frames submitted and not yet read back, oldest first (at most `frames_in_flight`).
    pub(crate) pending: std::collections::VecDeque<crate::frame::Pending>,
    /// Reports of frames completed on the way (a new frame waiting for its slot, a resize), oldest first: see
    /// [`Renderer::take_completed`].
    pub(crate) completed: Vec<FrameReport>,
    /// How many frames may be in flight at once (1: every frame is waited for before the next is recorded).
    frames_in_flight: usize,
    /// Frames submitted so far (the next frame's slot is this modulo `frames_in_flight`).
    pub(crate) submitted: u64,
    pub targets: Option<Targets>,
    targets_key: Option<TargetsKey>,
    /// The settings asked for, and what they resolved to on this device (what every frame reads).
    settings: Settings,
    pub(crate) config: ResolvedSettings,
    /// GPU-driven batching: slots recorded next frame (adapted from frame to frame).
    pub slots_hint: u32,
    /// Reuse the caustic stages when nothing they depend on changed (off for profiling, which times them).
    pub reuse: bool,
    /// Bumped whenever the scene's geometry or materials change.
    scene_generation: u64,
    /// The last frame's caustic inputs, with its traversal and transport state (once it completed).
    pub(crate) last_caustic: Option<(String, Vec<LightReport>)>,
    /// The last frame's eye-view inputs (caustic inputs, uniforms, preview, targets): a frame with the same ones
    /// has the same beauty image, and records no eye or composite pass.
    pub(crate) last_eye: Option<u64>,
    /// Bumped whenever the targets are created or resized.
    pub(crate) targets_generation: u64,
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Nothing the GPU may still use is destroyed before it is done (an error can leave a submit in flight).
        let _ = self.device.wait_idle();
    }
}

/// The two-interface model refracts through front and back glass surfaces; it has no mirrors.
fn check_transport(scene: &Scene, settings: &ResolvedSettings) -> AppResult<()> {
    if settings.transport == Transport::TwoInterface {
        if let Some(o) = scene
            .objects
            .iter()
            .find(|o| matches!(o.material, Material::Dielectric { absorption, .. } if absorption.max_element() > 0.0))
        {
            return Err(AppError::BadInput(format!(
                "{}: object `{}` absorbs: absorption needs --transport exact (the two-interface model has none)",
                scene.path.display(),
                o.name
            )));
        }
        if let Some(m) = scene.objects.iter().find(|o| o.is_mirror()) {
            return Err(AppError::BadInput(format!(
                "{}: object `{}` is a mirror: mirrors need --transport exact (the two-interface model only refracts)",
                scene.path.display(),
                m.name
            )));
        }
        if let Some(o) =
            scene.objects.iter().find(|o| matches!(o.material, Material::Dielectric { abbe, .. } if abbe > 0.0))
        {
            return Err(AppError::BadInput(format!(
                "{}: object `{}` disperses (`abbe`): dispersion needs --transport exact (the two-interface model has one IOR per texel)",
                scene.path.display(),
                o.name
            )));
        }
    }
    Ok(())
}

/// 1..=MAX_LIGHTS lights (the scene parsers enforce it; scenes built in code are checked here).
fn check_lights(scene: &Scene) -> AppResult<()> {
    let n = scene.lights.len();
    if n == 0 || n > MAX_LIGHTS {
        return Err(AppError::BadInput(format!(
            "{}: the scene has {n} lights; this renderer handles 1 to {MAX_LIGHTS}",
            scene.path.display()
        )));
    }
    Ok(())
}

/// What the targets' allocation depends on: g-buffer side, caustic map size, photon budget bits, debug photons,
/// ray queue capacity, passes, ray size and frames in flight.
type TargetsKey = (u32, u32, u64, u32, u32, usize, u32, usize);

/// The per-frame resources of one frame in flight (its uniforms and readback buffer live in [`Targets`]).
pub(crate) struct FrameSlot {
    pub recorder: Recorder,
    pub timestamps: Timestamps,
}

impl FrameSlot {
    fn new(device: &Arc<Device>) -> VkResult<Self> {
        Ok(FrameSlot { recorder: Recorder::new(device)?, timestamps: Timestamps::new(device, 16384)? })
    }
}

impl Renderer {
    pub fn new(device: Arc<Device>, scene: Scene, settings: Settings) -> AppResult<Self> {
        let config = settings.resolve(&device.info)?;
        check_transport(&scene, &config)?;
        check_lights(&scene)?;
        let mut recorder = Recorder::new(&device)?;
        let scene_buffers = SceneBuffers::new(&device, &mut recorder, &scene)?;
        Ok(Renderer {
            passes: Passes::new(&device)?,
            nearest: Sampler::new(&device, vk::Filter::NEAREST)?,
            linear: Sampler::new(&device, vk::Filter::LINEAR)?,
            slots: vec![FrameSlot::new(&device)?],
            pending: Default::default(),
            completed: Vec::new(),
            frames_in_flight: 1,
            submitted: 0,
            recorder,
            scene_buffers,
            scene,
            targets: None,
            targets_key: None,
            settings,
            config,
            slots_hint: 0,
            reuse: true,
            scene_generation: 0,
            last_caustic: None,
            last_eye: None,
            targets_generation: 0,
            device,
        })
    }

    /// Replace the scene (after moving the light, changing an IOR, ...): re-uploads its triangles when they
    /// changed. Lights and cameras are read every frame, so changing only them is free.
    pub fn set_scene(&mut self, scene: Scene) -> AppResult<()> {
        check_transport(&scene, &self.config)?;
        check_lights(&scene)?;
        let same_geometry = scene.objects.len() == self.scene.objects.len()
            && scene.objects.iter().zip(&self.scene.objects).all(|(a, b)| {
                a.material == b.material && a.mesh.positions == b.mesh.positions && a.mesh.indices == b.mesh.indices
            });
        if !same_geometry {
            self.device.wait_idle()?;
            self.scene_buffers = SceneBuffers::new(&self.device, &mut self.recorder, &scene)?;
            self.scene_generation += 1;
        }
        self.scene = scene;
        Ok(())
    }

    /// What the caustic stages depend on: the lights, the geometry and materials (by generation), the settings
    /// and the light-side targets.
    pub(crate) fn caustic_key(&self) -> String {
        // The eye view's own settings (supersampling, sky, eye-ray depth, exposure, preview) do not touch the
        // caustics.
        let s = ResolvedSettings { aa: 1, sky: None, eye_depth: 0, exposure_ev: 0.0, ..self.config.clone() };
        format!("{:?}|{}|{:?}|{:?}", self.scene.lights, self.scene_generation, s, self.targets_key)
    }

    pub fn camera_view(&self, camera: &Camera, width: u32, height: u32) -> CameraView {
        CameraView::new(camera, width, height, self.scene.bounds())
    }

    /// Let up to `n` frames be in flight (1..=MAX_FRAMES_IN_FLIGHT): [`Renderer::submit_frame_at`] then returns
    /// before the GPU has finished, and waits only for the frame that last used the slot it takes. Headless
    /// rendering keeps 1; the viewer uses 2 on GPUs.
    pub fn set_frames_in_flight(&mut self, n: usize) -> AppResult<()> {
        let n = n.clamp(1, crate::vk::swapchain::MAX_FRAMES_IN_FLIGHT);
        if n == self.frames_in_flight {
            return Ok(());
        }
        self.finish_frames()?;
        while self.slots.len() < n {
            self.slots.push(FrameSlot::new(&self.device)?);
        }
        self.frames_in_flight = n;
        Ok(())
    }

    pub fn frames_in_flight(&self) -> usize {
        self.frames_in_flight
    }

    /// Replace the settings: resolved for this device and checked against the scene before they take effect.
    pub fn set_settings(&mut self, settings: Settings) -> AppResult<()> {
        let config = settings.resolve(&self.device.info)?;
        check_transport(&self.scene, &config)?;
        if config.method != self.config.method
            || config.level != self.config.level
            || config.metric != self.config.metric
        {
            self.slots_hint = 0;
        }
        self.settings = settings;
        self.config = config;
        Ok(())
    }

    /// The settings asked for (automatic choices still automatic).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The settings as this device resolved them: what every frame renders with.
    pub fn config(&self) -> &ResolvedSettings {
        &self.config
    }

    /// Create the targets, or re-create what a change of settings or output size invalidates: a new window size
    /// only touches the eye-sized targets, not the light maps or the photon buffer.
    pub(crate) fn ensure_targets(&mut self, width: u32, height: u32, aa: u32) -> AppResult<()> {
        let s = &self.config;
        let lights = self.scene.lights.len();
        let passes = lights * self.scene.color_channels();
        let key = (
            s.gbuffer_side(),
            s.caustic_res,
            s.photon_budget_mib.to_bits(),
            s.debug_photons,
            s.ray_queue_capacity(),
            passes,
            s.ray_bytes(),
            self.frames_in_flight,
        );
        let same_key = self.targets_key == Some(key);
        let same_size = self.targets.as_ref().is_some_and(|t| (t.width, t.height, t.aa) == (width, height, aa));
        if same_key && same_size {
            return Ok(());
        }
        // The frames in flight read their results from the buffers about to be replaced: finish them first.
        self.finish_frames()?;
        self.targets_generation += 1;
        self.device.wait_idle()?;
        let s = &self.config;
        match self.targets.as_mut() {
            Some(t) if same_key => t.resize(&self.device, s, width, height, aa)?,
            _ => {
                self.targets = None;
                let slots = self.frames_in_flight;
                self.targets = Some(Targets::new(&self.device, s, width, height, aa, lights, passes, slots)?);
                self.targets_key = Some(key);
            }
        }
        Ok(())
    }

    /// The uniforms of one pass: light `index` (its views and power; the exposure follows the first light) and
    /// color `channel` (0: one gray pass; 1, 2, 3: red, green, blue).
    pub fn frame_data(&self, views: &Views, targets: &Targets, index: usize, channel: u32) -> FrameData {
        let s = &self.config;
        let light = &self.scene.lights[index];
        let light0 = &self.scene.lights[0];
        let (lo, hi) = self.scene.bounds();
        let (rlo, rhi) = self
            .scene
            .refractors()
            .map(|o| o.mesh.bounds())
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(a, b), (c, d)| (a.min(c), b.max(d)));
        let diameter = if self.scene.has_refractors() { (rhi - rlo).length() } else { 0.0 };
        let power = light.color * light.intensity;
        // Exposure: the diffuse radiance of the brightest albedo under the light at its target maps to ~0.6.
        let e_ref = match light0.kind {
            LightKind::Spot | LightKind::Point => light0.intensity / (light0.target - light0.position).length_squared(),
            LightKind::Directional => light0.intensity,
        } * light0.color.max_element().max(1e-6);
        let albedo = self
            .scene
            .receivers()
            .map(|o| match o.material {
                Material::Diffuse { albedo } => albedo.max_element(),
                _ => 0.0,
            })
            .fold(0.0f32, f32::max)
            .max(0.05);
        let l_ref = (albedo / std::f32::consts::PI * e_ref).max(1e-12);
        let mut pyramid = [[0u32; 4]; (MAX_PYRAMID_MIPS / 4) as usize];
        for (m, off) in targets.photon.pyramid_offsets.iter().enumerate() {
            pyramid[m / 4][m % 4] = *off;
        }
        let photon_view = views.photon.unwrap_or(views.receiver);
        let sky = s.sky.unwrap_or(crate::settings::SKY_AUTO * l_ref);
        // The eye buffers hold `aa`×`aa` samples per output pixel: the same image plane, a finer grid.
        let mut camera = GpuView::from_camera(&views.camera);
        let aa = targets.aa as f32;
        camera.extent = [camera.extent[0] * aa, camera.extent[1] * aa, camera.extent[2] / aa, camera.extent[3] / aa];
        FrameData {
            photon_view: GpuView::from_light(&photon_view, s.gbuffer_side()),
            receiver_view: GpuView::from_light(&views.receiver, s.caustic_res),
            camera,
            light_power: [power.x, power.y, power.z, light.intensity],
            scene_min: [lo.x, lo.y, lo.z, diameter],
            scene_max: [hi.x, hi.y, hi.z, 0.6 / l_ref * s.exposure_ev.exp2()],
            grid: [s.gbuffer_side(), s.gbuffer_level(), s.caustic_res, s.gbuffer_level() + 1],
            traversal: [
                s.level,
                s.metric.code() | ((s.batching as u32) << 8),
                s.check_level,
                s.batch_photons(targets.photon.capacity),
            ],
            params: [s.error_bound, s.shadow_bias, s.flux_threshold, s.tau],
            transport: [
                (s.transport == Transport::Exact) as u32,
                s.ray_queue_capacity(),
                targets.photon.capacity,
                channel | ((s.footprint == Footprint::Differential) as u32) << 8,
            ],
            pyramid,
            // The environment's light is added once: by the first light's eye shading (and the composite, which reads
            // the first pass's uniforms).
            eye: [if index == 0 { sky } else { 0.0 }, s.eye_depth as f32, 0.0, 0.0],
            material: [self.scene_buffers.shared_ior.unwrap_or(0.0), s.weak_branches, s.weak_block as f32, 0.0],
        }
    }

    /// After a frame, set the batch slots GPU-driven batching records next time: as many as this frame used plus
    /// a margin when it finished every tile; twice what it needed when tiles were left over (the frame's caustic
    /// is then incomplete: render it again, as `commands::Session::frame` does, or accept it for one frame, as
    /// the viewer does, since an acquired swapchain image is presented once).
    pub fn adapt_batch_slots(&mut self, report: &FrameReport) -> SlotVerdict {
        let Some(st) = report.state.as_ref() else { return SlotVerdict::Complete };
        if report.unfinished_tiles == 0 || report.batch_slots >= MAX_BATCHES {
            if report.batch_slots > 1 {
                self.slots_hint = (st.slots_used + st.slots_used / 4 + 1).min(MAX_BATCHES);
            }
            return if report.unfinished_tiles == 0 { SlotVerdict::Complete } else { SlotVerdict::OutOfSlots };
        }
        // The caustic map is incomplete: the next frame must recompute it with more slots, not reuse it.
        self.last_caustic = None;
        let needed = st.slots_used + st.stack_size;
        self.slots_hint = (needed.max(report.batch_slots) * 2).min(MAX_BATCHES);
        SlotVerdict::Incomplete
    }

    /// Batch slots to record for GPU-driven adaptive traversal: one when the worst case (every cell of the photon
    /// window covered) fits the photon buffer, else an estimate refined from frame to frame.
    pub fn batch_slots(&self, capacity: u32) -> u32 {
        let s = &self.config;
        if s.batch_slots > 0 {
            return s.batch_slots;
        }
        if s.method != Method::Adaptive {
            return 1;
        }
        // The worst case: every cell of every level a candidate (the buffer's entries), and every cell of the
        // last level a photon (the batch's photons).
        let cells0 = (LEVEL0_RES * LEVEL0_RES) as f64;
        let l = s.level as i32;
        let photons = cells0 * 4f64.powi(l);
        let worst = cells0 * (4f64.powi(l + 1) - 1.0) / 3.0 + photons;
        let need = (worst / capacity as f64).max(photons / s.batch_photons(capacity) as f64);
        if need <= 1.0 {
            return 1;
        }
        if self.slots_hint > 0 {
            return self.slots_hint;
        }
        (need.ceil() as u32).clamp(2, 64)
    }
}
