// Shading of a diffuse receiver point, shared by the deferred eye shading (glsl/eye_shade.comp) and the eye-view ray
// tracer (glsl/glass.comp): direct irradiance from the light through a filtered shadow map, caustic
// irradiance from the light-space caustic map (common/deposit_light_map.glsl), and the environment (docs/design.md "Eye view").
// Needs u_frame and the samplers t_shadow (light depth of all objects), t_irradiance (caustic irradiance, linear
// filtering), t_recv (receivers from the light: normal, distance), t_env (the environment map) and t_env_irradiance (its
// irradiance map).
#ifndef RECEIVER_GLSL
#define RECEIVER_GLSL
#include "common/types.glsl"
#include "common/emitter.glsl"
#include "common/gbuffer.glsl"
#include "common/deposit_light_map.glsl"

const float RECV_PI = 3.14159265358979;

// Depth along the light's forward axis from a shadow-map depth value.
float linear_depth(GpuView v, float z) {
    float n = v.down.w, f = v.forward.w;
    return view_is_ortho(v) ? n + z * (f - n) : f * n / (f - z * (f - n));
}

// Percentage-closer filtering: a 4x4 grid of shadow-map texels with bilinear weights over a 3x3-texel tent (the
// 2x2 bilinear PCF, box-filtered over 3x3 positions a texel apart), so that a shadow edge is a smooth ramp about
// three texels wide instead of a staircase of texels.
// A light with size (`size`: a sun's tangent of its angular radius, over an orthographic shadow map; a sphere
// light's radius, m, over a perspective one): the fraction of it that reaches p. A sun's direction tilted by t (on
// the tangent plane) meets a blocker at depth z_b where the straight ray through p + (z - z_b) t does, so the lit
// fraction is the shadow test averaged over the disk of radius (z - z_b) size around p; a sphere's, of radius
// size (z - z_b) / z_b (Fernando's percentage-closer soft shadows): a blocker search over the widest
// such disk (4x4 tests) gives the blockers' mean depth, then 8x8 tests spread uniformly over that disk, the pattern
// turned by an angle hashed from p's texel (noise, which the eye's samples average, in place of 64 bands). Where the
// search finds no blocker, p sees the whole sun; a penumbra under 1.5 texels takes the 3x3 tent.
// The penumbra's radius (m) that blockers at depth zb cast at depth z from a light of `size` (soft_lit_fraction).
float penumbra(bool ortho, float size, float z, float zb) { return (z - zb) * (ortho ? size : size / max(zb, 1e-3)); }

float soft_lit_fraction(GpuView v, sampler2D shadow, vec3 img, vec2 st, float texel, float slope, float bias_texels,
                        float light_size, out bool hard) {
    hard = false;
    ivec2 size = textureSize(shadow, 0);
    bool ortho = view_is_ortho(v);
    float near = v.down.w;
    // The widest penumbra: blockers at the near plane.
    float search = clamp(penumbra(ortho, light_size, img.z, near) / texel, 1.0, ortho ? float(max(size.x, size.y)) : 128.0);
    float blockers = 0.0, depth = 0.0;
    for (int j = 0; j < 4; j++) {
        for (int i = 0; i < 4; i++) {
            vec2 o = (vec2(i, j) + 0.5) / 2.0 - 1.0;
            ivec2 q = clamp(ivec2(floor(st + 0.5 + o * search)), ivec2(0), size - 1);
            float z = linear_depth(v, texelFetch(shadow, q, 0).x);
            float bias = bias_texels * texel * (1.0 + length(o) * search * slope);
            if (z < img.z - bias) {
                blockers += 1.0;
                depth += z;
            }
        }
    }
    if (blockers == 0.0) return 1.0;
    float w = penumbra(ortho, light_size, img.z, depth / blockers) / texel;
    if (w < 1.5) {
        hard = true;
        return 1.0;
    }
    ivec2 t = ivec2(floor(st));
    float turn = float(emitter_hash(uint(t.x) * 73856093u ^ uint(t.y) * 19349663u) >> 8) * (6.28318531 / 16777216.0);
    mat2 rot = mat2(cos(turn), sin(turn), -sin(turn), cos(turn));
    float lit = 0.0;
    for (int j = 0; j < 8; j++) {
        for (int i = 0; i < 8; i++) {
            vec2 o = w * (rot * emitter_disk((vec2(i, j) + 0.5) / 8.0));
            ivec2 q = clamp(ivec2(floor(st + 0.5 + o)), ivec2(0), size - 1);
            float bias = bias_texels * texel * (1.0 + length(o) * slope);
            lit += img.z - bias <= linear_depth(v, texelFetch(shadow, q, 0).x) ? 1.0 : 0.0;
        }
    }
    return lit / 64.0;
}

