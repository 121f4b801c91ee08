// The GPU structs (generated from src/gpu_types.rs and src/bvh/records.rs, where each is documented) and the
// helpers that read them.
#ifndef TYPES_GLSL
#define TYPES_GLSL
#include "generated/gpu_structs.glsl"

// The front surface's index of refraction: shared by the scene's refractors, else from the IOR buffer's texel.
#define FRONT_IOR(aux_texel) (u_frame.frame.shared_ior != 0.0 ? u_frame.frame.shared_ior : (aux_texel))

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

// A color photon's tint (docs/design.md "Color"): its weight per channel over their mean, so that the three sum to
// 3, packed as the red and green shares of that 3 in two unorm16 (GpuRayMedium.tint); blue is the rest.
uint tint_pack(vec3 c) { return packUnorm2x16(c.rg / 3.0); }
vec3 tint_unpack(uint w) {
    vec2 rg = unpackUnorm2x16(w) * 3.0;
    return vec3(rg, max(3.0 - rg.x - rg.y, 0.0));
}

#endif
