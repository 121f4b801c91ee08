#version 460
// Caustic irradiance: each caustic-map texel holds flux (W, for a white light); divide by the receiver area the texel covers,
// A = Omega * d^2 / |cos| (spot) or side^2 / |cos| (directional), to get W/m^2.
#include "common/types.glsl"
#include "common/view.glsl"
#include "common/gbuffer.glsl"
#include "common/splat_levels.glsl"

layout(std140, set = 0, binding = RS_FRAME) uniform FrameUbo { FrameData u_frame; };
#ifdef RESOLVE_TEXELS
// The compute splat's flux texels (a texel view of the buffer: level 0, then the coarse levels). The levels from 2
// up have been added into level 1 (glsl/splat_collapse.comp); level 1's share is added here, as splat_collapse.comp
// would add it into level 0 (splat_parents and splat_share, glsl/common/splat_levels.glsl), which saves that pass
// over the whole map and the copy into the flux image.
layout(set = 0, binding = RS_FLUX) uniform samplerBuffer t_flux;
// Color photons: the texels hold a plane per channel (red, green, blue; glsl/splat.comp).
layout(constant_id = RESOLVE_COLOR_ID) const bool RESOLVE_COLOR = false;

// The flux at texel q of the plane that starts at texel `base`.
float flux_at(ivec2 q, ivec2 size, int base) {
    float f = texelFetch(t_flux, base + q.y * size.x + q.x).r;
    if (splat_levels(size) == 0u) return f;
    ivec2 coarse = size >> 1, p, n;
    splat_parents(q, coarse, p, n);
    int cb = base + int(splat_level_offset(size, 1u));
    float a = texelFetch(t_flux, cb + p.y * coarse.x + p.x).r, b = texelFetch(t_flux, cb + p.y * coarse.x + n.x).r;
    float c = texelFetch(t_flux, cb + n.y * coarse.x + p.x).r, d = texelFetch(t_flux, cb + n.y * coarse.x + n.x).r;
    float v = splat_share(a, b, c, d);
    return v != 0.0 ? f + v : f;
}

// The flux per channel, or the one gray flux in each.
vec3 flux_rgb(ivec2 q, ivec2 size) {
    if (!RESOLVE_COLOR) return vec3(flux_at(q, size, 0));
    int plane = int(flux_plane(size));
    return vec3(flux_at(q, size, 0), flux_at(q, size, plane), flux_at(q, size, 2 * plane));
}
#else
// The flux image (the raster splat's target, or the compute splat's level 0 copied into it).
layout(set = 0, binding = RS_FLUX) uniform sampler2D t_flux;

vec3 flux_rgb(ivec2 q, ivec2 size) { return vec3(texelFetch(t_flux, q, 0).r); }
#endif
layout(set = 0, binding = RS_RECEIVERS) uniform usampler2D t_recv;
layout(set = 0, binding = RS_IRRADIANCE, rgba32f) uniform image2D o_irradiance;

// keep, scale: the irradiance written is keep times what the map holds plus scale times this flux's (a frame's
// remaining batches add to it; a progressive accumulation's photon set is averaged into it).
layout(push_constant) uniform ResolvePushBlock { ResolvePush pc; };

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    GpuView v = u_frame.light.receiver_view;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(v.extent.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    vec4 r = geo_fetch(t_recv, p);
    vec3 e = vec3(0.0);
    if (r.w > 0.0) {
        float area = view_texel_area(v, p, r.xyz, r.w);
        // The map holds flux for a white light; the light's color (per unit intensity) tints it here. Spectral
        // photons carried it (glsl/splat.comp, spectral_tint).
        vec3 tint = u_frame.light.light_intensity > 0.0 ? u_frame.light.light_power / u_frame.light.light_intensity : vec3(0.0);
        if (u_frame.pass.channel == CHANNEL_SPECTRAL) tint = vec3(1.0);
        e = flux_rgb(p, size) * tint / area;
    }
    // A color pass (docs/design.md "Color") writes its own channel; the red pass starts the texel, the green
    // and blue passes keep what the earlier ones wrote. One store either way, chosen per channel: a CPU driver runs
    // both sides of a branch, and an image store is a loop over the lanes for each channel. A gray pass and color
    // photons write all three.
    uint c = u_frame.pass.channel;
    bool all_channels = c == 0u || c >= CHANNEL_RGB;
    vec4 prev = pc.keep != 0.0 || !all_channels && c > 1u ? imageLoad(o_irradiance, p) : vec4(0.0);
    bvec3 mine = all_channels ? bvec3(true) : equal(uvec3(1u, 2u, 3u), uvec3(c));
    vec3 rgb = mix(prev.rgb, pc.keep * prev.rgb + pc.scale * e, mine);
    imageStore(o_irradiance, p, vec4(rgb, 0.0));
}
