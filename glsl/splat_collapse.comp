#version 460
// Adds coarse level pc.level of the flux texels into the level below it (glsl/common/splat_levels.glsl), after a
// frame's splats: each texel of the finer level takes its four nearest coarse texels with bilinear weights (9, 3,
// 3, 1)/16, a quarter of that (the coarse texel's flux spreads over four times as many texels). Each coarse texel
// so gives its children weights (1, 3, 3, 1)/8 per axis, which sum to 1: flux is conserved, edges included
// (the neighbour index is clamped to the level, which folds the weight that would fall off back onto the edge).
// Dispatched once per level, coarsest first, with a barrier between: level m - 1 is complete before it is added on.
#include "common/photon_bindings.glsl"
#include "common/photon_push.glsl"
#include "common/splat_levels.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    ivec2 size = ivec2(u_frame.receiver_view.extent.xy);
    uint m = pc.level;
    ivec2 fine = size >> (m - 1u), coarse = size >> m;
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, fine))) return;
    ivec2 p = q >> 1;
    // The second-nearest coarse texel: below for an even fine texel, above for an odd one.
    ivec2 n = clamp(p + (q & 1) * 2 - 1, ivec2(0), coarse - 1);
    uint cb = splat_level_offset(size, m);
    float a = flux_texels[cb + p.y * coarse.x + p.x], b = flux_texels[cb + p.y * coarse.x + n.x];
    float c = flux_texels[cb + n.y * coarse.x + p.x], d = flux_texels[cb + n.y * coarse.x + n.x];
    float v = (0.5625 * a + 0.1875 * (b + c) + 0.0625 * d) * 0.25;
    if (v != 0.0) flux_texels[splat_level_offset(size, m - 1u) + q.y * fine.x + q.x] += v;
}
