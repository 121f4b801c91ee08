// The scene BVH's structs (src/bvh.rs mirrors them), shared by the photon passes and the composite.
#ifndef BVH_TYPES_GLSL
#define BVH_TYPES_GLSL
struct BvhInstance {
    vec4 object_from_world[3];
    vec4 world_from_object[3];
    vec4 lo;        // world bounds; w: root node bits (pair layout)
    vec4 hi;        // w: root node bits (single layout)
    vec4 material;  // x: IOR (dielectric) or albedo; y: 1 dielectric, 2 mirror, 0 diffuse receiver; z: absorption
    vec4 pad;       // x: root node bits (threaded layout); yzw: a diffuse receiver's rgb albedo
    vec4 ior_rgb;   // dielectric: IOR of the red, green and blue channels (docs/design.md "Color"); w: root bits (wide)
    vec4 sigma_rgb; // dielectric: absorption coefficient per channel (1/m)
};
// Two node layouts (src/bvh.rs): "pair" holds both children's boxes (loK.w: child node or first triangle, hiK.w:
// triangle count, 0 for an inner child); "single" one box per node (lo.w: first child or triangle, hi.w: count).
struct BvhNode { vec4 lo0; vec4 hi0; vec4 lo1; vec4 hi1; };
struct BvhNodeSingle { vec4 lo; vec4 hi; };
// "wide" (src/bvh.rs, WideNode): a compressed 8-wide node. w0: the box's low corner p, then the scale exponents
// (bytes 0-2) and the inner-child mask (byte 3); w1: first inner child, first triangle-list entry, then the eight
// children's meta bytes; w2-w4: their quantized planes, a byte per child (x: low 0-3, low 4-7, high 0-3, high 4-7;
// y in w3, z in w4).
struct BvhNodeWide { uvec4 w0; uvec4 w1; uvec4 w2; uvec4 w3; uvec4 w4; };
// The wide layout's variants read the triangles, their normals, the instances, the wide nodes and the triangle
// list as uniform texel buffers (src/passes/photons.rs, BVH_TEXEL_BINDINGS), the other variants as storage
// buffers. The layout is the one CPU devices trace, and a CPU driver (lavapipe) loads a storage buffer one lane at
// a time, each behind a branch, where a texel fetch gathers the whole SIMD group.
#if defined(BVH_LAYOUT_WIDE)
#define BVH_TEXELS 1
#endif
#endif
