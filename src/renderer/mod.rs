//! The renderer: the pipelines, the scene on the GPU, the targets and the frames in flight. It turns a frame's
//! inputs (a [`FrameDesc`]) into the decisions of a [`FramePlan`](crate::frame::FramePlan) (views, uniforms,
//! what the last frame's maps can serve) and hands the recording to [`crate::frame::record_frame`], which sees only
//! what it borrows.

mod estimate;
mod keys;
mod queue;
#[cfg(test)]
mod refit_tests;
mod scene_api;
mod uniforms;
mod views;
mod water;
#[cfg(test)]
mod water_tests;

pub use crate::frame::{Aov, AovData, FrameReport, SlotVerdict};
pub use estimate::FrameEstimate;
pub use queue::MAX_FRAMES_IN_FLIGHT;
pub use scene_api::{InstanceId, MeshId};
pub use views::{emitters, lights_without_receivers, Emitter, Views};

use crate::error::{Error, Result};
use crate::frame::deposit::{Deposit, DEPOSITS};
use crate::frame::{FramePlan, FrameResources, Rec, SceneUpdate};
use crate::passes::Passes;
use crate::scene::view::CameraView;
use crate::scene::{Camera, Material, Scene, MAX_LIGHTS};
use crate::scene_gpu::SceneBuffers;
use crate::settings::{CarriedColor, ResolvedSettings, Settings, Transport};
use crate::targets::Targets;
use crate::vk::{Device, Recorder, Sampler, SubmitSync, Tracker};
use ash::vk;
use keys::{Caches, CausticKey, MapPlan, TargetsKey};
use queue::{FrameQueue, Pending};
use std::sync::Arc;
use std::time::Instant;

/// Commands appended to a frame's last command buffer after its composite (the viewer's copy into the swapchain
/// image), with the frame's output images, left as transfer sources.
pub type Finish<'a> = &'a mut dyn FnMut(&Device, vk::CommandBuffer, &FrameOutput);

/// A frame's output images on the GPU, as transfer sources once the frame's commands have run.
pub struct FrameOutput<'a> {
    /// The tone-mapped beauty image (R8G8B8A8_UNORM, sRGB-encoded values), at the output size.
    pub beauty: &'a crate::vk::Image,
    /// The linear radiance before exposure and tone mapping (R32G32B32A32_SFLOAT), W/(m²·sr).
    pub hdr: &'a crate::vk::Image,
}

/// A completed frame: what it did, and the AOV it read back.
#[derive(Debug)]
pub struct Frame {
    /// Timings, photon counts, the traversal and transport state.
    pub report: FrameReport,
    /// The AOV the frame description asked for (None when it asked for none).
    pub image: Option<AovData>,
}

/// An image of the host's that [`Renderer::record`] copies the beauty image into: same size as the frame's output,
/// created with `TRANSFER_DST` usage in a format that supports blits (`BLIT_DST`), in `old_layout` when the
/// recorded commands start; it is left in `new_layout`. The renderer orders its copy after all earlier commands on
/// the queue and before all later ones (`ALL_COMMANDS` on both sides).
#[derive(Clone, Copy, Debug)]
pub struct RecordTarget {
    /// The host's image.
    pub image: vk::Image,
    /// Its size (the frame's output size).
    pub extent: vk::Extent2D,
    /// Its layout before the recorded commands.
    pub old_layout: vk::ImageLayout,
    /// Its layout after them.
    pub new_layout: vk::ImageLayout,
}

/// A frame recorded into a host's command buffer ([`Renderer::record`]): pass it to [`Renderer::complete`] once
/// the host's submission of that command buffer has finished.
#[must_use = "a recorded frame must be completed (Renderer::complete) after the host's submission finishes"]
#[derive(Debug)]
pub struct RecordedFrame {
    _private: (),
}

/// The scene BVH as the stats report it.
#[derive(Clone, Copy, Debug, Default)]
pub struct BvhStats {
    /// Whether it has been built (the first exact-transport frame builds it).
    pub built: bool,
    /// Host build time, ms.
    pub build_ms: f64,
    /// Triangles and instances in it.
    pub triangles: usize,
    /// Instances (one per object with triangles).
    pub instances: usize,
    /// Nodes of the layout the settings trace with.
    pub nodes: usize,
}

/// One frame's inputs: the camera and output size, what to read back, and the viewer's per-frame choices.
#[derive(Clone, Copy, Debug)]
pub struct FrameDesc<'a> {
    /// The eye camera at the output size (see [`Renderer::camera_view`]).
    pub camera: &'a CameraView,
    /// The AOV to read back (None: none; the beauty image stays on the GPU for a presenter).
    pub aov: Option<Aov>,
    /// Render at this level when it is below the settings' level (progressive refinement); None: the settings'.
    pub level: Option<u32>,
    /// A preview: one eye sample per pixel (glass traced as in a still under exact transport).
    pub preview: bool,
}

impl<'a> FrameDesc<'a> {
    /// A full frame from `camera`, reading back `aov`.
    pub fn new(camera: &'a CameraView, aov: Option<Aov>) -> Self {
        FrameDesc { camera, aov, level: None, preview: false }
    }
}

/// The compiled pipelines of the renderers on one device. Renderers on a device share their pipelines while one
/// of them, or a `Pipelines`, holds them: a second renderer (another scene, a scene reloaded) compiles nothing that
/// the first compiled. Hold one to keep them between renderers that do not overlap.
#[derive(Clone)]
pub struct Pipelines(Arc<Passes>);

impl Pipelines {
    /// The pipelines of `device`'s renderers, created (not yet compiled: each compiles when a frame first needs it)
    /// if no holder has them.
    pub fn new(device: &Arc<Device>) -> Result<Self> {
        Ok(Pipelines(device.shared(|| Passes::new(device))?))
    }
}

