// The emitter interface (docs/design.md "Emitters and deposits"). A light view emits its photons from the cells of a
// quadtree over its refinement domain: a window of its image plane, LEVEL0_RES << L cells a side at level L. An
// emitter kind answers three questions, and the photon passes ask nothing else of a light:
// - its domain: whether an image-plane point emits (emitter_holds), and whether a cell's rectangle touches the
//   domain or lies wholly inside it (emitter_touches, emitter_contains: the traversal's conservative tests);
// - a cell's measure: the solid angle (sr) or the area across the beam (m^2) it emits into, so that a photon's
//   flux is the light's intensity times it (emitter_measure);
// - its sample: the ray of an image-plane point and a point u of the unit square (each cell's own, from
//   emitter_cell_sample), and how it changes across a cell (emitter_ray, emitter_ray_diff).
// The kinds (emitter_kind; src/scene/view.rs EmitterKind writes the view's lanes that say which):
// - EMITTER_BEAM: a directional light, rays over the window (an orthographic view): parallel, or a sun's, whose
//   radiance is uniform over a disk of directions (LightUniforms.beam_spread, the tangent of its angular radius):
//   each cell's ray takes the direction u maps to on that disk, through the cell at the glass's depth
//   (beam_pivot), so that a tilted ray still meets the glass where its cell's coverage says;
// - EMITTER_OPEN: a point light whose objects all lie in front of it, rays from a point over the whole window;
// - EMITTER_CONE: a spot light, rays from a point within a cone (right.w its cosine);
// - EMITTER_SQUARE: a face of a point light's cube, rays from a point through the square |x|, |y| <= 1 of its
//   image plane (right.w = VIEW_SQUARE_DOMAIN), so that the faces partition the sphere of directions.
// A light with size samples it with the cell's point u: a sun (a beam whose radiance is uniform over a disk of
// directions) tilts the cell's ray by u's point of that disk; a sphere light (a point or spot light with
// LightUniforms.light_radius) starts it at u's point of the sphere's disk across the cell's direction, aimed at
// where the straight ray is at the glass's depth. Either way the ray still meets the glass where its cell's
// coverage says, and the light's intensity through the cell is unchanged.
// A light's direct light and shadows hold the same domain (common/receiver.glsl).
#ifndef EMITTER_GLSL
#define EMITTER_GLSL
#include "common/view.glsl"

uint emitter_kind(GpuView v) {
    if (view_is_ortho(v)) return EMITTER_BEAM;
    if (v.right.w <= -1.0) return EMITTER_OPEN;
    if (v.right.w >= float(VIEW_SQUARE_DOMAIN)) return EMITTER_SQUARE;
    return EMITTER_CONE;
}

// The domain: whether image-plane point xy emits (hard edge).
bool emitter_holds(GpuView v, vec2 xy) {
    switch (emitter_kind(v)) {
    case EMITTER_SQUARE: return max(abs(xy.x), abs(xy.y)) <= 1.0;
    case EMITTER_CONE: return inversesqrt(1.0 + dot(xy, xy)) >= v.right.w;
    default: return true;
    }
}

// Whether the image-plane rectangle [lo, hi] intersects the domain (conservative).
bool emitter_touches(GpuView v, vec2 lo, vec2 hi) {
    switch (emitter_kind(v)) {
    case EMITTER_SQUARE: return all(lessThanEqual(lo, vec2(1.0))) && all(greaterThanEqual(hi, vec2(-1.0)));
    case EMITTER_CONE: {
        float c = v.right.w;
        float t2 = (1.0 - c * c) / (c * c);  // tan^2 of the half-angle
        vec2 q = clamp(vec2(0.0), lo, hi);
        return dot(q, q) <= t2;
    }
    default: return true;
    }
}

// Whether the rectangle lies wholly inside the domain (its farthest corner does: both domains are symmetric and
// convex).
bool emitter_contains(GpuView v, vec2 lo, vec2 hi) {
    uint k = emitter_kind(v);
    if (k == EMITTER_BEAM || k == EMITTER_OPEN) return true;
    return emitter_holds(v, max(abs(lo), abs(hi)));
}

// The solid angle (sr), or the area across a beam (m^2), of a square image-plane cell of side d centered at xy.
float emitter_measure(GpuView v, vec2 xy, float d) { return view_cell_measure(v, xy, d); }

// A point of the unit square for cell (level, xy), so that any few neighbouring cells spread evenly over it: the 2D
// R2 sequence (Roberts 2018, in 32-bit fixed point) at the cell's Morton index, shifted by a hash of the level.
uint emitter_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    return x ^ (x >> 16);
}
uint emitter_spread_bits(uint v) {
    v &= 0xFFFFu;
    v = (v | (v << 8)) & 0x00FF00FFu;
    v = (v | (v << 4)) & 0x0F0F0F0Fu;
    v = (v | (v << 2)) & 0x33333333u;
    return (v | (v << 1)) & 0x55555555u;
}
// A point of the unit square from two 32-bit fixed-point fractions (their top 24 bits: exact in a float).
vec2 emitter_unit(uvec2 q) { return vec2(q >> 8u) * (1.0 / 16777216.0); }

