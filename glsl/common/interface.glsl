// A specular interface hit by a ray through the scene BVH: the ray-origin offset, the deterministic Fresnel split
// of a dielectric (or a mirror's reflection), and the instances' materials. Shared by the exact photon transport
// (glsl/common/transport.glsl) and the eye-view ray tracer (glsl/glass.comp). Needs optics.glsl and bvh.glsl
// (and the BVH bindings).
#ifndef INTERFACE_GLSL
#define INTERFACE_GLSL
#include "common/optics.glsl"
#include "common/bvh.glsl"
#include "common/spectrum.glsl"

// A spectral photon's wavelength (nm; glsl/wave.comp, WAVE_SPECTRAL), else 0: every IOR and absorption coefficient
// is then the material's at that wavelength, whatever the channel.
float ray_nm = 0.0;

// Offset a hit point off its surface along the geometric normal `n` (pointing to the side the new ray leaves
// on), by a few ulps of the point's coordinates (Waechter and Binder, "A Fast and Robust Method for Avoiding
// Self-Intersection", Ray Tracing Gems, 2019): robust at any scale, unlike a fixed epsilon.
vec3 offset_ray(vec3 p, vec3 n) {
    const float origin = 1.0 / 32.0, float_scale = 1.0 / 65536.0, int_scale = 256.0;
    ivec3 of = ivec3(int_scale * n);
    vec3 pi = vec3(intBitsToFloat(floatBitsToInt(p.x) + (p.x < 0.0 ? -of.x : of.x)),
                   intBitsToFloat(floatBitsToInt(p.y) + (p.y < 0.0 ? -of.y : of.y)),
                   intBitsToFloat(floatBitsToInt(p.z) + (p.z < 0.0 ? -of.z : of.z)));
    return vec3(abs(p.x) < origin ? p.x + float_scale * n.x : pi.x,
                abs(p.y) < origin ? p.y + float_scale * n.y : pi.y,
                abs(p.z) < origin ? p.z + float_scale * n.z : pi.z);
}

// A dielectric interface, split deterministically (the CPU reference picks one branch by Russian roulette with
// the same probabilities). The reflectance F comes from the interpolated normal where it faces the ray, else from
// the geometric one; each branch's direction falls back to the geometric normal when the interpolated one would
// send it to the wrong side of the surface. Total internal reflection reflects everything (F = 1).
struct Split {
    float F;        // reflected fraction; 1 - F is refracted
    vec3 refl;      // reflected direction
    vec3 refr;      // refracted direction (unused when F == 1)
    vec3 p_refl;    // origins, offset to the side each branch leaves on
    vec3 p_refr;
    bool ok;        // false: no valid direction on either normal (a numerical dead end)
    // For ray differentials: the normal each branch used (facing the incident side), and the multiple of the
    // interpolated normal it is (+-1), or 0 when it is the geometric one (which does not vary across the triangle).
    vec3 n_refl, n_refr;
    float k_refl, k_refr;
    float eta;      // n_incident / n_transmitted
};

