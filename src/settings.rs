//! Renderer settings: the method, its parameters, and the resolutions of the maps.

use crate::error::{Error, Result};
use crate::shaders::consts::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// Where photons come from.
pub enum Method {
    /// One photon per covered cell of the 64·2^level grid.
    Dense,
    /// Adaptive traversal of the photon quadtree (Wyman & Nichols 2009), GPU-driven as in Piao 2015.
    Adaptive,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// Adaptive traversal's stopping metric.
pub enum Metric {
    /// Refine every covered cell down to the maximal level.
    MaxLevel,
    /// Stop refining a cell once its children land within the error bound in the caustic map.
    MaxError,
    /// Stop refining a cell once merging its children changes the caustic map (box-filtered to 64²) by at most
    /// the target error times the cell's flux (docs/design.md, "The flux-error metric").
    FluxError,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// What the flux-error metric measures its error in (docs/design.md, "Camera-driven refinement").
pub enum Refine {
    /// The light's caustic map, box-filtered to 64²: photons go where the caustic needs them, wherever it is seen.
    #[default]
    Light,
    /// The camera's image, box-filtered to 64²: a cell whose landings the camera does not see is final at the
    /// check level, and one it sees refines as finely as its image needs, so a zoomed view gets the photons. The
    /// caustic maps then depend on the camera.
    Camera,
}

impl Refine {
    /// The name `--refine` uses.
    pub fn name(self) -> &'static str {
        match self {
            Refine::Light => "light",
            Refine::Camera => "camera",
        }
    }

    /// FrameUniforms::refine: REFINE_LIGHT or REFINE_CAMERA (src/shader_consts.rs), which glsl/traverse.comp tests.
    pub fn code(self) -> u32 {
        use crate::shaders::consts::{REFINE_CAMERA, REFINE_LIGHT};
        match self {
            Refine::Light => REFINE_LIGHT,
            Refine::Camera => REFINE_CAMERA,
        }
    }
}

impl Metric {
    /// The name `--metric` and the bench use.
    pub fn name(self) -> &'static str {
        match self {
            Metric::MaxLevel => "max-level",
            Metric::MaxError => "max-error",
            Metric::FluxError => "flux-error",
        }
    }