/// The same pipelines, not equal ones.
impl PartialEq for Pipelines {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl std::fmt::Debug for Pipelines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Pipelines({:p})", Arc::as_ptr(&self.0))
    }
}

/// The renderer: it shares the pipelines of its device ([`Pipelines`]), owns the scene on the GPU, the targets and the frames in flight, and renders
/// frames from [`FrameDesc`]s (see the crate's documentation).
pub struct Renderer {
    device: Arc<Device>,
    passes: Pipelines,
    scene: Scene,
    scene_buffers: SceneBuffers,
    /// The meshes' BVH trees, kept across rebuilds of the scene's buffers: adding an object builds only its mesh's.
    blas_cache: crate::bvh::BlasCache,
    nearest: Sampler,
    linear: Sampler,
    /// One-off uploads (scene buffers).
    recorder: Recorder,
    queue: FrameQueue,
    targets: Option<Targets>,
    targets_key: Option<TargetsKey>,
    /// Bumped whenever the targets are created or resized.
    targets_generation: u64,
    /// Every tracked resource's last access, from frame to frame (the queue runs frames in recording order).
    tracker: Tracker,
    /// The settings asked for, and what they resolved to on this device (what every frame reads).
    settings: Settings,
    config: ResolvedSettings,
    /// Reuse the caustic stages when nothing they depend on changed (off for profiling, which times them).
    reuse: bool,
    /// The photon sets a still frame's caustic maps average at most (1: each frame traces one set).
    accumulation: u32,
    /// Bumped whenever the scene's geometry or materials change.
    scene_generation: u64,
    /// The geometry or materials changed: the scene's buffers are rebuilt before the next frame.
    geometry_dirty: bool,
    /// The meshes (object space) and which mesh and transform each scene object is.
    instances: scene_api::Instances,
    caches: Caches,
    /// The frame-in-flight slot of the last frame recorded (a continuation reads its states from there).
    last_slot: usize,
    /// What stepping the simulated water surfaces keeps between frames.
    water: water::WaterSims,
}

/// Which passes of the last frame a continuation finishes, and the slot holding their states.
struct ContinuationPlan {
    passes: Vec<bool>,
    from_slot: usize,
}

impl Drop for Renderer {
    fn drop(&mut self) {
        // Nothing the GPU may still use is destroyed before it is done (an error can leave a submit in flight).
        let _ = self.device.wait_idle();
    }
}

/// The two-interface model refracts through front and back glass surfaces; it has no mirrors.
fn check_transport(scene: &Scene, settings: &ResolvedSettings) -> Result<()> {
    if settings.transport != Transport::TwoInterface {
        return Ok(());
    }
    // (what the object does and what that needs, what the two-interface model lacks, whether an object does it)
    type Needs = (&'static str, &'static str, fn(&crate::scene::Object) -> bool);
    let needs: [Needs; 4] = [
        ("absorbs: absorption needs", "has none", |o| o.absorption().max_element() > 0.0),
        ("is a mirror: mirrors need", "only refracts", |o| o.is_mirror()),
        ("has another medium beside it (`outside`, `priority`): media need", "has air around all glass", |o| {
            o.outside.is_some() || o.priority > 0
        }),
        (
            "disperses (`abbe`): dispersion needs",
            "has one IOR per texel",
            |o| matches!(o.material, Material::Dielectric { abbe, .. } if abbe > 0.0),
        ),
    ];
    for (does, lacks, test) in needs {
        if let Some(o) = scene.objects.iter().find(|o| test(o)) {
            let rule = format!(
                "{}: object `{}` {does} exact transport (the two-interface model {lacks})",
                scene.path.display(),
                o.name
            );
            return Err(Error::setting("Quality::transport", "two-interface", rule));
        }
    }
    Ok(())
}

/// Each `outside` names another dielectric (the scene parsers enforce it; scenes built in code are checked here).
fn check_media(scene: &Scene) -> Result<()> {
    match scene.bad_outside() {
        Some(i) => Err(Error::BadInput(format!(
            "{}: object `{}` has outside = object {:?}: a dielectric's outside must be another dielectric object",
            scene.path.display(),
            scene.objects[i].name,
            scene.objects[i].outside
        ))),
        None => Ok(()),
    }
}

/// 1..=MAX_LIGHTS lights (the scene parsers enforce it; scenes built in code are checked here).
fn check_lights(scene: &Scene) -> Result<()> {
    let n = scene.lights.len();
    if n == 0 || n > MAX_LIGHTS {
        return Err(Error::BadInput(format!(
            "{}: the scene has {n} lights; this renderer handles 1 to {MAX_LIGHTS}",
            scene.path.display()
        )));
    }
    for (i, l) in scene.lights.iter().enumerate() {
        check_cone(l, || format!("{}: light {i}", scene.path.display()))?;
    }
    Ok(())
}

/// A spot light's cone is one its light view can be fitted to ([`crate::scene::spot_cone_ok`]); `which` names the
/// light in the error.
fn check_cone(light: &crate::scene::Light, which: impl FnOnce() -> String) -> Result<()> {
    if light.kind == crate::scene::LightKind::Spot && !crate::scene::spot_cone_ok(light.cone) {
        return Err(Error::BadInput(format!(
            "{}: a spot light's cone half-angle must lie in [{}, 90) degrees (got {}°)",
            which(),
            crate::scene::MIN_CONE_DEG,
            light.cone.to_degrees()
        )));
    }
    Ok(())
}

