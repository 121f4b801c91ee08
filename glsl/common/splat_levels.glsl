// The flux texels' coarse levels (docs/design.md step 5, "Splat footprint"): under differential footprints a
// compute splat adds a tent wider than SPLAT_FINE_RADIUS at the level of the flux texels where it is at most that
// wide, and splat_collapse.comp adds each level into the one below it before the flux map is read. Level m is the
// map halved m times (as many times as both sides allow, at most SPLAT_LEVELS), stored after level m - 1.
// src/targets.rs sizes the buffer with the same arithmetic.
#ifndef SPLAT_LEVELS_GLSL
#define SPLAT_LEVELS_GLSL

uint splat_levels(ivec2 size) {
    return min(SPLAT_LEVELS, uint(min(findLSB(uint(size.x)), findLSB(uint(size.y)))));
}

uint splat_level_offset(ivec2 size, uint m) {
    uint o = 0u;
    for (uint k = 0u; k < m; k++) o += uint((size.x >> k) * (size.y >> k));
    return o;
}

// The flux texels' planes (red, green and blue for color photons, else one) each hold a map's level 0 and its
// coarse levels: plane k starts k flux_plane(size) texels in.
uint flux_plane(ivec2 size) { return splat_level_offset(size, splat_levels(size) + 1u); }

// Texel q of level m - 1 takes a share of four texels of level m (`coarse` its size): its parent p and, along
// each axis, the second-nearest n (below for an even q, above for an odd one; clamped to the level, which folds the
// weight that would fall off back onto the edge). splat_share weighs their values a (p), b (n.x, p.y), c (p.x,
// n.y) and d (n) bilinearly, (9, 3, 3, 1)/16, and takes a quarter: each coarse texel so hands its children weights
// (1, 3, 3, 1)/8 per axis, which sum to 1. splat_collapse.comp adds the coarser levels this way and the resolve
// the first (resolve.comp), so both must weigh alike.
void splat_parents(ivec2 q, ivec2 coarse, out ivec2 p, out ivec2 n) {
    p = q >> 1;
    n = clamp(p + (q & 1) * 2 - 1, ivec2(0), coarse - 1);
}

float splat_share(float a, float b, float c, float d) { return (0.5625 * a + 0.1875 * (b + c) + 0.0625 * d) * 0.25; }

#endif
