// The binding layout shared by every photon pass (init, plan, traverse, stats, dense emit, splat).
// src/passes/photons.rs pushes the same list in the same order.
#ifndef PHOTON_BINDINGS_GLSL
#define PHOTON_BINDINGS_GLSL
#include "common/types.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = 1) buffer StateBuf { TraversalState state; };
layout(std430, set = 0, binding = 2) buffer PhotonBuf { uvec2 photons[]; };
// Indirect commands: dispatch[level] (x, y, z, pad) for each traversal level, then the splat's draw command
// (vertexCount, instanceCount, firstVertex, firstInstance).
layout(std430, set = 0, binding = 3) buffer IndirectBuf { uvec4 dispatch_cmd[MAX_LEVELS]; uvec4 draw_cmd; };
layout(std430, set = 0, binding = 4) readonly buffer CoverageBuf { uint coverage[]; };
layout(set = 0, binding = 5) uniform sampler2D t_front;      // refractor front: normal.xyz, distance (0: none)
layout(set = 0, binding = 6) uniform sampler2D t_front_aux;  // refractor front: index of refraction
layout(set = 0, binding = 7) uniform sampler2D t_back;       // refractor back: normal.xyz, distance
layout(set = 0, binding = 8) uniform sampler2D t_recv;       // receivers from the light: normal.xyz, distance
// Debug photon dump (tests), three rows per splatted photon:
//   (cell x, cell y, level | status << 8 | radius << 16, bits(flux.r)), bits(uv.x, uv.y, map_px.x, map_px.y),
//   bits(hit.x, hit.y, hit.z), 0.
layout(std430, set = 0, binding = 9) buffer DebugBuf { uvec4 debug_header; uvec4 debug_rows[]; };

#endif
