//! The GPU structs, each defined once, here: build.rs writes them into the shaders' `generated/gpu_structs.glsl`
//! (with these doc comments), and asserts every field's offset in Rust (`gpu_layout.rs`, included below) and in
//! each compiled shader's SPIR-V, whether it reads the struct as std140 or std430.

use crate::shaders::consts::*;
use bytemuck::{Pod, Zeroable};
use std::mem::size_of;

/// A view from a point (perspective: spot light, perspective camera) or along a direction (orthographic:
/// directional light, orthographic camera). See src/scene/view.rs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuView {
    /// World to clip.
    pub view_proj: [f32; 16],
    /// xyz; w: 0 perspective, 1 orthographic.
    pub origin: [f32; 4],
    /// xyz; w: cosine of the spot cone (-1: no cone).
    pub right: [f32; 4],
    /// xyz; w: near.
    pub down: [f32; 4],
    /// xyz; w: far.
    pub forward: [f32; 4],
    /// Image-plane window: x0, y0, width, height.
    pub window: [f32; 4],
    /// Texels: width, height, 1/width, 1/height.
    pub extent: [f32; 4],
}

/// The frame's part of the uniforms, the same in every pass: the eye, the scene, the targets, and the settings of
/// the photons, transport and eye view.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameUniforms {
    /// The eye.
    pub camera: GpuView,
    /// The scene's bounds.
    pub scene_min: [f32; 3],
    /// The refractors' bounding diameter (m).
    pub refractor_diameter: f32,
    pub scene_max: [f32; 3],
    /// Exposure: 1 / the reference radiance, times 2^EV.
    pub exposure: f32,
    /// Start of each coverage mip in the coverage buffer.
    pub pyramid: [[u32; 4]; (MAX_PYRAMID_MIPS / 4) as usize],
    /// The refractor g-buffers' side R, log2(R/64), and the caustic map's side M.
    pub gbuffer_res: u32,
    pub gbuffer_level: u32,
    pub caustic_res: u32,
    /// The traversal: its deepest level (its metric is compiled into its pipeline, `Metric::code`), whether an
    /// overflowing batch splits (1) or drops its work (0), the first level checked for convergence, and the
    /// photons one batch may emit (`Settings::batch_photons`).
    pub max_level: u32,
    pub batching: u32,
    pub check_level: u32,
    pub batch_photons: u32,
    /// 1 for exact transport, 0 for two-interface; rays per queue; splat records per batch.
    pub exact: u32,
    pub queue_rays: u32,
    pub record_capacity: u32,
    /// 1: differential footprints (rays carry their differentials: 3 vec4s each, else 2).
    pub differential: u32,
    /// Max-error's bound (caustic-map texels), the shadow bias (texels), exact transport's flux threshold
    /// (relative to the photon's), flux-error's per-cell threshold tau (`Settings::tau`).
    pub error_bound: f32,
    pub shadow_bias: f32,
    pub flux_threshold: f32,
    pub tau: f32,
    /// The eye rays' depth cap (interfaces).
    pub eye_depth: f32,
    /// 1 when some glass disperses (the eye view traces each color channel with its own IOR), else 0.
    pub disperses: f32,
    /// 1 when the scene has an environment map, else 0.
    pub environment: f32,
    /// The index of refraction every refractor shares (-1: all mirrors), 0 when they differ: then the light and
    /// eye views draw it per texel into their IOR buffers.
    pub shared_ior: f32,
    /// Exact transport's weak-branch fraction (0: off), and the weak-branch block's side in cells.
    pub weak_fraction: f32,
    pub weak_block: f32,
    /// 1: the eye deposit is on: a landing the light's caustic map cannot hold is deposited in the eye's image
    /// where the camera sees it (docs/design.md "The eye deposit").
    pub eye_deposit: u32,
    /// Progressive accumulation (docs/design.md "Frames that build on each other"): the index of this frame's
    /// photon set among those the caustic maps average (0: a new average, whose photons leave their cells'
    /// centers; k > 0 shifts every cell's sample by the k-th point of a low-discrepancy sequence). Its weight in
    /// the average is 1 / (k + 1) ([`FrameUniforms::set_weight`]).
    pub sample_index: u32,
    /// What the flux-error metric measures its error in: REFINE_LIGHT (the light's caustic map) or REFINE_CAMERA
    /// (the camera's image; `Refine::code`).
    pub refine: u32,
}

