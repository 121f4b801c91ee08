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
    // For ray differentials: the normal each branch used (facing the incident side), and the multiple of the
    // interpolated normal it is (+-1), or 0 when it is the geometric one (which does not vary across the triangle).
    vec3 n_refl, n_refr;
    float k_refl, k_refr;
    float eta;      // n_incident / n_transmitted
};

// A mirror (`mirror`) reflects everything (F = 1), with the same normal choices.
Split split_interface(vec3 d, vec3 p, vec3 ng, vec3 ns, float ior, bool mirror) {
    Split s;
    bool entering = dot(d, ng) < 0.0;
    float eta = entering ? 1.0 / ior : ior;
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
        float n1 = entering ? 1.0 : ior, n2 = entering ? ior : 1.0;
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
bool inst_is_dielectric(uint inst) { return bvh_instances[inst].material.y > 0.5; }
bool inst_is_mirror(uint inst) { return bvh_instances[inst].material.y > 1.5; }
// The color channel this pass traces: 0 for one gray pass, 1..3 for red, green, blue (FrameData.transport.w).
uint color_channel() { return u_frame.transport.w & 0xffu; }
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

// Ray differentials (Igehy, "Tracing Ray Differentials", SIGGRAPH 1999): how a photon ray's origin and unit
// direction change across one cell width of its emitting cell, along the light view's two cell axes x and y
// (`--footprint differential`). At the receiver, dP/dx and dP/dy are the sides of the parallelogram the cell
// covers there, which sizes the splat.
struct RayDiff {
    vec3 dpx, dpy;  // dP/dx, dP/dy (m per cell)
    vec3 ddx, ddy;  // dD/dx, dD/dy (per cell)
};

// A cell's ray and its differentials. Perspective (spot light): P is the light's position, so dP = 0, and
// D = d/|d| with d = x right + y down + forward, so dD = (dd - D (D.dd)) / |d| with dd = one cell side along
// right (or down). Orthographic (directional): dP = one cell side along right (or down), dD = 0.
RayDiff cell_ray_diff(uint level, uvec2 xy, vec3 rd) {
    View v = u_frame.photon_view;
    vec2 side = v.window.zw / float(LEVEL0_RES << level);
    vec3 ex = side.x * v.right.xyz, ey = side.y * v.down.xyz;
    RayDiff r;
    if (view_is_ortho(v)) {
        r.dpx = ex;
        r.dpy = ey;
        r.ddx = vec3(0.0);
        r.ddy = vec3(0.0);
    } else {
        vec2 pxy = view_xy_of_uv(v, cell_center_uv(level, xy));
        float len = length(pxy.x * v.right.xyz + pxy.y * v.down.xyz + v.forward.xyz);
        r.dpx = vec3(0.0);
        r.dpy = vec3(0.0);
        r.ddx = (ex - rd * dot(rd, ex)) / len;
        r.ddy = (ey - rd * dot(rd, ey)) / len;
    }
    return r;
}

// Transfer to a hit at distance t on a surface of normal n (Igehy eq. 10-12): dP' = dP + t dD + dt D with
// dt = -(dP + t dD).n / (D.n), so that dP' lies in the surface's tangent plane.
void diff_transfer(inout RayDiff r, vec3 rd, float t, vec3 n) {
    float dn = dot(rd, n);
    vec3 px = r.dpx + t * r.ddx, py = r.dpy + t * r.ddy;
    if (abs(dn) > 1e-8) {
        px -= rd * (dot(px, n) / dn);
        py -= rd * (dot(py, n) / dn);
    }
    r.dpx = px;
    r.dpy = py;
}

// Reflection R = D - 2 (D.N) N: dR = dD - 2 ((D.N) dN + (dD.N + D.dN) N).
vec3 diff_reflect(vec3 d, vec3 dd, vec3 n, vec3 dn) {
    return dd - 2.0 * (dot(d, n) * dn + (dot(dd, n) + dot(d, dn)) * n);
}

// Refraction T = eta D + mu N with N facing the incident side, cos_i = -D.N, cos_t = -T.N, mu = eta cos_i - cos_t
// (Igehy eq. 15-17): dT = eta dD + mu dN + dmu N, dcos_i = -(dD.N + D.dN), dmu = (eta - eta^2 cos_i / cos_t) dcos_i.
vec3 diff_refract(vec3 d, vec3 dd, vec3 n, vec3 dn, vec3 t, float eta) {
    float ci = -dot(d, n), ct = max(-dot(t, n), 1e-6);
    float mu = eta * ci - ct;
    float dci = -(dot(dd, n) + dot(d, dn));
    float dmu = (eta - eta * eta * ci / ct) * dci;
    return eta * dd + mu * dn + dmu * n;
}

// Derivative of a caustic-map position (texels) along a world offset dp at p (the receiver view's projection).
vec2 view_px_diff(View v, vec3 p, vec3 dp) {
    vec3 d = p - v.origin.xyz;
    vec3 a = vec3(dot(d, v.right.xyz), dot(d, v.down.xyz), dot(d, v.forward.xyz));
    vec3 da = vec3(dot(dp, v.right.xyz), dot(dp, v.down.xyz), dot(dp, v.forward.xyz));
    vec2 dxy = view_is_ortho(v) ? da.xy : (da.xy * a.z - a.xy * da.z) / (a.z * a.z);
    return dxy / v.window.zw * v.extent.xy;
}

// Splat radii (texels, per map axis) from the cell's landing parallelogram: its extent along each axis,
// |dx.x| + |dy.x| and |dx.y| + |dy.y| (a tent of that half-width interpolates between neighbouring photons, as the
// cell radius does for an unsheared lattice), rounded, and clamped to [max(1, r_cell / 4), min(8 r_cell,
// MAX_SPLAT_RADIUS)] where r_cell is the cell footprint's radius. Packed as rx | ry << 16 (exact in a float).
uint footprint_radii(vec2 mx, vec2 my, uint r_cell) {
    vec2 ext = abs(mx) + abs(my);
    float lo = max(1.0, floor(float(r_cell) / 4.0));
    float hi = min(8.0 * float(r_cell), float(MAX_SPLAT_RADIUS));
    if (any(isnan(ext)) || any(isinf(ext))) ext = vec2(float(r_cell));
    uvec2 r = uvec2(clamp(round(ext), vec2(lo), vec2(hi)));
    return r.x | (r.y << 16);
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
