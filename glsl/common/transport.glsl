// Exact photon transport (docs/design.md step 4, `--transport exact`): rays through the scene BVH, a deterministic
// Fresnel split at every dielectric interface, and the landing point of a path on the receivers. The wave shader
// follows every branch; the traversal's max-error metric follows each child's dominant branch.
// Needs photon_bindings, photon.glsl and bvh.glsl.
#ifndef TRANSPORT_GLSL
#define TRANSPORT_GLSL
#include "common/bvh.glsl"
#include "common/interface.glsl"
#include "common/emitter.glsl"


// The emitter's ray through the photon grid's point uv with sample u (common/emitter.glsl; (0.5, 0.5): the
// straight ray of a light with size).
void cell_ray_at(vec2 uv, vec2 u, out vec3 ro, out vec3 rd) {
    GpuView v = u_frame.light.photon_view;
    emitter_ray(v, view_xy_of_uv(v, uv), u, ro, rd);
}

// The photon ray of a cell: at its sample (cell_sample_uv), with the cell's own point of a light with size.
void cell_ray(uint level, uvec2 xy, out vec3 ro, out vec3 rd) {
    cell_ray_at(cell_sample_uv(level, xy), emitter_cell_sample(level, xy), ro, rd);
}

// A cell's ray and its differentials across one cell side (emitter_ray_diff).
RayDiff cell_ray_diff(uint level, uvec2 xy, vec3 rd) {
    GpuView v = u_frame.light.photon_view;
    vec2 side = v.window.zw / float(LEVEL0_RES << level);
    return emitter_ray_diff(v, view_xy_of_uv(v, cell_sample_uv(level, xy)), side, rd);
}

// A ray's differentials in a queue: four half-float pairs. Only the parts across the ray's unit direction D are
// kept, in an orthonormal basis around D (Duff et al., JCGT 2017), so rebuilt exactly from D's stored bits:
// - dP's part along D does not matter, as the next transfer's dt absorbs it (dP + a D gives the same dP');
// - dD's part along D is zero for a unit direction (and a reflection or refraction maps it onto the child's own
//   direction, which the transfer absorbs again).
// They are scaled by the photon's cell side first, so that the halves hold O(1) values (a cell's own spread at
// unit distance), and clamped to the half range; a value past it or a NaN makes footprint_radii fall back to
// the cell radius.
void diff_basis(vec3 d, out vec3 b1, out vec3 b2) {
    float sgn = d.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sgn + d.z), b = d.x * d.y * a;
    b1 = vec3(1.0 + sgn * d.x * d.x * a, sgn * b, -sgn * d.x);
    b2 = vec3(b, sgn + d.y * d.y * a, -d.y);
}

uint diff_pack2(vec3 v, vec3 b1, vec3 b2, float k) {
    vec2 c = clamp(vec2(dot(v, b1), dot(v, b2)) * k, vec2(-65504.0), vec2(65504.0));
    return packHalf2x16(c);
}

vec3 diff_unpack2(uint u, vec3 b1, vec3 b2, float k) {
    vec2 c = unpackHalf2x16(u) * k;
    return c.x * b1 + c.y * b2;
}

// The packed differentials of a ray of unit direction d whose photon's cell has side `side`.
uvec4 diff_pack(RayDiff r, vec3 d, float side) {
    vec3 b1, b2;
    diff_basis(d, b1, b2);
    float k = 1.0 / side;
    return uvec4(diff_pack2(r.dpx, b1, b2, k), diff_pack2(r.dpy, b1, b2, k), diff_pack2(r.ddx, b1, b2, k),
                 diff_pack2(r.ddy, b1, b2, k));
}

