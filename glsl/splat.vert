#version 460
// Splat (DESIGN.md step 5), drawn with vkCmdDrawIndirect: one point per emitted photon. The photon is traced
// through the refractor to the receivers and drawn at its landing texel of the light-space caustic map, with a
// footprint that follows its cell: the size of the cell on the caustic map for max-level and dense photons
// (so that neighbours' tents overlap and interpolate), the children's spread for max-error clusters.
#include "common/photon_bindings.glsl"
#include "common/photon_push.glsl"
#include "common/coverage.glsl"
#include "common/photon.glsl"

layout(location = 0) flat out vec3 v_flux;
layout(location = 1) flat out vec3 v_splat;  // center (texels), radius (texels)

void main() {
    uvec2 cell = photons[gl_VertexIndex];
    uint level = cell_level(cell);
    uvec2 xy = cell_xy(cell);
    Hit h = trace_cell(level, xy);
    uint r = cell_radius(cell);
    if (r == 0u) {
        float texel = u_frame.receiver_view.window.z * u_frame.receiver_view.extent.z;
        r = uint(clamp(round(cell_side(level) / texel), 1.0, float(MAX_SPLAT_RADIUS)));
    }
    vec2 size = u_frame.receiver_view.extent.xy;
    if (h.status == HIT_OK) {
        gl_Position = vec4(h.map_px / size * 2.0 - 1.0, 0.5, 1.0);
        gl_PointSize = float(2u * r);
    } else {
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);  // outside the clip volume: the point is discarded
        gl_PointSize = 1.0;
    }
    v_flux = h.flux;
    v_splat = vec3(h.map_px, float(r));
    if (pc.debug != 0u && level >= pc.debug_min_level) {
        uint i = atomicAdd(debug_header.x, 1u);
        if (i < debug_header.y) {
            vec2 uv = cell_center_uv(level, xy);
            debug_rows[3u * i] = uvec4(xy, level | (h.status << 8) | (r << 16), floatBitsToUint(h.flux.r));
            debug_rows[3u * i + 1u] = floatBitsToUint(vec4(uv, h.map_px));
            debug_rows[3u * i + 2u] = uvec4(floatBitsToUint(h.pos), 0u);
        }
    }
}
