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

#endif