RayDiff diff_unpack(uvec4 u, vec3 d, float side) {
    vec3 b1, b2;
    diff_basis(d, b1, b2);
    RayDiff r;
    r.dpx = diff_unpack2(u.x, b1, b2, side);
    r.dpy = diff_unpack2(u.y, b1, b2, side);
    r.ddx = diff_unpack2(u.z, b1, b2, side);
    r.ddy = diff_unpack2(u.w, b1, b2, side);
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

// Differentials across `k` cells instead of one (a weak branch carried for a 2x2 block: k = 2).
void diff_scale(inout RayDiff r, float k) {
    r.dpx *= k;
    r.dpy *= k;
    r.ddx *= k;
    r.ddy *= k;
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
vec2 view_px_diff(GpuView v, vec3 p, vec3 dp) {
    vec3 d = p - v.origin.xyz;
    vec3 a = vec3(dot(d, v.right.xyz), dot(d, v.down.xyz), dot(d, v.forward.xyz));
    vec3 da = vec3(dot(dp, v.right.xyz), dot(dp, v.down.xyz), dot(dp, v.forward.xyz));
    vec2 dxy = view_is_ortho(v) ? da.xy : (da.xy * a.z - a.xy * da.z) / (a.z * a.z);
    return dxy / v.window.zw * v.extent.xy;
}

// The splat of a cell's landing parallelogram (mx, my: where one cell step along each light-view axis moves the
// landing, in texels; docs/design.md step 5, "Splat footprint"). Neighbouring cells land on the lattice that mx and
// my span; first the lattice's two shortest vectors replace them (Lagrange-Gauss reduction: where a caustic folds,
// mx and my are long and nearly parallel while the landings lie about a texel apart). Then a sheared separable
// tent takes their second moments: along the axis they extend more (say y) a tent of radius ry =
// sqrt(mx.y² + my.y²); across it, row by row, a tent of radius rx = |det(mx, my)| / ry whose center moves by
// s = (mx.x mx.y + my.x my.y) / ry² texels per texel of y (|s| <= 1). For an axis-aligned lattice that is the tent
// of its spacing, which interpolates between neighbouring photons; a sheared one keeps its width across its rows,
// where the tent of its bounding box would blur it. The radii are rounded and clamped to [max(1, r_cell / 4),
// min(16 r_cell, MAX_SPLAT_RADIUS)], r_cell the cell footprint's radius; a row's tent of integer radius sums to
// exactly rx at any center, so the weights still sum to exactly rx ry. Packed by splat_pack
// (glsl/common/photon_bindings.glsl).
float footprint_radii(vec2 mx, vec2 my, uint r_cell) {
    float lo = max(1.0, floor(float(r_cell) / 4.0));
    float hi = min(16.0 * float(r_cell), float(MAX_SPLAT_RADIUS));
    for (int i = 0; i < 4; i++) {
        if (dot(mx, mx) > dot(my, my)) {
            vec2 t = mx;
            mx = my;
            my = t;
        }
        float aa = dot(mx, mx);
        my -= (aa > 0.0 ? round(dot(mx, my) / aa) : 0.0) * mx;
    }
    vec2 sq = mx * mx + my * my;  // the moments along x and y, times 6 (a tent of radius r has variance r² / 6)
    bool shear_y = sq.x > sq.y;   // the lattice extends more along x: shear the columns
    float major = sqrt(shear_y ? sq.x : sq.y);
    float minor = major > 0.0 ? abs(mx.x * my.y - mx.y * my.x) / major : 0.0;
    float s = major > 0.0 ? (mx.x * mx.y + my.x * my.y) / (major * major) : 0.0;
    if (isnan(major + minor + s) || isinf(major + minor + s)) {
        major = minor = float(r_cell);
        s = 0.0;
    }
    float ra = clamp(round(major), lo, hi), rb = clamp(round(minor), lo, hi);
    s = clamp(s, -1.0, 1.0);
    // The taps' box is rb + |s| ra wide across the rows: kept within 2 MAX_SPLAT_RADIUS - 1 (a point of at most
    // 254 pixels for the raster splat).
    rb = max(1.0, min(rb, floor(2.0 * float(MAX_SPLAT_RADIUS) - 1.0 - abs(s) * ra)));
    return splat_pack(uvec2(shear_y ? vec2(ra, rb) : vec2(rb, ra)), s, shear_y);
}

// A sun's or a sphere light's photon lands up to `jitter` samples from where its cell's straight ray would (the
// light's image over the ray's last segment), each cell taking another point of the light: a footprint of side
// `side` samples grows by this factor, to that scatter and at most 3 times, so that neighbouring tents overlap
// where the light's size scatters them (common/deposit_light_map.glsl, common/deposit_eye.glsl).
float footprint_widening(float jitter, float side) { return clamp(jitter / max(side, 1.0), 1.0, 3.0); }

const uint DOM_OK = 0u;       // landed on a receiver after >= 1 specular interaction
const uint DOM_DIRECT = 1u;   // landed on a receiver with none
const uint DOM_ESCAPED = 2u;
const uint DOM_CUT = 3u;      // interaction cap or a dead end
const uint DOM_LONG = 4u;     // still in the glass after CHECK_INTERACTIONS: where it lands is not known

// The checks follow a dominant path through at most this many interactions (the waves, through MAX_INTERACTIONS).
// A longer path is a light path trapped in the glass (total internal reflection): its cell refines under max-error,
// and flux-error bounds it as a child that may land anywhere with its dominant flux.
#ifndef CHECK_INTERACTIONS
#define CHECK_INTERACTIONS 8u
#endif

// Follow a cell's dominant path (the larger branch at every interface) to where it ends, for the max-error
// and flux-error metrics: its status, the landing texel of the caustic map and the landing point (world space), its
// interaction count, and its throughput (the product of the branch fractions it kept: the share of the cell's flux
// that follows it).
uint trace_dominant(uint level, uvec2 xy, out vec2 map_px, out vec3 land, out uint events, out float throughput) {
    vec3 ro, rd;
    // The straight ray: a light with size refines where its center's caustic needs it (the sampled rays are the
    // waves').
    cell_ray_at(cell_center_uv(level, xy), vec2(0.5), ro, rd);
    map_px = vec2(-1e9);
    land = vec3(0.0);
    events = 0u;
    throughput = 1.0;
    for (uint k = 0u; k <= MAX_INTERACTIONS; k++) {
        if (k == CHECK_INTERACTIONS) return DOM_LONG;
        SceneHit hit;
        if (!bvh_closest(ro, rd, 1.0 / 0.0, hit)) return DOM_ESCAPED;
        vec3 p = bvh_hit_point(hit);
        if (!inst_is_dielectric(hit.inst)) {
            GpuView rv = u_frame.light.receiver_view;
            map_px = view_uv(rv, p) * rv.extent.xy;
            land = p;
            return events == 0u ? DOM_DIRECT : DOM_OK;
        }
        if (k == MAX_INTERACTIONS) break;
        vec3 ng, ns;
        bvh_normals(hit, ng, ns);
        // (The dominant path carries no medium: each surface is an explicit interface.)
        Crossing x = crossing_at(hit.inst, dot(rd, ng) < 0.0, AIR, uvec2(0u), color_channel(), false);
        Split s = split_interface(rd, p, ng, ns, x.n_in, x.n_out, inst_is_mirror(hit.inst));
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
