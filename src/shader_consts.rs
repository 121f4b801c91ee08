// Constants shared by Rust and GLSL. build.rs `include!`s this file and passes every constant to shaderc as a
// macro definition, so the two sides cannot drift. Keep it to plain `pub const NAME: u32 = value;` lines.

/// Side of the traversal work group (Piao's 8x8). The bench sweeps TRAVERSE_WG_SWEEP.
pub const TRAVERSE_WG: u32 = 8;
/// Side of the level-0 photon grid (Wyman's 64x64).
pub const LEVEL0_RES: u32 = 64;
/// Traversal levels 0..MAX_LEVELS (level 16 is a 4,194,304² grid). Cell x and y are packed in 24 bits.
pub const MAX_LEVELS: u32 = 17;
/// Work-group size of 1D compute passes.
pub const LINEAR_WG: u32 = 64;
/// Side of the work group of 2D image passes.
pub const TILE_WG: u32 = 8;
/// Largest splat radius in caustic-map texels (point size 2r must stay within lavapipe's 255).
pub const MAX_SPLAT_RADIUS: u32 = 64;
/// The eye deposit's widest tent radius, in eye samples: its records are few (the landings the light's caustic map
/// cannot hold), and their tents at most (2 EYE_SPLAT_RADIUS + 1)² taps.
pub const EYE_SPLAT_RADIUS: u32 = 8;
/// Side of the shared-memory window in which the tiled compute splat gathers a work group's taps.
pub const SPLAT_TILE: u32 = 32;
/// Differential footprints, compute splats: a tent wider than this many texels (either radius) is splatted at the
/// coarse level of the flux texels where it is at most this wide, so that its taps stay few whatever its width.
pub const SPLAT_FINE_RADIUS: u32 = 4;
/// Coarse levels of the flux texels (each half the one before a side): radii up to SPLAT_FINE_RADIUS·2^SPLAT_LEVELS.
pub const SPLAT_LEVELS: u32 = 4;
/// Mip levels kept in the coverage pyramid (covers refractor g-buffers up to 64·2^(MAX_PYRAMID_MIPS-1)).
pub const MAX_PYRAMID_MIPS: u32 = 12;
/// Largest number of photon batches recorded per frame.
pub const MAX_BATCHES: u32 = 4096;
/// Capacity of the GPU tile stack used by batching (depth-first: at most 3 per level, plus one).
pub const TILE_STACK: u32 = 96;
/// water_step.comp's modes: step a simulated water surface, or drop into it.
pub const WATER_STEP: u32 = 0;
/// See WATER_STEP.
pub const WATER_DROP: u32 = 1;
/// Exact transport: the most specular interactions a path may have before it is cut (the CPU reference's cap).
pub const MAX_INTERACTIONS: u32 = 32;
/// Exact transport: energy-account terms are fixed point with 2^ACCOUNT_SHIFT units per sr (or m²).
pub const ACCOUNT_SHIFT: u32 = 44;

