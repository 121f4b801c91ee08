//! Renderer settings: the method, its parameters, and the resolutions of the maps.

use crate::error::{AppError, AppResult};
use crate::shaders::consts::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// One photon per covered cell of the 64·2^level grid.
    Dense,
    /// Adaptive traversal of the photon quadtree (Wyman & Nichols 2009), GPU-driven as in Piao 2015.
    Adaptive,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// Refine every covered cell down to the maximal level.
    MaxLevel,
    /// Stop refining a cell once its children land within the error bound in the caustic map.
    MaxError,
    /// Stop refining a cell once merging its children changes the caustic map (box-filtered to 64²) by at most
    /// the target error times the cell's flux (docs/design.md, "The flux-error metric").
    FluxError,
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

    /// The code the traverse shader reads (FrameData.traversal.y, bits 0-7).
    pub fn code(self) -> u32 {
        match self {
            Metric::MaxLevel => 0,
            Metric::MaxError => 1,
            Metric::FluxError => 2,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Driven {
    /// Every indirect command is written by the GPU; no host readback inside a frame.
    Gpu,
    /// The host reads each level's count back and records the next dispatch directly (the baseline).
    Cpu,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
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
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CoopChecks {
    /// On for GPUs, off for CPU devices (docs/experiments.md, "Cooperative checks").
    Auto,
    On,
    Off,
}

impl CoopChecks {
    /// `auto` follows the measured rule: on a GPU a level's checks are few and long, and four lanes finish them
    /// about four times sooner; a CPU device runs the same work either way and loses the early returns.
    pub fn resolve(self, info: &crate::vk::DeviceInfo) -> CoopChecks {
        match self {
            CoopChecks::Auto if info.is_cpu() => CoopChecks::Off,
            CoopChecks::Auto => CoopChecks::On,
            c => c,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Footprint {
    /// The splat radius follows the photon's cell: its side over a caustic-map texel.
    Cell,
    /// Exact transport: the radius per map axis comes from where the cell lands, by ray differentials (Igehy
    /// 1999) carried through every interface; the ray queues grow from 32 to 80 bytes a ray.
    Differential,
}

impl Footprint {
    /// vec4s per ray in the exact transport's queues.
    pub fn ray_vec4s(self) -> u32 {
        match self {
            Footprint::Cell => 2,
            Footprint::Differential => 5,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Splat {
    /// Points drawn with vkCmdDrawIndirect and additive blending (the papers' design).
    Raster,
    /// A compute pass dispatched indirectly, adding each tap with a float atomic.
    Compute,
    /// The compute splat with contention control: a work group gathers its taps in a shared-memory window first.
    Tiled,
    /// The fastest the device has, by the rule measured in docs/results.md: tiled on GPUs, compute on CPU devices.
    Auto,
}

impl Splat {
    /// The splat a device runs. `auto` follows the measured rule (docs/results.md, "Splat throughput"): on an H200 the
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

#[derive(Clone, Debug, serde::Serialize)]
pub struct Settings {
    pub transport: Transport,
    /// Beauty exposure in stops, on top of the automatic one (the brightest receiver's direct radiance at the
    /// light's target maps to 0.6 before the tone map).
    pub exposure_ev: f32,
    /// Eye-view supersampling: AA x AA samples per pixel of the beauty image (1: one at the pixel center).
    pub aa: u32,
    /// The environment's sky radiance, W/(m²·sr) (docs/design.md "Environment"); None: automatic (SKY_AUTO of
    /// the reference radiance); 0: off.
    pub sky: Option<f32>,
    /// Exact transport: interfaces an eye ray is followed through before it takes the environment's radiance.
    pub eye_depth: u32,
    /// A preview of the eye view (the viewer's frames while the view moves; not an option): one eye sample per
    /// pixel, and glass by the two-surface deferred refraction instead of tracing through the BVH.
    pub preview: bool,
    /// How splat records reach the caustic flux map.
    pub splat: Splat,
    /// Where the splat radius comes from (exact transport; the two-interface trace always uses the cell's).
    pub footprint: Footprint,
    /// Exact transport: a Fresnel child below this fraction of its photon's flux is cut (and accounted).
    pub flux_threshold: f32,
    /// Exact transport: a Fresnel branch below this fraction of its photon's flux is traced once per block of
    /// sibling photons ([`Settings::weak_block`]), by one of them carrying the block's share with a splat as wide as
    /// the block (0: off).
    pub weak_branches: f32,
    /// The side of a weak-branch block in cells of the maximal level: 2 or 4, 0 for automatic
    /// ([`Settings::weak_block`]).
    pub weak_block: u32,
    /// Exact transport: the BVH node layout the waves traverse (`auto` until [`Settings::resolve_for_device`]
    /// picks one).
    pub bvh_layout: crate::bvh::BvhLayout,
    pub method: Method,
    pub metric: Metric,
    /// Photon grid level: 64·2^level cells per side (dense), or the maximal traversal level (adaptive).
    pub level: u32,
    pub driven: Driven,
    /// Photon buffer size in MiB; 0: automatic (the renderer picks it for the device, see
    /// [`Settings::resolve_for_device`]).
    pub photon_budget_mib: f64,
    /// Bytes one storage-buffer binding may span on the device (its maxStorageBufferRange, at most 2 GiB). Set by
    /// the renderer; lavapipe's 128 MiB until then.
    pub binding_limit: u64,
    /// Side of the light-view refractor g-buffers (power of two, >= 64).
    pub gbuffer_res: u32,
    /// Side of the caustic map, the receiver g-buffer and the shadow map.
    pub caustic_res: u32,
    /// Max-error bound, in caustic-map texels.
    pub error_bound: f32,
    /// Flux-error metric: the target error E, the relative L1 at 64² that merging cells may add to max-level's
    /// image at the same level; mapped to the per-cell threshold tau by the measured table of src/calibration.rs.
    pub target_error: f32,
    /// Flux-error metric: tau itself, overriding the one derived from `target_error` (the hidden `--tau`, for
    /// measuring the calibration).
    pub tau: Option<f32>,
    /// First level at which max-error and flux-error check convergence (`--check-level`); None: the default,
    /// [`Settings::check_level`].
    pub check_level: Option<u32>,
    /// Traversal work-group side (1, 2, 4, 8, 16).
    pub traverse_wg: u32,
    /// Four lanes per candidate for the metrics' checks (`auto` until [`Settings::resolve_for_device`]); used where
    /// [`Settings::coop_traversal`] says.
    pub coop_checks: CoopChecks,
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

impl Default for Settings {
    fn default() -> Self {
        Settings {
            transport: Transport::Exact,
            exposure_ev: 0.0,
            aa: 2,
            sky: None,
            eye_depth: 8,
            preview: false,
            splat: Splat::Auto,
            footprint: Footprint::Cell,
            flux_threshold: 1e-3,
            weak_branches: 0.05,
            weak_block: 0,
            bvh_layout: crate::bvh::BvhLayout::Auto,
            method: Method::Adaptive,
            metric: Metric::MaxLevel,
            level: 5,
            driven: Driven::Gpu,
            photon_budget_mib: 0.0,
            binding_limit: LAVAPIPE_BINDING_LIMIT,
            gbuffer_res: 1024,
            caustic_res: 1024,
            error_bound: 1.0,
            target_error: DEFAULT_TARGET_ERROR,
            tau: None,
            check_level: None,
            traverse_wg: TRAVERSE_WG,
            coop_checks: CoopChecks::Auto,
            batching: true,
            batch_slots: 0,
            shadow_bias: 1.5,
            debug_photons: 0,
            debug_min_level: 0,
        }
    }
}

/// lavapipe's maxStorageBufferRange: the binding limit assumed until the device is known.
pub const LAVAPIPE_BINDING_LIMIT: u64 = 128 << 20;

/// The automatic photon budget: 64 MiB on CPU devices and on devices whose bindings span less than 512 MiB;
/// elsewhere 1/64 of the largest device-local heap, within 64..=512 MiB. 512 MiB is 67M photon entries, 3.8 GB
/// with the splat records and exact transport's ray queues (33.5M rays each), and the most a batch can use: its
/// 16.8M photons (half a queue) fill the waves' 24-bit photon index ([`MAX_BATCH_PHOTONS`]). On a GPU of 32 GB or
/// more, exact transport then runs level 6 (13.2M photons on the sphere) in one batch.
pub fn auto_photon_budget_mib(info: &crate::vk::DeviceInfo, binding_limit: u64) -> f64 {
    let small = info.is_cpu() || binding_limit < 512 << 20;
    let mib = if small { 64.0 } else { ((info.device_local_bytes >> 20) as f64 / 64.0).clamp(64.0, 512.0) };
    mib.min(max_budget_mib(binding_limit))
}

/// Photons one exact-transport batch may hold: a ray names its photon by a 24-bit index (glsl/wave.comp).
pub const MAX_BATCH_PHOTONS: u32 = 1 << 24;

/// Largest photon budget for a binding limit: the splat records (16 bytes per 8-byte photon entry) must fit one
/// binding. 64 MiB under lavapipe's 128 MiB.
pub fn max_budget_mib(binding_limit: u64) -> f64 {
    (binding_limit / 2) as f64 / (1024.0 * 1024.0)
}

/// The debug photon dump (48 bytes per photon) must fit one 128 MiB storage-buffer binding.
pub const MAX_DEBUG_PHOTONS: u32 = 2_000_000;

/// Max-error's first checked level, and flux-error's up to `--level` - 1 ([`Settings::check_level`]).
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

pub const TRAVERSE_WG_SWEEP: [u32; 5] = [1, 2, 4, 8, 16];
/// The traversal work-group side built with cooperative checks (build.rs: `traverse.comp` `*_coop`).
pub const COOP_WG: u32 = 8;

impl Settings {
    pub fn validate(&self) -> AppResult<()> {
        let bad = |m: String| Err(AppError::BadInput(m));
        if self.level >= MAX_LEVELS {
            return bad(format!("--level {}: must be at most {}", self.level, MAX_LEVELS - 1));
        }
        if !self.gbuffer_res.is_power_of_two() || self.gbuffer_res < LEVEL0_RES || self.gbuffer_res > 8192 {
            return bad(format!("--gbuffer-res {}: must be a power of two in 64..=8192", self.gbuffer_res));
        }
        if self.gbuffer_res.trailing_zeros() - LEVEL0_RES.trailing_zeros() >= MAX_PYRAMID_MIPS {
            return bad(format!("--gbuffer-res {}: too many pyramid levels", self.gbuffer_res));
        }
        if self.caustic_res < 16 || self.caustic_res > 8192 {
            return bad(format!("--caustic-res {}: must lie in 16..=8192", self.caustic_res));
        }
        if !(self.photon_budget_mib.is_finite() && self.photon_budget_mib >= 0.0) {
            return bad(format!("--photon-budget {}: must be > 0 MiB (or 0: automatic)", self.photon_budget_mib));
        }
        if !(self.error_bound.is_finite() && self.error_bound > 0.0) {
            return bad(format!("--error-bound {}: must be > 0 texels", self.error_bound));
        }
        if !(self.target_error.is_finite() && self.target_error > 0.0 && self.target_error <= 1.0) {
            return bad(format!(
                "--target-error {}: must lie in (0, 1] (the relative L1 at 64² that merging may add)",
                self.target_error
            ));
        }
        if let Some(tau) = self.tau {
            if !(tau.is_finite() && tau > 0.0 && tau <= crate::calibration::TAU_MAX) {
                return bad(format!("--tau {tau}: must lie in (0, {}]", crate::calibration::TAU_MAX));
            }
        }
        if !(self.exposure_ev.is_finite() && self.exposure_ev.abs() <= 32.0) {
            return bad(format!("--exposure {}: must lie in [-32, 32] stops", self.exposure_ev));
        }
        if !(1..=MAX_AA).contains(&self.aa) {
            return bad(format!("--aa {}: must lie in 1..={MAX_AA}", self.aa));
        }
        if let Some(sky) = self.sky {
            if !(sky.is_finite() && sky >= 0.0) {
                return bad(format!("--sky {sky}: must be a radiance >= 0 W/(m²·sr)"));
            }
        }
        if !(1..=MAX_EYE_DEPTH).contains(&self.eye_depth) {
            return bad(format!("--eye-depth {}: must lie in 1..={MAX_EYE_DEPTH}", self.eye_depth));
        }
        if !(self.flux_threshold.is_finite() && (0.0..1.0).contains(&self.flux_threshold)) {
            return bad(format!("--flux-threshold {}: must lie in [0, 1)", self.flux_threshold));
        }
        if !(self.weak_branches.is_finite() && (0.0..1.0).contains(&self.weak_branches)) {
            return bad(format!("--weak-branches {}: must lie in [0, 1)", self.weak_branches));
        }
        if ![0, 2, 4].contains(&self.weak_block) {
            return bad(format!("--weak-block {}: must be 2, 4 or 0 (automatic)", self.weak_block));
        }
        if !TRAVERSE_WG_SWEEP.contains(&self.traverse_wg) {
            return bad(format!("--traverse-wg {}: must be one of 1, 2, 4, 8, 16", self.traverse_wg));
        }
        if self.debug_photons > MAX_DEBUG_PHOTONS {
            return bad(format!("--debug-photons {}: at most {MAX_DEBUG_PHOTONS}", self.debug_photons));
        }
        if self.batch_slots > MAX_BATCHES {
            return bad(format!("--batch-slots {}: at most {MAX_BATCHES}", self.batch_slots));
        }
        Ok(())
    }

    /// Whether traversal runs the cooperative checks: `--coop-checks on` (or `auto` on a GPU), exact transport,
    /// max-error or flux-error, and work groups of 8x8 (the one side built with four lanes per candidate: 16
    /// candidates a group).
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

    /// Fit the settings to the device: its binding limit, the BVH layout and the cooperative checks when `auto`,
    /// and the photon budget when automatic (0). A budget larger than the device's bindings allow is bad input.
    pub fn resolve_for_device(&mut self, info: &crate::vk::DeviceInfo) -> AppResult<()> {
        self.binding_limit = (info.limits.max_storage_buffer_range as u64).min(2 << 30);
        self.bvh_layout = self.bvh_layout.resolve(info);
        self.coop_checks = self.coop_checks.resolve(info);
        if self.photon_budget_mib == 0.0 {
            self.photon_budget_mib = auto_photon_budget_mib(info, self.binding_limit);
        }
        let max = max_budget_mib(self.binding_limit);
        if self.photon_budget_mib > max {
            return Err(AppError::BadInput(format!(
                "--photon-budget {}: at most {max} MiB on {} (the splat records, 16 bytes per 8-byte photon entry, \
                 must fit one storage-buffer binding of {} MiB: its maxStorageBufferRange)",
                self.photon_budget_mib,
                info.name,
                self.binding_limit >> 20
            )));
        }
        Ok(())
    }

    /// The flux-error metric's per-cell threshold tau: `--tau` if given, else the one the calibration table maps
    /// `--target-error` to.
    pub fn tau(&self) -> f32 {
        self.tau.unwrap_or_else(|| crate::calibration::tau_for_target_error(self.target_error))
    }

    /// The first level checked for convergence: `--check-level` if given, else level 3 (Wyman & Nichols' 512²
    /// level), and under flux-error at most `--level` - 1, so that the metric acts at every level from 1 on (with
    /// the check level at `--level` or above it would emit max-level's photons and pay for a traversal; at level 3,
    /// check level 2 reaches dense's error on the sphere 9% faster and 0.87% in 27% less time on lavapipe,
    /// docs/bench/llvmpipe-llvm-15-0-6-256-bits/speed_error_exact_levels3-5.md).
    pub fn check_level(&self) -> u32 {
        self.check_level.unwrap_or(match self.metric {
            Metric::FluxError => DEFAULT_CHECK_LEVEL.min(self.level.saturating_sub(1)),
            _ => DEFAULT_CHECK_LEVEL,
        })
    }

    /// Exact transport's weak-branch block side, in cells of the maximal level (docs/design.md step 4):
    /// `--weak-block` if given, else 4. A block's turns follow its cells, not its photons, so every method shares
    /// the same blocks.
    pub fn weak_block(&self) -> u32 {
        match self.weak_block {
            0 => 4,
            b => b,
        }
    }

    /// The photon budget in MiB: an automatic one (0) not resolved for a device yet counts as 64.
    pub fn photon_budget(&self) -> f64 {
        if self.photon_budget_mib == 0.0 {
            64f64.min(max_budget_mib(self.binding_limit))
        } else {
            self.photon_budget_mib
        }
    }

    /// Photon-buffer entries (8 bytes each). Each has a 16-byte splat record, and that buffer must stay within one
    /// binding (`binding_limit`; 8 Mi entries under lavapipe's 128 MiB).
    pub fn photon_capacity(&self) -> u32 {
        let max = (self.binding_limit / 16).min(u32::MAX as u64 / 2) as u32;
        (((self.photon_budget() * 1024.0 * 1024.0) / 8.0).floor().max(8.0) as u32).min(max)
    }

    /// Exact transport: rays per queue (32 bytes each, 80 with ray differentials; two queues; each within one
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
        16 * self.footprint.ray_vec4s()
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
pub fn parse_size(s: &str, flag: &str) -> AppResult<(u32, u32)> {
    let bad =
        || AppError::BadInput(format!("{flag} `{s}`: expected WxH with 1 <= W, H <= 16384 (for example 512x512)"));
    let (w, h) = s.trim().split_once(['x', 'X']).ok_or_else(bad)?;
    let w: u32 = w.trim().parse().map_err(|_| bad())?;
    let h: u32 = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(bad());
    }
    Ok((w, h))
}

#[cfg(test)]
mod tests {
    use super::*;
    use ash::vk as avk;

    fn device(kind: avk::PhysicalDeviceType, gib: u64) -> crate::vk::DeviceInfo {
        crate::vk::DeviceInfo {
            name: "test".into(),
            driver: "test".into(),
            kind,
            api_version: 0,
            limits: avk::PhysicalDeviceLimits { max_storage_buffer_range: u32::MAX, ..Default::default() },
            timestamp_period: 1.0,
            timestamp_valid_bits: 64,
            float_atomic_add: true,
            device_local_bytes: gib << 30,
        }
    }

    #[test]
    fn the_automatic_budget_follows_device_memory_and_a_batch_fits_the_photon_index() {
        let gpu = avk::PhysicalDeviceType::DISCRETE_GPU;
        let binding = 2u64 << 30;
        assert_eq!(auto_photon_budget_mib(&device(gpu, 141), binding), 512.0);
        assert_eq!(auto_photon_budget_mib(&device(gpu, 16), binding), 256.0);
        assert_eq!(auto_photon_budget_mib(&device(gpu, 2), binding), 64.0);
        assert_eq!(auto_photon_budget_mib(&device(avk::PhysicalDeviceType::CPU, 64), binding), 64.0);
        assert_eq!(auto_photon_budget_mib(&device(gpu, 141), LAVAPIPE_BINDING_LIMIT), 64.0);
        // The automatic budget on a large GPU, and the largest a 2 GiB binding allows: a batch never holds more
        // photons than the rays' 24-bit index names.
        for (mib, batch) in [(512.0, MAX_BATCH_PHOTONS), (1024.0, MAX_BATCH_PHOTONS), (256.0, 1 << 23)] {
            let s = Settings { photon_budget_mib: mib, binding_limit: binding, ..Settings::default() };
            let t = s.batch_photons(s.photon_capacity());
            assert_eq!(t, batch, "{mib} MiB");
            assert!(t <= s.ray_queue_capacity() / 2, "{mib} MiB");
        }
    }
}
