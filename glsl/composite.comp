#version 460
// Eye-view composite: deferred refraction of the refractors (Wyman & Nichols sec. 3.1) over the receivers, then
// tone mapping into the 8-bit beauty image. Per pixel on glass: Fresnel reflection of the environment, and the
// refracted ray through the front surface, to the back surface (bracketed search in the eye back buffer), out
// again (total internal reflection handled), to whatever lies behind in the eye-view receiver buffer (bracketed
// secant search), or the environment where it misses.
#include "common/types.glsl"
#include "common/view.glsl"
#include "common/optics.glsl"
#include "common/march.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = 1) uniform sampler2D t_radiance;      // receivers: rgb radiance, a: eye distance
layout(set = 0, binding = 2) uniform sampler2D t_front;         // refractor front: normal, eye distance
layout(set = 0, binding = 3) uniform sampler2D t_front_aux;     // refractor front: index of refraction
layout(set = 0, binding = 4) uniform sampler2D t_back;          // refractor back: normal, eye distance
layout(set = 0, binding = 5) uniform sampler2D t_radiance_lin;  // the radiance buffer, linear filtering
layout(set = 0, binding = 6, rgba8) uniform writeonly image2D o_beauty;
layout(set = 0, binding = 7, rgba32f) uniform writeonly image2D o_hdr;  // linear radiance, before exposure

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

// A dim sky over a darker ground, in units of the scene's reference radiance.
vec3 environment(vec3 d) {
    float ref = 1.0 / u_frame.scene_max.w;
    float up = clamp(d.y, -1.0, 1.0);
    vec3 sky = mix(vec3(0.30, 0.33, 0.38), vec3(0.16, 0.22, 0.34), max(up, 0.0));
    vec3 ground = vec3(0.08, 0.075, 0.07);
    return ref * mix(ground, sky, smoothstep(-0.05, 0.05, up));
}

vec3 behind(View cam, vec3 o, vec3 dir) {
    vec3 lo = u_frame.scene_min.xyz, hi = u_frame.scene_max.xyz;
    vec3 pad = 1e-2 * max(hi - lo, vec3(1.0));
    vec3 hit;
    if (find_surface(cam, t_radiance, o, dir, ray_box_exit(o, dir, lo - pad, hi + pad), hit)) {
        return textureLod(t_radiance_lin, view_uv(cam, hit), 0.0).rgb;
    }
    return environment(dir);
}

vec3 shade_glass(View cam, vec3 ro, vec3 rd, vec4 front, float ior) {
    vec3 p1 = ro + rd * front.w;
    vec3 n1 = dot(front.xyz, rd) > 0.0 ? -front.xyz : front.xyz;
    if (ior < 0.0) return environment(reflect(rd, n1));  // a mirror
    float F1 = fresnel_dielectric(-dot(rd, n1), 1.0, ior);
    vec3 reflected = environment(reflect(rd, n1));
    vec3 t1;
    if (!refract_dir(rd, n1, 1.0 / ior, t1)) return reflected;
    vec3 p2, n2;
    if (!find_exit(cam, t_back, u_frame.scene_min.w, p1, t1, p2, n2)) {
        return F1 * reflected + (1.0 - F1) * behind(cam, p1, t1);
    }
    if (dot(n2, t1) < 0.0) n2 = -n2;
    float F2 = fresnel_dielectric(dot(t1, n2), ior, 1.0);
    vec3 t2;
    vec3 transmitted;
    if (refract_dir(t1, -n2, ior, t2)) {
        // The internally reflected part (F2) would need a third interface: approximate it by the environment.
        transmitted = (1.0 - F2) * behind(cam, p2, t2) + F2 * environment(reflect(t1, -n2));
    } else {
        transmitted = environment(reflect(t1, -n2));  // total internal reflection at the back surface
    }
    return F1 * reflected + (1.0 - F1) * transmitted;
}

vec3 tonemap(vec3 x) {
    // Narkowicz's ACES fit, then the sRGB transfer function.
    vec3 y = clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0);
    return mix(12.92 * y, 1.055 * pow(y, vec3(1.0 / 2.4)) - 0.055, greaterThan(y, vec3(0.0031308)));
}

void main() {
    View cam = u_frame.camera;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 size = ivec2(cam.extent.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    vec2 uv = (vec2(p) + 0.5) * cam.extent.zw;
    vec3 ro, rd;
    view_ray(cam, uv, ro, rd);
    vec4 rad = texelFetch(t_radiance, p, 0);
    vec4 front = texelFetch(t_front, p, 0);
    vec3 L;
    if (front.w > 0.0 && (rad.w <= 0.0 || front.w < rad.w)) {
        L = shade_glass(cam, ro, rd, front, texelFetch(t_front_aux, p, 0).x);
    } else if (rad.w > 0.0) {
        L = rad.rgb;
    } else {
        L = environment(rd);
    }
    imageStore(o_beauty, p, vec4(tonemap(L * u_frame.scene_max.w), 1.0));
    imageStore(o_hdr, p, vec4(L, 1.0));
}