impl FrameUniforms {
    /// The weight of this frame's photon set in a progressive accumulation's average, 1 / (k + 1): the resolve
    /// blends the set's irradiance with it, and the eye deposit's lookup reads the sets' summed flux as their mean
    /// (glsl/common/deposit_eye.glsl computes the same).
    pub fn set_weight(&self) -> f32 {
        1.0 / (self.sample_index + 1) as f32
    }
}

/// A light's part of the uniforms: its views, its power, and its color as a spectrum.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct LightUniforms {
    /// The light's view fitted to the refractors: the photon grid and the refractor g-buffers.
    pub photon_view: GpuView,
    /// The light's view over the receivers: the caustic map, the receiver g-buffer and the shadow map.
    pub receiver_view: GpuView,
    /// I·color, W/sr (W/m² for directional lights).
    pub light_power: [f32; 3],
    /// The intensity I, W/sr (W/m²).
    pub light_intensity: f32,
    /// The light's color as a spectrum for photons that carry a wavelength: its `RgbSpectrum` coefficients (the
    /// scale is twice its color's largest channel), or zeros. Scalars: std140 would align an array to 16 bytes.
    pub light_spectrum_c0: f32,
    pub light_spectrum_c1: f32,
    pub light_spectrum_c2: f32,
    /// A light with size (glsl/common/emitter.glsl): the tangent of the angular radius it shows the glass (a sun's
    /// own; a sphere light's radius over its distance; 0: a point or parallel rays), and the distance from its
    /// view's origin, along its rays, at which each cell's rays cross the cell (the glass's middle).
    pub beam_spread: f32,
    pub beam_pivot: f32,
    /// A sphere light's radius, m (0: a point).
    pub light_radius: f32,
    /// To a multiple of 16 bytes, as std140 places the struct (scalars: std140 aligns an array to 16 bytes).
    pub pad1: u32,
    pub pad2: u32,
}

/// A pass's part of the uniforms: what differs between the passes of one light.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct PassUniforms {
    /// The pass's color channel: 0 one gray pass; 1, 2, 3: red, green, blue; `CHANNEL_RGB`, `CHANNEL_SPECTRAL`:
    /// photons that carry their color, or their wavelength.
    pub channel: u32,
    /// The environment's sky radiance, W/(m²·sr) (0: off, and on every pass but the first light's).
    pub sky: f32,
    /// To a multiple of 16 bytes, as std140 places the struct.
    pub pad: [u32; 2],
}

/// What every pass of a frame reads (a uniform buffer, std140): the frame's part, the pass's light's, and the
/// pass's own.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FrameData {
    /// The same in every pass of the frame.
    pub frame: FrameUniforms,
    /// The pass's light.
    pub light: LightUniforms,
    /// The pass's own.
    pub pass: PassUniforms,
}

/// One traversal level's counts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable, PartialEq, Eq, serde::Serialize)]
pub struct LevelCounters {
    /// Cells of the level that were candidates.
    pub candidates: u32,
    /// Candidates refined into their four children.
    pub refined: u32,
    /// Photons emitted at the level.
    pub emitted: u32,
    /// Candidates dropped (covering no refractor).
    pub dropped: u32,
    /// Max-error and flux-error: candidates refined without a check, predicted by their parent's.
    pub checks_skipped: u32,
    /// From the check level on: candidates not checked because they are only partly covered or reach outside
    /// the cone.
    pub unchecked: u32,
}