    /// Its index among the traversal's pipelines (build.rs compiles traverse.comp per metric, TRAVERSE_METRIC
    /// METRIC_MAX_ERROR or METRIC_FLUX_ERROR; max-level's traversal is TRAVERSE_MAX_LEVEL's).
    pub fn code(self) -> u32 {
        use crate::shaders::consts::{METRIC_FLUX_ERROR, METRIC_MAX_ERROR, METRIC_MAX_LEVEL};
        match self {
            Metric::MaxLevel => METRIC_MAX_LEVEL,
            Metric::MaxError => METRIC_MAX_ERROR,
            Metric::FluxError => METRIC_FLUX_ERROR,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// Who writes adaptive traversal's dispatch arguments.
pub enum Driven {
    /// Every indirect command is written by the GPU; no host readback inside a frame.
    Gpu,
    /// The host reads each level's count back and records the next dispatch directly (the baseline).
    Cpu,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// How light travels through the glass.
pub enum Transport {
    /// Every glass path: rays through a BVH of the scene's triangles, in waves, with a deterministic Fresnel split.
    Exact,
    /// The papers' image-space model: refraction through one front and one back surface of the light-view
    /// g-buffers (exact for light refracted exactly twice).
    TwoInterface,
}

/// Whether four invocations share each traversal candidate's checks (`--coop-checks`, glsl/traverse.comp
/// TRAVERSE_COOP): under exact transport, max-error and flux-error trace a cell's four children's dominant paths in
/// four lanes at once instead of one after another.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum CoopChecks {
    /// On for GPUs, off for CPU devices (docs/experiments.md, "Cooperative checks").
    Auto,
    /// Four lanes a candidate.
    On,
    /// One lane a candidate.
    Off,
}

/// A switch on the command line (`on` or `off`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum OnOff {
    /// On.
    On,
    /// Off.
    Off,
}

impl CoopChecks {
    /// `auto` follows the measured rule: on a GPU a level's checks are few and long, and four lanes finish them
    /// about four times sooner; a CPU device runs the same work either way and loses the early returns.
    pub fn resolve(self, class: DeviceClass) -> CoopChecks {
        match self {
            CoopChecks::Auto if class == DeviceClass::Cpu => CoopChecks::Off,
            CoopChecks::Auto => CoopChecks::On,
            c => c,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// Where a photon's splat radius comes from.
pub enum Footprint {
    /// The splat radius follows the photon's cell: its side over a caustic-map texel.
    Cell,
    /// Exact transport (the default): the radius per map axis comes from where the cell lands, by ray
    /// differentials (Igehy 1999) carried through every interface, packed into 16 more bytes a ray (48 instead of
    /// 32); the compute splats put the wide tents this gives on coarse levels of the flux texels.
    Differential,
}

impl Footprint {
    /// vec4s per ray in the exact transport's queues.
    pub fn ray_vec4s(self) -> u32 {
        match self {
            Footprint::Cell => RAY_VEC4S_CELL,
            Footprint::Differential => RAY_VEC4S_DIFFERENTIAL,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// How splat records reach the caustic flux map.
pub enum Splat {
    /// Points drawn with vkCmdDrawIndirect and additive blending (the papers' design).
    Raster,
    /// A compute pass dispatched indirectly, adding each tap with a float atomic.
    Compute,
    /// The compute splat with contention control: a work group gathers its taps in a shared-memory window first.
    Tiled,
    /// The fastest the device has, by the rule measured in docs/experiments.md: tiled on GPUs, compute on CPU devices.
    Auto,
}

impl Splat {
    /// The splat a device runs. `auto` follows the measured rule (docs/experiments.md, "Splat throughput"): on an H200 the
    /// compute splats are 12-20x faster than the point draw and the tiled one is faster still where light
    /// focuses; on lavapipe the compute splat is 6-8x faster than the point draw, and the tiled one's barriers
    /// make it about 2x slower than the untiled one. Without float atomics: raster.
    pub fn resolve(self, info: &crate::vk::context::DeviceInfo) -> Splat {
        if !info.float_atomic_add {
            return Splat::Raster;
        }
        match self {
            Splat::Auto if info.is_cpu() => Splat::Compute,
            Splat::Auto => Splat::Tiled,
            s => s,
        }
    }

    /// Whether the records reach the map through a compute pass (either compute splat).
    pub fn is_compute(self) -> bool {
        matches!(self, Splat::Compute | Splat::Tiled)
    }
}

/// The quality a user chooses against time: what is rendered and how finely. Everything here has a flag of
/// `render` and a line in its `--help`; the defaults are chosen for the device where they say so.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Quality {
    /// How light travels through the glass.
    pub transport: Transport,
    /// Where photons come from: a dense grid, or adaptive traversal of the photon quadtree.
    pub method: Method,
    /// Adaptive traversal's stopping metric.
    pub metric: Metric,
    /// What the flux-error metric measures its error in: the light's caustic map or the camera's image.
    pub refine: Refine,
    /// Photon grid level: 64·2^level cells per side (dense), or the maximal traversal level (adaptive). None: the
    /// device's default ([`default_level`]).
    pub level: Option<u32>,
    /// Flux-error metric: the target error E, the relative L1 at 64² that merging cells may add to max-level's
    /// image at the same level; mapped to the per-cell threshold tau by the measured table of src/calibration.rs.
    pub target_error: f32,
    /// Side of the caustic map, the receiver g-buffer and the shadow map.
    pub caustic_res: u32,
    /// Eye-view supersampling: AA x AA samples per pixel of the beauty image (1: one at the pixel center).
    pub aa: u32,
    /// Beauty exposure in stops, on top of the automatic one (the brightest receiver's direct radiance at the
    /// light's target maps to 0.6 before the tone map).
    pub exposure_ev: f32,
    /// The environment's sky radiance, W/(m²·sr) (docs/design.md "Environment"); None: automatic (SKY_AUTO of
    /// the reference radiance); 0: off.
    pub sky: Option<f32>,
    /// Exact transport: interfaces an eye ray is followed through before it takes the environment's radiance.
    pub eye_depth: u32,
    /// Photon buffer size in MiB; 0: automatic ([`auto_photon_budget_mib`]).
    pub photon_budget_mib: f64,
}

impl Default for Quality {
    fn default() -> Self {
        Quality {
            transport: Transport::Exact,
            method: Method::Adaptive,
            metric: Metric::FluxError,
            refine: Refine::Light,
            level: None,
            target_error: DEFAULT_TARGET_ERROR,
            caustic_res: 1024,
            aa: 2,
            exposure_ev: 0.0,
            sky: None,
            eye_depth: 8,
            photon_budget_mib: 0.0,
        }
    }
}

/// The knobs for measuring and tuning the renderer (`--help` lists them under "Tuning"). Their defaults are the
/// measured best per device, so a user needs none of them; each exists so that its alternative can be measured.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Tuning {
    /// How splat records reach the caustic flux map.
    pub splat: Splat,
    /// Where the splat radius comes from (exact transport; the two-interface trace always uses the cell's).
    pub footprint: Footprint,
    /// Exact transport: a Fresnel child below this fraction of its photon's flux is cut (and accounted).
    pub flux_threshold: f32,
    /// Exact transport: a Fresnel branch below this fraction of its photon's flux is traced once per block of
    /// sibling photons ([`ResolvedSettings::weak_block`]), by one of them carrying the block's share with a splat
    /// as wide as the block (0: off).
    pub weak_branches: f32,
    /// The side of a weak-branch block in cells of the maximal level: 2 or 4, 0 for automatic (4).
    pub weak_block: u32,
    /// Exact transport: the BVH node layout the waves traverse.
    pub bvh_layout: BvhLayout,
    /// Who writes adaptive traversal's dispatch arguments: the GPU, or the host after a readback per level.
    pub driven: Driven,
    /// Side of the light-view refractor g-buffers (power of two, >= 64).
    pub gbuffer_res: u32,
    /// Max-error bound, in caustic-map texels.
    pub error_bound: f32,
    /// Flux-error metric: tau itself, overriding the one derived from the target error (for measuring the
    /// calibration).
    pub tau: Option<f32>,
    /// First level at which max-error and flux-error check convergence; None: [`default_check_level`].
    pub check_level: Option<u32>,
    /// Traversal work-group side (1, 2, 4, 8, 16).
    pub traverse_wg: u32,
    /// Four lanes per candidate for the metrics' checks.
    pub coop_checks: CoopChecks,
    /// Exact transport with a compute splat: deposit the landings that the light's caustic map cannot hold in the
    /// eye's image where the camera sees them (docs/design.md "The eye deposit"); off: count them as `unseen`.
    pub eye_deposit: bool,
    /// Split batches on overflow (off only for tests: overflowing work is then dropped and counted).
    pub batching: bool,
    /// Batch slots recorded per frame for GPU-driven batching (0: automatic).
    pub batch_slots: u32,
    /// Shadow-map bias, in shadow-map texels.
    pub shadow_bias: f32,
    /// Dump up to this many splatted photons for tests (0: off)...
    pub debug_photons: u32,
    /// ...of this level or deeper.
    pub debug_min_level: u32,
}

impl Default for Tuning {
    fn default() -> Self {
        Tuning {
            splat: Splat::Auto,
            footprint: Footprint::Differential,
            flux_threshold: 1e-3,
            weak_branches: 0.05,
            weak_block: 0,
            bvh_layout: BvhLayout::Auto,
            driven: Driven::Gpu,
            gbuffer_res: 1024,
            error_bound: 1.0,
            tau: None,
            check_level: None,
            traverse_wg: TRAVERSE_WG,
            coop_checks: CoopChecks::Auto,
            eye_deposit: true,
            batching: true,
            batch_slots: 0,
            shadow_bias: 1.5,
            debug_photons: 0,
            debug_min_level: 0,
        }
    }
}

/// What a renderer is asked for: the user's quality choices and the tuning knobs. [`Settings::resolve`] turns it
/// into the [`ResolvedSettings`] a device renders with.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Settings {
    /// The user's choices.
    pub quality: Quality,
    /// The tuning knobs.
    pub tuning: Tuning,
}

/// Settings resolved for one device: every automatic choice made (level, photon budget, splat, BVH layout,
/// cooperative checks, weak-branch block, check level, tau) and the device's binding limit known. The renderer
/// and the GPU code read only this; it changes only through [`Settings::resolve`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ResolvedSettings {
    /// See [`Quality::transport`].
    pub transport: Transport,
    /// See [`Quality::method`].
    pub method: Method,
    /// See [`Quality::metric`].
    pub metric: Metric,
    /// See [`Quality::refine`]: camera-driven only under adaptive flux-error (the other methods ignore it, as the
    /// CLI warns), so that the traversal, the deposits and the reuse rule all read this one value.
    pub refine: Refine,
    /// The photon level (the device's default resolved).
    pub level: u32,
    /// See [`Quality::target_error`].
    pub target_error: f32,
    /// See [`Quality::caustic_res`].
    pub caustic_res: u32,
    /// See [`Quality::aa`].
    pub aa: u32,
    /// See [`Quality::exposure_ev`].
    pub exposure_ev: f32,
    /// See [`Quality::sky`].
    pub sky: Option<f32>,
    /// See [`Quality::eye_depth`].
    pub eye_depth: u32,
    /// Photon buffer size in MiB (the automatic budget resolved).
    pub photon_budget_mib: f64,
    /// The splat that runs (never `auto`).
    pub splat: Splat,
    /// See [`Tuning::footprint`].
    pub footprint: Footprint,
    /// See [`Tuning::flux_threshold`].
    pub flux_threshold: f32,
    /// See [`Tuning::weak_branches`].
    pub weak_branches: f32,
    /// The weak-branch block side in cells of the maximal level: 2 or 4.
    pub weak_block: u32,
    /// The BVH layout the waves trace (never `auto`).
    pub bvh_layout: BvhLayout,
    /// See [`Tuning::driven`].
    pub driven: Driven,
    /// See [`Tuning::gbuffer_res`].
    pub gbuffer_res: u32,
    /// See [`Tuning::error_bound`].
    pub error_bound: f32,
    /// Flux-error's per-cell threshold: the tuning's `tau`, else the one the target error maps to.
    pub tau: f32,
    /// The first level max-error and flux-error check.
    pub check_level: u32,
    /// See [`Tuning::traverse_wg`].
    pub traverse_wg: u32,
    /// On or off (never `auto`).
    pub coop_checks: CoopChecks,
    /// The eye deposit runs: [`Tuning::eye_deposit`], under exact transport with a compute splat.
    pub eye_deposit: bool,
    /// See [`Tuning::batching`].
    pub batching: bool,
    /// See [`Tuning::batch_slots`].
    pub batch_slots: u32,
    /// See [`Tuning::shadow_bias`].
    pub shadow_bias: f32,
    /// See [`Tuning::debug_photons`].
    pub debug_photons: u32,
    /// See [`Tuning::debug_min_level`].
    pub debug_min_level: u32,
    /// Bytes one storage-buffer binding may span on the device (its maxStorageBufferRange, at most 2 GiB).
    pub binding_limit: u64,
    /// The scene has absorbing or overlapping media (`Scene::has_media`): exact transport's rays carry their
    /// medium. The renderer sets it from its scene ([`Renderer::scene_settings`](crate::Renderer::scene_settings));
    /// [`Settings::resolve`] leaves it off.
    pub media: bool,
    /// What the photons carry of their color (docs/design.md "Color"). Set by the renderer like `media`.
    pub carried_color: CarriedColor,
}

/// What a frame's photons carry of their color (docs/design.md "Color"). Carried color takes one pass per light
/// through exact transport and a compute splat whose resolve reads the flux texels, in three planes; elsewhere a
/// scene whose light depends on color takes one pass per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CarriedColor {
    /// None: one gray pass, or one pass per color channel.
    #[default]
    None,
    /// Color photons: some medium absorbs colors unequally and no glass disperses, so red, green and blue take the
    /// same paths, each ray with its RGB tint (in its medium word) and each record with its color.
    Tint,
    /// Spectral photons: some glass disperses, so each photon traces one wavelength, stratified over the cells, and
    /// its record deposits that wavelength's RGB.
    Wavelength,
}

impl CarriedColor {
    /// Whether the photons carry color: the records carry it and the flux texels hold three planes.
    pub fn carried(self) -> bool {
        self != CarriedColor::None
    }

    /// glsl/splat.comp's `SPLAT_COLOR`: gray records, records with an RGB tint, or with a wavelength.
    pub fn splat_code(self) -> u32 {
        use crate::shaders::consts::{SPLAT_GRAY, SPLAT_TINT, SPLAT_WAVELENGTH};
        match self {
            CarriedColor::None => SPLAT_GRAY,
            CarriedColor::Tint => SPLAT_TINT,
            CarriedColor::Wavelength => SPLAT_WAVELENGTH,
        }
    }
}

impl Default for ResolvedSettings {
    /// The default settings as lavapipe resolves them (for host-side computations and tests that need no device).
    fn default() -> Self {
        Settings::default().resolve_with(DeviceClass::Cpu, LAVAPIPE_BINDING_LIMIT, 0).expect("the defaults are valid")
    }
}

/// What the automatic settings depend on: CPU devices (lavapipe) and GPUs differ in what runs fastest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceClass {
    /// A CPU device (lavapipe).
    Cpu,
    /// A GPU.
    Gpu,
}

/// The default photon level for a device class: 5 (a 2048² grid) on GPUs, 4 (1024²) on CPU devices. On two CPU
/// cores (lavapipe) the default render of the sphere (exact transport, adaptive flux-error, 512×512 at AA 2) takes
/// 7.4 s at level 4 and 14 s at level 5, and a scene with two lights and colored glass (six passes) about six
/// times as long, so level 4 keeps the default render well under a minute there.
pub fn default_level(class: DeviceClass) -> u32 {
    match class {
        DeviceClass::Gpu => 5,
        DeviceClass::Cpu => 4,
    }
}

/// lavapipe's maxStorageBufferRange: the binding limit assumed until the device is known.
pub const LAVAPIPE_BINDING_LIMIT: u64 = 128 << 20;

/// The automatic photon budget: 64 MiB on CPU devices and on devices whose bindings span less than 512 MiB;
/// elsewhere 1/64 of the largest device-local heap, within 64..=512 MiB. 512 MiB is 67M photon entries, 3.8 GB
/// with the splat records and exact transport's ray queues (33.5M rays each), and the most a batch can use: its
/// 16.8M photons (half a queue) fill the waves' 24-bit photon index ([`MAX_BATCH_PHOTONS`]). On a GPU of 32 GB or
/// more, exact transport then runs level 6 (13.2M photons on the sphere) in one batch.
pub fn auto_photon_budget_mib(cpu: bool, binding_limit: u64, device_local_bytes: u64) -> f64 {
    let small = cpu || binding_limit < 512 << 20;
    let mib = if small { 64.0 } else { ((device_local_bytes >> 20) as f64 / 64.0).clamp(64.0, 512.0) };
    mib.min(max_budget_mib(binding_limit))
}

/// Photons one exact-transport batch may hold: a ray names its photon by a 24-bit index (glsl/wave.comp).
pub const MAX_BATCH_PHOTONS: u32 = 1 << PHOTON_INDEX_BITS;

/// Largest photon budget for a binding limit: the splat records (16 bytes per 8-byte photon entry) must fit one
/// binding. 64 MiB under lavapipe's 128 MiB.
pub fn max_budget_mib(binding_limit: u64) -> f64 {
    (binding_limit / 2) as f64 / (1024.0 * 1024.0)
}

/// The debug photon dump (48 bytes per photon) must fit one 128 MiB storage-buffer binding.
pub const MAX_DEBUG_PHOTONS: u32 = 2_000_000;

/// Max-error's first checked level, and flux-error's up to `--level` - 1 ([`default_check_level`]).
pub const DEFAULT_CHECK_LEVEL: u32 = 3;
/// Default `--target-error` of the flux-error metric: a rel-L1 (64²) of at most 0.1% added to max-level's image
/// (τ = 0.02 by src/calibration.rs; docs/design.md, "The flux-error metric", says why).
pub const DEFAULT_TARGET_ERROR: f32 = 0.001;

/// Largest eye-view supersampling factor (per side).
pub const MAX_AA: u32 = 4;

/// Deepest eye-ray tree (interfaces).
pub const MAX_EYE_DEPTH: u32 = 32;

/// The automatic sky radiance, as a fraction of the reference radiance (the diffuse radiance of the brightest
/// albedo under the light at its target): the sky lights a white floor to this fraction of the lit floor.
pub const SKY_AUTO: f32 = 0.25;

/// The traversal work-group sides `--traverse-wg` takes.
pub const TRAVERSE_WG_SWEEP: [u32; 5] = [1, 2, 4, 8, 16];
/// The traversal work-group side built with cooperative checks (build.rs: `traverse.comp` `*_coop`).
pub const COOP_WG: u32 = 8;

impl Settings {
    /// Check every value's range; the errors name the field ([`Error::Setting`]).
    pub fn validate(&self) -> Result<()> {
        let (q, t) = (&self.quality, &self.tuning);
        let bad = |field, value: &dyn std::fmt::Display, rule: String| Err(Error::setting(field, value, rule));
        if let Some(level) = q.level {
            if level >= MAX_LEVELS {
                return bad("Quality::level", &level, format!("must be at most {}", MAX_LEVELS - 1));
            }
        }
        if !t.gbuffer_res.is_power_of_two() || t.gbuffer_res < LEVEL0_RES || t.gbuffer_res > 8192 {
            return bad("Tuning::gbuffer_res", &t.gbuffer_res, "must be a power of two in 64..=8192".into());
        }
        if t.gbuffer_res.trailing_zeros() - LEVEL0_RES.trailing_zeros() >= MAX_PYRAMID_MIPS {
            return bad("Tuning::gbuffer_res", &t.gbuffer_res, "too many pyramid levels".into());
        }
        if q.caustic_res < 16 || q.caustic_res > 8192 {
            return bad("Quality::caustic_res", &q.caustic_res, "must lie in 16..=8192".into());
        }
        if !(q.photon_budget_mib.is_finite() && q.photon_budget_mib >= 0.0) {
            return bad("Quality::photon_budget_mib", &q.photon_budget_mib, "must be > 0 MiB (or 0: automatic)".into());
        }
        if !(t.error_bound.is_finite() && t.error_bound > 0.0) {
            return bad("Tuning::error_bound", &t.error_bound, "must be > 0 texels".into());
        }
        if !(q.target_error.is_finite() && q.target_error > 0.0 && q.target_error <= 1.0) {
            let rule = "must lie in (0, 1] (the relative L1 at 64² that merging may add)";
            return bad("Quality::target_error", &q.target_error, rule.into());
        }
        if let Some(tau) = t.tau {
            if !(tau.is_finite() && tau > 0.0 && tau <= crate::calibration::TAU_MAX) {
                return bad("Tuning::tau", &tau, format!("must lie in (0, {}]", crate::calibration::TAU_MAX));
            }
        }
        if !(q.exposure_ev.is_finite() && q.exposure_ev.abs() <= 32.0) {
            return bad("Quality::exposure_ev", &q.exposure_ev, "must lie in [-32, 32] stops".into());
        }
        if !(1..=MAX_AA).contains(&q.aa) {
            return bad("Quality::aa", &q.aa, format!("must lie in 1..={MAX_AA}"));
        }
        if let Some(sky) = q.sky {
            if !(sky.is_finite() && sky >= 0.0) {
                return bad("Quality::sky", &sky, "must be a radiance >= 0 W/(m²·sr)".into());
            }
        }
        if !(1..=MAX_EYE_DEPTH).contains(&q.eye_depth) {
            return bad("Quality::eye_depth", &q.eye_depth, format!("must lie in 1..={MAX_EYE_DEPTH}"));
        }
        if !(t.flux_threshold.is_finite() && (0.0..1.0).contains(&t.flux_threshold)) {
            return bad("Tuning::flux_threshold", &t.flux_threshold, "must lie in [0, 1)".into());
        }
        if !(t.weak_branches.is_finite() && (0.0..1.0).contains(&t.weak_branches)) {
            return bad("Tuning::weak_branches", &t.weak_branches, "must lie in [0, 1)".into());
        }
        if ![0, 2, 4].contains(&t.weak_block) {
            return bad("Tuning::weak_block", &t.weak_block, "must be 2, 4 or 0 (automatic)".into());
        }
        if !TRAVERSE_WG_SWEEP.contains(&t.traverse_wg) {
            return bad("Tuning::traverse_wg", &t.traverse_wg, "must be one of 1, 2, 4, 8, 16".into());
        }
        if t.debug_photons > MAX_DEBUG_PHOTONS {
            return bad("Tuning::debug_photons", &t.debug_photons, format!("at most {MAX_DEBUG_PHOTONS}"));
        }
        if t.batch_slots > MAX_BATCHES {
            return bad("Tuning::batch_slots", &t.batch_slots, format!("at most {MAX_BATCHES}"));
        }
        Ok(())
    }

    /// Resolve the settings for a device: its binding limit, and every automatic choice by the rules measured on
    /// each device class. A photon budget larger than the device's bindings allow is bad input.
    pub fn resolve(&self, info: &crate::vk::DeviceInfo) -> Result<ResolvedSettings> {
        let class = if info.is_cpu() { DeviceClass::Cpu } else { DeviceClass::Gpu };
        let binding_limit = (info.limits.max_storage_buffer_range as u64).min(2 << 30);
        let mut c = self.resolve_with(class, binding_limit, info.device_local_bytes)?;
        c.splat = self.tuning.splat.resolve(info);
        let max = max_budget_mib(binding_limit);
        if c.photon_budget_mib > max {
            return Err(Error::setting(
                "Quality::photon_budget_mib",
                c.photon_budget_mib,
                format!(
                    "at most {max} MiB on {} (the splat records, 16 bytes per 8-byte photon entry, must fit one \
                     storage-buffer binding of {} MiB: its maxStorageBufferRange)",
                    info.name,
                    binding_limit >> 20
                ),
            ));
        }
        Ok(c)
    }

    /// [`Settings::resolve`] from the device's class, binding limit and device-local memory (the splat as the
    /// class resolves it with float atomics).
    pub fn resolve_with(
        &self,
        class: DeviceClass,
        binding_limit: u64,
        device_local_bytes: u64,
    ) -> Result<ResolvedSettings> {
        self.validate()?;
        let (q, t) = (&self.quality, &self.tuning);
        let cpu = class == DeviceClass::Cpu;
        let level = q.level.unwrap_or(default_level(class));
        if q.method == Method::Dense && level > 12 {
            let rule = "the dense method goes up to level 12 (262,144² photons); the adaptive one goes deeper";
            return Err(Error::setting("Quality::level", level, rule));
        }
        let photon_budget_mib = if q.photon_budget_mib == 0.0 {
            auto_photon_budget_mib(cpu, binding_limit, device_local_bytes)
        } else {
            q.photon_budget_mib
        };
        let splat = match t.splat {
            Splat::Auto if cpu => Splat::Compute,
            Splat::Auto => Splat::Tiled,
            s => s,
        };
        Ok(ResolvedSettings {
            transport: q.transport,
            method: q.method,
            metric: q.metric,
            refine: if q.method == Method::Adaptive && q.metric == Metric::FluxError {
                q.refine
            } else {
                Refine::Light
            },
            level,
            target_error: q.target_error,
            caustic_res: q.caustic_res,
            aa: q.aa,
            exposure_ev: q.exposure_ev,
            sky: q.sky,
            eye_depth: q.eye_depth,
            photon_budget_mib,
            splat,
            // The two-interface trace always sizes its splats by the cell.
            footprint: if q.transport == Transport::TwoInterface { Footprint::Cell } else { t.footprint },
            flux_threshold: t.flux_threshold,
            weak_branches: t.weak_branches,
            weak_block: if t.weak_block == 0 { 4 } else { t.weak_block },
            bvh_layout: t.bvh_layout.resolve(class),
            driven: t.driven,
            gbuffer_res: t.gbuffer_res,
            error_bound: t.error_bound,
            tau: t.tau.unwrap_or_else(|| crate::calibration::tau_for_target_error(q.target_error)),
            check_level: t.check_level.unwrap_or_else(|| default_check_level(q.metric, level)),
            traverse_wg: t.traverse_wg,
            coop_checks: t.coop_checks.resolve(class),
            eye_deposit: t.eye_deposit && q.transport == Transport::Exact && splat.is_compute(),
            batching: t.batching,
            batch_slots: t.batch_slots,
            shadow_bias: t.shadow_bias,
            debug_photons: t.debug_photons,
            debug_min_level: t.debug_min_level,
            binding_limit,
            media: false,
            carried_color: CarriedColor::None,
        })
    }
}

/// The first level checked for convergence when the tuning names none: level 3 (Wyman & Nichols' 512² level),
/// and under flux-error at most `level` - 1, so that the metric acts at every level from 1 on (with the check
/// level at `level` or above it would emit max-level's photons and pay for a traversal; at level 3, check level 2
/// reaches dense's error on the sphere 9% faster and 0.87% in 27% less time on lavapipe,
/// docs/bench/llvmpipe-llvm-15-0-6-256-bits/speed_error_exact_levels3-5.md).
pub fn default_check_level(metric: Metric, level: u32) -> u32 {
    match metric {
        Metric::FluxError => DEFAULT_CHECK_LEVEL.min(level.saturating_sub(1)),
        _ => DEFAULT_CHECK_LEVEL,
    }
}

impl ResolvedSettings {
    /// Whether traversal runs the cooperative checks: on (`auto` on a GPU), exact transport, max-error or
    /// flux-error, and work groups of 8x8 (the one side built with four lanes per candidate: 16 candidates a
    /// group).
    pub fn coop_traversal(&self) -> bool {
        self.coop_checks == CoopChecks::On
            && self.transport == Transport::Exact
            && self.method == Method::Adaptive
            && matches!(self.metric, Metric::MaxError | Metric::FluxError)
            && self.traverse_wg == COOP_WG
    }

    /// Traversal's work-group side as the dispatches count candidates: `traverse_wg`, or half of it with the
    /// cooperative checks (four invocations per candidate).
    pub fn traverse_dispatch_wg(&self) -> u32 {
        if self.coop_traversal() {
            self.traverse_wg / 2
        } else {
            self.traverse_wg
        }
    }

    /// The flux-error metric's per-cell threshold tau.
    pub fn tau(&self) -> f32 {
        self.tau
    }

    /// The first level checked for convergence.
    pub fn check_level(&self) -> u32 {
        self.check_level
    }

    /// Exact transport's weak-branch block side, in cells of the maximal level (docs/design.md step 4). A
    /// block's turns follow its cells, not its photons, so every method shares the same blocks.
    pub fn weak_block(&self) -> u32 {
        self.weak_block
    }

    /// The photon budget in MiB.
    pub fn photon_budget(&self) -> f64 {
        self.photon_budget_mib
    }

    /// Photon-buffer entries (8 bytes each). Each has a 16-byte splat record, and that buffer must stay within one
    /// binding (`binding_limit`; 8 Mi entries under lavapipe's 128 MiB).
    pub fn photon_capacity(&self) -> u32 {
        let max = (self.binding_limit / 16).min(u32::MAX as u64 / 2) as u32;
        (((self.photon_budget() * 1024.0 * 1024.0) / 8.0).floor().max(8.0) as u32).min(max)
    }

    /// Exact transport: rays per queue (32 bytes each, 48 with ray differentials; two queues; each within one
    /// binding) and splat records per batch (one per photon-buffer entry, as for the two-interface trace).
    /// Two-interface: none.
    pub fn ray_queue_capacity(&self) -> u32 {
        match self.transport {
            Transport::Exact => {
                let max = (self.binding_limit / self.ray_bytes() as u64).min(u32::MAX as u64) as u32;
                (self.photon_capacity() / 2).clamp(8, max)
            }
            Transport::TwoInterface => 0,
        }
    }

    /// Bytes per ray in the exact transport's queues.
    pub fn ray_bytes(&self) -> u32 {
        16 * self.ray_vec4s()
    }

    /// vec4s per ray in the exact transport's queues: the ray, its differentials with that footprint, and its
    /// medium where the scene has media.
    pub fn ray_vec4s(&self) -> u32 {
        self.footprint.ray_vec4s() + if self.media { RAY_VEC4S_MEDIUM } else { 0 }
    }

    /// Photons one batch may emit (a dense band, or an adaptive batch's photons; an adaptive batch's candidates
    /// may fill the rest of the buffer beside them while it traverses). Under exact transport wave 0 appends up
    /// to two children per photon, so a batch emits at most half a ray queue: a larger one would traverse, then
    /// overflow its queue and be split after all its work. And at most [`MAX_BATCH_PHOTONS`], which the rays'
    /// photon index can name.
    pub fn batch_photons(&self, capacity: u32) -> u32 {
        match self.transport {
            Transport::Exact => capacity.min(self.ray_queue_capacity() / 2).clamp(8, MAX_BATCH_PHOTONS),
            Transport::TwoInterface => capacity,
        }
    }

    /// Side of the refractor g-buffers this frame uses. The two-interface trace reads surfaces from them, so it
    /// uses `gbuffer_res` as given. Exact transport reads them only for coverage (which cells to emit; each cell's
    /// own ray decides the rest), so they are fitted to the photon grid: a finer buffer than the grid adds nothing
    /// but rasterization and pyramid work.
    pub fn gbuffer_side(&self) -> u32 {
        match self.transport {
            Transport::Exact => self.gbuffer_res.min(LEVEL0_RES << self.level.min(12)).max(LEVEL0_RES),
            Transport::TwoInterface => self.gbuffer_res,
        }
    }

    /// log2(gbuffer_side / 64).
    pub fn gbuffer_level(&self) -> u32 {
        self.gbuffer_side().trailing_zeros() - LEVEL0_RES.trailing_zeros()
    }
}

/// Parse `WxH`; `flag` names the option in the message.
pub fn parse_size(s: &str, flag: &str) -> Result<(u32, u32)> {
    let bad = || Error::BadInput(format!("{flag} `{s}`: expected WxH with 1 <= W, H <= 16384 (for example 512x512)"));
    let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(bad());
    }
    Ok((w, h))
}

/// The output size: `--size` when given (with a warning when its aspect differs from the one the camera was
/// authored at), else 512 pixels high and as wide as the camera's authored aspect (512x512 without one).
pub fn output_size(size: Option<&str>, flag: &str, camera: &crate::scene::Camera) -> Result<(u32, u32)> {
    match (size, camera.aspect) {
        (Some(s), aspect) => {
            let (w, h) = parse_size(s, flag)?;
            if let Some(a) = aspect {
                let given = w as f32 / h as f32;
                if (given / a - 1.0).abs() > 0.01 {
                    log::warn!(
                        "{flag} {w}x{h} (aspect {given:.3}) differs from camera `{}`'s authored aspect {a:.3}: the \
                         image keeps the camera's vertical extent and shows {} at the sides",
                        camera.name,
                        if given > a { "more" } else { "less" }
                    );
                }
            }
            Ok((w, h))
        }
        (None, Some(a)) => {
            let w = ((512.0 * a / 2.0).round() as u32 * 2).clamp(2, 16384);
            Ok((w, 512))
        }
        (None, None) => Ok((512, 512)),
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
/// The BVH node layout exact transport's waves trace.
pub enum BvhLayout {
    /// The faster layout for the device, by the rule measured in docs/experiments.md ("BVH layouts"):
    /// single on GPUs, wide on CPU devices. The settings resolve it to the layout it picks, so the stats report
    /// that.
    Auto,
    /// Both children's boxes in the parent (64-byte nodes).
    Pair,
    /// One box per node (32-byte nodes).
    Single,
    /// One box per node in depth-first order with escape links: a stackless traversal (32-byte nodes).
    Threaded,
    /// Compressed 8-wide nodes (80 bytes) with children's boxes quantized to 8 bits a plane (Ylitie, Karras and
    /// Laine 2017), walked in the ray's octant order.
    Wide,
}

impl BvhLayout {
    /// The layout a device traces with: `auto` follows the measured rule. On the H200 the single-box layout's
    /// bounce waves are 10-15% faster than the pair layout's (frame: 8-10% faster at level 5, sphere and bunny);
    /// the wide layout has not been timed on a GPU yet. On lavapipe the pair layout is about 20% faster than the
    /// single one, and the wide layout's bounce waves are about 20% faster than the pair layout's.
    pub fn resolve(self, class: DeviceClass) -> BvhLayout {
        match self {
            BvhLayout::Auto if class == DeviceClass::Cpu => BvhLayout::Wide,
            BvhLayout::Auto => BvhLayout::Single,
            l => l,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_automatic_budget_follows_device_memory_and_a_batch_fits_the_photon_index() {
        let binding = 2u64 << 30;
        assert_eq!(auto_photon_budget_mib(false, binding, 141 << 30), 512.0);
        assert_eq!(auto_photon_budget_mib(false, binding, 16 << 30), 256.0);
        assert_eq!(auto_photon_budget_mib(false, binding, 2 << 30), 64.0);
        assert_eq!(auto_photon_budget_mib(true, binding, 64 << 30), 64.0);
        assert_eq!(auto_photon_budget_mib(false, LAVAPIPE_BINDING_LIMIT, 141 << 30), 64.0);
        // The automatic budget on a large GPU, and the largest a 2 GiB binding allows: a batch never holds more
        // photons than the rays' 24-bit index names.
        for (mib, batch) in [(512.0, MAX_BATCH_PHOTONS), (1024.0, MAX_BATCH_PHOTONS), (256.0, 1 << 23)] {
            let mut s = Settings::default();
            s.quality.photon_budget_mib = mib;
            let c = s.resolve_with(DeviceClass::Gpu, binding, 141 << 30).unwrap();
            let t = c.batch_photons(c.photon_capacity());
            assert_eq!(t, batch, "{mib} MiB");
            assert!(t <= c.ray_queue_capacity() / 2, "{mib} MiB");
        }
    }

    #[test]
    fn resolving_makes_every_automatic_choice() {
        for class in [DeviceClass::Cpu, DeviceClass::Gpu] {
            let c = Settings::default().resolve_with(class, LAVAPIPE_BINDING_LIMIT, 1 << 30).unwrap();
            assert_eq!(c.level, default_level(class));
            assert!(c.photon_budget_mib > 0.0);
            assert!(!matches!(c.splat, Splat::Auto));
            assert_ne!(c.bvh_layout, BvhLayout::Auto);
            assert_ne!(c.coop_checks, CoopChecks::Auto);
            assert!([2, 4].contains(&c.weak_block));
        }
    }

    #[test]
    fn camera_driven_refinement_resolves_under_flux_error_only() {
        let resolved = |method, metric| {
            let mut s = Settings::default();
            (s.quality.method, s.quality.metric, s.quality.refine) = (method, metric, Refine::Camera);
            s.resolve_with(DeviceClass::Cpu, LAVAPIPE_BINDING_LIMIT, 1 << 30).unwrap().refine
        };
        assert_eq!(resolved(Method::Adaptive, Metric::FluxError), Refine::Camera);
        assert_eq!(resolved(Method::Adaptive, Metric::MaxError), Refine::Light);
        assert_eq!(resolved(Method::Dense, Metric::FluxError), Refine::Light);
    }
}
