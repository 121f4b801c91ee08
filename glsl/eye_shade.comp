#version 460
// Eye view of the receivers (docs/design.md step 7), deferred: the raster pass wrote their eye-view g-buffer
// (normal and distance, and albedo); here each pixel is shaded under one light: direct irradiance through a
// filtered shadow map, caustic irradiance averaged over the pixel's footprint on the caustic map, and the
// environment. The first light writes the targets, each further light adds its light (dispatches in order).
// Shading runs on every compute unit: on GPUs whose graphics units are few, a fragment shader doing this is the
// eye view's largest cost.
// Variant WITH_AOVS also writes the caustics and direct AOVs (W/m^2), for frames that read one back.
#include "common/types.glsl"
#include "common/view.glsl"
#include "common/gbuffer.glsl"

layout(std140, set = 0, binding = EB_FRAME) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = EB_SHADOW) uniform sampler2D t_shadow;      // depth of all objects from the light
layout(set = 0, binding = EB_IRRADIANCE) uniform sampler2D t_irradiance;  // caustic irradiance, W/m^2 (linear filtering)
layout(set = 0, binding = EB_RECEIVERS) uniform usampler2D t_recv;       // receivers from the light: normal, distance
layout(set = 0, binding = EB_ENV) uniform sampler2D t_env;                 // the environment map
layout(set = 0, binding = EB_ENV_IRRADIANCE) uniform sampler2D t_env_irradiance;  // its irradiance map

#include "common/receiver.glsl"

layout(set = 0, binding = EB_EYE) uniform usampler2D t_eye;     // receivers from the eye: normal, distance (0: none)
layout(set = 0, binding = EB_ALBEDO) uniform sampler2D t_albedo;   // their albedo
// The eye deposit (docs/design.md "The eye deposit"): caustic flux per eye sample, W, three planes (red, green,
// blue), of the landings the lights' caustic maps could not hold, every light's.
layout(std430, set = 0, binding = EB_EYE_FLUX) readonly buffer EyeFluxBuf { float eye_flux[]; };
#include "common/deposit_eye.glsl"
layout(set = 0, binding = EB_RADIANCE, rgba32f) uniform image2D o_radiance;  // rgb: radiance (W/m^2/sr); a: eye distance
#ifdef WITH_AOVS
layout(set = 0, binding = EB_CAUSTICS, rgba32f) uniform image2D o_caustics;  // rgb: caustic irradiance (W/m^2)
layout(set = 0, binding = EB_DIRECT, rgba32f) uniform image2D o_direct;    // rgb: direct irradiance (W/m^2)
#endif

layout(push_constant) uniform ShadePushBlock { ShadePush pc; };

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void store(ivec2 q, vec4 radiance, vec3 caustic, vec3 direct) {
    if (pc.add != 0u) {
        radiance.rgb += imageLoad(o_radiance, q).rgb;
#ifdef WITH_AOVS
        caustic += imageLoad(o_caustics, q).rgb;
        direct += imageLoad(o_direct, q).rgb;
#endif
    }
    imageStore(o_radiance, q, radiance);
#ifdef WITH_AOVS
    imageStore(o_caustics, q, vec4(caustic, 1.0));
    imageStore(o_direct, q, vec4(direct, 1.0));
#endif
}

// The ray through pixel q's center.
void pixel_ray(GpuView cam, ivec2 q, out vec3 ro, out vec3 rd) { view_ray(cam, (vec2(q) + 0.5) * cam.extent.zw, ro, rd); }

// Where pixel q's ray meets the plane through p with normal n (p itself when the ray grazes it).
vec3 on_plane(GpuView cam, ivec2 q, vec3 p, vec3 n) {
    vec3 ro, rd;
    pixel_ray(cam, q, ro, rd);
    float c = dot(rd, n);
    return abs(c) > 1e-6 ? ro + rd * (dot(p - ro, n) / c) : p;
}

void main() {
    GpuView cam = u_frame.frame.camera;
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = imageSize(o_radiance);
    if (q.x >= size.x || q.y >= size.y) return;
    vec4 g = geo_fetch(t_eye, q);
    if (g.w <= 0.0) {
        // No receiver: the first light clears the pixel, a further one leaves it.
        if (pc.add == 0u) store(q, vec4(0.0), vec3(0.0), vec3(0.0));
        return;
    }
    // The g-buffer's distance runs along the pixel's ray from its origin (view.glsl), for both projections.
    vec3 ro, rd;
    pixel_ray(cam, q, ro, rd);
    vec3 p = ro + rd * g.w;
    vec3 n = g.xyz;
    vec3 e_direct = direct_irradiance(p, n);
    // Caustics, averaged over the pixel's footprint on the map: the uv offsets to where the next pixels' rays
    // meet the receiver's tangent plane (the screen-space derivatives of uv), so that a caustic sharper than a
    // pixel keeps its flux: sum E * pixel area stays the flux that landed under the pixel.
    GpuView lv = u_frame.light.receiver_view;
    vec2 uv = view_uv(lv, p);
    vec2 dx = view_uv(lv, on_plane(cam, q + ivec2(1, 0), p, n)) - uv;
    vec2 dy = view_uv(lv, on_plane(cam, q + ivec2(0, 1), p, n)) - uv;
    // Under camera-driven refinement the eye deposit holds every landing the camera sees: the map is not read.
    vec3 e_caustic = eye_deposit_first() ? vec3(0.0) : caustic_irradiance(p, n, rd, dx, dy);
    // The eye deposit holds every light's: the first light's shading adds it.
    if (pc.add == 0u && u_frame.frame.eye_deposit != 0u) e_caustic += eye_deposit_irradiance(cam, q, size, n, g.w);
    // The environment lights the side the eye sees (its radiance is 0 in further lights' uniforms).
    vec3 n_eye = dot(n, view_dir_to(cam, p)) > 0.0 ? -n : n;
    vec3 e_env = environment_irradiance(n_eye);
    vec3 albedo = texelFetch(t_albedo, q, 0).rgb;
    store(q, vec4(albedo / RECV_PI * (e_direct + e_caustic + e_env), g.w), e_caustic, e_direct);
}
