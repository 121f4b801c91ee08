#version 460
// Splat (docs/design.md step 5), drawn with vkCmdDrawIndirect: one point per emitted photon, at its
// landing texel of the light-space caustic map, sized by its footprint. The trace pass filled the splat records.
#define SPLAT_RECORDS_READ_ONLY
#include "common/photon_bindings.glsl"

layout(location = 0) flat out float v_flux;
layout(location = 1) flat out vec4 v_splat;  // center (texels), radii rx, ry (texels)
layout(location = 2) flat out vec2 v_shear;  // shear, and 1 when it moves the columns (SplatShape)

void main() {
    GpuSplat s = splats[gl_VertexIndex];
    vec2 size = u_frame.light.receiver_view.extent.xy;
    SplatShape k = splat_shape(s.shape > 0.0 ? s.shape : 1.0);
    if (s.shape > 0.0) {
        gl_Position = vec4(s.texel / size * 2.0 - 1.0, 0.5, 1.0);
        vec2 e = splat_extent(k);
        gl_PointSize = 2.0 * max(e.x, e.y);
    } else {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: the point is discarded
        gl_PointSize = 1.0;
    }
    // The weights' normalization; at an edge the fragments that the map clips away are given back to the ones on it.
    v_flux = s.shape > 0.0 ? s.flux * splat_norm(s.texel, k, ivec2(size)) : 0.0;
    v_splat = vec4(s.texel, k.r);
    v_shear = vec2(k.s, k.shear_y ? 1.0 : 0.0);
}