// Exact transport's energy account: the index of each term in `TransportState.account` (src/gpu_types.rs
// ACCOUNT_TERMS names them in this order).
/// Photons that entered the transport.
pub const ACC_EMITTED: u32 = 0;
/// Reached a receiver after one or more specular interactions.
pub const ACC_CAUSTIC: u32 = 1;
/// Reached a receiver with none (direct light, counted by the direct AOV).
pub const ACC_DIRECT: u32 = 2;
/// Left the scene.
pub const ACC_ESCAPED: u32 = 3;
/// Children below the flux threshold.
pub const ACC_THRESHOLD: u32 = 4;
/// Met a dielectric after the interaction cap.
pub const ACC_CAP: u32 = 5;
/// Numerical dead ends (no valid direction on either normal).
pub const ACC_LOST: u32 = 6;
/// Did not fit a queue (only without batching: with it the batch is split instead).
pub const ACC_OVERFLOW: u32 = 7;
/// Absorbed inside glass (Beer–Lambert).
pub const ACC_ABSORBED: u32 = 8;
/// The part of ACC_CAUSTIC with exactly one interaction (not a term of the partition).
pub const ACC_ONE_EVENT: u32 = 9;
/// Weak branches a photon left to the sibling that carries its block's.
pub const ACC_WEAK_LEFT: u32 = 10;
/// The extra flux the weight carriers took on for their siblings (an input: emitted + carried = the outputs).
pub const ACC_WEAK_CARRIED: u32 = 11;
/// Reached a receiver after one or more specular interactions where the light's view sees another receiver (in
/// front of it, or behind it), or outside the light's view: the caustic map, which holds one receiver per texel,
/// cannot hold this light (the floor of a deep pool beside its wall, lit by refraction where the wall shades it
/// along the light's straight rays).
pub const ACC_UNSEEN: u32 = 12;
/// The part of ACC_CAUSTIC that the light's caustic map could not hold and the eye deposit took: landings on the
/// receivers the camera sees (docs/design.md "The eye deposit"; not a term of the partition).
pub const ACC_EYE: u32 = 13;
/// Terms of the account.
pub const ACC_TERMS: u32 = 14;

// The binary BVH layouts a refit writes (`RefitPush::layouts`, glsl/refit.comp): a bit per layout, bit k the layout
// in slot k of `BvhBuffers` (pair 0, single 1, threaded 2; the wide layout, slot 3, has refit_wide.comp).
/// The pair layout's nodes.
pub const REFIT_PAIR: u32 = 1;
/// The single-box layout's nodes.
pub const REFIT_SINGLE: u32 = 2;
/// The threaded layout's nodes.
pub const REFIT_THREADED: u32 = 4;

// glsl/splat.comp's SPLAT_COLOR (`CarriedColor::splat_code`): what a record carries of its color.
/// Gray records.
pub const SPLAT_GRAY: u32 = 0;
/// Records with an RGB tint (color photons, `splat_tints`).
pub const SPLAT_TINT: u32 = 1;
/// Records with a wavelength (spectral photons).
pub const SPLAT_WAVELENGTH: u32 = 2;

// The adaptive traversal's metrics (`Metric::code`; traverse.comp's TRAVERSE_METRIC takes one of the last two, and
// max-level's variant is TRAVERSE_MAX_LEVEL's).
/// `--metric max-level`.
pub const METRIC_MAX_LEVEL: u32 = 0;
/// `--metric max-error`.
pub const METRIC_MAX_ERROR: u32 = 1;
/// `--metric flux-error`.
pub const METRIC_FLUX_ERROR: u32 = 2;

// What the flux-error metric measures its error in (`Refine::code`, FrameUniforms::refine; traverse.comp).
/// `--refine light`: the light's caustic map.
pub const REFINE_LIGHT: u32 = 0;
/// `--refine camera`: the camera's image.
pub const REFINE_CAMERA: u32 = 1;

// The indirect-command buffer's slots (`IndirectCommand`, src/gpu_types.rs): one dispatch per traversal level
// (0..MAX_LEVELS), then these.
/// The two-interface trace's dispatch.
pub const INDIRECT_TRACE: u32 = MAX_LEVELS;
/// The raster splat's draw (vertexCount, instanceCount, firstVertex, firstInstance).
pub const INDIRECT_DRAW: u32 = MAX_LEVELS + 1;
/// Exact transport: the current wave's dispatch.
pub const INDIRECT_WAVE: u32 = MAX_LEVELS + 2;
/// The compute splat's dispatch over the draw's records.
pub const INDIRECT_SPLAT: u32 = MAX_LEVELS + 3;
/// Commands in the buffer.
pub const INDIRECT_COMMANDS: u32 = MAX_LEVELS + 4;

