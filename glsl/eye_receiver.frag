#version 460
// Receiver shading: direct irradiance from the light with a filtered shadow map, and caustic irradiance looked up
// in the light-space irradiance map (only where this point is the surface the light sees). Outputs the AOVs in
// W/m^2, and the radiance with the environment's light added (glsl/common/receiver.glsl).
#include "common/types.glsl"
#include "common/view.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = 1) uniform sampler2D t_shadow;      // depth of all objects from the light
layout(set = 0, binding = 2) uniform sampler2D t_irradiance;  // caustic irradiance, W/m^2 (linear filtering)
layout(set = 0, binding = 3) uniform usampler2D t_recv;       // receivers from the light: normal, distance

#include "common/receiver.glsl"

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
layout(location = 2) flat in vec3 v_albedo;

layout(location = 0) out vec4 o_radiance;  // rgb: outgoing radiance (W/m^2/sr); a: distance from the eye
// Variant RADIANCE_ONLY (frames that read back neither AOV) writes only the radiance: on GPUs with few raster
// units each 128-bit target costs a share of the pass.
#ifndef RADIANCE_ONLY
layout(location = 1) out vec4 o_caustics;  // rgb: caustic irradiance (W/m^2)
layout(location = 2) out vec4 o_direct;    // rgb: direct irradiance (W/m^2)
#endif

void main() {
    vec3 n = normalize(v_normal);
    vec3 p = v_world;
    vec3 e_direct = direct_irradiance(p, n);
    // Caustics, averaged over the pixel's footprint on the map (the screen-space derivatives of its uv), so that
    // a caustic sharper than a pixel keeps its flux: Σ E · pixel area stays the flux that landed under the pixel.
    vec2 uv = view_uv(u_frame.receiver_view, p);
    vec3 e_caustic = caustic_irradiance(p, dFdx(uv), dFdy(uv));
    vec3 dv = p - u_frame.camera.origin.xyz;
    float eye_dist = u_frame.camera.origin.w > 0.5 ? dot(dv, u_frame.camera.forward.xyz) : length(dv);
    // The environment lights the side the eye sees.
    vec3 n_eye = dot(n, view_dir_to(u_frame.camera, p)) > 0.0 ? -n : n;
    vec3 e_env = environment_irradiance(n_eye);
    o_radiance = vec4(v_albedo / RECV_PI * (e_direct + e_caustic + e_env), max(eye_dist, 1e-6));
#ifndef RADIANCE_ONLY
    o_caustics = vec4(e_caustic, 1.0);
    o_direct = vec4(e_direct, 1.0);
#endif
}
