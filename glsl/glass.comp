#version 460
// The glass pass of exact transport (docs/design.md "Eye view"), dispatched before the composite at the eye buffers'
// resolution: each eye sample that sees glass first traces the eye ray through the scene BVH, splitting at every
// dielectric interface into its reflected and refracted branches (Fresnel, total internal reflection, mirrors,
// Beer–Lambert absorption inside the glass) down to the depth cap; a branch ends on a diffuse receiver (shaded
// with every bound light's direct light and caustic irradiance, and the environment's light) or in the
// environment. Its radiance goes to o_glass, which the composite reads.
#include "common/composite_bindings.glsl"

// Specialization constants (src/passes/composite.rs, GlassKey): what the scene and the pass need, so that a CPU
// driver, which runs both sides of every branch under a mask, runs no code for what the scene lacks. Each flag is
// tested together with the uniform it mirrors.
// The lights whose maps are bound, 1-3 (the first's at CB_FRAME, CB_SHADOW, ...).
layout(constant_id = GLASS_LIGHT_COUNT_ID) const uint GLASS_LIGHT_COUNT = 1u;
layout(constant_id = GLASS_DISPERSIVE_ID) const bool GLASS_DISPERSIVE = true;  // some glass disperses (u_frame.frame.disperses)
layout(constant_id = GLASS_ENVIRONMENT_ID) const bool GLASS_ENVIRONMENT = true;  // an environment map (u_frame.frame.environment)
layout(constant_id = GLASS_TEXTURED_ID) const bool GLASS_TEXTURED = true;  // some receiver has an albedo texture
layout(constant_id = GLASS_MEDIA_ID) const bool GLASS_MEDIA = true;  // absorbing or overlapping media (ResolvedSettings::media)
#define ENVIRONMENT_MAP GLASS_ENVIRONMENT
// The pass's second and third lights: uniforms, shadow map, caustic map, receivers from the light. (The
// environment comes with u_frame: a later pass's first light carries none.)
layout(std140, set = 0, binding = CB_LIGHT1) uniform Light1 { FrameData u_light1; };
layout(set = 0, binding = CB_SHADOW1) uniform sampler2D t_shadow1;
layout(set = 0, binding = CB_IRRADIANCE1) uniform sampler2D t_irradiance1;
layout(set = 0, binding = CB_RECEIVERS1) uniform usampler2D t_recv1;
layout(std140, set = 0, binding = CB_LIGHT2) uniform Light2 { FrameData u_light2; };
layout(set = 0, binding = CB_SHADOW2) uniform sampler2D t_shadow2;
layout(set = 0, binding = CB_IRRADIANCE2) uniform sampler2D t_irradiance2;
layout(set = 0, binding = CB_RECEIVERS2) uniform usampler2D t_recv2;

#include "common/receiver.glsl"
#include "common/deposit_eye.glsl"

#include "common/bvh_types.glsl"
layout(std430, set = 0, binding = CB_BVH_PAIR) readonly buffer BvhPair { PairNode bvh_nodes[]; };
#ifdef BVH_TEXELS
layout(set = 0, binding = CB_BVH_INSTANCES) uniform samplerBuffer bvh_instance_texels;
layout(set = 0, binding = CB_BVH_TRIS) uniform samplerBuffer bvh_tri_texels;
layout(set = 0, binding = CB_BVH_NORMALS) uniform samplerBuffer bvh_normal_texels;
layout(set = 0, binding = CB_BVH_WIDE) uniform usamplerBuffer bvh_wide_texels;
layout(set = 0, binding = CB_BVH_WIDE_PRIMS) uniform usamplerBuffer bvh_wide_prim_texels;
#else
layout(std430, set = 0, binding = CB_BVH_INSTANCES) readonly buffer BvhInstances { GpuInstance bvh_instances[]; };
layout(std430, set = 0, binding = CB_BVH_TRIS) readonly buffer BvhTris { vec4 bvh_tris[]; };
layout(std430, set = 0, binding = CB_BVH_NORMALS) readonly buffer BvhNormals { vec4 bvh_normal_rows[]; };
#endif
#include "common/bvh.glsl"
#define GRAY_MATERIALS
#include "common/interface.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