// The surface separates the medium of IOR n_in (behind the geometric normal ng) from n_out (in front of it). A
// mirror (`mirror`) reflects everything (F = 1), with the same normal choices.
Split split_interface(vec3 d, vec3 p, vec3 ng, vec3 ns, float n_in, float n_out, bool mirror) {
    Split s;
    bool entering = dot(d, ng) < 0.0;
    float eta = entering ? n_out / n_in : n_in / n_out;
    vec3 ng_f = entering ? ng : -ng;  // faces the incident side
    vec3 ns_f = dot(ns, ng) > 0.0 ? (entering ? ns : -ns) : ng_f;
    bool use_ns = dot(ns, ng) > 0.0 && -dot(d, ns_f) > 0.0;
    vec3 n = use_ns ? ns_f : ng_f;
    float k_n = use_ns ? (entering ? 1.0 : -1.0) : 0.0;
    s.eta = eta;
    s.n_refl = n;
    s.k_refl = k_n;
    s.n_refr = n;
    s.k_refr = k_n;
    float cos_i = -dot(d, n);
    s.ok = cos_i > 0.0;
    s.F = 1.0;
    s.refl = reflect(d, n);
    if (dot(s.refl, ng_f) <= 0.0) {
        s.refl = reflect(d, ng_f);
        s.n_refl = ng_f;
        s.k_refl = 0.0;
    }
    s.ok = s.ok && dot(s.refl, ng_f) > 0.0;
    s.refr = vec3(0.0);
    if (s.ok) {
        float n1 = entering ? n_out : n_in, n2 = entering ? n_in : n_out;
        s.F = mirror ? 1.0 : fresnel_dielectric(cos_i, n1, n2);
        vec3 t;
        if (s.F < 1.0 && refract_dir(d, n, eta, t)) {
            if (dot(t, ng_f) >= 0.0) {
                // The interpolated normal bends the ray back out: refract about the geometric normal instead.
                float c = -dot(d, ng_f);
                if (!(c > 0.0 && refract_dir(d, ng_f, eta, t) && dot(t, ng_f) < 0.0)) s.F = 1.0;
                s.n_refr = ng_f;
                s.k_refr = 0.0;
            }
            s.refr = t;
        } else {
            s.F = 1.0;
        }
    }
    s.p_refl = offset_ray(p, ng_f);
    s.p_refr = offset_ray(p, -ng_f);
    return s;
}

// Specular: a dielectric or a mirror (everything else is a diffuse receiver).
bool inst_is_dielectric(uint inst) { return bvh_instance(inst).material.y > 0.5; }
bool inst_is_mirror(uint inst) { return bvh_instance(inst).material.y > 1.5; }
// The color channel whose IORs this pass traces: 0 for one gray pass, 1..3 for red, green, blue
// (PassUniforms.channel). Color photons (CHANNEL_RGB) meet no dispersion: they take the gray pass's paths, and carry
// their colour in their tint (glsl/wave.comp, WAVE_COLOR); spectral photons (CHANNEL_SPECTRAL) take their
// wavelength's (ray_nm), and wherever they do not say (the traversal's checks) the d line's. The eye view
// (glass.comp, GRAY_MATERIALS) names its channels itself: its uniforms are a photon pass's, whose channel is not
// the eye's.
#ifdef GRAY_MATERIALS
uint color_channel() { return 0u; }
#else
uint color_channel() { return u_frame.pass.channel >= CHANNEL_RGB ? 0u : u_frame.pass.channel; }
#endif
// A dielectric's IOR and absorption coefficient (1/m) in channel c (0: the gray pass's d-line IOR and mean
// absorption).
float inst_ior_in(uint inst, uint c) {
    if (ray_nm > 0.0) return cauchy_ior(bvh_instance(inst).ior_rgb.xyz, ray_nm);
    return c == 0u ? bvh_instance(inst).material.x : bvh_instance(inst).ior_rgb[c - 1u];
}
float inst_sigma_in(uint inst, uint c) {
    if (ray_nm > 0.0) return rgb_spectrum(bvh_instance(inst).sigma_rgb.xyz, bvh_instance(inst).pad.yzw, ray_nm);
    return c == 0u ? bvh_instance(inst).material.z : bvh_instance(inst).sigma_rgb[c - 1u];
}
// Media (docs/design.md "Media"): a medium is 0 for air (IOR 1, no absorption), else a dielectric instance + 1,
// whose IOR and absorption it has. A dielectric's surface separates its own medium (behind its geometric normal)
// from the one its record names beyond it (`sigma_rgb.w`, src/bvh/mod.rs `set_media`).
const uint AIR = 0u;
uint inst_medium(uint inst) { return inst + 1u; }
uint inst_outside(uint inst) { return uint(bvh_instance(inst).sigma_rgb.w); }
float medium_ior_in(uint m, uint c) { return m == AIR ? 1.0 : inst_ior_in(m - 1u, c); }
float medium_sigma_in(uint m, uint c) { return m == AIR ? 0.0 : inst_sigma_in(m - 1u, c); }
vec3 medium_sigma_rgb(uint m) {
    if (m == AIR) return vec3(0.0);
    // A ray of one wavelength: the absorption's spectrum there, in every channel.
    return ray_nm > 0.0 ? vec3(inst_sigma_in(m - 1u, 0u)) : bvh_instance(m - 1u).sigma_rgb.xyz;
}

