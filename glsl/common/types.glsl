// Structs shared with Rust (src/gpu_types.rs mirrors each with size asserts). std140/std430-safe: vec4/uvec4 only.
#ifndef TYPES_GLSL
#define TYPES_GLSL

// A view from a point (perspective: spot light, perspective camera) or along a direction (orthographic:
// directional light, orthographic camera). See src/scene/view.rs.
struct View {
    mat4 view_proj;   // world -> clip
    vec4 origin;      // xyz; w: 0 perspective, 1 orthographic
    vec4 right;       // xyz; w: cosine of the spot cone (-1: no cone)
    vec4 down;        // xyz; w: near
    vec4 forward;     // xyz; w: far
    vec4 window;      // image-plane window: x0, y0, width, height
    vec4 extent;      // texels: width, height, 1/width, 1/height
};

struct FrameData {
    View photon_view;    // light view fitted to the refractors: photon grid and refractor g-buffers
    View receiver_view;  // light view over the receivers: caustic map, receiver g-buffer, shadow map
    View camera;         // eye
    vec4 light_power;    // rgb: I*color (W/sr; W/m^2 for directional lights); w: intensity
    vec4 scene_min;      // xyz: scene bounds; w: refractor bounding diameter (m)
    vec4 scene_max;      // xyz; w: exposure (1 / reference radiance)
    uvec4 grid;          // x: refractor g-buffer res R; y: log2(R/64); z: caustic map res M; w: pyramid mips
    uvec4 traversal;     // x: max level; y: bits 0-7 metric (0 max-level, 1 max-error, 2 flux-error), bit 8 batching;
                         // z: first level checked for convergence; w: photons one batch may emit
    vec4 params;         // x: error bound (caustic-map texels); y: shadow bias (texels); z: exact transport's
                         // flux threshold (relative to the photon's flux); w: flux-error's per-cell threshold tau
                         // (src/calibration.rs maps --target-error to it)
    uvec4 transport;     // x: 1 exact transport, 0 two-interface; y: rays per queue; z: splat records (one per
                         // photon-buffer entry: the buffer's entries); w: bits
                         // 0-7 the color channel of this pass (0: one gray pass; 1, 2, 3: red, green, blue),
                         // bit 8 differential footprints
    uvec4 pyramid[MAX_PYRAMID_MIPS / 4];  // start of each coverage mip in the coverage buffer
    vec4 eye;            // x: sky radiance (W/m^2/sr; 0: off); y: eye-ray depth cap (interfaces); z: 1 when glass disperses
    vec4 material;       // x: the IOR every refractor shares (-1: mirrors), 0 if they differ (then: IOR buffers);
                         // y: exact transport's weak-branch fraction (0: off; wave.comp); z: the weak-branch
                         // block side in cells (2 or 4)
};

// The front surface's index of refraction: shared by the scene's refractors, else from the IOR buffer's texel.
#define FRONT_IOR(aux_texel) (u_frame.material.x != 0.0 ? u_frame.material.x : (aux_texel))

struct LevelCounters {
    uint candidates;
    uint refined;
    uint emitted;
    uint dropped;
    uint checks_skipped;  // max-error and flux-error: refined without a check, predicted by the parent's
    uint unchecked;       // ...and from the check level on, candidates not checked because they are only partly
                          // covered or reach outside the cone (refined, or dropped if nothing is covered)
};