// Direct and caustic irradiance at receiver point p (shading normal ns), which the eye's ray reaches along d, from
// one light, its caustics averaged over the pixel's footprint: the square of side `width` on the tangent plane
// (axes t1, t2), in its caustic map (`maps`: else direct light only).
vec3 light_irradiance(GpuView lv, vec3 power, float bias, float spread, sampler2D shadow, sampler2D irr, usampler2D recv,
                      vec3 p, vec3 ns, vec3 d, vec3 t1, vec3 t2, float width, bool maps) {
    vec3 e = direct_irradiance_in(lv, power, bias, spread, shadow, p, ns);
    if (!maps) return e;
    vec2 uv = view_uv(lv, p);
    vec2 dx = view_uv(lv, p + t1 * width) - uv, dy = view_uv(lv, p + t2 * width) - uv;
    return e + light_map_irradiance(lv, irr, recv, p, ns, d, dx, dy);
}

// The same summed over the pass's lights (GLASS_LIGHT_COUNT of them).
vec3 lights_irradiance(vec3 p, vec3 ns, vec3 d, vec3 t1, vec3 t2, float width, bool maps) {
    vec3 e = light_irradiance(u_frame.light.receiver_view, u_frame.light.light_power, u_frame.frame.shadow_bias, shadow_size(u_frame.light), t_shadow,
                              t_irradiance, t_recv, p, ns, d, t1, t2, width, maps);
    if (GLASS_LIGHT_COUNT > 1u) {
        e += light_irradiance(u_light1.light.receiver_view, u_light1.light.light_power, u_light1.frame.shadow_bias, shadow_size(u_light1.light), t_shadow1,
                              t_irradiance1, t_recv1, p, ns, d, t1, t2, width, maps);
    }
    if (GLASS_LIGHT_COUNT > 2u) {
        e += light_irradiance(u_light2.light.receiver_view, u_light2.light.light_power, u_light2.frame.shadow_bias, shadow_size(u_light2.light), t_shadow2,
                              t_irradiance2, t_recv2, p, ns, d, t1, t2, width, maps);
    }
    return e;
}

// The eye deposit's irradiance at receiver point p (shading normal ns) that an eye ray reached through glass: where
// the eye sample that p projects to sees p itself (the receivers' radiance holds that sample's eye distance in
// .a, 0 where it sees none: receiver_seen), its flux over the receiver area the sample covers at p, as the eye
// shading reads it for the samples that see p directly.
vec3 eye_deposit_at(vec3 p, vec3 ns) {
    GpuView cam = u_frame.frame.camera;
    vec2 uv;
    if (!receiver_seen(cam, t_radiance, p, uv)) return vec3(0.0);
    ivec2 size = textureSize(t_radiance, 0);
    ivec2 q = clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1);
    return eye_deposit_irradiance(cam, q, size, ns, view_dist(cam, p));
}

// A branch below this fraction of the eye ray's throughput is not traced: it takes the environment's radiance
// in its direction instead (so that nothing turns black where the tree is cut).
const float EYE_THRESHOLD = 0.05;
const int EYE_STACK = 8;