impl Renderer {
    /// A renderer on `device` for `scene`, with `settings` resolved for the device (bad settings or a scene the
    /// transport cannot render are bad input).
    pub fn new(device: Arc<Device>, scene: Scene, settings: Settings) -> Result<Self> {
        let config = settings.resolve(&device.info)?;
        check_transport(&scene, &config)?;
        check_lights(&scene)?;
        check_media(&scene)?;
        for i in views::lights_without_receivers(&scene) {
            log::warn!(
                "{}: light {i} reaches no receiver: it lights only the glass (is it aimed where you meant?)",
                scene.path.display()
            );
        }
        let mut recorder = Recorder::new(&device)?;
        let t0 = Instant::now();
        let instances = scene_api::Instances::of(&scene);
        let scene_buffers = SceneBuffers::new(&device, &mut recorder, &scene, &instances.view())?;
        let t1 = Instant::now();
        let passes = Pipelines::new(&device)?;
        log::info!(
            "renderer ready: scene buffers {:.0} ms, pipelines {:.0} ms",
            (t1 - t0).as_secs_f64() * 1e3,
            t1.elapsed().as_secs_f64() * 1e3
        );
        Ok(Renderer {
            passes,
            nearest: Sampler::new(&device, vk::Filter::NEAREST)?,
            linear: Sampler::new(&device, vk::Filter::LINEAR)?,
            queue: FrameQueue::new(&device)?,
            recorder,
            scene_buffers,
            blas_cache: crate::bvh::BlasCache::default(),
            scene,
            targets: None,
            targets_key: None,
            targets_generation: 0,
            tracker: Tracker::new(&device),
            settings,
            config,
            reuse: true,
            accumulation: 1,
            scene_generation: 0,
            geometry_dirty: false,
            instances,
            caches: Caches::default(),
            last_slot: 0,
            water: Default::default(),
            device,
        })
    }

    /// The device it renders on.
    pub fn device(&self) -> &Arc<Device> {
        &self.device
    }

    /// The scene as the renderer holds it.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's buffers on the GPU (its BVH's statistics among them).
    pub fn scene_buffers(&self) -> &SceneBuffers {
        &self.scene_buffers
    }

    /// Replace the scene (after moving the light, changing an IOR, ...): its triangles are uploaded again before
    /// the next frame when they changed. Lights and cameras are read every frame, so changing only them is free.
    /// The scene's objects become its instances again: a TOML scene's still objects each their own mesh with the
    /// identity transform, the others their object-space mesh with their placement.
    pub fn set_scene(&mut self, scene: Scene) -> Result<()> {
        check_transport(&scene, &self.config)?;
        check_lights(&scene)?;
        let same_geometry = scene.objects.len() == self.scene.objects.len()
            && scene.objects.iter().zip(&self.scene.objects).all(|(a, b)| {
                // An animated object's mesh on the GPU is its object-space one, and a deforming one's bounds.
                type Bounds = Option<(glam::Vec3, glam::Vec3)>;
                fn local(o: &crate::scene::Object) -> Option<(&[glam::Vec3], Bounds)> {
                    o.animation.as_ref().map(|x| (&x.mesh.positions[..], x.deform_bounds()))
                }
                a.material == b.material
                    && a.mesh.positions == b.mesh.positions
                    && a.mesh.indices == b.mesh.indices
                    && local(a) == local(b)
            });
        if !same_geometry {
            self.geometry_dirty = true;
            self.instances = scene_api::Instances::of(&scene);
        }
        self.scene = scene;
        Ok(())
    }

    /// Replace light `index` (its position, target, power...). Checked as a whole scene would be: a spot light
    /// that would see glass behind it, or a point light inside glass, is refused, and the scene keeps the light it
    /// had.
    pub fn set_light(&mut self, index: usize, light: crate::scene::Light) -> Result<()> {
        if index >= self.scene.lights.len() {
            return Err(Error::BadInput(format!("light {index}: the scene has {} lights", self.scene.lights.len())));
        }
        check_cone(&light, || format!("light {index}"))?;
        let sized = light.radius.is_finite() && light.radius >= 0.0;
        if !(sized && (0.0..=10f32.to_radians()).contains(&light.angular_radius)) {
            return Err(Error::BadInput(format!(
                "light {index}: a radius must be finite and >= 0 m (got {}), an angular radius within [0, 10]° (got {}°)",
                light.radius,
                light.angular_radius.to_degrees()
            )));
        }
        // As the scene file says it: a sun has an angular size, a bulb a radius.
        let directional = light.kind == crate::scene::LightKind::Directional;
        if (directional && light.radius > 0.0) || (!directional && light.angular_radius > 0.0) {
            return Err(Error::BadInput(format!(
                "light {index}: a directional light (a sun) has an angular radius and no radius, a spot or point light \
                 a radius and no angular radius"
            )));
        }
        let old = std::mem::replace(&mut self.scene.lights[index], light);
        let view = CameraView::new(
            &self.scene.cameras.first().cloned().unwrap_or_else(default_camera),
            16,
            16,
            self.scene.bounds(),
        );
        let checked = views::emitters(&self.scene).and_then(|es| {
            es.into_iter().filter(|e| e.light == index).try_for_each(|e| {
                Views::new(&self.scene, &self.config, &view, e)?;
                Ok(())
            })
        });
        if let Err(e) = checked {
            self.scene.lights[index] = old;
            return Err(e);
        }
        Ok(())
    }

    /// Replace the settings: resolved for this device and checked against the scene before they take effect.
    pub fn set_settings(&mut self, settings: Settings) -> Result<()> {
        let config = settings.resolve(&self.device.info)?;
        check_transport(&self.scene, &config)?;
        if config.method != self.config.method
            || config.level != self.config.level
            || config.metric != self.config.metric
        {
            self.queue.reset_batch_slots();
        }
        self.settings = settings;
        self.config = config;
        Ok(())
    }