// A progressive accumulation's k-th photon set (FrameUniforms.sample_index) rotates it by the k-th point of the
// 4D R-sequence's last two dimensions, so that the sets fill each cell's disk evenly, apart from where they sample the
// cell (emitter_set_offset).
vec2 emitter_cell_sample(uint level, uvec2 xy) {
    uint n = emitter_spread_bits(xy.x) | (emitter_spread_bits(xy.y) << 1);
    uint h = emitter_hash(level + 0x9e3779b9u);
    uint k = u_frame.frame.sample_index;
    uvec2 q = uvec2(n * 0xC13FA9A9u + h, n * 0x91E10DA5u + emitter_hash(h)) + k * uvec2(0xA0F2EC75u, 0x89E18285u);
    return emitter_unit(q);
}

// Where a progressive accumulation's k-th photon set samples each cell, as an offset from its center in cells:
// (0, 0) for the first set, then the 2D R2 sequence (Roberts 2018, in 32-bit fixed point) started at the center,
// so that the sets' points fill every cell evenly and any n of them average as a stratified grid n times finer.
vec2 emitter_set_offset() {
    uint k = u_frame.frame.sample_index;
    return emitter_unit(k * uvec2(0xC13FA9A9u, 0x91E10DA5u) + 0x80000000u) - 0.5;
}

// Shirley and Chiu's concentric map of the unit square onto the unit disk (area-preserving).
vec2 emitter_disk(vec2 u) {
    vec2 o = 2.0 * u - 1.0;
    if (o.x == 0.0 && o.y == 0.0) return vec2(0.0);
    const float QUARTER_PI = 0.78539816339;
    bool wide = abs(o.x) > abs(o.y);
    float r = wide ? o.x : o.y;
    float theta = wide ? QUARTER_PI * (o.y / o.x) : 2.0 * QUARTER_PI - QUARTER_PI * (o.x / o.y);
    return r * vec2(cos(theta), sin(theta));
}

// The ray of image-plane point xy and sample u. A sun's (a beam with beam_spread > 0): its direction u's point of
// the disk of directions, through xy's point at depth beam_pivot, from the view's plane. A sphere light's
// (light_radius > 0): from u's point of the sphere's disk across the straight ray, through the straight ray's point
// at distance beam_pivot. Needs u_frame.
void emitter_ray(GpuView v, vec2 xy, vec2 u, out vec3 ro, out vec3 rd) {
    view_ray_xy(v, xy, ro, rd);
    float spread = u_frame.light.beam_spread, radius = u_frame.light.light_radius;
    float pivot = u_frame.light.beam_pivot;
    if (emitter_kind(v) == EMITTER_BEAM) {
        if (spread > 0.0) {
            vec2 d = spread * emitter_disk(u);
            rd = normalize(v.forward.xyz + d.x * v.right.xyz + d.y * v.down.xyz);
            ro += v.forward.xyz * pivot - rd * (pivot / dot(rd, v.forward.xyz));
        }
    } else if (radius > 0.0) {
        vec3 b1 = normalize(cross(rd, abs(rd.y) < 0.9 ? vec3(0.0, 1.0, 0.0) : vec3(1.0, 0.0, 0.0)));
        vec3 b2 = cross(rd, b1);
        vec2 d = radius * emitter_disk(u);
        vec3 aim = ro + rd * pivot;
        ro += d.x * b1 + d.y * b2;
        rd = normalize(aim - ro);
    }
}

// Ray differentials (Igehy, "Tracing Ray Differentials", SIGGRAPH 1999): how a photon ray's origin and unit
// direction change across one cell width of its emitting cell, along the light view's two cell axes x and y
// (`--footprint differential`). At the receiver, dP/dx and dP/dy are the sides of the parallelogram the cell
// covers there, which sizes the splat.
struct RayDiff {
    vec3 dpx, dpy;  // dP/dx, dP/dy (m per cell)
    vec3 ddx, ddy;  // dD/dx, dD/dy (per cell)
};

// The differentials of the ray rd through xy across a cell of sides `side`. From a point (every kind but a beam):
// P is the light's position, so dP = 0, and D = d/|d| with d = x right + y down + forward, so dD = (dd - D (D.dd))
// / |d| with dd = one cell side along right (or down). A beam: dP = one cell side along right (or down), dD = 0.
RayDiff emitter_ray_diff(GpuView v, vec2 xy, vec2 side, vec3 rd) {
    vec3 ex = side.x * v.right.xyz, ey = side.y * v.down.xyz;
    RayDiff r;
    if (emitter_kind(v) == EMITTER_BEAM) {
        r.dpx = ex;
        r.dpy = ey;
        r.ddx = vec3(0.0);
        r.ddy = vec3(0.0);
    } else {
        float len = length(xy.x * v.right.xyz + xy.y * v.down.xyz + v.forward.xyz);
        r.dpx = vec3(0.0);
        r.dpy = vec3(0.0);
        r.ddx = (ex - rd * dot(rd, ex)) / len;
        r.ddy = (ey - rd * dot(rd, ey)) / len;
    }
    return r;
}

#endif
