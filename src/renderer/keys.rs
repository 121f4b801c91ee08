//! Reuse by dependency: what the caustic stages and the eye view depend on, as typed keys. A frame whose key equals
//! the last frame's reuses that frame's maps (or its whole beauty image).

use crate::frame::LightReport;
use crate::gpu_types::GpuView;
use crate::scene::view::CameraView;
use crate::scene::Light;
use crate::settings::{Refine, ResolvedSettings};

/// What the targets' allocation depends on: the sizes of the light maps and buffers, the passes, the ray size and
/// the frames in flight (the output size only touches the eye-sized targets).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TargetsKey {
    pub gbuffer_side: u32,
    pub caustic_res: u32,
    pub photon_budget_bits: u64,
    pub debug_photons: u32,
    pub ray_queue_capacity: u32,
    pub passes: usize,
    pub ray_bytes: u32,
    pub carried_color: bool,
    pub frames_in_flight: usize,
}

impl TargetsKey {
    pub fn new(s: &ResolvedSettings, passes: usize, frames_in_flight: usize) -> Self {
        TargetsKey {
            gbuffer_side: s.gbuffer_side(),
            caustic_res: s.caustic_res,
            photon_budget_bits: s.photon_budget_mib.to_bits(),
            debug_photons: s.debug_photons,
            ray_queue_capacity: s.ray_queue_capacity(),
            passes,
            ray_bytes: s.ray_bytes(),
            carried_color: s.carried_color.carried(),
            frames_in_flight,
        }
    }
}

/// What the caustic stages depend on: the lights, the geometry and materials (by generation), the objects'
/// transforms, the settings that
/// touch them (not the eye view's own: supersampling, sky, eye-ray depth, exposure) and the light-side targets.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CausticKey {
    pub lights: Vec<Light>,
    pub scene_generation: u64,
    /// Every object's transform (moving one needs no new generation), and the scene's time (its bits) with the
    /// drops into simulated water so far, when something deforms.
    pub transforms: (Vec<glam::Mat4>, Option<(u32, u64)>),
    pub settings: ResolvedSettings,
    pub targets: Option<TargetsKey>,
    /// The camera's uniform bytes where camera-driven refinement makes the photons depend on it (`--refine
    /// camera`), else None.
    pub camera: Option<Vec<u8>>,
}

impl CausticKey {
    pub fn new(
        lights: &[Light],
        scene_generation: u64,
        transforms: (Vec<glam::Mat4>, Option<(u32, u64)>),
        s: &ResolvedSettings,
        targets: Option<TargetsKey>,
        camera: &CameraView,
    ) -> Self {
        let settings = ResolvedSettings { aa: 1, sky: None, eye_depth: 0, exposure_ev: 0.0, ..s.clone() };
        // Camera-driven refinement chooses the photons by what the camera sees: a new eye view traces afresh.
        let camera = (s.refine == Refine::Camera).then(|| bytemuck::bytes_of(&GpuView::from_camera(camera)).to_vec());
        CausticKey { lights: lights.to_vec(), scene_generation, transforms, settings, targets, camera }
    }
}

/// What the eye view depends on besides the caustic maps: every pass's uniforms (camera, light views, exposure,
/// sky), the preview flag and the eye targets (by generation).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct EyeKey {
    pub caustic: CausticKey,
    /// The uniforms' bytes.
    pub uniforms: Vec<u8>,
    pub preview: bool,
    pub targets_generation: u64,
}

/// The last frame's keys: its caustic inputs with the traversal and transport state of each pass (filled in once
/// the frame completes), and its eye-view inputs.
#[derive(Default)]
pub(crate) struct Caches {
    pub caustic: Option<(CausticKey, Vec<LightReport>)>,
    pub eye: Option<EyeKey>,
    /// The eye view (the camera's uniform bytes and the eye targets' generation) that the eye deposit's flux was
    /// deposited or cleared for.
    pub eye_deposit: Option<(Vec<u8>, u64)>,
    /// The photon sets the caustic maps (and the eye deposit) average now: 1 after a frame that traced afresh.
    pub sets: u32,
}

/// What a frame does with the last frame's maps ([`Caches::plan`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct MapPlan {
    /// The last frame's maps serve this one: nothing is traced.
    pub reused: bool,
    /// Clear the eye deposit before the photons.
    pub clear: bool,
    /// The index of the photon set this frame traces among those its maps average (0: they start afresh).
    pub set: u32,
}