// Exact transport's rays.
/// vec4s per ray with the cell footprint: a `GpuRay` (src/gpu_types.rs).
pub const RAY_VEC4S_CELL: u32 = 2;
/// vec4s per ray with ray differentials: one more, dP/dx, dP/dy, dD/dx and dD/dy across the ray as half-float pairs
/// (`diff_pack`, glsl/common/transport.glsl).
pub const RAY_VEC4S_DIFFERENTIAL: u32 = 3;
/// vec4s a ray's medium adds, last in its entry, when the scene has absorbing or overlapping media: a
/// `GpuRayMedium`.
pub const RAY_VEC4S_MEDIUM: u32 = 1;
/// `PassUniforms::channel` of a pass whose photons carry their color (red, green and blue at once; glsl/wave.comp
/// `WAVE_COLOR`): 0 is one gray pass, 1-3 one channel each.
pub const CHANNEL_RGB: u32 = 4;
/// `PassUniforms::channel` of a pass of spectral photons (each a wavelength, its RGB deposited; glsl/wave.comp
/// `WAVE_SPECTRAL`).
pub const CHANNEL_SPECTRAL: u32 = 5;
/// The most volumes with a priority a ray can be inside at once (`GpuRayMedium::inside`): one more is not entered.
pub const MAX_NESTED: u32 = 4;
/// A ray's meta word holds its photon's index (counted from the photon buffer's top) in this many low bits, and
/// its interactions above them: a batch holds at most 2^PHOTON_INDEX_BITS photons.
pub const PHOTON_INDEX_BITS: u32 = 24;

// Binding indices of the photon passes' shared layout (glsl/common/photon_bindings.glsl, src/passes/photons.rs).
/// Binding: the frame uniforms.
pub const PB_FRAME: u32 = 0;
/// Binding: the traversal state.
pub const PB_STATE: u32 = 1;
/// Binding: the photon buffer.
pub const PB_PHOTONS: u32 = 2;
/// Binding: the indirect commands.
pub const PB_INDIRECT: u32 = 3;
/// Binding: the coverage pyramid.
pub const PB_COVERAGE: u32 = 4;
/// Binding: the refractors' front g-buffer.
pub const PB_FRONT: u32 = 5;
/// Binding: the front surface's IOR.
pub const PB_FRONT_AUX: u32 = 6;
/// Binding: the refractors' back g-buffer.
pub const PB_BACK: u32 = 7;
/// Binding: the receivers seen from the light.
pub const PB_RECEIVERS: u32 = 8;
/// Binding: the debug photon dump.
pub const PB_DEBUG: u32 = 9;
/// Binding: the splat records.
pub const PB_SPLATS: u32 = 10;
/// Binding: the transport state.
pub const PB_TRANSPORT: u32 = 11;
/// Binding: the ray queue a wave reads (the two queues swap bindings from wave to wave).
pub const PB_RAYS_IN: u32 = 12;
/// Binding: the ray queue a wave appends to.
pub const PB_RAYS_OUT: u32 = 13;
/// Binding: the BVH nodes (pair layout).
pub const PB_BVH_PAIR: u32 = 14;
/// Binding: the BVH triangles.
pub const PB_BVH_TRIS: u32 = 15;
/// Binding: the BVH vertex normals.
pub const PB_BVH_NORMALS: u32 = 16;
/// Binding: the BVH instances.
pub const PB_BVH_INSTANCES: u32 = 17;
/// Binding: the BVH nodes (single layout).
pub const PB_BVH_SINGLE: u32 = 18;
/// Binding: the flux map as texels (compute splat).
pub const PB_FLUX_TEXELS: u32 = 19;
/// Binding: the BVH nodes (threaded layout).
pub const PB_BVH_THREADED: u32 = 20;
/// Binding: the BVH nodes (wide layout).
pub const PB_BVH_WIDE: u32 = 21;
/// Binding: the wide layout's triangle list.
pub const PB_BVH_WIDE_PRIMS: u32 = 22;
/// Binding: each splat record's color (color photons, `GpuRayMedium::tint`'s encoding).
pub const PB_SPLAT_TINTS: u32 = 23;
/// Binding: the receivers seen from the eye (the eye deposit's visibility).
pub const PB_EYE: u32 = 24;
/// Binding: the eye deposit's flux, W per eye sample, three planes (red, green, blue).
pub const PB_EYE_FLUX: u32 = 25;
/// Bindings of the layout.
pub const PB_COUNT: u32 = 26;