/// Traversal state, read and written by init, traverse and stats (Piao's shared command buffer), extended with a
/// tile stack for batching: a batch traverses one tile (a block of level-0 cells, or one cell of a deeper level).
/// If the batch would overflow the photon buffer it is aborted and its tile split into four, so the committed
/// batches partition the photons exactly and a tiny budget gives the same image as a large one.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct TraversalState {
    /// Where the current level's candidates start in the photon buffer.
    pub read_offset: u32,
    /// Candidates of the current level.
    pub read_count: u32,
    /// Candidates appended for the next level.
    pub write_count: u32,
    /// Photons emitted so far in the batch.
    pub emit_count: u32,
    /// Photon-buffer entries in use.
    pub used: u32,
    /// Photon-buffer entries in all.
    pub capacity: u32,
    /// The level the current batch's tile starts at (MAX_LEVELS: no tile left).
    pub start_level: u32,
    /// Whether the current batch overflowed and was aborted.
    pub aborted: u32,
    /// Whether batching splits overflowing tiles (else their work is dropped and counted).
    pub batching: u32,
    /// Tiles pending on the GPU's stack.
    pub stack_size: u32,
    /// Batches committed this frame.
    pub batches_committed: u32,
    /// Batches aborted (their tile split into four) this frame.
    pub batches_aborted: u32,
    /// Entries dropped without batching.
    pub overflow_dropped: u32,
    /// The most photon-buffer entries in use at once.
    pub peak_used: u32,
    /// Photons emitted this frame.
    pub photons_total: u32,
    /// Batch slots the frame used.
    pub slots_used: u32,
    /// The current batch's tile: (t, x, y, -); t < 0: a 2^-t block of level-0 cells; t >= 0: a cell of level t.
    pub tile: [i32; 4],
    /// The current batch's per-level counters.
    pub batch_levels: [LevelCounters; MAX_LEVELS as usize],
    /// The frame's per-level counters.
    pub levels: [LevelCounters; MAX_LEVELS as usize],
    /// The GPU's tile stack.
    pub stack: [[i32; 4]; TILE_STACK as usize],
}

/// Energy-account terms of exact transport (`ACC_*` in src/shader_consts.rs), in order.
/// `caustics_one_interaction` is the part of `caustics` with exactly one interaction (for a closed mesh: a single
/// external reflection); it is not a term of the partition. The last two are the weak branches
/// (`--weak-branches`): `weak_left`, the flux photons left to the sibling that carries their block's weak branches,
/// and `weak_carried`, the extra flux those carriers took on. The account closes as
/// `emitted + weak_carried = caustics + direct + escaped + cut_threshold + cut_cap + lost + overflow + absorbed +
/// weak_left + unseen` ([`TransportState::residual`]); `unseen` is caustic light the caustic map cannot hold
/// (`ACC_UNSEEN`).
pub const ACCOUNT_TERMS: [&str; ACC_TERMS as usize] = [
    "emitted",
    "caustics",
    "direct",
    "escaped",
    "cut_threshold",
    "cut_cap",
    "lost",
    "overflow",
    "absorbed",
    "caustics_one_interaction",
    "weak_left",
    "weak_carried",
    "unseen",
    "caustics_eye",
];

/// Exact transport (docs/design.md step 4, `--transport exact`): the state of the waves of one batch and the
/// energy account. Wave k traces ray queue k & 1 (wave 0: the batch's emitted photons) and appends the children
/// to queue (k + 1) & 1 with atomicAdd; the transport shader turns out_count into the next wave's dispatch
/// arguments. Account terms are flux / light intensity (sr for spot lights, m² for directional ones) in 64-bit
/// fixed point (2^ACCOUNT_SHIFT units per 1), added as (lo, hi) word pairs with a carry, so the sums are exact
/// and repeatable. The terms' indices (`ACC_EMITTED` ... `ACC_UNSEEN`, `ACC_TERMS`) are constants of
/// src/shader_consts.rs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TransportState {
    /// Rays of the wave being traced (wave 0: the emitted photons).
    pub in_count: u32,
    /// Rays appended for the next wave.
    pub out_count: u32,
    /// Reservations of the next wave's queue (failed ones roll back).
    pub out_reserved: u32,
    /// Splat records appended this batch.
    pub records: u32,
    /// Reservations of splat records.
    pub records_reserved: u32,
    /// Rays per queue.
    pub queue_capacity: u32,
    /// Splat records per batch.
    pub record_capacity: u32,
    /// Reservations that did not fit (this frame).
    pub overflows: u32,
    /// Rays traced this frame.
    pub rays_traced: u32,
    /// Splat records drawn this frame.
    pub records_total: u32,
    /// Waves that traced at least one ray this frame.
    pub waves: u32,
    /// The most specular interactions of a deposited path this frame.
    pub max_depth: u32,
    /// The current batch's energy account (fixed point, `(lo, hi)` words per term).
    pub batch_account: [[u32; 2]; ACC_TERMS as usize],
    /// The frame's energy account (fixed point, `(lo, hi)` words per term; see [`TransportState::account`]).
    pub account: [[u32; 2]; ACC_TERMS as usize],
    /// Rays each wave traced this frame, in pairs ([`TransportState::wave_rays`] flattens them: waves 0 to
    /// MAX_INTERACTIONS, then a pad), because bytemuck and Default stop at 32-element arrays.
    pub wave_rays_pairs: [[u32; 2]; (MAX_INTERACTIONS as usize + 2) / 2],
}