    /// The settings asked for (automatic choices still automatic).
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The pipelines this renderer shares with the other renderers of its device.
    pub fn pipelines(&self) -> &Pipelines {
        &self.passes
    }

    /// The settings as this device resolved them: what every frame renders with.
    pub fn config(&self) -> &ResolvedSettings {
        &self.config
    }

    /// Reuse the last frame's caustic maps (and beauty image) when nothing they depend on changed (the default),
    /// or recompute every stage of every frame (profiling and benchmarks).
    pub fn set_reuse(&mut self, reuse: bool) {
        self.reuse = reuse;
    }

    /// Progressive accumulation: while nothing the caustic maps depend on changes (nor, where the eye deposit runs,
    /// the eye view), each frame traces a fresh photon set (each cell sampled at a new point of a low-discrepancy
    /// sequence) and its maps average it with the sets before, up to `sets` of them; later frames then reuse the
    /// average. Any change starts a new average. 1 (the default): each frame traces one set, and reuses it.
    /// Needs reuse on ([`Renderer::set_reuse`]).
    pub fn set_accumulation(&mut self, sets: u32) {
        self.accumulation = sets.max(1);
    }

    /// The eye view of `camera` at `width`×`height`.
    pub fn camera_view(&self, camera: &Camera, width: u32, height: u32) -> CameraView {
        CameraView::new(camera, width, height, self.scene.bounds())
    }

    /// Let up to `n` frames be in flight (1..=MAX_FRAMES_IN_FLIGHT): [`Renderer::submit`] then returns before the
    /// GPU has finished, and waits only for the frame that last used the slot it takes. Headless rendering keeps
    /// 1; the viewer uses 2 on GPUs.
    pub fn set_frames_in_flight(&mut self, n: usize) -> Result<()> {
        let n = n.clamp(1, MAX_FRAMES_IN_FLIGHT);
        if n == self.queue.frames_in_flight() {
            return Ok(());
        }
        self.finish_frames()?;
        self.queue.set_frames_in_flight(&self.device, n)?;
        Ok(())
    }

    /// Frames that may be in flight at once.
    pub fn frames_in_flight(&self) -> usize {
        self.queue.frames_in_flight()
    }

    /// Render one frame and wait for it: its report, and the AOV it read back. A frame whose GPU-driven batches
    /// run out of batch slots with tiles of the photon quadtree left is not rendered again: the batches it
    /// committed stay in its maps, and further submissions trace the remaining tiles and add their light (each
    /// one host round trip, counted in the report's `host_readbacks` and `continuations`).
    pub fn render(&mut self, desc: &FrameDesc) -> Result<Frame> {
        let start = Instant::now();
        self.finish_frames()?;
        self.submit(desc, None, &SubmitSync::default())?;
        let (mut report, mut image) = self.queue.wait_last(self.targets.as_ref(), &mut self.caches)?;
        loop {
            let pending: Vec<bool> =
                report.lights.iter().map(|l| l.caustics && l.state.is_some_and(|s| s.stack_size > 0)).collect();
            // Each slot commits a batch or splits a tile into four smaller ones, so the tiles run out; the frame's
            // slots in all stay within MAX_BATCHES.
            if !pending.contains(&true) || report.batch_slots >= crate::shaders::consts::MAX_BATCHES {
                break;
            }
            // More slots next time: the ones this frame needed, with a margin.
            self.queue.adapt_batch_slots(&report, &mut self.caches);
            let tiles: u32 = report.lights.iter().filter_map(|l| l.state.map(|s| s.stack_size)).sum();
            log::info!(
                "the photon buffer held {} batches of this frame; tracing its {tiles} remaining tiles in another \
                 submission (a larger photon budget, Quality::photon_budget_mib, avoids it)",
                report.batch_slots
            );
            let from_slot = self.last_slot;
            let plan = ContinuationPlan { passes: pending.clone(), from_slot };
            self.record_into(None, desc, None, &SubmitSync::default(), Some(&plan))?;
            let (next, next_image) = self.queue.wait_last(self.targets.as_ref(), &mut self.caches)?;
            report.absorb(next, &pending);
            image = next_image;
        }
        report.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        self.queue.adapt_batch_slots(&report, &mut self.caches);
        Ok(Frame { report, image })
    }