// Binding indices of the composite and the glass pass (glsl/common/composite_bindings.glsl, src/passes/composite.rs).
/// Binding: the frame uniforms.
pub const CB_FRAME: u32 = 0;
/// Binding: the receivers' radiance.
pub const CB_RADIANCE: u32 = 1;
/// Binding: the refractors' front seen from the eye.
pub const CB_FRONT: u32 = 2;
/// Binding: its IOR.
pub const CB_FRONT_AUX: u32 = 3;
/// Binding: the refractors' back seen from the eye.
pub const CB_BACK: u32 = 4;
/// Binding: the radiance with linear filtering.
pub const CB_RADIANCE_LINEAR: u32 = 5;
/// Binding: the beauty image (written).
pub const CB_BEAUTY: u32 = 6;
/// Binding: the linear beauty image (written).
pub const CB_HDR: u32 = 7;
/// Binding: the shadow map.
pub const CB_SHADOW: u32 = 8;
/// Binding: the caustic irradiance map.
pub const CB_IRRADIANCE: u32 = 9;
/// Binding: the receivers seen from the light.
pub const CB_RECEIVERS: u32 = 10;
/// Binding: the BVH nodes (pair layout).
pub const CB_BVH_PAIR: u32 = 11;
/// Binding: the BVH triangles.
pub const CB_BVH_TRIS: u32 = 12;
/// Binding: the BVH vertex normals.
pub const CB_BVH_NORMALS: u32 = 13;
/// Binding: the BVH instances.
pub const CB_BVH_INSTANCES: u32 = 14;
/// Binding: the receivers' albedo textures (an array).
pub const CB_ALBEDO_TEXTURES: u32 = 15;
/// Binding: the environment map.
pub const CB_ENV: u32 = 16;
/// Binding: the environment's irradiance map.
pub const CB_ENV_IRRADIANCE: u32 = 17;
/// Binding: the glass's radiance per eye sample, under every light (exact transport).
pub const CB_GLASS: u32 = 18;
/// Bindings: the glass pass's second light (its uniforms, shadow map, caustic map, receivers), then its third,
/// four bindings further (its first light's are CB_FRAME, CB_SHADOW, CB_IRRADIANCE and CB_RECEIVERS). Three lights
/// a pass: lavapipe (Mesa 22.3) crashes on a layout of 31 push descriptors with a fourth; a fourth light takes a
/// second pass.
pub const CB_LIGHT1: u32 = 19;
/// See [`CB_LIGHT1`].
pub const CB_SHADOW1: u32 = 20;
/// See [`CB_LIGHT1`].
pub const CB_IRRADIANCE1: u32 = 21;
/// See [`CB_LIGHT1`].
pub const CB_RECEIVERS1: u32 = 22;
/// See [`CB_LIGHT1`].
pub const CB_LIGHT2: u32 = 23;
/// See [`CB_LIGHT1`].
pub const CB_SHADOW2: u32 = 24;
/// See [`CB_LIGHT1`].
pub const CB_IRRADIANCE2: u32 = 25;
/// See [`CB_LIGHT1`].
pub const CB_RECEIVERS2: u32 = 26;
/// Binding: the BVH nodes (wide layout; the glass pass traces it where the waves do).
pub const CB_BVH_WIDE: u32 = 27;
/// Binding: the wide layout's triangle list.
pub const CB_BVH_WIDE_PRIMS: u32 = 28;
/// Binding: the eye deposit's flux (the photon passes' `PB_EYE_FLUX`), which the glass pass reads where an eye ray
/// reaches a receiver that the eye's samples see.
pub const CB_EYE_FLUX: u32 = 29;
/// Bindings of the layout.
pub const CB_COUNT: u32 = 30;
/// Lights one glass pass shades with.
pub const GLASS_LIGHTS: u32 = 3;
/// A light view's `right.w` (GpuView) at or above this: the view is a face of a point light's cube, whose domain
/// is the square |x|, |y| <= 1 of its image plane (else `right.w` is the spot cone's cosine, or -1 for none).
pub const VIEW_SQUARE_DOMAIN: u32 = 2;
/// The emitter kinds (glsl/common/emitter.glsl, src/scene/view.rs `EmitterKind`): a directional light's parallel
/// beam,
pub const EMITTER_BEAM: u32 = 0;
/// a point light's rays over its whole window,
pub const EMITTER_OPEN: u32 = 1;
/// a spot light's cone,
pub const EMITTER_CONE: u32 = 2;
/// a face of a point light's cube.
pub const EMITTER_SQUARE: u32 = 3;

