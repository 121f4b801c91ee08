// Exact photon transport (docs/design.md step 5, `--transport exact`): rays through the scene BVH, a deterministic
// Fresnel split at every dielectric interface, and the landing point of a path on the receivers. The wave shader
// follows every branch; the traversal's max-error metric follows each child's dominant branch.
// Needs photon_bindings, photon.glsl and bvh.glsl.
#ifndef TRANSPORT_GLSL
#define TRANSPORT_GLSL
#include "common/bvh.glsl"

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
};

// A mirror (`mirror`) reflects everything (F = 1), with the same normal choices.
Split split_interface(vec3 d, vec3 p, vec3 ng, vec3 ns, float ior, bool mirror) {
    Split s;
    bool entering = dot(d, ng) < 0.0;
    float eta = entering ? 1.0 / ior : ior;
    vec3 ng_f = entering ? ng : -ng;  // faces the incident side
    vec3 ns_f = dot(ns, ng) > 0.0 ? (entering ? ns : -ns) : ng_f;
    vec3 n = -dot(d, ns_f) > 0.0 ? ns_f : ng_f;
    float cos_i = -dot(d, n);
    s.ok = cos_i > 0.0;
    s.F = 1.0;
    s.refl = reflect(d, n);
    if (dot(s.refl, ng_f) <= 0.0) s.refl = reflect(d, ng_f);
    s.ok = s.ok && dot(s.refl, ng_f) > 0.0;
    s.refr = vec3(0.0);
    if (s.ok) {
        float n1 = entering ? 1.0 : ior, n2 = entering ? ior : 1.0;
        s.F = mirror ? 1.0 : fresnel_dielectric(cos_i, n1, n2);
        vec3 t;
        if (s.F < 1.0 && refract_dir(d, n, eta, t)) {
            if (dot(t, ng_f) >= 0.0) {
                // The interpolated normal bends the ray back out: refract about the geometric normal instead.
                float c = -dot(d, ng_f);
                if (!(c > 0.0 && refract_dir(d, ng_f, eta, t) && dot(t, ng_f) < 0.0)) s.F = 1.0;
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
bool inst_is_dielectric(uint inst) { return bvh_instances[inst].material.y > 0.5; }
bool inst_is_mirror(uint inst) { return bvh_instances[inst].material.y > 1.5; }
// The color channel this pass traces: 0 for one gray pass, 1..3 for red, green, blue (FrameData.transport.w).
uint color_channel() { return u_frame.transport.w; }
float inst_ior(uint inst) {
    uint c = color_channel();
    return c == 0u ? bvh_instances[inst].material.x : bvh_instances[inst].ior_rgb[c - 1u];
}
float inst_sigma(uint inst) {
    uint c = color_channel();
    return c == 0u ? bvh_instances[inst].material.z : bvh_instances[inst].sigma_rgb[c - 1u];
}

// The photon ray of a cell: from the light through the cell's center.
void cell_ray(uint level, uvec2 xy, out vec3 ro, out vec3 rd) {
    View v = u_frame.photon_view;
    view_ray_xy(v, view_xy_of_uv(v, cell_center_uv(level, xy)), ro, rd);
}

const uint DOM_OK = 0u;       // landed on a receiver after >= 1 specular interaction
const uint DOM_DIRECT = 1u;   // landed on a receiver with none
const uint DOM_ESCAPED = 2u;
const uint DOM_CUT = 3u;      // interaction cap or a dead end

// Follow a cell's dominant path (the larger branch at every interface) to where it ends, for the max-error
// and flux-error metrics: its status, the landing texel of the caustic map, its interaction count, and its
// throughput (the product of the branch fractions it kept: the share of the cell's flux that follows it).
uint trace_dominant(uint level, uvec2 xy, out vec2 map_px, out uint events, out float throughput) {
    vec3 ro, rd;
    cell_ray(level, xy, ro, rd);
    map_px = vec2(-1e9);
    events = 0u;
    throughput = 1.0;
    for (uint k = 0u; k <= MAX_INTERACTIONS; k++) {
        SceneHit hit;
        if (!bvh_closest(ro, rd, 1.0 / 0.0, hit)) return DOM_ESCAPED;
        vec3 p = bvh_hit_point(hit);
        if (!inst_is_dielectric(hit.inst)) {
            View rv = u_frame.receiver_view;
            map_px = view_uv(rv, p) * rv.extent.xy;
            return events == 0u ? DOM_DIRECT : DOM_OK;
        }
        if (k == MAX_INTERACTIONS) break;
        vec3 ng, ns;
        bvh_normals(hit, ng, ns);
        Split s = split_interface(rd, p, ng, ns, inst_ior(hit.inst), inst_is_mirror(hit.inst));
        if (!s.ok) break;
        bool refl = s.F >= 0.5;
        throughput *= refl ? s.F : 1.0 - s.F;
        ro = refl ? s.p_refl : s.p_refr;
        rd = normalize(refl ? s.refl : s.refr);
        events++;
    }
    return DOM_CUT;
}

#endif
