// Tracing one photon from the light through the refractor to the receivers (docs/design.md step 4): front surface
// from the light-view front buffer, refraction with Fresnel transmittance, the exit point on the back surface by
// a bracketed search, refraction out (total internal reflection drops the photon: a two-interface method cannot
// follow it), and the receiver hit by a bracketed secant search. Used by the splat for every emitted photon and
// by traversal (the max-error metric traces a cell's four children). Needs photon_bindings and coverage.
#ifndef PHOTON_GLSL
#define PHOTON_GLSL
#include "common/emitter.glsl"
#include "common/optics.glsl"
#include "common/march.glsl"

const uint HIT_OK = 0u;
const uint HIT_OUTSIDE_CONE = 1u;
const uint HIT_MISS = 2u;        // the cell's center does not see a refractor
const uint HIT_NO_EXIT = 4u;     // no back surface found along the refracted ray
const uint HIT_TIR = 5u;         // total internal reflection
const uint HIT_ESCAPED = 6u;     // left the caustic map without meeting a receiver

struct Hit {
    vec2 map_px;   // landing point in caustic-map texels
    float flux;    // W (for a white light; the light's color multiplies it in the resolve)
    vec3 pos;      // landing point, world space
    uint status;
};

Hit trace_photon(vec2 uv, float side, bool covered) {
    Hit h;
    h.status = HIT_OK;
    h.flux = 0.0;
    h.map_px = vec2(-1e9);
    h.pos = vec3(0.0);
    GpuView v = u_frame.light.photon_view;
    GpuView rv = u_frame.light.receiver_view;
    vec2 xy = view_xy_of_uv(v, uv);
    if (!emitter_holds(v, xy)) { h.status = HIT_OUTSIDE_CONE; return h; }
    vec4 front;
    if (!covered || !geo_sample(t_front, uv, front)) { h.status = HIT_MISS; return h; }
    vec3 ro, rd;
    // (The two-interface trace reads the front surface where the straight ray meets it: a sun's rays are parallel.)
    view_ray_xy(v, xy, ro, rd);
    vec3 p1 = ro + rd * front.w;
    // (A receiver between the light and the refractor shadows it: coverage.comp leaves such texels uncovered.)
    ivec2 aux_size = textureSize(t_front_aux, 0);
    float ior = FRONT_IOR(texelFetch(t_front_aux, clamp(ivec2(uv * vec2(aux_size)), ivec2(0), aux_size - 1), 0).x);
    vec3 n1 = dot(front.xyz, rd) > 0.0 ? -front.xyz : front.xyz;
    float F1 = fresnel_dielectric(-dot(rd, n1), 1.0, ior);
    vec3 t1;
    if (!refract_dir(rd, n1, 1.0 / ior, t1)) { h.status = HIT_TIR; return h; }
    vec3 p2, n2;
    if (!find_exit(v, t_back, u_frame.frame.refractor_diameter, p1, t1, p2, n2)) { h.status = HIT_NO_EXIT; return h; }
    if (dot(n2, t1) < 0.0) n2 = -n2;  // outward, along the ray
    float F2 = fresnel_dielectric(dot(t1, n2), ior, 1.0);
    vec3 t2;
    if (!refract_dir(t1, -n2, ior, t2)) { h.status = HIT_TIR; return h; }
    vec3 lo = u_frame.frame.scene_min, hi = u_frame.frame.scene_max;
    vec3 pad = 1e-3 * max(hi - lo, vec3(1.0));
    vec3 p3;
    if (!find_surface(rv, t_recv, p2, t2, ray_box_exit(p2, t2, lo - pad, hi + pad), p3)) {
        h.status = HIT_ESCAPED;
        return h;
    }
    h.pos = p3;
    h.map_px = view_uv(rv, p3) * rv.extent.xy;
    h.flux = u_frame.light.light_intensity * emitter_measure(v, xy, side) * (1.0 - F1) * (1.0 - F2);
    return h;
}

float cell_side(uint level) { return u_frame.light.photon_view.window.z / float(LEVEL0_RES << level); }

// Exact: (x + 0.5) needs at most 23 bits at level 16 and the divisor is a power of two.
vec2 cell_center_uv(uint level, uvec2 xy) { return (vec2(xy) + 0.5) / float(LEVEL0_RES << level); }

// Where the cell's photon samples it: its center, shifted by a progressive accumulation's photon set
// (emitter_set_offset: none for the first). The traversal's checks trace the centers, so every set refines alike.
vec2 cell_sample_uv(uint level, uvec2 xy) {
    return (vec2(xy) + 0.5 + emitter_set_offset()) / float(LEVEL0_RES << level);
}

// A progressive accumulation's k-th photon set (FrameUniforms.sample_index) splats footprints (k + 1)^(-1/4) as
// wide, down to one texel of the deposit, so that the average's blur (the mean of its sets' squared widths, about
// 2 / sqrt(n) of one set's after n sets) falls as its noise does, and the average converges to the unblurred
// caustic (progressive photon mapping's radius reduction, alpha = 1/2). Narrowing by sqrt(k + 1), as the sets' grid
// refines, left each early set sparse and noisy: the error fell more slowly over the first 16 sets
// (docs/experiments.md). Both deposits' footprints take it (after a light's widening), and the two-interface
// trace's radius.
float set_narrowing() { return inversesqrt(sqrt(float(u_frame.frame.sample_index + 1u))); }

// A round splat radius of r texels narrowed so (at least one texel).
uint set_narrowed_radius(uint r) { return max(1u, uint(round(float(r) * set_narrowing()))); }

// A splat radius (caustic-map texels) for a light-view square of `side`: its size on the map.
uint side_splat_radius(float side) {
    float texel = u_frame.light.receiver_view.window.z * u_frame.light.receiver_view.extent.z;
    return uint(clamp(round(side / texel), 1.0, float(MAX_SPLAT_RADIUS)));
}

// The splat footprint follows the cell: its size on the caustic map for max-level and dense photons (so that
// neighbours' tents overlap and interpolate), the children's spread for max-error clusters.
uint cell_splat_radius(uvec2 cell) {
    uint r = cell_radius(cell);
    return r == 0u ? side_splat_radius(cell_side(cell_level(cell))) : r;
}

// Weak branches (glsl/wave.comp, docs/design.md step 4): the maximal level's blocks are weak_block() (2 or 4) of
// its cells a side. A photon at least as large as a block shares with its siblings instead, where traverse.comp
// marks them.
uint weak_block() { return uint(u_frame.frame.weak_block); }
uint weak_block_shift() { return findLSB(weak_block()); }
bool weak_by_siblings(uint level) { return level + weak_block_shift() <= u_frame.frame.max_level; }

// A photon's flux in units of the light's intensity (sr, or m^2 for a directional light): Omega of its cell.
float cell_measure(uint level, uvec2 xy) {
    GpuView v = u_frame.light.photon_view;
    return emitter_measure(v, view_xy_of_uv(v, cell_center_uv(level, xy)), cell_side(level));
}

// The two-interface trace of a cell's center (the traversal's checks), or of its photon's sample (`sampled`).
Hit trace_cell(uint level, uvec2 xy, bool sampled) {
    vec2 uv = sampled ? cell_sample_uv(level, xy) : cell_center_uv(level, xy);
    return trace_photon(uv, cell_side(level), leaf_covered(level, xy));
}

#endif