// Radiance along the eye ray ro + t rd (which reaches glass first), through every interface, with the IORs of
// channel c (0: the d line, for glass that does not disperse), under every light and the environment. Each branch
// knows the medium it travels in (the eye is in air; docs/design.md "Media"), and each segment is absorbed by it per
// channel (Beer–Lambert with the red, green and blue coefficients), so the colors of absorbing glass, and of a floor
// seen through a liquid, show in every trace. A segment in an absorbing medium that meets nothing is absorbed
// entirely: the medium has no end there. A receiver reached through the
// glass takes its caustic irradiance averaged over the pixel's footprint there: the pixel's width at the distance
// the ray has run (the glass's own magnification aside), across the receiver's tangent plane.
vec3 trace_glass(vec3 ro, vec3 rd, uint c) {
    uint cap = uint(u_frame.frame.eye_depth);
    GpuView cam = u_frame.frame.camera;
    // A pixel's width at unit distance (perspective) or its width (orthographic).
    float pixel = cam.window.z * cam.extent.z;
    bool ortho = view_is_ortho(cam);
    vec3 so[EYE_STACK], sd[EYE_STACK], sw[EYE_STACK];
    uint sn[EYE_STACK], sm[EYE_STACK];
    uvec2 sv[EYE_STACK];
    float sl[EYE_STACK];
    int sp = 0;
    so[0] = ro; sd[0] = rd; sw[0] = vec3(1.0); sn[0] = 0u; sl[0] = 0.0; sm[0] = AIR; sv[0] = uvec2(0u);
    sp = 1;
    vec3 L = vec3(0.0);
    while (sp > 0) {
        sp--;
        vec3 o = so[sp], d = sd[sp], w = sw[sp];
        uint depth = sn[sp], m = GLASS_MEDIA ? sm[sp] : AIR;
        uvec2 nested = GLASS_MEDIA ? sv[sp] : uvec2(0u);
        float run = sl[sp];
        vec3 sigma = GLASS_MEDIA ? medium_sigma_rgb(m) : vec3(0.0);
        SceneHit hit;
        if (!bvh_closest(o, d, 1.0 / 0.0, hit)) {
            L += w * vec3(equal(sigma, vec3(0.0))) * environment(d);
            continue;
        }
        if (GLASS_MEDIA) w *= exp(-sigma * hit.t);
        vec3 p = bvh_hit_point(hit);
        vec3 ng, ns;
        bvh_normals(hit, ng, ns);
        GpuInstance I = bvh_instance(hit.inst);
        if (!inst_is_dielectric(hit.inst)) {
            vec3 albedo = I.pad.yzw;
            float width = pixel * (ortho ? 1.0 : run + hit.t);
            if (GLASS_TEXTURED && I.material.w > 0.5) {
                // A textured receiver: its uv (packed in the triangle's and the normals' w) through the instance's
                // uv transform, read at the mip the pixel's footprint there spans: its width times the texels per
                // meter of this triangle (the square root of its uv area over its world area, in texels).
                uint t = hit.tri;
                vec3 b = hit.bary;
                vec2 u0 = vec2(bvh_tri(3u * t).w, bvh_normal_row(3u * t).w);
                vec2 u1 = vec2(bvh_tri(3u * t + 1u).w, bvh_normal_row(3u * t + 1u).w);
                vec2 u2 = vec2(bvh_tri(3u * t + 2u).w, bvh_normal_row(3u * t + 2u).w);
                mat2 m = mat2(I.ior_rgb.x, I.sigma_rgb.x, I.ior_rgb.y, I.sigma_rgb.y);
                vec2 uv = m * (u0 * b.x + u1 * b.y + u2 * b.z) + vec2(I.ior_rgb.z, I.sigma_rgb.z);
                vec2 e1 = m * (u1 - u0), e2 = m * (u2 - u0);
                vec3 q0 = bvh_tri(3u * t).xyz;
                vec3 w1 = bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2],
                                    bvh_tri(3u * t + 1u).xyz - q0, 0.0);
                vec3 w2 = bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2],
                                    bvh_tri(3u * t + 2u).xyz - q0, 0.0);
                float uv_area = abs(e1.x * e2.y - e1.y * e2.x);
                float world_area = length(cross(w1, w2));
                float texels = sqrt(uv_area / max(world_area, 1e-30)) * float(textureSize(t_albedo_textures, 0).x);
                float lod = log2(max(width * texels, 1e-6));
                albedo *= textureLod(t_albedo_textures, vec3(uv, I.material.w - 1.0), lod).rgb;
            }
            vec3 n_eye = dot(ns, d) > 0.0 ? -ns : ns;
            vec3 t1 = normalize(cross(ns, abs(ns.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
            vec3 t2 = cross(ns, t1);
            // Under camera-driven refinement the eye deposit holds every landing on a point the eye's samples see
            // directly: the lights' maps are read only elsewhere, as the eye shading does.
            vec2 uv_eye;
            bool maps = !eye_deposit_first() || !receiver_seen(u_frame.frame.camera, t_radiance, p, uv_eye);
            vec3 e = lights_irradiance(p, ns, d, t1, t2, width, maps) + environment_irradiance(n_eye);
            // The eye deposit holds every light's: the first glass pass adds it.
            if (pc.add == 0u && u_frame.frame.eye_deposit != 0u) e += eye_deposit_at(p, ns);
            L += w * albedo / RECV_PI * e;
            continue;
        }
        if (depth >= cap) {
            L += w * environment(d);
            continue;
        }
        Crossing x = crossing_at(hit.inst, dot(d, ng) < 0.0, m, nested, c, GLASS_MEDIA);
        if (GLASS_MEDIA && x.through) {
            // A volume's surface inside one of higher priority: no interface; the branch goes on beyond it.
            so[sp] = offset_ray(p, dot(d, ng) > 0.0 ? ng : -ng); sd[sp] = d; sw[sp] = w; sn[sp] = depth + 1u;
            sl[sp] = run + hit.t; sm[sp] = x.m_refr; sv[sp] = x.l_refr;
            sp++;
            continue;
        }
        Split s = split_interface(d, p, ng, ns, x.n_in, x.n_out, inst_is_mirror(hit.inst));
        if (!s.ok) continue;
        // The refraction crosses the surface (x's medium and volumes); the reflection stays in the branch's.
        vec3 wr = w * s.F, wt = w * (1.0 - s.F);
        if (s.F < 1.0) {
            if (max(wt.r, max(wt.g, wt.b)) >= EYE_THRESHOLD && sp < EYE_STACK) {
                so[sp] = s.p_refr; sd[sp] = normalize(s.refr); sw[sp] = wt; sn[sp] = depth + 1u;
                sl[sp] = run + hit.t; sm[sp] = x.m_refr; sv[sp] = x.l_refr;
                sp++;
            } else {
                L += wt * environment(normalize(s.refr));
            }
        }
        if (max(wr.r, max(wr.g, wr.b)) >= EYE_THRESHOLD && sp < EYE_STACK) {
            so[sp] = s.p_refl; sd[sp] = normalize(s.refl); sw[sp] = wr; sn[sp] = depth + 1u;
            sl[sp] = run + hit.t; sm[sp] = m; sv[sp] = nested;
            sp++;
        } else {
            L += wr * environment(normalize(s.refl));
        }
    }
    return L;
}