// Binding indices of the eye view's shading (glsl/eye_shade.comp, src/passes/eye.rs).
/// Binding: the frame uniforms.
pub const EB_FRAME: u32 = 0;
/// Binding: the shadow map.
pub const EB_SHADOW: u32 = 1;
/// Binding: the caustic irradiance map.
pub const EB_IRRADIANCE: u32 = 2;
/// Binding: the receivers seen from the light.
pub const EB_RECEIVERS: u32 = 3;
/// Binding: the receivers seen from the eye.
pub const EB_EYE: u32 = 4;
/// Binding: their albedo.
pub const EB_ALBEDO: u32 = 5;
/// Binding: the environment map.
pub const EB_ENV: u32 = 6;
/// Binding: the environment's irradiance map.
pub const EB_ENV_IRRADIANCE: u32 = 7;
/// Binding: the eye deposit's flux (the photon passes' `PB_EYE_FLUX`).
pub const EB_EYE_FLUX: u32 = 8;
/// Binding: the radiance (written).
pub const EB_RADIANCE: u32 = 9;
/// Binding: the caustics AOV (written).
pub const EB_CAUSTICS: u32 = 10;
/// Binding: the direct AOV (written).
pub const EB_DIRECT: u32 = 11;
/// Bindings of the layout.
pub const EB_COUNT: u32 = 12;

// Pass modes: what a pass's `mode` push constant selects (the passes push these; the shaders compare with them).
/// glsl/init.comp: frame start (clear the counters, push the root tile).
pub const INIT_FRAME: u32 = 0;
/// glsl/init.comp: batch start (pop a tile, write its level-0 candidates).
pub const INIT_BATCH: u32 = 1;
/// glsl/init.comp: a dense band.
pub const INIT_DENSE: u32 = 2;
/// glsl/stats.comp: after a traversal level.
pub const STATS_LEVEL: u32 = 0;
/// glsl/stats.comp: after the last level: commit the batch.
pub const STATS_COMMIT: u32 = 1;
/// glsl/stats.comp: a dense band's photons are all emitted.
pub const STATS_DENSE: u32 = 2;
/// glsl/transport.comp: begin a dense batch's waves.
pub const TRANSPORT_BEGIN_DENSE: u32 = 0;
/// glsl/transport.comp: begin an adaptive batch's waves (nothing when it has no tile or aborted).
pub const TRANSPORT_BEGIN_ADAPTIVE: u32 = 1;
/// glsl/transport.comp: after a wave: its appended children become the next wave.
pub const TRANSPORT_AFTER_WAVE: u32 = 2;
/// glsl/transport.comp: commit the batch.
pub const TRANSPORT_COMMIT: u32 = 3;