    /// Record a frame into the host's command buffer `cmd` (begun, outside a render pass), and, when `target` is
    /// given, copy its beauty image into the host's image. The host submits `cmd` to the device's queue (the one
    /// it gave [`crate::gpu::Context::import`], or [`Device::queue`]), waits for it, and then passes the returned
    /// token to [`Renderer::complete`], before the next frame is rendered or recorded. CPU-driven traversal
    /// (`--driven cpu`) submits mid-frame and cannot be recorded this way.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        desc: &FrameDesc,
        target: Option<&RecordTarget>,
    ) -> Result<RecordedFrame> {
        if self.queue.has_external() {
            return Err(Error::BadInput(
                "a recorded frame has not been completed: call Renderer::complete after its submission finishes".into(),
            ));
        }
        if self.config.driven == crate::settings::Driven::Cpu && self.config.method == crate::settings::Method::Adaptive
        {
            return Err(Error::BadInput(
                "CPU-driven traversal reads each level back mid-frame: it cannot record into a host's command buffer"
                    .into(),
            ));
        }
        self.finish_frames()?;
        let mut copy = |d: &Device, cmd: vk::CommandBuffer, out: &FrameOutput| {
            if let Some(t) = target {
                copy_to_target(d, cmd, out.beauty, t);
            }
        };
        self.record_into(Some(cmd), desc, Some(&mut copy), &SubmitSync::default(), None)?;
        Ok(RecordedFrame { _private: () })
    }

    /// Read back a frame recorded with [`Renderer::record`]. The host must have waited for the submission of the
    /// command buffer it was recorded into.
    pub fn complete(&mut self, frame: RecordedFrame) -> Result<Frame> {
        let RecordedFrame { .. } = frame;
        let (report, image) = self.queue.complete_external(self.targets.as_ref(), &mut self.caches)?;
        Ok(Frame { report, image })
    }

    /// The scene BVH's statistics (built: once an exact-transport frame has run).
    pub fn bvh_stats(&self) -> BvhStats {
        let b = &self.scene_buffers.bvh;
        BvhStats {
            built: b.is_built(),
            build_ms: b.build_ms,
            triangles: b.triangle_count,
            instances: b.instance_count,
            nodes: b.node_count(self.config.bvh_layout),
        }
    }

    /// The index of refraction the light and eye views take from the uniforms when every refractor shares it
    /// (None: they differ, and an IOR buffer is drawn).
    pub fn shared_ior(&self) -> Option<f32> {
        self.scene_buffers.shared_ior
    }

    /// The frame-in-flight slot the next frame takes. When every slot is in flight, this first waits for the
    /// oldest frame, the last to use that slot, and keeps its report for [`Renderer::take_completed`]. The viewer
    /// calls it before acquiring a swapchain image with that slot's semaphore.
    pub fn next_slot(&mut self) -> Result<usize> {
        self.queue.next_slot(self.targets.as_ref(), &mut self.caches)
    }

    /// Wait for every frame in flight and keep their reports for [`Renderer::take_completed`].
    pub fn finish_frames(&mut self) -> Result<()> {
        self.queue.finish(self.targets.as_ref(), &mut self.caches)
    }

    /// The reports of the frames completed since the last call, oldest first.
    pub fn take_completed(&mut self) -> Vec<FrameReport> {
        self.queue.take_completed()
    }

    /// After a frame, adapt the batch slots GPU-driven batching records next time (see
    /// [`SlotVerdict`]); an incomplete frame's maps are not reused.
    pub fn adapt_batch_slots(&mut self, report: &FrameReport) -> SlotVerdict {
        self.queue.adapt_batch_slots(report, &mut self.caches)
    }

    /// The batch slots GPU-driven batching records next (0: not adapted yet).
    pub fn slots_hint(&self) -> u32 {
        self.queue.slots_hint()
    }

    /// Create the targets, or re-create what a change of settings or output size invalidates: a new window size
    /// only touches the eye-sized targets, not the light maps or the photon buffer.
    /// Also drops the tracker's histories of the buffers and images destroyed since the last frame (it runs once per
    /// frame).
    /// `lights`: the frame's light views ([`views::emitters`]), each with its own receiver maps.
    fn ensure_targets(&mut self, s: &ResolvedSettings, lights: usize, width: u32, height: u32, aa: u32) -> Result<()> {
        self.tracker.prune();
        let passes = lights * self.color_passes(s);
        let key = TargetsKey::new(s, passes, self.queue.frames_in_flight());
        let same_key = self.targets_key == Some(key);
        let same_size = self.targets.as_ref().is_some_and(|t| (t.width, t.height, t.aa) == (width, height, aa));
        if same_key && same_size {
            return Ok(());
        }
        // The frames in flight read their results from the buffers about to be replaced: finish them first.
        self.finish_frames()?;
        self.targets_generation += 1;
        self.device.wait_idle()?;
        // The replaced resources' history goes with them; the kept ones' stays.
        match self.targets.as_mut() {
            Some(t) if same_key => t.resize(&self.device, s, width, height, aa)?,
            _ => {
                self.targets = None;
                self.tracker.clear();
                let slots = self.queue.frames_in_flight();
                self.targets = Some(Targets::new(&self.device, s, width, height, aa, lights, passes, slots)?);
                self.targets_key = Some(key);
            }
        }
        Ok(())
    }

    /// The resolved settings as the frames apply them to the scene now: with the rays' media (and so their bytes
    /// in the queues) where exact transport meets absorbing or overlapping media.
    pub fn scene_settings(&self) -> ResolvedSettings {
        let mut s = self.config.clone();
        s.media = s.transport == Transport::Exact && self.scene.has_media();
        // Photons carry their color where the compute splat adds the records' colors and the resolve reads its
        // three planes as texels: spectral photons where some glass disperses, else color photons, whose tint
        // rides in their medium word, where some medium absorbs colors unequally.
        let planes = 3 * crate::targets::splat_texels(s.caustic_res);
        let capable = s.transport == Transport::Exact
            && s.splat.is_compute()
            && crate::passes::flux_format(&self.device) == ash::vk::Format::R32_SFLOAT
            && planes <= self.device.info.limits.max_texel_buffer_elements as u64;
        s.carried_color = match (capable, self.scene.disperses(), self.scene.color_channels() == 3 && s.media) {
            (true, true, _) => CarriedColor::Wavelength,
            (true, false, true) => CarriedColor::Tint,
            _ => CarriedColor::None,
        };
        s
    }

    /// Photon passes per light under the settings `s`: 3 (red, green, blue) where colour changes the paths, or
    /// the photons cannot carry it, 1 otherwise (gray, or color photons).
    fn color_passes(&self, s: &ResolvedSettings) -> usize {
        if s.carried_color.carried() {
            1
        } else {
            self.scene.color_channels()
        }
    }

    /// The settings of the frame `desc`: the scene's, at its level (progressive refinement renders below the
    /// chosen one).
    fn frame_settings(&self, desc: &FrameDesc) -> ResolvedSettings {
        let mut s = self.scene_settings();
        s.level = desc.level.map_or(s.level, |l| l.min(s.level));
        s
    }

    /// Record and submit a frame without waiting for it: its report comes later from
    /// [`Renderer::take_completed`], once a later frame needs its slot or [`Renderer::finish_frames`] is called.
    /// `finish` appends commands to its last command buffer and `sync` gives that submission its semaphores.
    pub fn submit(&mut self, desc: &FrameDesc, finish: Option<Finish>, sync: &SubmitSync) -> Result<()> {
        if self.queue.has_external() {
            return Err(Error::BadInput(
                "a recorded frame has not been completed: call Renderer::complete after its submission finishes".into(),
            ));
        }
        crate::cpu_zone!("record and submit");
        self.record_into(None, desc, finish, sync, None)
    }

    /// Rebuild the scene's buffers when its geometry or materials changed (after the frames in flight that bind
    /// them are done). Returns whether it did.
    fn update_scene(&mut self) -> Result<bool> {
        if !self.geometry_dirty {
            return Ok(false);
        }
        self.finish_frames()?;
        self.scene_buffers = SceneBuffers::new(&self.device, &mut self.recorder, &self.scene, &self.instances.view())?;
        // The new buffers hold every object where it is now.
        self.instances.clear_moved();
        self.scene_generation += 1;
        self.geometry_dirty = false;
        Ok(true)
    }

    /// The scene update of this frame: the objects moved since the last one, placed on the GPU, and the BVH's
    /// instance records (its host copy moved with them) when it is built.
    fn take_scene_update(&mut self) -> SceneUpdate {
        use crate::gpu_types::{MorphPush, WaterPush};
        use crate::scene_gpu::Deformer;
        let moved = self.instances.take_moved();
        let mut deformed: std::collections::BTreeSet<usize> = self.instances.take_deformed().into_iter().collect();
        let mut up = SceneUpdate::default();
        self.step_water(&mut up, &mut deformed);
        let heights: Vec<Option<u32>> = (0..self.scene.objects.len()).map(|i| self.heights_now(i)).collect();
        let sb = &mut self.scene_buffers;
        // Water's BVH triangles are gathered from the vertices its raster job displaces: when they are all
        // written (the GPU holds their rest state), so are those.
        if sb.bvh.stale_deform {
            deformed.extend((0..sb.deformers.len()).filter(|&i| matches!(sb.deformers[i], Some(Deformer::Water(_)))));
        }
        let mut bvh_moved = false;
        for &(i, transform) in &moved {
            up.moves.push(crate::gpu_types::SceneUpdatePush::new(transform, &sb.objects[i]));
            bvh_moved |= sb.bvh.set_transform(i, transform);
            // A moved deforming object is placed at rest: deform it again.
            if sb.deformers[i].is_some() {
                deformed.insert(i);
            }
        }
        if bvh_moved {
            up.instances = sb.bvh.instance_records().map(|r| r.to_vec());
        }
        let time = self.scene.time;
        for &i in &deformed {
            let transform = self.instances.transform_of(i);
            match sb.deformers[i] {
                Some(Deformer::Water(w)) => {
                    up.water_vertices.push(WaterPush::raster(transform, &sb.objects[i], time, &w, heights[i]))
                }
                Some(Deformer::Morph(m)) => up.morph_vertices.push(MorphPush::raster(transform, &sb.objects[i], &m)),
                None => {}
            }
        }
        // The BVH's triangles and boxes: the deformed ones' (each deforming mesh once), or every one's when the
        // GPU holds their rest state (just built, or a layout just uploaded).
        let stale = std::mem::take(&mut sb.bvh.stale_deform);
        let mut refit_meshes = std::collections::BTreeSet::new();
        for i in 0..sb.deformers.len() {
            let Some(deformer) = sb.deformers[i] else { continue };
            let mesh = self.instances.mesh_of(i);
            let Some(r) = sb.bvh.refit_mesh(mesh) else { continue };
            if (stale || deformed.contains(&i)) && refit_meshes.insert(mesh) {
                match deformer {
                    Deformer::Water(w) => up.water_triangles.push(WaterPush::bvh(&r, &w)),
                    Deformer::Morph(m) => up.morph_triangles.push(MorphPush::bvh(&r, &m)),
                }
                up.refit_meshes += 1;
                // One job a height; `layouts` names the binary layouts refit.comp writes (none: no binary refit).
                let jobs = |levels: Vec<[u32; 2]>, layouts: u32| {
                    levels.into_iter().map(move |[first, count]| crate::gpu_types::RefitPush {
                        first,
                        count,
                        layouts,
                        pad: 0,
                    })
                };
                let layouts = sb.bvh.layout_mask();
                if layouts != 0 {
                    up.refits.extend(jobs(sb.bvh.refit_levels(&r), layouts));
                }
                up.wide_refits.extend(jobs(sb.bvh.wide_refit_levels(&r), 0));
            }
        }
        // The weights at the frame's time, for every morphing object (a few floats each).
        if !up.morph_vertices.is_empty() || !up.morph_triangles.is_empty() {
            let mut weights = Vec::new();
            for (i, d) in sb.deformers.iter().enumerate() {
                if let (Some(Deformer::Morph(_)), Some(m)) =
                    (d, self.scene.objects[i].animation.as_ref().and_then(|a| a.morph.as_ref()))
                {
                    weights.extend(m.weights_at(time));
                }
            }
            up.morph_weights = Some(weights);
        }
        up
    }

    /// What the caustic maps depend on beyond the transforms when something deforms: the scene's time (its bits)
    /// and the drops into simulated water so far.
    fn deform_key(&self) -> Option<(u32, u64)> {
        let deforms = self.scene_buffers.deformers.iter().any(|w| w.is_some());
        deforms.then_some((self.scene.time.to_bits(), self.water.events))
    }

    /// The BVH the frame's transport traces (built, and its layout uploaded, once needed) and the scene update the
    /// frame runs, with its report. `rebuilt`: whether the scene's buffers were rebuilt before this frame; `before`:
    /// the device's wait-idles, the recorder's blocking submits and the BVH's BLAS builds before it.
    fn bvh_and_scene_update(
        &mut self,
        s: &ResolvedSettings,
        rebuilt: bool,
        (idles, submits, builds): (u64, u64, usize),
    ) -> Result<(SceneUpdate, crate::frame::SceneUpdateReport)> {
        if s.transport == Transport::Exact && !self.scene_buffers.bvh.has(s.bvh_layout) {
            // The waves and the eye view's glass trace the BVH: built, and this layout uploaded, once needed. The
            // buffers it replaces are bound by the frames in flight.
            self.finish_frames()?;
            let instances = self.instances.view();
            self.scene_buffers.bvh.ensure(
                &self.device,
                &mut self.recorder,
                &self.scene,
                &instances,
                s.bvh_layout,
                &mut self.blas_cache,
            )?;
        }
        if s.transport == Transport::Exact {
            self.scene_buffers.bvh.trace_with(s.bvh_layout);
        }
        let scene_update = self.take_scene_update();
        // A rebuilt scene's BVH counts from zero.
        let builds = if rebuilt { 0 } else { builds };
        let scene_report = crate::frame::SceneUpdateReport {
            moved_objects: scene_update.moves.len() as u32,
            instance_bytes: scene_update.instances.as_ref().map_or(0, |r| std::mem::size_of_val(&r[..]) as u64),
            blas_builds: (self.scene_buffers.bvh.blas_builds - builds) as u32,
            blas_refits: scene_update.refit_meshes,
            deformed_objects: (scene_update.water_vertices.len() + scene_update.morph_vertices.len()) as u32,
            rebuilt,
            blocking_submits: self.recorder.blocking_submits - submits,
            wait_idles: self.device.wait_idle_count() - idles,
        };
        Ok((scene_update, scene_report))
    }

    /// Record a frame into `host_cmd` (the host's command buffer; the host submits it) or into the next slot's own
    /// command buffer, which is then submitted with `sync`.
    fn record_into(
        &mut self,
        host_cmd: Option<vk::CommandBuffer>,
        desc: &FrameDesc,
        finish: Option<Finish>,
        sync: &SubmitSync,
        continuation: Option<&ContinuationPlan>,
    ) -> Result<()> {
        let start = Instant::now();
        let (idles, submits, builds) =
            (self.device.wait_idle_count(), self.recorder.blocking_submits, self.scene_buffers.bvh.blas_builds);
        let rebuilt = self.update_scene()?;
        let slot = self.next_slot()?;
        self.last_slot = slot;
        let s = self.frame_settings(desc);
        let camera = desc.camera;
        let aa = eye_samples(desc, s.aa);
        let emitters = views::emitters(&self.scene)?;
        self.ensure_targets(&s, emitters.len(), camera.width, camera.height, aa)?;
        let (scene_update, scene_report) = self.bvh_and_scene_update(&s, rebuilt, (idles, submits, builds))?;
        // Color: 3 passes per light view (red, green, blue) when some glass disperses, or absorbs unequally and
        // the photons cannot carry their color, else 1.
        let nc = self.color_passes(&s);
        let views = emitters.iter().map(|&e| Views::new(&self.scene, &s, camera, e)).collect::<Result<Vec<_>>>()?;
        // Reuse by dependency: the light-view stages, the photons and the caustic map depend on the lights, the
        // geometry and materials, and the settings, not on the camera or the output size. When none of those
        // changed since the last frame submitted, only the eye and composite passes are recorded (the queue runs
        // frames in order, so a frame in flight that computes the maps finishes them before this one reads them).
        // Water changes with the scene's time; rigid motion is in the transforms.
        let key = CausticKey::new(
            &self.scene.lights,
            self.scene_generation,
            (self.instances.transforms(), self.deform_key()),
            &s,
            self.targets_key,
            camera,
        );
        let targets = self.targets.as_mut().expect("targets");
        let mut data = uniforms::pass_data(&self.scene, &self.scene_buffers, &s, &emitters, &views, targets, nc);
        // The deposits that run: the light maps, and the eye deposit where the targets hold it.
        let eye_deposit = targets.eye_deposit(&s);
        let deposits: Vec<Deposit> = DEPOSITS.into_iter().filter(|&d| d != Deposit::Eye || eye_deposit).collect();
        let eye_view = deposits
            .iter()
            .any(|d| d.declares().follows_camera)
            .then(|| (bytemuck::bytes_of(&data[0].frame.camera).to_vec(), self.targets_generation));
        let plan = self.caches.plan(&key, eye_view, self.reuse, continuation.is_some(), self.accumulation);
        let MapPlan { reused, clear: clear_deposits, set } = plan;
        uniforms::set_photon_set(&mut data, set);
        let eye_reused = self.caches.eye_reused(&key, &data, desc, reused, self.targets_generation);
        for (ubo, d) in targets.ubos[slot].iter_mut().zip(&data) {
            ubo.write(0, std::slice::from_ref(d))?;
        }
        let targets = &*targets;
        let caustics: Vec<bool> = views.iter().map(|v| v.photon.is_some()).collect();
        let plan = FramePlan {
            scene_update: &scene_update,
            settings: &s,
            data: &data,
            caustics: &caustics,
            emitters: &emitters,
            channels: nc,
            photon_view: views[0].photon,
            reused,
            eye_reused,
            deposits: &deposits,
            clear_deposits,
            preview: desc.preview,
            aov: desc.aov,
            batch_slots: self.queue.batch_slots(&s, targets.photon.capacity),
            continuation: continuation
                .map(|c| crate::frame::Continuation { passes: &c.passes, from_slot: c.from_slot }),
        };
        let res = FrameResources {
            device: &self.device,
            passes: &self.passes.0,
            scene: &self.scene_buffers,
            nearest: &self.nearest,
            linear: &self.linear,
            targets,
            slot,
        };
        let frame_slot = &mut self.queue.slots[slot];
        let (mut report, lights_end, aov) =
            match record_commands(&res, &plan, frame_slot, &mut self.tracker, host_cmd, finish) {
                Ok(r) => r,
                Err(e) => {
                    // What the queue will run of this frame is not known: forget what the caches knew; nor whether
                    // the scene update ran: the scene's buffers are rebuilt before the next frame.
                    self.caches.clear();
                    self.geometry_dirty = true;
                    return Err(e.into());
                }
            };
        report.scene = scene_report;
        report.photon_sets = set + 1;
        if host_cmd.is_none() {
            frame_slot.recorder.submit_with(sync)?;
        }
        if !reused {
            // The maps this frame computes serve the next frames with the same inputs; its traversal and transport
            // state join them once it completes.
            self.caches.caustic = Some((key.clone(), report.lights.clone()));
        }
        self.queue.push(Pending {
            slot,
            report,
            start,
            lights_end,
            aov,
            key,
            settings: s,
            external: host_cmd.is_some(),
        });
        Ok(())
    }
}