// Eye sample q's ray.
void sample_ray(ivec2 q, out vec3 ro, out vec3 rd) {
    view_ray(u_frame.frame.camera, (vec2(q) + 0.5) * u_frame.frame.camera.extent.zw, ro, rd);
}

// Whether eye sample q sees glass first.
bool sees_glass(ivec2 q) {
    vec4 rad = texelFetch(t_radiance, q, 0);
    vec4 front = geo_fetch(t_front, q);
    return front.w > 0.0 && (rad.w <= 0.0 || front.w < rad.w);
}

// Write sample q's glass radiance (alpha: it sees glass), onto what an earlier pass wrote where pc.add says.
void store_glass(ivec2 q, vec3 L, bool glass) {
    if (pc.add != 0u) L += imageLoad(o_glass, q).rgb;
    imageStore(o_glass, q, vec4(L, glass ? 1.0 : 0.0));
}

// Sample q's radiance through dispersive glass: one trace at a wavelength in each eye bin (spread by u), each
// channel the bins' traces weighed by their shares of its response (EYE_BIN_SHARES).
vec3 trace_spectral(ivec2 q, float u) {
    vec3 o, d, L = vec3(0.0);
    sample_ray(q, o, d);
    for (uint b = 0u; b < EYE_BINS; b++) {
        ray_nm = eye_wavelength(b, u);
        L += EYE_BIN_SHARES[b] * trace_glass(o, d, 0u);
    }
    ray_nm = 0.0;
    return L;
}