// Specialization constants: each GLSL `layout(constant_id = NAME_ID) const ... NAME` takes its ID from here, and
// the passes specialize it by the same constant; build.rs fails a shader whose constant NAME has no NAME_ID here
// or another ID.
/// glsl/wave.comp: wave 0, whose rays start at the photons' cells.
pub const WAVE_PRIMARY_ID: u32 = 0;
/// glsl/wave.comp: the rays carry ray differentials.
pub const WAVE_DIFFERENTIAL_ID: u32 = 1;
/// glsl/wave.comp: the most subgroups a work group can have (the bound of its loop over them).
pub const WAVE_SUBGROUPS_ID: u32 = 3;
/// glsl/glass.comp: the lights whose maps are bound (1-3).
pub const GLASS_LIGHT_COUNT_ID: u32 = 3;
/// glsl/glass.comp: some glass disperses.
pub const GLASS_DISPERSIVE_ID: u32 = 4;
/// glsl/glass.comp: an environment map.
pub const GLASS_ENVIRONMENT_ID: u32 = 5;
/// glsl/glass.comp: some receiver has an albedo texture.
pub const GLASS_TEXTURED_ID: u32 = 6;
/// glsl/wave.comp: the rays carry their medium (the scene has absorbing or overlapping media).
pub const WAVE_MEDIA_ID: u32 = 7;
/// glsl/glass.comp: the scene has absorbing or overlapping media.
pub const GLASS_MEDIA_ID: u32 = 7;
/// glsl/wave.comp: the rays carry their color (an RGB tint in their medium word), so that one pass takes a light's
/// photons through glass that absorbs colors unequally (docs/design.md "Color").
pub const WAVE_COLOR_ID: u32 = 8;
/// glsl/wave.comp: each photon traces one wavelength (some glass disperses; docs/design.md "Color").
pub const WAVE_SPECTRAL_ID: u32 = 9;
/// glsl/splat.comp: the records carry their color (1: an RGB tint, 2: a wavelength), and the flux texels hold three
/// planes (red, green, blue).
pub const SPLAT_COLOR_ID: u32 = 0;
/// glsl/resolve.comp: the same.
pub const RESOLVE_COLOR_ID: u32 = 0;
/// glsl/coverage.comp: the pass builds mip 0 from the g-buffers.
pub const COVERAGE_MIP0_ID: u32 = 0;