// Traversal state, read and written by init, traverse and stats (Piao's shared command buffer), extended with a
// tile stack for batching: a batch traverses one tile (a block of level-0 cells, or one cell of a deeper level).
// If the batch would overflow the photon buffer it is aborted and its tile split into four, so the committed
// batches partition the photons exactly and a tiny budget gives the same image as a large one.
struct TraversalState {
    uint read_offset;    // current level's candidates: [read_offset, read_offset + read_count)
    uint read_count;
    uint write_count;    // children appended this level (atomic); they follow the candidates
    uint emit_count;     // photons emitted this batch (atomic); they fill the buffer from the top down
    uint used;           // entries reserved this batch (atomic): candidates + children + emitted
    uint capacity;       // photon buffer entries a batch may use (photons and, while traversing, candidates)
    uint start_level;    // the batch's first traversal level (MAX_LEVELS: no tile, nothing to do)
    uint aborted;        // the batch overflowed
    uint batching;       // 1: an overflow aborts and splits the batch; 0: the overflowing work is dropped
    uint stack_size;     // pending tiles
    uint batches_committed;
    uint batches_aborted;  // overflow events that split a batch
    uint overflow_dropped; // entries dropped by overflows with batching off
    uint peak_used;
    uint photons_total;    // photons splatted, all batches
    uint slots_used;       // batch slots that found a tile
    ivec4 tile;            // the batch's tile: (t, x, y, -); t < 0: a 2^-t block of level-0 cells; t >= 0: a cell
    LevelCounters batch_levels[MAX_LEVELS];  // this batch's counts, committed into `levels` on success
    LevelCounters levels[MAX_LEVELS];
    ivec4 stack[TILE_STACK];
};

// Exact transport (docs/design.md step 4, `--transport exact`): the state of the waves of one batch and the energy
// account. Wave k traces ray queue k & 1 (wave 0: the batch's emitted photons) and appends the children to queue
// (k + 1) & 1 with atomicAdd; the transport shader turns out_count into the next wave's dispatch arguments.
// Account terms are flux / light intensity (sr for spot lights, m^2 for directional ones) in 64-bit fixed point
// (2^ACCOUNT_SHIFT units per 1), added as (lo, hi) word pairs with a carry, so the sums are exact and repeatable.
// The terms' indices (ACC_EMITTED ... ACC_WEAK_CARRIED, ACC_TERMS) are constants of src/shader_consts.rs.

struct TransportState {
    uint in_count;         // rays of the wave being traced (wave 0: the emitted photons)
    uint out_count;        // rays appended for the next wave (atomic, successful reservations only)
    uint out_reserved;     // capacity check for out_count (atomic; failed reservations roll back)
    uint records;          // splat records appended this batch (atomic)
    uint records_reserved;
    uint queue_capacity;   // rays per queue
    uint record_capacity;  // splat records per batch
    uint overflows;        // reservations that did not fit (frame)
    uint rays_traced;      // frame total
    uint records_total;    // splat records drawn (frame)
    uint waves;            // waves that traced at least one ray (frame)
    uint max_depth;        // most specular interactions of a deposited path (frame)
    uvec2 batch_account[ACC_TERMS];
    uvec2 account[ACC_TERMS];
    uint wave_rays[MAX_INTERACTIONS + 2u];  // rays each wave traced (frame; index: the wave, 0 the photons; + a pad)
};

// Photon encoding: a quadtree cell (level, x, y) with exact integer addressing.
//   .x: bits 0..23 cell x, bits 24..31 splat radius in caustic-map texels (0: derive from the level)
//   .y: bits 0..23 cell y, bits 24..28 level, bits 29..31 the weak-branch siblings of a photon too large for the
//       maximal level's blocks (traverse.comp, wave.comp; 0: none shared): which of its three siblings, in raster
//       order, are photons of its level, set only where every sibling is such a photon or covers nothing
uvec2 pack_cell(uint level, uint x, uint y, uint radius) {
    return uvec2((x & 0xFFFFFFu) | (min(radius, 255u) << 24), (y & 0xFFFFFFu) | (level << 24));
}
uint cell_level(uvec2 c) { return (c.y >> 24) & 0x1Fu; }
uint cell_siblings(uvec2 c) { return c.y >> 29; }
uvec2 with_siblings(uvec2 c, uint mask) { return uvec2(c.x, (c.y & 0x1FFFFFFFu) | (mask << 29)); }
uvec2 cell_xy(uvec2 c) { return uvec2(c.x & 0xFFFFFFu, c.y & 0xFFFFFFu); }
uint cell_radius(uvec2 c) { return c.x >> 24; }

#endif