// Dispersive glass at 2×2 samples a pixel (pc.pixels): one invocation traces pixel p's four samples, spectrally:
// a wavelength in each of the EYE_BINS bins (spread over the pixels by eye_jitter), each channel the bins' traces
// weighed by their shares of its response. Where all four samples see glass, the samples of one diagonal (a hash of
// the pixel picks which) trace bins 0 and 2, and 2 and 4, those of the other 1 and 3, and 3 and 5: eight traces,
// and every sample takes the pixel's result, each bin's traces averaged. Bin 2 is traced at both samples of one
// diagonal and bin 3 at both of the other, so an edge seen through the glass (any line through the pixel between
// its samples makes one diagonal straddle it) shows as the two traces of one wavelength differing by more than a
// tenth; there, and where only some samples see glass (its silhouette), every sample that sees glass traces every
// bin. The traces run in one loop over (sample, bin) jobs, so that the trace is compiled once.
void glass_pixel(ivec2 p) {
    bool glass[4];
    uint seen = 0u;
    for (int k = 0; k < 4; k++) {
        glass[k] = sees_glass(2 * p + ivec2(k & 1, k >> 1));
        seen += glass[k] ? 1u : 0u;
    }
    // Jobs as (sample, bin) bits: sample k, bin b traced where bit EYE_BINS k + b of `todo` is set.
    uint diag = spectrum_hash(uint(p.x) ^ spectrum_hash(uint(p.y))) & 1u;
    uint a0 = diag, a1 = 3u - diag, g0 = 1u - diag, g1 = 2u + diag;
    uint mosaic = (5u << (EYE_BINS * a0)) | (20u << (EYE_BINS * a1)) | (10u << (EYE_BINS * g0)) |
                  (40u << (EYE_BINS * g1));
    uint everything = 0u;
    for (uint k = 0u; k < 4u; k++) everything |= glass[k] ? ((1u << EYE_BINS) - 1u) << (EYE_BINS * k) : 0u;
    uint todo = seen == 4u ? mosaic : everything;
    float u = eye_jitter(p);
    vec3 L[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    // The two traces of bin 2 (at a0, a1) and of bin 3 (at g0, g1).
    vec3 probe[4] = vec3[4](vec3(0.0), vec3(0.0), vec3(0.0), vec3(0.0));
    for (int pass = 0; pass < 2; pass++) {
        while (todo != 0u) {
            uint bit = uint(findLSB(todo));
            todo &= todo - 1u;
            uint k = bit / EYE_BINS, b = bit % EYE_BINS;
            vec3 o, d;
            sample_ray(2 * p + ivec2(k & 1u, k >> 1), o, d);
            ray_nm = eye_wavelength(b, u);
            vec3 t = trace_glass(o, d, 0u);
            L[k] += EYE_BIN_SHARES[b] * t;
            if (b == 2u || b == 3u) probe[(b - 2u) * 2u + (k == a0 || k == g0 ? 0u : 1u)] = t;
        }
        ray_nm = 0.0;
        if (pass == 1 || seen != 4u) break;
        vec3 r = vec3(probe[0]), s = vec3(probe[1]), g = vec3(probe[2]), h = vec3(probe[3]);
        if (any(greaterThan(abs(r - s), 0.1 * max(r, s) + 1e-6)) ||
            any(greaterThan(abs(g - h), 0.1 * max(g, h) + 1e-6))) {
            // An edge: every sample's other bins too.
            todo = everything & ~mosaic;
        } else {
            // Each bin once: the probes' two traces averaged.
            vec3 pixel = L[0] + L[1] + L[2] + L[3] - 0.5 * EYE_BIN_SHARES[2] * (r + s) - 0.5 * EYE_BIN_SHARES[3] * (g + h);
            for (int k = 0; k < 4; k++) L[k] = pixel;
            break;
        }
    }
    for (int k = 0; k < 4; k++) store_glass(2 * p + ivec2(k & 1, k >> 1), L[k], glass[k]);
}

// One eye sample (eye-buffer texel) per invocation: where glass is in front, its radiance under every light.
void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (GLASS_DISPERSIVE && pc.pixels != 0u) {
        if (2 * q.x < imageSize(o_glass).x && 2 * q.y < imageSize(o_glass).y) glass_pixel(q);
        return;
    }
    if (q.x >= imageSize(o_glass).x || q.y >= imageSize(o_glass).y) return;
    bool glass = sees_glass(q);
    vec3 L = vec3(0.0);
    if (glass) {
        // Dispersive glass (FrameUniforms.disperses): each wavelength follows its own IOR's path.
        if (GLASS_DISPERSIVE && u_frame.frame.disperses > 0.5) {
            L = trace_spectral(q, eye_jitter(q));
        } else {
            vec3 ro, rd;
            sample_ray(q, ro, rd);
            L = trace_glass(ro, rd, 0u);
        }
    }
    store_glass(q, L, glass);
}