// Binding indices of the pipelines with a layout of their own. Each shader names its bindings by these constants and
// each pass binds by them (`ordered`, src/vk/pipeline.rs); the layout itself is reflected from the SPIR-V.
/// glsl/resolve.comp: the frame uniforms.
pub const RS_FRAME: u32 = 0;
/// glsl/resolve.comp: the flux (an image, or the compute splat's texels).
pub const RS_FLUX: u32 = 1;
/// glsl/resolve.comp: the light's receiver g-buffer.
pub const RS_RECEIVERS: u32 = 2;
/// glsl/resolve.comp: the caustic irradiance it writes.
pub const RS_IRRADIANCE: u32 = 3;
/// glsl/coverage.comp: the frame uniforms.
pub const CV_FRAME: u32 = 0;
/// glsl/coverage.comp: the coverage pyramid it writes.
pub const CV_COVERAGE: u32 = 1;
/// glsl/coverage.comp: the refractors' front g-buffer.
pub const CV_FRONT: u32 = 2;
/// glsl/coverage.comp: the light's receiver g-buffer.
pub const CV_RECEIVERS: u32 = 3;
/// glsl/morph.comp: the morph targets' records.
pub const MO_MORPHS: u32 = 0;
/// glsl/morph.comp: the targets' weights.
pub const MO_WEIGHTS: u32 = 1;
/// glsl/morph.comp (vertices): the object-space vertices.
pub const MO_OBJECT_VERTICES: u32 = 2;
/// glsl/morph.comp (vertices): the world-space vertices it writes.
pub const MO_WORLD_VERTICES: u32 = 3;
/// glsl/morph.comp (MORPH_BVH): the rest triangles.
pub const MO_REST_TRIS: u32 = 2;
/// glsl/morph.comp (MORPH_BVH): the rest vertex normals.
pub const MO_REST_NORMALS: u32 = 3;
/// glsl/morph.comp (MORPH_BVH): each BVH triangle corner's vertex.
pub const MO_REST_CORNERS: u32 = 4;
/// glsl/morph.comp (MORPH_BVH): the BVH triangles it writes.
pub const MO_BVH_TRIS: u32 = 5;
/// glsl/morph.comp (MORPH_BVH): the BVH normals it writes.
pub const MO_BVH_NORMALS: u32 = 6;
/// glsl/water.comp: the wave records.
pub const WA_WAVES: u32 = 0;
/// glsl/water.comp: the object-space vertices.
pub const WA_OBJECT_VERTICES: u32 = 1;
/// glsl/water.comp: the world-space vertices it writes.
pub const WA_WORLD_VERTICES: u32 = 2;
/// glsl/water.comp: the simulated heights.
pub const WA_HEIGHTS: u32 = 3;
/// glsl/water.comp: the displaced positions it writes, for its BVH mode.
pub const WA_DISPLACED: u32 = 4;
/// glsl/water.comp (WATER_BVH): the displaced positions.
pub const WA_BVH_DISPLACED: u32 = 0;
/// glsl/water.comp (WATER_BVH): each BVH triangle corner's vertex.
pub const WA_REST_CORNERS: u32 = 1;
/// glsl/water.comp (WATER_BVH): the BVH triangles it writes.
pub const WA_BVH_TRIS: u32 = 2;
/// glsl/water.comp (WATER_BVH): the BVH normals it writes.
pub const WA_BVH_NORMALS: u32 = 3;
/// glsl/water_step.comp: the simulated heights (two steps' fields).
pub const WS_HEIGHTS: u32 = 0;
/// glsl/refit.comp: the refit nodes.
pub const RF_NODES: u32 = 0;
/// glsl/refit.comp: the order in which the nodes are refitted.
pub const RF_ORDER: u32 = 1;
/// glsl/refit.comp: the refitted boxes.
pub const RF_BOXES: u32 = 2;
/// glsl/refit.comp: the BVH triangles.
pub const RF_TRIS: u32 = 3;
/// glsl/refit.comp: the pair layout's nodes.
pub const RF_PAIR: u32 = 4;
/// glsl/refit.comp: the single layout's nodes.
pub const RF_SINGLE: u32 = 5;
/// glsl/refit.comp: the threaded layout's nodes.
pub const RF_THREADED: u32 = 6;
/// glsl/refit_wide.comp: the order in which the wide nodes are refitted.
pub const RW_ORDER: u32 = 0;
/// glsl/refit_wide.comp: the refitted boxes.
pub const RW_BOXES: u32 = 1;
/// glsl/refit_wide.comp: the BVH triangles.
pub const RW_TRIS: u32 = 2;
/// glsl/refit_wide.comp: the wide nodes.
pub const RW_NODES: u32 = 3;
/// glsl/refit_wide.comp: the wide layout's triangle list.
pub const RW_PRIMS: u32 = 4;
/// glsl/scene_update.comp: the object-space vertices.
pub const SU_OBJECT_VERTICES: u32 = 0;
/// glsl/scene_update.comp: the world-space vertices it writes.
pub const SU_WORLD_VERTICES: u32 = 1;
/// glsl/scene_update.comp: the object-space indices.
pub const SU_OBJECT_INDICES: u32 = 2;
/// glsl/scene_update.comp: the world-space indices it writes.
pub const SU_WORLD_INDICES: u32 = 3;
/// glsl/geometry.frag (the eye's receivers): the albedo textures.
pub const GE_ALBEDO_TEXTURES: u32 = 0;
/// glsl/overlay.frag (the viewer's overlay): the texture its triangles sample.
pub const OV_TEXTURE: u32 = 0;
