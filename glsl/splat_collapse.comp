#version 460
// Adds coarse level pc.level of the flux texels into the level below it (glsl/common/splat_levels.glsl), after a
// frame's splats: each texel of the finer level takes its share of its four nearest coarse texels (splat_parents,
// splat_share: bilinear weights under which every coarse texel hands out exactly its flux, edges included).
// Dispatched once per level, coarsest first, with a barrier between: level m - 1 is complete before it is added on.
// Where the resolve reads the flux texels, it adds level 1 itself (glsl/resolve.comp). The dispatch's z is the plane
// (red, green, blue for color photons).
#include "common/photon_bindings.glsl"
layout(push_constant) uniform SplatCollapsePushBlock { SplatCollapsePush pc; };
#include "common/splat_levels.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    ivec2 size = ivec2(u_frame.light.receiver_view.extent.xy);
    uint m = pc.level;
    ivec2 fine = size >> (m - 1u), coarse = size >> m;
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(q, fine))) return;
    ivec2 p, n;
    splat_parents(q, coarse, p, n);
    uint base = gl_GlobalInvocationID.z * flux_plane(size);
    uint cb = base + splat_level_offset(size, m);
    float a = flux_texels[cb + p.y * coarse.x + p.x], b = flux_texels[cb + p.y * coarse.x + n.x];
    float c = flux_texels[cb + n.y * coarse.x + p.x], d = flux_texels[cb + n.y * coarse.x + n.x];
    float v = splat_share(a, b, c, d);
    if (v != 0.0) flux_texels[base + splat_level_offset(size, m - 1u) + q.y * fine.x + q.x] += v;
}
