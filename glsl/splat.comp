#version 460
// Compute splat (docs/design.md step 5, `--splat compute`), dispatched indirectly over the records the draw would
// draw: the same separable integer-radius tent as splat.frag, evaluated at the same texel centers, each tap added
// to the flux map with a float atomic. The weights of a record sum to exactly 1 over the texel lattice, so flux is
// conserved as by the point draw; only the order of the float additions differs. As with points, a record whose
// center lies outside the map is dropped (a point primitive is clipped by its vertex).
#extension GL_EXT_shader_atomic_float : require
#include "common/photon_bindings.glsl"

layout(local_size_x = LINEAR_WG) in;

void main() {
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * LINEAR_WG + gl_LocalInvocationIndex;
    if (i >= draw_cmd.x) return;
    vec4 s = splats[draw_cmd.z + i];
    float r = s.w;
    ivec2 size = ivec2(u_frame.receiver_view.extent.xy);
    if (!(r > 0.0) || !(s.x >= 0.0 && s.y >= 0.0 && s.x <= float(size.x) && s.y <= float(size.y))) return;
    // Texel centers p + 0.5 with |p + 0.5 - c| < r on each axis.
    ivec2 lo = max(ivec2(ceil(s.xy - r - 0.5)), ivec2(0));
    ivec2 hi = min(ivec2(floor(s.xy + r - 0.5)), size - 1);
    for (int y = lo.y; y <= hi.y; y++) {
        float wy = max(0.0, 1.0 - abs(float(y) + 0.5 - s.y) / r) / r;
        if (wy == 0.0) continue;
        for (int x = lo.x; x <= hi.x; x++) {
            float wx = max(0.0, 1.0 - abs(float(x) + 0.5 - s.x) / r) / r;
            if (wx > 0.0) atomicAdd(flux_texels[y * size.x + x], s.z * (wx * wy));
        }
    }
}
