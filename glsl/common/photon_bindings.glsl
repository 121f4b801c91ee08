// The binding layout shared by every photon pass (init, plan, traverse, stats, dense emit, splat).
// Each binding's index is a constant of src/shader_consts.rs (PB_*), which src/passes/photons.rs binds by too.
#ifndef PHOTON_BINDINGS_GLSL
#define PHOTON_BINDINGS_GLSL
#include "common/types.glsl"

layout(std140, set = 0, binding = PB_FRAME) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = PB_STATE) buffer StateBuf { TraversalState state; };
// The wave's read-only inputs (the photons, the coverage pyramid) are texel buffers where it reads the BVH as texels
// (WAVE_TEXELS, glsl/wave.comp; common/bvh_types.glsl says why).
#ifdef WAVE_TEXELS
layout(set = 0, binding = PB_PHOTONS) uniform usamplerBuffer photon_texels;
uvec2 photon_at(uint i) { return texelFetch(photon_texels, int(i)).xy; }
#else
layout(std430, set = 0, binding = PB_PHOTONS) buffer PhotonBuf { uvec2 photons[]; };
uvec2 photon_at(uint i) { return photons[i]; }
#endif
// Indirect commands: dispatch[level] (x, y, z, pad) for each traversal level, the photon trace's dispatch, then
// the splat's draw command (vertexCount, instanceCount, firstVertex, firstInstance).
// Exact transport adds the current wave's dispatch.
layout(std430, set = 0, binding = PB_INDIRECT) buffer IndirectBuf { uvec4 indirect_cmd[INDIRECT_COMMANDS]; };
#define dispatch_cmd indirect_cmd
#define trace_cmd indirect_cmd[INDIRECT_TRACE]
#define draw_cmd indirect_cmd[INDIRECT_DRAW]
#define wave_cmd indirect_cmd[INDIRECT_WAVE]
#define splat_cmd indirect_cmd[INDIRECT_SPLAT]
#ifdef WAVE_TEXELS
layout(set = 0, binding = PB_COVERAGE) uniform usamplerBuffer coverage_texels;
uint coverage_at(uint i) { return texelFetch(coverage_texels, int(i)).x; }
#else
layout(std430, set = 0, binding = PB_COVERAGE) readonly buffer CoverageBuf { uint coverage[]; };
uint coverage_at(uint i) { return coverage[i]; }
#endif
layout(set = 0, binding = PB_FRONT) uniform usampler2D t_front;     // refractor front: normal, distance (0: none; common/gbuffer.glsl)
layout(set = 0, binding = PB_FRONT_AUX) uniform sampler2D t_front_aux;  // refractor front: index of refraction
layout(set = 0, binding = PB_BACK) uniform usampler2D t_back;      // refractor back: normal, distance
layout(set = 0, binding = PB_RECEIVERS) uniform usampler2D t_recv;      // receivers from the light: normal, distance
// Debug photon dump (tests), three rows per splatted photon:
//   (cell x, cell y, level | status << 8 | radius << 16, bits(flux.r)), bits(uv.x, uv.y, map_px.x, map_px.y),
//   bits(hit.x, hit.y, hit.z), 0.
layout(std430, set = 0, binding = PB_DEBUG) buffer DebugBuf { uvec4 debug_header; uvec4 debug_rows[]; };
// Splat records, one per emitted photon (same index): landing point (caustic-map texels), flux (W, before the
// light's color), splat radii (texels; 0: the photon did not land) as the float of rx | ry << 16, an exact integer
// below 2^24; ry = 0 means ry = rx (a plain radius r is the isotropic tent of radius r).
layout(std430, set = 0, binding = PB_SPLATS) buffer SplatBuf { vec4 splats[]; };
vec2 splat_radii(float w) {
    uint r = uint(w);
    uint rx = r & 0xFFFFu, ry = r >> 16;
    return vec2(float(rx), float(ry == 0u ? rx : ry));
}
// The weight of texel x (its center x + 0.5) in a tent of radius r centred at c, before normalization (splat.frag
// weighs its fragments the same way).
float tent(int x, float c, float r) {
    return max(0.0, 1.0 - abs(float(x) + 0.5 - c) / r);
}
// The sum over the texel centers of a map n texels wide (0 <= x < n) of tent(x, c, r): exactly r for an integer r
// whose tent lies inside the map, less where it reaches past an edge.
float tent_sum(float c, float r, int n) {
    int lo = max(int(ceil(c - r - 0.5)), 0), hi = min(int(floor(c + r - 0.5)), n - 1);
    float s = 0.0;
    for (int x = lo; x <= hi; x++) s += tent(x, c, r);
    return s;
}
// The factor that makes the on-map weights of a splat of integer radii r centred at c (texels) sum to exactly 1:
// 1 for a tent inside the map; at an edge the taps that would fall off it are given back to the ones on it, so a
// record whose center lands on the map deposits all its flux there, however wide its tent.
float splat_edge_norm(vec2 c, vec2 r, ivec2 size) {
    if (all(greaterThanEqual(c - r, vec2(0.0))) && all(lessThanEqual(c + r, vec2(size)))) return 1.0;
    float on_map = tent_sum(c.x, r.x, size.x) * tent_sum(c.y, r.y, size.y);
    return on_map > 0.0 ? (r.x * r.y) / on_map : 0.0;
}

