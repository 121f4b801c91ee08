// Coverage pyramid lookups. Mip m of the pyramid has (R >> m)^2 entries; bit 0: any refractor texel below is
// covered (max), bit 1: all are (min). Grid level l (64*2^l cells per side) maps to mip g - l, g = log2(R/64);
// finer levels share the base texel that contains them.
#ifndef COVERAGE_GLSL
#define COVERAGE_GLSL
#include "common/emitter.glsl"

uint pyramid_offset(uint m) { return u_frame.frame.pyramid[m >> 2][m & 3u]; }

uint coverage_bits(uint level, uvec2 xy) {
    uint R = u_frame.frame.gbuffer_res, g = u_frame.frame.gbuffer_level;
    if (level <= g) {
        uint m = g - level;
        uint res = R >> m;
        return coverage_at(pyramid_offset(m) + xy.y * res + xy.x);
    }
    uvec2 t = xy >> (level - g);
    return coverage_at(pyramid_offset(0u) + t.y * R + t.x);
}

bool cell_any_covered(uint level, uvec2 xy) { return (coverage_bits(level, xy) & 1u) != 0u; }
bool cell_all_covered(uint level, uvec2 xy) { return (coverage_bits(level, xy) & 2u) != 0u; }

// The base texel that contains the cell's center. Dense and adaptive both call this, so that adaptive
// max-level at level L emits exactly dense's cells.
uvec2 leaf_texel(uint level, uvec2 xy) {
    uint g = u_frame.frame.gbuffer_level;
    if (level >= g) return xy >> (level - g);
    uint s = g - level;
    return ((2u * xy + 1u) << s) >> 1;
}

bool leaf_covered(uint level, uvec2 xy) {
    uvec2 t = leaf_texel(level, xy);
    return (coverage_at(pyramid_offset(0u) + t.y * u_frame.frame.gbuffer_res + t.x) & 1u) != 0u;
}

// Is the leaf cell (level, xy) a photon of the dense grid: its center's base texel is covered and its center lies
// inside the cone. Dense emission and max-level traversal both decide by this one function, with the same float
// arithmetic, so that max-level traversal emits exactly dense's cells.
bool leaf_emitted(uint level, uvec2 xy) {
    GpuView v = u_frame.light.photon_view;
    float side = v.window.z / float(LEVEL0_RES << level);
    vec2 center = v.window.xy + (vec2(xy) + 0.5) * side;
    return leaf_covered(level, xy) && emitter_holds(v, center);
}

#endif
