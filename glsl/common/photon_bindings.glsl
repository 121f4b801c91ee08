// The binding layout shared by every photon pass (init, plan, traverse, stats, dense emit, splat).
// src/passes/photons.rs pushes the same list in the same order.
#ifndef PHOTON_BINDINGS_GLSL
#define PHOTON_BINDINGS_GLSL
#include "common/types.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = 1) buffer StateBuf { TraversalState state; };
layout(std430, set = 0, binding = 2) buffer PhotonBuf { uvec2 photons[]; };
// Indirect commands: dispatch[level] (x, y, z, pad) for each traversal level, the photon trace's dispatch, then
// the splat's draw command (vertexCount, instanceCount, firstVertex, firstInstance).
// Exact transport adds the current wave's dispatch.
layout(std430, set = 0, binding = 3) buffer IndirectBuf {
    uvec4 dispatch_cmd[MAX_LEVELS];
    uvec4 trace_cmd;
    uvec4 draw_cmd;
    uvec4 wave_cmd;
    uvec4 splat_cmd;  // the compute splat's dispatch over the draw's records
};
layout(std430, set = 0, binding = 4) readonly buffer CoverageBuf { uint coverage[]; };
layout(set = 0, binding = 5) uniform usampler2D t_front;     // refractor front: normal, distance (0: none; common/gbuffer.glsl)
layout(set = 0, binding = 6) uniform sampler2D t_front_aux;  // refractor front: index of refraction
layout(set = 0, binding = 7) uniform usampler2D t_back;      // refractor back: normal, distance
layout(set = 0, binding = 8) uniform usampler2D t_recv;      // receivers from the light: normal, distance
// Debug photon dump (tests), three rows per splatted photon:
//   (cell x, cell y, level | status << 8 | radius << 16, bits(flux.r)), bits(uv.x, uv.y, map_px.x, map_px.y),
//   bits(hit.x, hit.y, hit.z), 0.
layout(std430, set = 0, binding = 9) buffer DebugBuf { uvec4 debug_header; uvec4 debug_rows[]; };
// Splat records, one per emitted photon (same index): landing point (caustic-map texels), flux (W, before the
// light's color), splat radii (texels; 0: the photon did not land) as the float of rx | ry << 16, an exact integer
// below 2^24; ry = 0 means ry = rx (a plain radius r is the isotropic tent of radius r).
layout(std430, set = 0, binding = 10) buffer SplatBuf { vec4 splats[]; };
vec2 splat_radii(float w) {
    uint r = uint(w);
    uint rx = r & 0xFFFFu, ry = r >> 16;
    return vec2(float(rx), float(ry == 0u ? rx : ry));
}

// Exact transport (src/bvh.rs, glsl/common/bvh.glsl): the wave state, two ray queues, and the scene BVH.
// A ray is two vec4: origin and throughput (relative to its photon's flux); direction and bits(photon index |
// interactions << 24); with `--footprint differential` three more hold its ray differentials (glsl/wave.comp). The photon index points into the photon buffer, whose cell gives the flux and footprint.
layout(std430, set = 0, binding = 11) buffer TransportBuf { TransportState tstate; };
layout(std430, set = 0, binding = 12) buffer RayQueue0 { vec4 queue0[]; };
layout(std430, set = 0, binding = 13) buffer RayQueue1 { vec4 queue1[]; };
struct BvhInstance {
    vec4 object_from_world[3];
    vec4 world_from_object[3];
    vec4 lo;        // world bounds; w: root node bits (pair layout)
    vec4 hi;        // w: root node bits (single layout)
    vec4 material;  // x: IOR (dielectric) or albedo; y: 1 dielectric, 2 mirror, 0 diffuse receiver; z: absorption
    vec4 pad;       // x: root node bits (threaded layout); yzw: a diffuse receiver's rgb albedo
    vec4 ior_rgb;   // dielectric: IOR of the red, green and blue channels (docs/design.md "Color")
    vec4 sigma_rgb; // dielectric: absorption coefficient per channel (1/m)
};
// Two node layouts (src/bvh.rs): "pair" holds both children's boxes (loK.w: child node or first triangle, hiK.w:
// triangle count, 0 for an inner child); "single" one box per node (lo.w: first child or triangle, hi.w: count).
struct BvhNode { vec4 lo0; vec4 hi0; vec4 lo1; vec4 hi1; };
struct BvhNodeSingle { vec4 lo; vec4 hi; };
layout(std430, set = 0, binding = 14) readonly buffer BvhNodes { BvhNode bvh_nodes[]; };
layout(std430, set = 0, binding = 18) readonly buffer BvhNodesSingle { BvhNodeSingle bvh_nodes_single[]; };
layout(std430, set = 0, binding = 15) readonly buffer BvhTris { vec4 bvh_tris[]; };          // 3 per triangle
layout(std430, set = 0, binding = 16) readonly buffer BvhNormals { vec4 bvh_normal_rows[]; }; // 3 per triangle
layout(std430, set = 0, binding = 17) readonly buffer BvhInstances { BvhInstance bvh_instances[]; };
uint bvh_instance_count() { return uint(bvh_instances.length()); }

// The compute splat's target: the caustic flux map as one float per texel (row-major), added to atomically, then
// copied into the flux image that the resolve reads.
layout(std430, set = 0, binding = 19) buffer FluxBuf { float flux_texels[]; };
// The threaded layout (src/bvh.rs): depth-first nodes with escape links; lo.w: escape, hi.w: count << 29 | first.
layout(std430, set = 0, binding = 20) readonly buffer BvhNodesThreaded { BvhNodeSingle bvh_nodes_threaded[]; };

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