// The medium a branch of a split at `inst` travels in: a reflection stays in the ray's own medium `m`; a refraction
// crosses into the instance (entering: the ray met the front of its surface) or out to the medium beyond it.
uint refracted_medium(uint inst, bool entering) { return entering ? inst_medium(inst) : inst_outside(inst); }

// Volumes with a priority (`priority`, material.w; 0 for an explicit interface): a ray keeps those it is inside, up
// to MAX_NESTED, as instance + 1 in the 16-bit slots of a uvec2 (0: empty; GpuRayMedium.inside), and the medium
// where volumes overlap is the highest priority's (ties: the higher instance). Schmidt and Budge 2002.
uint inst_priority(uint inst) { return uint(bvh_instance(inst).material.w); }
uint nested_slot(uvec2 l, uint k) { return (l[k >> 1] >> ((k & 1u) * 16u)) & 0xFFFFu; }
uvec2 nested_set(uvec2 l, uint k, uint v) {
    uint sh = (k & 1u) * 16u;
    l[k >> 1] = (l[k >> 1] & ~(0xFFFFu << sh)) | (v << sh);
    return l;
}
uvec2 nested_add(uvec2 l, uint m) {
    for (uint k = 0u; k < MAX_NESTED; k++) {
        if (nested_slot(l, k) == 0u) return nested_set(l, k, m);
    }
    return l;  // full: not entered
}
uvec2 nested_remove(uvec2 l, uint m) {
    for (uint k = 0u; k < MAX_NESTED; k++) {
        if (nested_slot(l, k) == m) return nested_set(l, k, 0u);
    }
    return l;
}
uint nested_top(uvec2 l) {
    uint best = AIR, best_p = 0u;
    for (uint k = 0u; k < MAX_NESTED; k++) {
        uint m = nested_slot(l, k);
        uint p = m != 0u ? inst_priority(m - 1u) : 0u;
        if (m != 0u && (p > best_p || (p == best_p && m > best))) {
            best = m;
            best_p = p;
        }
    }
    return best;
}

// What a ray in medium m, inside the volumes l, meets at a hit on instance `inst` in channel c (`media`: the scene
// has media, so the ray carries m and l; else every surface is an explicit interface).
struct Crossing {
    bool through;        // a volume's surface inside one of higher priority: no interface there, the ray goes on
    float n_in, n_out;   // the IORs behind the surface (its inside) and in front of it
    uint m_refr;         // the medium beyond it
    uvec2 l_refr;        // the volumes the ray is inside beyond it
};

Crossing crossing_at(uint inst, bool entering, uint m, uvec2 l, uint c, bool media) {
    Crossing x;
    x.through = false;
    x.l_refr = l;
    uint pr = media ? inst_priority(inst) : 0u;
    if (pr == 0u) {
        x.n_in = inst_ior_in(inst, c);
        x.n_out = medium_ior_in(inst_outside(inst), c);
        x.m_refr = refracted_medium(inst, entering);
        return x;
    }
    x.l_refr = entering ? nested_add(l, inst_medium(inst)) : nested_remove(l, inst_medium(inst));
    x.m_refr = nested_top(x.l_refr);
    x.through = x.m_refr == m;
    float before = medium_ior_in(m, c), after = medium_ior_in(x.m_refr, c);
    x.n_in = entering ? after : before;
    x.n_out = entering ? before : after;
    return x;
}

#endif