/// Record `plan`'s commands into `host_cmd`, or into `frame_slot`'s own command buffer (begun here; the caller
/// submits it), then the host's `finish`. Returns the frame's report with its recording time and barrier batches,
/// the end of its light stages and the AOV it reads back. A recording error makes `tracker` forget what it knew.
fn record_commands(
    res: &FrameResources,
    plan: &FramePlan,
    frame_slot: &mut queue::FrameSlot,
    tracker: &mut Tracker,
    host_cmd: Option<vk::CommandBuffer>,
    finish: Option<Finish>,
) -> crate::vk::VkResult<(FrameReport, usize, Option<Aov>)> {
    let cmd = match host_cmd {
        Some(cmd) => cmd,
        None => frame_slot.recorder.begin()?,
    };
    let mut rec = Rec {
        recorder: host_cmd.is_none().then_some(&mut frame_slot.recorder),
        ts: &mut frame_slot.timestamps,
        sync: tracker,
        cmd,
        report: FrameReport::default(),
        record_time: 0.0,
        mark: Instant::now(),
    };
    let flushes = rec.sync.flushes();
    let (lights_end, aov) = crate::frame::record_frame(res, plan, &mut rec).inspect_err(|_| rec.sync.forget())?;
    if let Some(f) = finish {
        let eye = &res.targets.eye;
        f(res.device, rec.cmd, &FrameOutput { beauty: &eye.beauty, hdr: &eye.hdr });
    }
    rec.ts.mark(rec.cmd, "");
    rec.record_time += rec.mark.elapsed().as_secs_f64();
    let mut report = rec.report;
    report.record_ms = rec.record_time * 1e3;
    report.barrier_batches = rec.sync.flushes() - flushes;
    Ok((report, lights_end, aov))
}

