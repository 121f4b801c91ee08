#version 460
// Receiver shading: direct irradiance from the light with a shadow map, and caustic irradiance looked up in the
// light-space irradiance map (only where this point is the surface the light sees). Outputs the AOVs in W/m^2.
#include "common/types.glsl"
#include "common/view.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = 1) uniform sampler2D t_shadow;      // depth of all objects from the light
layout(set = 0, binding = 2) uniform sampler2D t_irradiance;  // caustic irradiance, W/m^2 (linear filtering)
layout(set = 0, binding = 3) uniform sampler2D t_recv;        // receivers from the light: normal, distance

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in vec3 v_albedo;

layout(location = 0) out vec4 o_radiance;  // rgb: outgoing radiance (W/m^2/sr); a: distance from the eye
layout(location = 1) out vec4 o_caustics;  // rgb: caustic irradiance (W/m^2)
layout(location = 2) out vec4 o_direct;    // rgb: direct irradiance (W/m^2)

const float PI = 3.14159265358979;

// Depth along the light's forward axis from a shadow-map depth value.
float linear_depth(View v, float z) {
    float n = v.down.w, f = v.forward.w;
    return view_is_ortho(v) ? n + z * (f - n) : f * n / (f - z * (f - n));
}

// 2x2 percentage-closer filtering with bilinear weights.
float lit_fraction(View v, vec3 p, vec3 n) {
    vec3 img = view_image(v, p);
    vec2 uv = (img.xy - v.window.xy) / v.window.zw;
    if (!uv_inside_strict(uv)) return 1.0;
    float texel = v.window.z * v.extent.z * (view_is_ortho(v) ? 1.0 : img.z);
    vec3 l = -view_dir_to(v, p);
    float cos_t = clamp(abs(dot(n, l)), 0.05, 1.0);
    float bias = u_frame.params.y * texel * (1.0 + sqrt(1.0 - cos_t * cos_t) / cos_t);
    ivec2 size = textureSize(t_shadow, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st));
    vec2 f = st - vec2(i0);
    float lit = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        float z = texelFetch(t_shadow, clamp(i0 + o, ivec2(0), size - 1), 0).x;
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        lit += w * (img.z - bias <= linear_depth(v, z) ? 1.0 : 0.0);
    }
    return lit;
}

void main() {
    vec3 n = normalize(v_normal);
    vec3 p = v_world;
    View lv = u_frame.receiver_view;
    // Direct light.
    vec3 e_direct = vec3(0.0);
    {
        vec3 img = view_image(lv, p);
        bool ortho = view_is_ortho(lv);
        vec3 l = -view_dir_to(lv, p);
        float cos_s = dot(n, l);
        bool in_cone = view_in_cone(lv, img.xy);
        if (cos_s > 0.0 && in_cone && img.z > 0.0) {
            float d2 = ortho ? 1.0 : dot(p - lv.origin.xyz, p - lv.origin.xyz);
            e_direct = u_frame.light_power.rgb * cos_s / d2 * lit_fraction(lv, p, n);
        }
    }
    // Caustics, from the light-space map: the average of the irradiance over the pixel's footprint on the map
    // (up to 8x8 bilinear taps spread along the screen-space derivatives), so that a caustic sharper than a pixel
    // keeps its flux: Σ E · pixel area stays the flux that landed under the pixel.
    vec3 e_caustic = vec3(0.0);
    {
        vec2 uv = view_uv(lv, p);
        vec2 dx = dFdx(uv), dy = dFdy(uv);
        if (uv_inside_strict(uv)) {
            ivec2 size = textureSize(t_recv, 0);
            vec4 r = texelFetch(t_recv, clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1), 0);
            float d = view_dist(lv, p);
            float texel = lv.window.z * lv.extent.z * (view_is_ortho(lv) ? 1.0 : d);
            if (r.w > 0.0 && abs(r.w - d) < 4.0 * texel + 1e-3 * d) {
                vec2 fx = dx * vec2(size), fy = dy * vec2(size);
                int nx = int(clamp(ceil(length(fx)), 1.0, 8.0));
                int ny = int(clamp(ceil(length(fy)), 1.0, 8.0));
                for (int j = 0; j < ny; j++) {
                    for (int i = 0; i < nx; i++) {
                        vec2 o = vec2((float(i) + 0.5) / float(nx) - 0.5, (float(j) + 0.5) / float(ny) - 0.5);
                        e_caustic += textureLod(t_irradiance, uv + o.x * dx + o.y * dy, 0.0).rgb;
                    }
                }
                e_caustic /= float(nx * ny);
            }
        }
    }
    vec3 dv = p - u_frame.camera.origin.xyz;
    float eye_dist = u_frame.camera.origin.w > 0.5 ? dot(dv, u_frame.camera.forward.xyz) : length(dv);
    o_radiance = vec4(v_albedo / PI * (e_direct + e_caustic), max(eye_dist, 1e-6));
    o_caustics = vec4(e_caustic, 1.0);
    o_direct = vec4(e_direct, 1.0);
}
