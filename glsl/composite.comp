#version 460
// Eye-view composite (docs/design.md "Eye view"): the glass over the receivers, supersampled, then tone mapped.
// Each output pixel averages AA x AA samples of the eye buffers (rendered AA times larger per side, AA =
// camera extent / beauty width): the linear radiance into the HDR image, and the tone-mapped values (before the
// sRGB encoding) into the beauty image.
// On glass, with EXACT_EYE (`--transport exact`): the glass pass's radiance (glsl/glass.comp). Without it: the
// papers' deferred refraction through two surfaces (Wyman & Nichols sec. 3.1), in the eye g-buffers.
#define GLASS_READ_ONLY
#include "common/composite_bindings.glsl"
#include "common/receiver.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

#ifndef EXACT_EYE
vec3 behind(GpuView cam, vec3 o, vec3 dir) {
    vec3 lo = u_frame.frame.scene_min, hi = u_frame.frame.scene_max;
    vec3 pad = 1e-2 * max(hi - lo, vec3(1.0));
    vec3 hit;
    if (find_surface(cam, t_radiance, o, dir, ray_box_exit(o, dir, lo - pad, hi + pad), hit)) {
        return textureLod(t_radiance_linear, view_uv(cam, hit), 0.0).rgb;
    }
    return environment(dir);
}

vec3 shade_glass(GpuView cam, vec3 ro, vec3 rd, vec4 front, float ior) {
    vec3 p1 = ro + rd * front.w;
    vec3 n1 = dot(front.xyz, rd) > 0.0 ? -front.xyz : front.xyz;
    if (ior < 0.0) return environment(reflect(rd, n1));  // a mirror
    float F1 = fresnel_dielectric(-dot(rd, n1), 1.0, ior);
    vec3 reflected = environment(reflect(rd, n1));
    vec3 t1;
    if (!refract_dir(rd, n1, 1.0 / ior, t1)) return reflected;
    vec3 p2, n2;
    if (!find_exit(cam, t_back, u_frame.frame.refractor_diameter, p1, t1, p2, n2)) {
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
#endif

// Narkowicz's ACES fit (display-linear, in [0, 1]).
vec3 aces(vec3 x) { return clamp((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14), 0.0, 1.0); }

vec3 srgb_encode(vec3 y) {
    return mix(12.92 * y, 1.055 * pow(y, vec3(1.0 / 2.4)) - 0.055, greaterThan(y, vec3(0.0031308)));
}

// Radiance of one eye sample: buffer texel q, at uv on the image plane.
vec3 shade_sample(GpuView cam, ivec2 q, vec2 uv) {
    vec3 ro, rd;
    view_ray(cam, uv, ro, rd);
    vec4 rad = texelFetch(t_radiance, q, 0);
    vec4 front = geo_fetch(t_front, q);
    if (front.w > 0.0 && (rad.w <= 0.0 || front.w < rad.w)) {
#ifdef EXACT_EYE
        // Traced by the glass pass, under every light.
        return imageLoad(o_glass, q).rgb;
#else
        return shade_glass(cam, ro, rd, front, FRONT_IOR(texelFetch(t_front_aux, q, 0).x));
#endif
    }
    if (rad.w > 0.0) return rad.rgb;
    return environment(rd);
}

void main() {
    GpuView cam = u_frame.frame.camera;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    ivec2 out_size = imageSize(o_beauty);
    if (p.x >= out_size.x || p.y >= out_size.y) return;
#ifdef SINGLE_SAMPLE
    // One eye sample per pixel (--aa 1, and the viewer's previews): no averaging loop in the kernel at all.
    vec3 L = shade_sample(cam, p, (vec2(p) + 0.5) * cam.extent.zw);
    imageStore(o_beauty, p, vec4(srgb_encode(aces(L * u_frame.frame.exposure)), 1.0));
    imageStore(o_hdr, p, vec4(L, 1.0));
#else
    int aa = max(int(cam.extent.x) / out_size.x, 1);
    vec3 sum = vec3(0.0), mapped = vec3(0.0);
    for (int j = 0; j < aa; j++) {
        for (int i = 0; i < aa; i++) {
            ivec2 q = p * aa + ivec2(i, j);
            vec3 L = shade_sample(cam, q, (vec2(q) + 0.5) * cam.extent.zw);
            sum += L;
            mapped += aces(L * u_frame.frame.exposure);
        }
    }
    float k = 1.0 / float(aa * aa);
    imageStore(o_beauty, p, vec4(srgb_encode(mapped * k), 1.0));
    imageStore(o_hdr, p, vec4(sum * k, 1.0));
#endif
}