float lit_fraction_in(GpuView v, sampler2D shadow, float bias_texels, float light_size, vec3 p, vec3 n) {
    vec3 img = view_image(v, p);
    vec2 uv = (img.xy - v.window.xy) / v.window.zw;
    if (!uv_inside_strict(uv)) return 1.0;
    float texel = view_sample_side(v, img.z);
    vec3 l = -view_dir_to(v, p);
    float cos_t = clamp(abs(dot(n, l)), 0.05, 1.0);
    if (light_size > 0.0) {
        bool hard;
        float slope = sqrt(1.0 - cos_t * cos_t) / cos_t;
        vec2 st0 = uv * vec2(textureSize(shadow, 0)) - 0.5;
        float lit = soft_lit_fraction(v, shadow, img, st0, texel, slope, bias_texels, light_size, hard);
        if (!hard) return lit;
    }
    // The tent reaches 2 texels out: the bias grows with it along the slope.
    float bias = bias_texels * texel * (1.0 + 2.0 * sqrt(1.0 - cos_t * cos_t) / cos_t);
    ivec2 size = textureSize(shadow, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st)) - 1;
    vec2 f = st - floor(st);
    // Weights of texel offsets -1..2 along one axis: the 1-texel linear kernel convolved with a 3-tap box.
    vec4 wx = vec4(1.0 - f.x, 1.0, 1.0, f.x) / 3.0;
    vec4 wy = vec4(1.0 - f.y, 1.0, 1.0, f.y) / 3.0;
    float lit = 0.0;
    for (int j = 0; j < 4; j++) {
        for (int i = 0; i < 4; i++) {
            float z = texelFetch(shadow, clamp(i0 + ivec2(i, j), ivec2(0), size - 1), 0).x;
            lit += wx[i] * wy[j] * (img.z - bias <= linear_depth(v, z) ? 1.0 : 0.0);
        }
    }
    return lit;
}

// Direct irradiance (W/m^2) at p with normal n from a light with view lv and power (W/sr, or W/m^2 across a
// directional beam), shadowed by its shadow map (softened by its size: shadow_size).
vec3 direct_irradiance_in(GpuView lv, vec3 power, float bias_texels, float light_size, sampler2D shadow, vec3 p, vec3 n) {
    vec3 img = view_image(lv, p);
    vec3 l = -view_dir_to(lv, p);
    float cos_s = dot(n, l);
    if (!(cos_s > 0.0 && emitter_holds(lv, img.xy) && img.z > 0.0)) return vec3(0.0);
    float d2 = view_is_ortho(lv) ? 1.0 : dot(p - lv.origin.xyz, p - lv.origin.xyz);
    return power * cos_s / d2 * lit_fraction_in(lv, shadow, bias_texels, light_size, p, n);
}

// A light's size for its soft shadows: a sun's tangent of its angular radius, a sphere light's radius (m).
float shadow_size(LightUniforms l) { return view_is_ortho(l.receiver_view) ? l.beam_spread : l.light_radius; }

// The frame's light (u_frame, t_shadow, t_irradiance, t_recv): what the eye shading and the composite use.
vec3 direct_irradiance(vec3 p, vec3 n) {
    return direct_irradiance_in(u_frame.light.receiver_view, u_frame.light.light_power, u_frame.frame.shadow_bias,
                                shadow_size(u_frame.light), t_shadow, p, n);
}
vec3 caustic_irradiance(vec3 p, vec3 n, vec3 eye, vec2 dx, vec2 dy) {
    return light_map_irradiance(u_frame.light.receiver_view, t_irradiance, t_recv, p, n, eye, dx, dy);
}

// The environment (docs/design.md "Environment"), seen directly, in reflections and through glass. With a map
// (`environment` = 1): its equirectangular radiance times `sky` (W/(m^2 sr) per map unit). Without: a sky of radiance
// L_sky * SKY_TINT over the upper hemisphere and a ground of L_sky * GROUND_TINT below, with L_sky = `sky` in
// W/(m^2 sr) (0: off), with a soft horizon (±3°) for looks.
// A shader that knows the scene has no environment map defines ENVIRONMENT_MAP false (a specialization constant),
// so that it compiles no map lookups.
#ifndef ENVIRONMENT_MAP
#define ENVIRONMENT_MAP true
#endif
const vec3 SKY_TINT = vec3(0.85, 0.95, 1.20);
const vec3 GROUND_TINT = vec3(0.30, 0.28, 0.25);

// The map's texture coordinates of unit direction d (src/scene/environment.rs): u = 0.5 + atan(x, -z) / 2pi,
// v = acos(y) / pi.
vec2 equirect_uv(vec3 d) {
    return vec2(0.5 + atan(d.x, -d.z) * (0.5 / RECV_PI), acos(clamp(d.y, -1.0, 1.0)) / RECV_PI);
}

vec3 environment(vec3 d) {
    if (ENVIRONMENT_MAP && u_frame.frame.environment > 0.5) return u_frame.pass.sky * textureLod(t_env, equirect_uv(d), 0.0).rgb;
    float up = clamp(d.y, -1.0, 1.0);
    return u_frame.pass.sky * mix(GROUND_TINT, SKY_TINT, smoothstep(-0.05, 0.05, up));
}

// Irradiance (W/m^2) of the environment on an unoccluded plane with unit normal n. With a map: its irradiance
// map (the cosine-weighted integral over the map for each texel's normal, interpolated bilinearly). Without: exact
// for the two hemispheres (the horizon band aside): a uniform upper hemisphere seen from a plane tilted by a
// gives pi L (1 + cos a) / 2.
vec3 environment_irradiance(vec3 n) {
    if (ENVIRONMENT_MAP && u_frame.frame.environment > 0.5) {
        // The irradiance map's rows run from pole to pole (src/scene/environment.rs): row j at v = j / (h - 1).
        vec2 uv = equirect_uv(n);
        float h = float(textureSize(t_env_irradiance, 0).y);
        uv.y = (uv.y * (h - 1.0) + 0.5) / h;
        return u_frame.pass.sky * textureLod(t_env_irradiance, uv, 0.0).rgb;
    }
    float c = clamp(n.y, -1.0, 1.0);
    return RECV_PI * u_frame.pass.sky * (SKY_TINT * (1.0 + c) + GROUND_TINT * (1.0 - c)) * 0.5;
}

#endif
