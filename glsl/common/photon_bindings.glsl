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
layout(std430, set = 0, binding = 3) buffer IndirectBuf { uvec4 dispatch_cmd[MAX_LEVELS]; uvec4 trace_cmd; uvec4 draw_cmd; };
layout(std430, set = 0, binding = 4) readonly buffer CoverageBuf { uint coverage[]; };
layout(set = 0, binding = 5) uniform sampler2D t_front;      // refractor front: normal.xyz, distance (0: none)
layout(set = 0, binding = 6) uniform sampler2D t_front_aux;  // refractor front: index of refraction
layout(set = 0, binding = 7) uniform sampler2D t_back;       // refractor back: normal.xyz, distance
layout(set = 0, binding = 8) uniform sampler2D t_recv;       // receivers from the light: normal.xyz, distance
// Debug photon dump (tests), three rows per splatted photon:
//   (cell x, cell y, level | status << 8 | radius << 16, bits(flux.r)), bits(uv.x, uv.y, map_px.x, map_px.y),
//   bits(hit.x, hit.y, hit.z), 0.
layout(std430, set = 0, binding = 9) buffer DebugBuf { uvec4 debug_header; uvec4 debug_rows[]; };
// Splat records, one per emitted photon (same index): landing point (caustic-map texels), flux (W, before the
// light's color), splat radius (texels; 0: the photon did not land).
layout(std430, set = 0, binding = 10) buffer SplatBuf { vec4 splats[]; };

// Dispatch arguments for n invocations in groups of `per_group`, 2D because a dimension holds at most 65535
// groups (lavapipe's limit).
uvec4 dispatch_groups(uint n, uint per_group) {
    uint g = (n + per_group - 1u) / per_group;
    uint gx = min(g, 65535u);
    return uvec4(gx, g == 0u ? 0u : (g + gx - 1u) / gx, 1u, 0u);
}

// The emitted photons are [capacity - n, capacity): set the trace dispatch and the splat draw for them.
void set_emitted(uint n, uint capacity) {
    trace_cmd = dispatch_groups(n, LINEAR_WG);
    draw_cmd = uvec4(n, 1u, capacity - n, 0u);
}

#endif