// Exact transport (src/bvh.rs, glsl/common/bvh.glsl): the wave state, two ray queues, and the scene BVH.
// A ray is two vec4: origin and throughput (relative to its photon's flux); direction and bits(photon index |
// interactions << PHOTON_INDEX_BITS); with `--footprint differential` three more hold its ray differentials (glsl/wave.comp). The photon index points into the photon buffer, whose cell gives the flux and footprint.
layout(std430, set = 0, binding = PB_TRANSPORT) buffer TransportBuf { TransportState tstate; };
layout(std430, set = 0, binding = PB_QUEUE0) buffer RayQueue0 { vec4 queue0[]; };
layout(std430, set = 0, binding = PB_QUEUE1) buffer RayQueue1 { vec4 queue1[]; };
#include "common/bvh_types.glsl"
layout(std430, set = 0, binding = PB_BVH_PAIR) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, set = 0, binding = PB_BVH_SINGLE) readonly buffer BvhNodesSingle { BvhNodeSingle bvh_nodes_single[]; };
#ifdef BVH_TEXELS
layout(set = 0, binding = PB_BVH_TRIS) uniform samplerBuffer bvh_tri_texels;       // 3 per triangle
layout(set = 0, binding = PB_BVH_NORMALS) uniform samplerBuffer bvh_normal_texels; // 3 per triangle
layout(set = 0, binding = PB_BVH_INSTANCES) uniform samplerBuffer bvh_instance_texels;  // 12 per instance
#else
layout(std430, set = 0, binding = PB_BVH_TRIS) readonly buffer BvhTris { vec4 bvh_tris[]; };          // 3 per triangle
layout(std430, set = 0, binding = PB_BVH_NORMALS) readonly buffer BvhNormals { vec4 bvh_normal_rows[]; }; // 3 per triangle
layout(std430, set = 0, binding = PB_BVH_INSTANCES) readonly buffer BvhInstances { BvhInstance bvh_instances[]; };
#endif

// The compute splat's target: the caustic flux map as one float per texel (row-major), added to atomically, then
// copied into the flux image that the resolve reads.
layout(std430, set = 0, binding = PB_FLUX_TEXELS) buffer FluxBuf { float flux_texels[]; };
// The threaded layout (src/bvh.rs): depth-first nodes with escape links; lo.w: escape, hi.w: count << 29 | first.
layout(std430, set = 0, binding = PB_BVH_THREADED) readonly buffer BvhNodesThreaded { BvhNodeSingle bvh_nodes_threaded[]; };
// The wide layout (src/bvh.rs): compressed 8-wide nodes, and its triangle list (indices into bvh_tris' triangles).
#ifdef BVH_TEXELS
layout(set = 0, binding = PB_BVH_WIDE) uniform usamplerBuffer bvh_wide_texels;  // 5 per node
layout(set = 0, binding = PB_BVH_WIDE_PRIMS) uniform usamplerBuffer bvh_wide_prim_texels;
#else
layout(std430, set = 0, binding = PB_BVH_WIDE) readonly buffer BvhNodesWide { BvhNodeWide bvh_nodes_wide[]; };
layout(std430, set = 0, binding = PB_BVH_WIDE_PRIMS) readonly buffer BvhWidePrims { uint bvh_wide_prims[]; };
#endif

// Dispatch arguments for n invocations in groups of `per_group`, 2D because a dimension holds at most 65535
// groups (lavapipe's limit).
uvec4 dispatch_groups(uint n, uint per_group) {
    uint g = (n + per_group - 1u) / per_group;
    uint gx = min(g, 65535u);
    return uvec4(gx, g == 0u ? 0u : (g + gx - 1u) / gx, 1u, 0u);
}

// The splat's draw over records [first, first + n), and the compute splat's dispatch for the same records.
void set_draw(uint n, uint first) {
    draw_cmd = uvec4(n, 1u, first, 0u);
    splat_cmd = dispatch_groups(n, LINEAR_WG);
}

// The emitted photons are [capacity - n, capacity): set the trace dispatch and the splat draw for them.
void set_emitted(uint n, uint capacity) {
    trace_cmd = dispatch_groups(n, LINEAR_WG);
    set_draw(n, capacity - n);
}

#endif