impl TransportState {
    /// Rays each wave traced this frame (index: the wave; 0: the photons' primary rays), up to the last wave that
    /// traced any. They sum to `rays_traced`.
    pub fn wave_rays(&self) -> Vec<u32> {
        let mut rays: Vec<u32> =
            self.wave_rays_pairs.iter().flatten().copied().take(MAX_INTERACTIONS as usize + 1).collect();
        let live = rays.iter().rposition(|&n| n > 0).map_or(0, |i| i + 1);
        rays.truncate(live);
        rays
    }

    /// The frame's energy account, in units of the light's intensity (sr, or m² for directional lights).
    pub fn account(&self) -> [f64; ACC_TERMS as usize] {
        self.account.map(|[lo, hi]| ((hi as u64) << 32 | lo as u64) as f64 / (1u64 << ACCOUNT_SHIFT) as f64)
    }

    /// The account in W (`intensity`: the light's, W/sr or W/m²), one `<term>_w` key per term.
    pub fn energy_json(&self, intensity: f64) -> serde_json::Map<String, serde_json::Value> {
        ACCOUNT_TERMS.iter().zip(self.account()).map(|(n, x)| (format!("{n}_w"), (x * intensity).into())).collect()
    }

    /// [`Self::energy_json`] with the `residual` key: the account as the stats report it.
    pub fn account_json(&self, intensity: f64) -> serde_json::Map<String, serde_json::Value> {
        let mut account = self.energy_json(intensity);
        account.insert("residual".into(), self.residual().into());
        account
    }

    /// |emitted + weak_carried − every destination| / emitted: how far the account is from closing (0 when
    /// nothing was emitted).
    pub fn residual(&self) -> f64 {
        let a = self.account();
        // Terms 1..=8, weak_left and unseen partition what came in; one-interaction is a part of `caustics`.
        let term = |k: u32| a[k as usize];
        let input = term(ACC_EMITTED) + term(ACC_WEAK_CARRIED);
        let out: f64 = (ACC_CAUSTIC..=ACC_ABSORBED).map(term).sum::<f64>() + term(ACC_WEAK_LEFT) + term(ACC_UNSEEN);
        if term(ACC_EMITTED) > 0.0 {
            (input - out).abs() / term(ACC_EMITTED)
        } else {
            (input - out).abs()
        }
    }
}

/// A ray of exact transport in a queue (glsl/wave.comp). A queue entry is this ray, RAY_VEC4S_CELL words, then the
/// parts the frame's settings add, in order: the packed ray differentials (one word, `--footprint differential`).
/// A part that a frame does not need is not in its entries, so a ray costs only what its scene uses. The entries
/// are read as texels on CPU drivers, so the ray travels as words (build/structs.rs, WORD_STRUCTS).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRay {
    /// Where it starts (m, world space).
    pub origin: [f32; 3],
    /// Its flux over its photon's.
    pub throughput: f32,
    /// Its unit direction.
    pub dir: [f32; 3],
    /// Its photon's entry, counted from the photon buffer's top (the low PHOTON_INDEX_BITS); its interactions so
    /// far (the 6 bits above); bit 31: a weak branch carried for its photon's block (LOD_RAY, glsl/wave.comp).
    pub meta: u32,
}