/// Whether the last caustic frame's light all landed in the lights' own maps (every pass's account, once its frame
/// completed, has no eye deposit and nothing unseen): its maps then serve any eye view.
pub(crate) fn light_maps_hold_all(reports: &[LightReport]) -> bool {
    use crate::frame::deposit::DEPOSITS;
    use crate::shaders::consts::ACC_UNSEEN;
    let camera_terms = || DEPOSITS.iter().map(|d| d.declares()).filter(|d| d.follows_camera).map(|d| d.account);
    reports.iter().all(|l| {
        !l.caustics
            || l.transport.is_some_and(|t| {
                let a = t.account();
                camera_terms().all(|term| a[term as usize] == 0.0) && a[ACC_UNSEEN as usize] == 0.0
            })
    })
}

impl Caches {
    /// Whether the frame reuses the whole eye view (`reused`: it reuses the caustic maps), and the eye key it leaves
    /// for the next frame. The eye view is reused with the same caustic inputs, the same uniforms (camera, views,
    /// exposure, sky, in `data`), the same kernels and targets, and only by frames that read back no eye AOV other
    /// than the composite's outputs; a caustics or direct AOV frame composites no beauty (src/frame/mod.rs), so no
    /// later frame reuses its eye.
    pub fn eye_reused(
        &mut self,
        key: &CausticKey,
        data: &[crate::gpu_types::FrameData],
        desc: &crate::renderer::FrameDesc,
        reused: bool,
        targets_generation: u64,
    ) -> bool {
        use crate::renderer::Aov;
        let eye_key = EyeKey {
            caustic: key.clone(),
            uniforms: bytemuck::cast_slice(data).to_vec(),
            preview: desc.preview,
            targets_generation,
        };
        let beauty = matches!(desc.aov, None | Some(Aov::Beauty) | Some(Aov::BeautyHdr));
        let eye_reused = reused && beauty && self.eye.as_ref() == Some(&eye_key);
        self.eye = beauty.then_some(eye_key);
        eye_reused
    }

    /// What a frame with the caustic inputs `key` does with the last frame's maps: reuse them (`reuse`: reuse is
    /// on), add another photon set to their average (while they average fewer than `sets` of the same inputs), or
    /// trace afresh; and whether it clears the eye deposit first. `eye_view`: the eye view the eye deposit is for,
    /// when it runs. The deposit depends on the eye too: maps that held every landing serve any eye view (the frame
    /// then clears the deposit for a new one), else only the eye view they were deposited for. A frame that traces
    /// afresh clears the deposit; a continuation (`continuation`) adds to it and reuses nothing.
    pub fn plan(
        &mut self,
        key: &CausticKey,
        eye_view: Option<(Vec<u8>, u64)>,
        reuse: bool,
        continuation: bool,
        sets: u32,
    ) -> MapPlan {
        let same_eye = self.eye_deposit == eye_view;
        if continuation {
            return MapPlan { reused: false, clear: false, set: self.sets.saturating_sub(1) };
        }
        let same = reuse
            && self.caustic.as_ref().is_some_and(|(k, reports)| {
                k == key && (eye_view.is_none() || same_eye || light_maps_hold_all(reports))
            });
        let plan = match (same, self.sets < sets) {
            // Another photon set into the average: the eye deposit keeps its sum unless the eye moved (then every
            // landing was in the lights' maps, and it holds nothing).
            (true, true) => MapPlan { reused: false, clear: eye_view.is_some() && !same_eye, set: self.sets },
            (true, false) => MapPlan { reused: true, clear: eye_view.is_some() && !same_eye, set: self.sets - 1 },
            (false, _) => MapPlan { reused: false, clear: eye_view.is_some(), set: 0 },
        };
        if !plan.reused {
            self.sets = plan.set + 1;
        }
        if eye_view.is_some() && (!plan.reused || plan.clear) {
            self.eye_deposit = eye_view;
        }
        plan
    }

    /// Forget both: the next frame recomputes everything.
    pub fn clear(&mut self) {
        self.caustic = None;
        self.eye = None;
        self.eye_deposit = None;
        self.sets = 0;
    }
}