/// The eye samples per pixel side of a frame: the caustics and direct AOVs are point samples at the pixel centers,
/// and so is a preview; the beauty is supersampled `aa`×`aa`.
fn eye_samples(desc: &FrameDesc, aa: u32) -> u32 {
    match desc.aov {
        Some(Aov::Caustics) | Some(Aov::Direct) => 1,
        _ if desc.preview => 1,
        _ => aa,
    }
}

fn default_camera() -> Camera {
    Camera {
        name: "default".into(),
        projection: crate::scene::Projection::Perspective { fov: 0.8 },
        position: glam::Vec3::new(0.0, 1.0, 3.0),
        target: glam::Vec3::ZERO,
        up: glam::Vec3::Y,
        aspect: None,
    }
}

/// Copy the beauty image (a transfer source) into the host's image, with its layout transitions.
fn copy_to_target(d: &Device, cmd: vk::CommandBuffer, beauty: &crate::vk::Image, t: &RecordTarget) {
    let range = crate::vk::image::COLOR_RANGE;
    let barrier = |old,
                   new,
                   src: (vk::PipelineStageFlags2, vk::AccessFlags2),
                   dst: (vk::PipelineStageFlags2, vk::AccessFlags2)| {
        vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src.0)
            .src_access_mask(src.1)
            .dst_stage_mask(dst.0)
            .dst_access_mask(dst.1)
            .old_layout(old)
            .new_layout(new)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(t.image)
            .subresource_range(range)
    };
    let all = (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE);
    let transfer = (vk::PipelineStageFlags2::ALL_TRANSFER, vk::AccessFlags2::TRANSFER_WRITE);
    let to_dst = [barrier(t.old_layout, vk::ImageLayout::TRANSFER_DST_OPTIMAL, all, transfer)];
    unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_dst)) };
    let layers = vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    };
    let corner = |e: vk::Extent2D| vk::Offset3D { x: e.width as i32, y: e.height as i32, z: 1 };
    let blit = vk::ImageBlit::default()
        .src_subresource(layers)
        .src_offsets([vk::Offset3D::default(), corner(beauty.extent)])
        .dst_subresource(layers)
        .dst_offsets([vk::Offset3D::default(), corner(t.extent)]);
    unsafe {
        d.cmd_blit_image(
            cmd,
            beauty.raw,
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            t.image,
            vk::ImageLayout::TRANSFER_DST_OPTIMAL,
            &[blit],
            vk::Filter::NEAREST,
        )
    };
    let to_new = [barrier(vk::ImageLayout::TRANSFER_DST_OPTIMAL, t.new_layout, transfer, all)];
    unsafe { d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&to_new)) };
}