/// The medium part of a queue entry, after the ray (and its differentials), when the scene has absorbing or
/// overlapping media (`Scene::has_media`, RAY_VEC4S_MEDIUM more words): which medium the ray travels in, so that
/// absorption follows it to whatever it meets, a receiver standing in a liquid included, and which volumes it is
/// inside, so that where volumes overlap the higher priority's medium is the one there (docs/design.md "Media").
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuRayMedium {
    /// The volumes with a priority it is inside: up to MAX_NESTED instances + 1 in 16-bit slots (0: empty).
    pub inside: [u32; 2],
    /// The ray's color where the photons carry theirs (`WAVE_COLOR`; else 0): its weight's red and green shares
    /// as two unorm16 (low, high) of three times the mean, which the throughput holds; blue is the rest
    /// (`tint_unpack`, glsl/common/interface.glsl). Splat records carry theirs the same way.
    pub tint: u32,
    /// 0: air; else the dielectric instance + 1 whose medium it is in (glsl/common/interface.glsl).
    pub medium: u32,
}

/// A splat record: where one photon path lands on a receiver, and what it deposits there (glsl/splat.comp,
/// glsl/splat.vert). One per emitted photon in the two-interface model (the same index), appended per record in
/// exact transport.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuSplat {
    /// Its center, caustic-map texels.
    pub texel: [f32; 2],
    /// Its flux (W, before the light's color).
    pub flux: f32,
    /// Its tent, packed (splat_pack, glsl/common/photon_bindings.glsl); 0: the photon did not land.
    pub shape: f32,
}

const _: () = assert!(size_of::<GpuRay>() == 16 * RAY_VEC4S_CELL as usize);
const _: () = assert!(RAY_VEC4S_DIFFERENTIAL == RAY_VEC4S_CELL + 1);
const _: () = assert!(size_of::<GpuRayMedium>() == 16 * RAY_VEC4S_MEDIUM as usize);

// Push constants of the photon passes: one struct per pass, each field with one meaning. The pipelines of the
// photon passes share one layout, whose push range is the largest of these (PHOTON_PUSH_BYTES).

/// Push constants of glsl/init.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct InitPush {
    /// INIT_FRAME, INIT_BATCH or INIT_DENSE (src/shader_consts.rs).
    pub mode: u32,
    /// The traversal work-group side the first level's dispatch arguments are computed for.
    pub wg_side: u32,
}

/// Push constants of glsl/traverse.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TraversePush {
    /// The level traversed.
    pub level: u32,
    /// The work-group side of the dispatch.
    pub wg_side: u32,
}

/// Push constants of glsl/stats.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct StatsPush {
    /// The level just traversed (or the dense level).
    pub level: u32,
    /// STATS_LEVEL, STATS_COMMIT or STATS_DENSE (src/shader_consts.rs).
    pub mode: u32,
    /// The work-group side the next level's dispatch arguments are computed for.
    pub wg_side: u32,
}

/// Push constants of glsl/dense_emit.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct DenseEmitPush {
    /// The dense level.
    pub level: u32,
    /// The first row of this band.
    pub row0: u32,
    /// The rows in this band.
    pub rows: u32,
}

/// Push constants of glsl/trace.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TracePush {
    /// 1: dump the traced photons into the debug buffer.
    pub debug: u32,
    /// Dump only photons at this level or deeper.
    pub debug_min_level: u32,
}

/// Push constants of glsl/transport.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct TransportPush {
    /// TRANSPORT_BEGIN_DENSE, TRANSPORT_BEGIN_ADAPTIVE, TRANSPORT_AFTER_WAVE or TRANSPORT_COMMIT
    /// (src/shader_consts.rs).
    pub mode: u32,
    /// 1: the batch may abort (adaptive traversal with batching).
    pub may_abort: u32,
    /// After a wave: the index of the wave it prepares (its rays count to that wave's).
    pub next_wave: u32,
}

/// Push constants of glsl/wave.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WavePush {
    /// 1: the batch may abort (adaptive traversal with batching).
    pub may_abort: u32,
}

/// A vertex's position and normal, w unused: a morphing mesh's base vertices and its targets' displacements
/// (`SceneBuffers::morphs`, glsl/morph.comp), and water's vertices displaced to the frame's time
/// (`SceneBuffers::displaced`, glsl/water.comp), in object space.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuPointNormal {
    pub position: [f32; 4],
    pub normal: [f32; 4],
}

/// A record of `SceneBuffers::waves` (glsl/water.comp). A wave: `a` = (direction x, direction z, k, ω), `b` =
/// (amplitude, 0, 0, 0). After a simulated surface's waves, the surface's record: `a` = (its nodes a side as the
/// float's bits, 1 / 2Δx, 1 / 2Δz, 0), `b` zero.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuWaveRecord {
    pub a: [f32; 4],
    pub b: [f32; 4],
}

