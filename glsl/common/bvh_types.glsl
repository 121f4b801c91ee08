// The scene BVH's records (generated from src/bvh/records.rs, where each layout is documented), shared by the
// photon passes and the composite.
#ifndef BVH_TYPES_GLSL
#define BVH_TYPES_GLSL
#include "generated/gpu_structs.glsl"
// The wide layout's variants read the triangles, their normals, the instances, the wide nodes and the triangle
// list as uniform texel buffers (src/passes/photons.rs, BVH_TEXEL_BINDINGS), the other variants as storage
// buffers. The layout is the one CPU devices trace, and a CPU driver (lavapipe) loads a storage buffer one lane at
// a time, each behind a branch, where a texel fetch gathers the whole SIMD group.
#if defined(BVH_LAYOUT_WIDE)
#define BVH_TEXELS 1
#endif
#endif
