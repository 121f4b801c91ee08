#version 460
// Caustic irradiance: each caustic-map texel holds flux (W, for a white light); divide by the receiver area the texel covers,
// A = Omega * d^2 / |cos| (spot) or side^2 / |cos| (directional), to get W/m^2.
#include "common/types.glsl"
#include "common/view.glsl"
#include "common/gbuffer.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = 1) uniform sampler2D t_flux;
layout(set = 0, binding = 2) uniform usampler2D t_recv;
layout(set = 0, binding = 3, rgba32f) uniform image2D o_irradiance;

// add: add to the irradiance already there (a frame's remaining batches) instead of writing it.
layout(push_constant) uniform ResolvePush { uint add; } pc;

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    View v = u_frame.receiver_view;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(v.extent.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 r = geo_fetch(t_recv, p);
    vec3 e = vec3(0.0);
    if (r.w > 0.0) {
        vec2 uv = (vec2(p) + 0.5) * v.extent.zw;
        vec2 xy = view_xy_of_uv(v, uv);
        vec3 ro, rd;
        view_ray_xy(v, xy, ro, rd);
        float cos_t = max(abs(dot(normalize(r.xyz), rd)), 0.02);
        float side = v.window.z * v.extent.z;
        float area = view_cell_measure(v, xy, side) / cos_t;
        if (!view_is_ortho(v)) area *= r.w * r.w;
        // The map holds flux for a white light; the light's color (per unit intensity) tints it here.
        vec3 tint = u_frame.light_power.w > 0.0 ? u_frame.light_power.rgb / u_frame.light_power.w : vec3(0.0);
        e = texelFetch(t_flux, p, 0).r * tint / area;
    }
    // A color pass (docs/design.md "Color") writes its own channel; the red pass starts the texel, the green
    // and blue passes keep what the earlier ones wrote.
    uint c = u_frame.transport.w & 0xffu;
    if (c != 0u) {
        vec4 prev = c == 1u && pc.add == 0u ? vec4(0.0) : imageLoad(o_irradiance, p);
        prev[c - 1u] = e[c - 1u] + (pc.add != 0u ? prev[c - 1u] : 0.0);
        imageStore(o_irradiance, p, prev);
        return;
    }
    vec4 prev = pc.add != 0u ? imageLoad(o_irradiance, p) : vec4(0.0);
    imageStore(o_irradiance, p, vec4(prev.rgb + e, 0.0));
}