/// One command of the indirect-command buffer (`PhotonBindings::indirect`, glsl/common/photon_bindings.glsl): a
/// dispatch's group counts (x, y, z, unused) or a draw's (vertexCount, instanceCount, firstVertex, firstInstance).
/// Its slots are the INDIRECT_* constants of src/shader_consts.rs.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct IndirectCommand {
    pub args: [u32; 4],
}

/// One photon of the two-interface trace's debug dump (`Tuning::debug_photons`, glsl/trace.comp), after the dump's
/// 16-byte header (count, capacity).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GpuDebugPhoton {
    /// Its cell's column and row at its level.
    pub x: u32,
    pub y: u32,
    /// Its level (bits 0-7), status (8-15) and splat radius (16-31).
    pub level_status_radius: u32,
    /// Its flux's first channel.
    pub flux: f32,
    /// The cell center's light-view texture coordinates.
    pub uv: [f32; 2],
    /// Where it lands in the caustic map (texels).
    pub map_px: [f32; 2],
    /// Where it hit a receiver (xyz; w unused).
    pub hit: [f32; 4],
}

/// Push constants of glsl/resolve.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ResolvePush {
    /// The irradiance written is `keep` times what the map holds plus `scale` times the flux's: (0, 1) writes it;
    /// (1, w) adds the rest of a frame's batches (traced after the first submission ran out of batch slots);
    /// (k / (k + 1), 1 / (k + 1)) averages the k-th photon set of a progressive accumulation into the k before it.
    pub keep: f32,
    pub scale: f32,
}

/// Push constants of glsl/overlay.vert: the target's size in the overlay's points (its vertices' unit).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct OverlayPush {
    pub size: [f32; 2],
}

/// Push constants of glsl/eye_shade.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct ShadePush {
    /// 0: the first light (write), 1: a further light (add).
    pub add: u32,
}

/// Push constants of the composite and the glass pass (glsl/common/composite_bindings.glsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CompositePush {
    /// The glass pass: 1 when each invocation traces a pixel's 2×2 samples of dispersive glass (glsl/glass.comp,
    /// `glass_pixel`), dispatched over the pixels; 0: one sample an invocation.
    pub pixels: u32,
    /// The glass pass: 1 to add to what an earlier pass wrote (a scene with more than GLASS_LIGHTS lights; its
    /// number of lights is a specialization constant, `GlassKey::lights`).
    pub add: u32,
}

/// Push constants of glsl/splat_collapse.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SplatCollapsePush {
    /// The coarse level of the flux texels added into the level below it.
    pub level: u32,
}

/// Push constants of geometry.vert/.frag.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct GeometryPush {
    pub view_proj: [f32; 16],
    /// xyz; w: 0 perspective, 1 orthographic.
    pub origin: [f32; 4],
    /// xyz.
    pub forward: [f32; 4],
}

impl GeometryPush {
    pub fn from_view(v: &GpuView) -> Self {
        GeometryPush { view_proj: v.view_proj, origin: v.origin, forward: v.forward }
    }
}

/// Push constants of scene_update.comp: one object's transform and its ranges in the scene's buffers.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct SceneUpdatePush {
    /// Rows of world_from_object's 3x4 affine part.
    pub rows: [[f32; 4]; 3],
    /// Rows of the inverse transpose of its 3x3 part; `nrows[0][3]` is 1 when it mirrors.
    pub nrows: [[f32; 4]; 3],
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub index_count: u32,
}

/// Push constants of water.comp: one water object's displacement (the plain build: its vertices, in object space
/// and, placed, as raster vertices in world space; the BVH build: its BVH triangles, gathered from those vertices).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WaterPush {
    /// Rows of world_from_object's 3x4 affine part (the plain build).
    pub rows: [[f32; 4]; 3],
    /// Rows of the inverse transpose of its 3x3 part (the plain build).
    pub nrows: [[f32; 4]; 3],
    /// The scene's time, s.
    pub time: f32,
    /// 0 without a simulated surface, else 1 + the first float of its heights now in `SceneBuffers::heights`
    /// (nodes and spacing in the record after its waves).
    pub heights: u32,
    pub first_wave: u32,
    pub wave_count: u32,
    /// Its first vertex in `SceneBuffers::displaced`: written by the raster build, read by the BVH build.
    pub displaced: u32,
    /// First vertex (raster) or rest triangle (BVH) read, first vertex or BVH triangle written, and how many.
    pub src: u32,
    pub dst: u32,
    pub count: u32,
}

/// Push constants of water_step.comp: one step of a simulated water surface (`mode` WATER_STEP) or one drop into
/// it (WATER_DROP), over its nodes² nodes (src/scene/water.rs runs the same on the host). Its heights are two
/// slots of nodes² floats from `base` in `SceneBuffers::heights`; `slot` (0 or 1) holds the heights now, the other
/// those one step before, which the step overwrites with the next.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct WaterStepPush {
    pub base: u32,
    pub nodes: u32,
    pub mode: u32,
    pub slot: u32,
    /// 1 − γ Δt, (c Δt / Δx)², (c Δt / Δz)² and the largest |h| (m).
    pub keep: f32,
    pub cx: f32,
    pub cz: f32,
    pub limit: f32,
    /// The water's size in x and z and its depth, m.
    pub size_x: f32,
    pub size_z: f32,
    pub depth: f32,
    pub body_count: u32,
    /// WATER_DROP: (x, z, radius, depth), m.
    pub drop: [f32; 4],
    /// WATER_STEP: each body's sphere (center, radius) at the step's start, then at its end.
    pub bodies: [[f32; 4]; 4],
}

/// Push constants of morph.comp: one morphing object's vertices weighted by its morph targets (the plain build: its
/// raster vertices, to world space; the MORPH_BVH build: its BVH triangles, in object space, read through their
/// rest corners).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct MorphPush {
    /// Rows of world_from_object's 3x4 affine part (the plain build).
    pub rows: [[f32; 4]; 3],
    /// Rows of the inverse transpose of its 3x3 part (the plain build).
    pub nrows: [[f32; 4]; 3],
    /// Its base vertices in the morph data (targets follow, `vertices` apart), its vertex and target counts, and
    /// its first weight.
    pub first: u32,
    pub vertices: u32,
    pub targets: u32,
    pub first_weight: u32,
    /// First vertex (the plain build) or rest triangle (MORPH_BVH) read, first vertex or BVH triangle written, and
    /// how many.
    pub src: u32,
    pub dst: u32,
    pub count: u32,
}

/// Push constants of refit.comp: one height of a deforming mesh's nodes (`count` of them from `first` in the refit
/// order), and the binary layouts on the GPU it writes (REFIT_PAIR, REFIT_SINGLE, REFIT_THREADED bits).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct RefitPush {
    pub first: u32,
    pub count: u32,
    pub layouts: u32,
    pub pad: u32,
}

/// Push constants of coverage.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct CoveragePush {
    /// The mip to build (0 only with `COVERAGE_MIP0`).
    pub mip: u32,
    /// The start of mip - 1, and of the mip, in the coverage buffer.
    pub src_offset: u32,
    pub dst_offset: u32,
    /// The mip's side.
    pub dst_res: u32,
}

/// One vertex: position, normal, material (dielectric: x = IOR; diffuse: rgb = albedo; w = 1 for dielectrics).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Vertex {
    /// xyz; w: the texture coordinate u (after the material's uv transform).
    pub position: [f32; 4],
    /// xyz; w: the texture coordinate v.
    pub normal: [f32; 4],
    /// A receiver: rgb albedo (factor), w -(albedo texture layer + 1) or 0; a refractor: x IOR, w 1.
    pub material: [f32; 4],
}

include!(concat!(env!("OUT_DIR"), "/gpu_layout.rs"));

const _: () = {
    // Within the 128 bytes of push constants every device has.
    assert!(size_of::<SceneUpdatePush>() <= 128);
    assert!(size_of::<WaterPush>() <= 128);
    assert!(size_of::<WaterStepPush>() <= 128);
    assert!(size_of::<MorphPush>() <= 128);
    assert!(size_of::<GeometryPush>() <= 128);
    // `wave_rays_pairs` holds waves 0 to MAX_INTERACTIONS and a pad.
    assert!(MAX_INTERACTIONS.is_multiple_of(2));
};
