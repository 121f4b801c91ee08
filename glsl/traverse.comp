#version 460
// Traverse one level of the photon quadtree (Wyman & Nichols sec. 3.2, Piao's traversal shader). Each invocation
// takes one candidate cell: a cell that covers no refractor (or lies outside the spot cone) is dropped; a final
// cell is emitted as a photon; otherwise its four children are appended to the photon buffer with atomicAdd
// (one reservation per work group, so a group of 64 cells costs a few global atomics, not 64).
// A cell is final at the maximal level, or, under the max-error metric, when its 2x2 children land within the
// error bound of one another in the caustic map: then one photon carries the whole cell's flux. Under the
// flux-error metric (docs/design.md, "The flux-error metric") a cell is final when merging its children into one
// photon changes the caustic map, box-filtered to 64², by at most tau times the cell's flux; when the
// same traces predict that each child would be final, the four children are emitted at once (look-ahead).
// In every variant the last level is fused into the one before: a cell at level L - 1 that refines emits those of
// its four children that dense emission would emit, instead of appending them as candidates of level L.
// TRAVERSE_MAX_LEVEL compiles the max-level variant: no metric code at all (llvmpipe runs both sides of a divergent
// branch under a mask, so code that max-level never takes still costs its full price there; docs/experiments.md).
// Likewise TRAVERSE_METRIC (METRIC_MAX_ERROR or METRIC_FLUX_ERROR, src/shader_consts.rs) compiles one metric's code
// only.
// TRAVERSE_COOP (exact transport, max-error and flux-error; `--coop-checks`): four invocations share each
// candidate, so a work group of side^2 invocations takes side^2 / 4 candidates. Each lane first traces one child's
// dominant path into shared memory, then lane 0 decides with the four results. A check then waits for the
// longest of four paths instead of all four in a row: on a GPU, where a level's few checked cells leave most
// lanes idle, that is about 4x shorter; on a CPU device it is the same work, and early returns trace less.
#include "common/photon_bindings.glsl"
layout(push_constant) uniform TraversePushBlock { TraversePush pc; };
#include "common/coverage.glsl"
#include "common/photon.glsl"
#include "common/transport.glsl"

#ifndef TRAVERSE_WG_SIDE
#define TRAVERSE_WG_SIDE TRAVERSE_WG
#endif
layout(local_size_x = TRAVERSE_WG_SIDE, local_size_y = TRAVERSE_WG_SIDE) in;

shared uint s_emit_n;      // photons this work group emits
shared uint s_child_n;     // cells this work group refines (4 entries each)
shared uint s_dropped;
shared uint s_emit_base;
shared uint s_child_base;
shared bool s_reserved;
shared uint s_leaf_cells;  // cells of level L - 1 whose children were tested here (fused last level)
shared uint s_leaf_emit;   // photons those children gave
shared uint s_skipped;     // checks skipped (predicted by the parent's)
shared uint s_unchecked;   // candidates from the check level on that could not be checked
#if !defined(TRAVERSE_MAX_LEVEL) && TRAVERSE_WG_SIDE >= 2
// Each candidate's action, so that a photon can tell whether its three siblings (the same group of four candidates,
// which a refined cell appends together) became photons of its level too: weak-branch sharing (wave.comp).
shared uint s_act[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
#endif

#ifdef TRAVERSE_COOP
const uint LANES = 4u;  // invocations per candidate
// The dominant paths of each candidate's four children (index 4 * candidate + child), traced one per lane, and
// whether a candidate's were traced.
shared vec2 s_dom_p[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
shared vec3 s_dom_land[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
shared uint s_dom_status[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
shared uint s_dom_events[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
shared float s_dom_thr[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE];
shared bool s_dom_ok[TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE / 4];
uint g_cand = 0u;  // this invocation's candidate in the work group
#else
const uint LANES = 1u;
#endif

// Child k's dominant path (trace_dominant) for the metrics' checks: from the lanes' shared results when they traced
// it (TRAVERSE_COOP), else traced here.
uint child_dominant(uint level, uvec2 xy, uint k, out vec2 p, out vec3 land, out uint events, out float thr) {
#ifdef TRAVERSE_COOP
    if (s_dom_ok[g_cand]) {
        uint j = 4u * g_cand + k;
        p = s_dom_p[j];
        land = s_dom_land[j];
        events = s_dom_events[j];
        thr = s_dom_thr[j];
        return s_dom_status[j];
    }
#endif
    return trace_dominant(level + 1u, 2u * xy + uvec2(k & 1u, k >> 1), p, land, events, thr);
}

// Whether the frame traces exact transport (else the two-interface model). The wide layout's variants run only
// under exact transport (its checks walk the layout the waves trace), so they compile no two-interface trace,
// which a CPU driver would run, masked, beside every check.
#if defined(BVH_LAYOUT_WIDE)
bool transport_exact() { return true; }
#else
bool transport_exact() { return u_frame.frame.exact != 0u; }
#endif

const uint ACT_DROP = 0u;
const uint ACT_EMIT = 1u;
const uint ACT_REFINE = 2u;
const uint ACT_EMIT_CHILDREN = 3u;  // flux-error look-ahead: four photons, the cell's children
const uint ACT_EMIT_LEAVES = 4u;    // refined at level L - 1: the children that pass dense's test, as photons

// The order in which a metric traces a cell's four children (k: x = k & 1, y = k >> 1): the diagonal pair first.
const uint CHILD_ORDER[4] = uint[4](0u, 3u, 1u, 2u);

// The photon view's rectangle of cell (level, xy).
void cell_rect(uint level, uvec2 xy, out vec2 lo, out vec2 hi) {
    float side = cell_side(level);
    lo = u_frame.light.photon_view.window.xy + vec2(xy) * side;
    hi = lo + side;
}

// Whether the cell touches a refractor inside the cone at all (else it is dropped).
bool cell_in_play(uint level, uvec2 xy) {
    vec2 lo, hi;
    cell_rect(level, xy, lo, hi);
    return cell_any_covered(level, xy) && emitter_touches(u_frame.light.photon_view, lo, hi);
}

// Whether the cell lies wholly on the refractors and inside the cone: the metrics check only such cells, because
// then the cluster's flux I*Omega(cell) equals the sum over the leaves that max-level traversal would have emitted.
bool cell_inside(uint level, uvec2 xy) {
    vec2 lo, hi;
    cell_rect(level, xy, lo, hi);
    return cell_all_covered(level, xy) && emitter_contains(u_frame.light.photon_view, lo, hi);
}

// Flux-error's look-ahead level: one above the check level, when that is above the maximal level's.
bool look_ahead_level(uint level) {
    return level + 1u == u_frame.frame.check_level && u_frame.frame.check_level < u_frame.frame.max_level;
}

#if !defined(TRAVERSE_MAX_LEVEL) && !defined(TRAVERSE_METRIC)
#define TRAVERSE_METRIC METRIC_MAX_ERROR
#endif

#if defined(TRAVERSE_METRIC) && TRAVERSE_METRIC == METRIC_MAX_ERROR

const uint CHILDREN_REFINE = 0xFFFFFFFFu;
const uint CHILDREN_DROP = 0xFFFFFFFEu;

// Max-error metric: trace the cell's four children. Returns the splat radius (texels) of the converged cluster,
// CHILDREN_DROP when all four fail the same way (all escape the receivers, all meet total internal reflection, ...:
// the cluster carries nothing to a receiver, so refining it would only multiply photons that get discarded), or
// CHILDREN_REFINE.
// Under exact transport each child follows its dominant path (the larger Fresnel branch at every interface). The
// cluster converges when all four land on a receiver after the same number of interactions and within the bound;
// children whose paths split (a silhouette, a TIR boundary, a different number of interfaces) refine. When all
// four end the same other way (escape, direct light, the cap), the cell is emitted rather than dropped: its
// weaker branches may still reach a receiver, and its own waves trace them all.
uint children_verdict_exact(uint level, uvec2 xy) {
    vec2 p[4];
    uint status[4], events[4];
    float thr;
    vec3 land;
    // Diagonal children first: they land farthest apart, so a cell that refines is usually known to after two.
    // Every early return is a REFINE the four traces would have given (the tests below only tighten as children are
    // added), so the verdicts, and the photons, are the same as tracing all four.
    for (uint j = 0u; j < 4u; j++) {
        uint k = CHILD_ORDER[j];
        status[k] = child_dominant(level, xy, k, p[k], land, events[k], thr);
        if (status[k] == DOM_LONG) return CHILDREN_REFINE;  // trapped in the glass: where it lands is unknown
        if (j == 0u) continue;
        if (status[k] != status[0]) return CHILDREN_REFINE;
        if (status[k] != DOM_OK) continue;
        if (events[k] != events[0]) return CHILDREN_REFINE;
        for (uint i = 0u; i < j; i++) {
            if (distance(p[k], p[CHILD_ORDER[i]]) > u_frame.frame.error_bound) return CHILDREN_REFINE;
        }
    }
    if (status[0] != DOM_OK) return 0u;
    float spread = 0.0;
    for (uint a = 0u; a < 4u; a++)
        for (uint b = a + 1u; b < 4u; b++) spread = max(spread, distance(p[a], p[b]));
    return uint(clamp(ceil(spread), 1.0, float(MAX_SPLAT_RADIUS)));
}

uint children_verdict(uint level, uvec2 xy) {
    if (transport_exact()) return children_verdict_exact(level, xy);
    vec2 p[4];
    uint status[4];
    // As in children_verdict_exact: stop tracing once the verdict can only be REFINE (a status that differs, or two
    // children that both reached the map farther apart than the bound).
    for (uint j = 0u; j < 4u; j++) {
        uint k = CHILD_ORDER[j];
        Hit h = trace_cell(level + 1u, 2u * xy + uvec2(k & 1u, k >> 1), false);
        status[k] = h.status;
        p[k] = h.map_px;
        if (j == 0u) continue;
        if (status[k] != status[0]) return CHILDREN_REFINE;
        if (status[k] != HIT_OK) continue;
        for (uint i = 0u; i < j; i++) {
            if (distance(p[k], p[CHILD_ORDER[i]]) > u_frame.frame.error_bound) return CHILDREN_REFINE;
        }
    }
    if (status[0] != HIT_OK) return CHILDREN_DROP;
    float spread = 0.0;
    for (uint a = 0u; a < 4u; a++)
        for (uint b = a + 1u; b < 4u; b++) spread = max(spread, distance(p[a], p[b]));
    return uint(clamp(ceil(spread), 1.0, float(MAX_SPLAT_RADIUS)));
}

#endif  // TRAVERSE_METRIC == METRIC_MAX_ERROR

#if defined(TRAVERSE_METRIC) && TRAVERSE_METRIC == METRIC_FLUX_ERROR

// Flux-error metric (docs/design.md, "The flux-error metric"). Each child k lands at p_k (caustic-map texels)
// carrying the caustic flux phi_k (W: its dominant path's under exact transport, the two-interface trace's
// otherwise; 0 when it does not reach a receiver after a specular interaction). Merging the four into one photon
// of the cell moves each phi_k to the flux-weighted centroid c; after the 64² box filter of the error metric
// that changes the map by at most E = sum_k 2 phi_k min(1, |p_k - c|_1 / w) in L1 (w: a 64² texel, in caustic-map
// texels). Children that all land after specular interactions are compared by position alone (a different number
// of interfaces does not matter if they land together). Children that end differently (a silhouette, TIR, an
// escape) can make the merged photon deposit anything between nothing and the cell's flux times the largest
// throughput, so then E = I Omega(cell) max_k T_k + sum_k phi_k. The cell is final when E <= tau I Omega(cell): summed over the final cells, the
// merging error is at most tau times the flux that meets the refractor. tau (params.w) is what src/calibration.rs
// maps `--target-error` to.
const uint FE_REFINE = 0u;
const uint FE_FINAL = 1u;     // emit the cell as one photon
const uint FE_CHILDREN = 2u;  // emit its four children (each predicted final)
const uint FE_DROP = 3u;

// Prediction (flux-error only): where the map is locally linear, E over the budget halves from one level to the next
// (E has a quarter of the flux and half the spread, the budget a quarter). A cell that refines with E above
// FE_PREDICT budgets has children at about FE_PREDICT / 2 = 1 budget, and one above 2^(d-1) FE_PREDICT budgets has
// descendants d levels down at about 1 budget: those d levels refine without their checks (predicted_skip). The
// candidates carry how many levels still skip in their radius bits, which candidates do not otherwise use (0:
// checked). Where the children end differently (a silhouette, a TIR edge), or all end away from the receivers (the
// weak branches' bound), E is in proportion to the flux and does not halve: every checked level below skips
// (predicted_skip_mixed). Where the map bends, or a child lies off the boundary, a cell so refined might have merged:
// it then costs photons, never error. FE_PREDICT = 2 is the look-ahead's own bound, so every cell that refines
// beyond the look-ahead's band predicts its children. Measured on lavapipe at level 5 (docs/experiments.md): one level
// against none, the bunny's frame 4% and 14% shorter at E = 0.001 and 0.0158 (a factor-2 margin, 4, against 2: the
// sphere's 11%, 6% and 0% at E = 0.001, 0.005 and 0.0158); the chains over several levels, from the early look-ahead
// on and through the mixed and weak bounds, the bunny's 27%, 26% and 11% shorter again, the sphere's 4%, 1% and 0%,
// for 0.02% to 6% more photons and the same error or less.
const float FE_PREDICT = 2.0;

// Camera-driven refinement (`--refine camera`; docs/design.md, "Camera-driven refinement"): the error is measured
// in the camera's image, box-filtered to 64², where light-driven refinement measures it in the light's caustic map.
// A landing's position is then in units of that image's boxes, and the camera's view holds it (`seen`) when it lies
// in front of the eye within one box of the image's edges, which a merged photon's tent may reach across.
bool camera_box(vec3 p, out vec2 q) {
    GpuView cam = u_frame.frame.camera;
    vec3 img = view_image(cam, p);
    q = (img.xy - cam.window.xy) / cam.window.zw * 64.0;
    return (view_is_ortho(cam) || img.z > 0.0) && all(greaterThan(q, vec2(-1.0))) && all(lessThan(q, vec2(65.0)));
}

// The levels below `level` whose cells are checked: the last level's are not (they are leaves).
uint checked_levels_below(uint level) {
    return level + 2u <= u_frame.frame.max_level ? u_frame.frame.max_level - level - 1u : 0u;
}

// How many levels below a refining cell skip their checks, from its E over its budget (`ratio`): the d-th level down
// is predicted to refine when ratio > 2^(d-1) FE_PREDICT. A chain that stops short of the last checked level skips
// one level less: the cells where it stops refine unchecked, and their four times as many children would all be
// checked, knowing nothing, where a check of the cells themselves costs a quarter and predicts for their children.
uint predicted_skip(uint level, float ratio) {
    uint below = min(checked_levels_below(level), 8u);
    uint d = ratio > FE_PREDICT ? uint(floor(log2(ratio / FE_PREDICT))) + 1u : 0u;
    return d >= below ? below : max(d, 1u) - 1u;
}

// Mixed endings (or the weak branches' bound, where all four children end away from the receivers): E is in
// proportion to the cell's flux, so E over the budget does not halve from one level to the next.
uint predicted_skip_mixed(uint level, float ratio) {
    return ratio > FE_PREDICT ? min(checked_levels_below(level), 8u) : 0u;
}

// `merge_only`: the caller only needs to know whether the cell could merge (one level above the check level), and
// how many levels below it are predicted to refine, so the traces stop as soon as e is known to exceed the budget
// and every checked level's prediction.
uint flux_error_verdict(uint level, uvec2 xy, bool merge_only, out uint radius, out uint skip) {
    radius = 0u;
    skip = 0u;
    bool exact = transport_exact();
    float intensity = u_frame.light.light_intensity;
    vec2 p[4];
    float phi[4] = float[4](0.0, 0.0, 0.0, 0.0);
    uint status[4], events[4];
    float t_max = 0.0, t_min = 1.0, rest = 0.0;
    float cell_flux = intensity * cell_measure(level, xy);
    float budget = u_frame.frame.tau * cell_flux;
    // The error's image: the caustic map (q = p, in its texels; w: a 64² box's side), or the camera's (q in its
    // boxes, w = 1), which holds only the landings it sees (`seen`).
    bool camera = u_frame.frame.refine == REFINE_CAMERA;
    float w = camera ? 1.0 : float(u_frame.frame.caustic_res) / 64.0;
    vec2 q[4];
    bool seen[4];
    // A cell refines when E exceeds this (twice the budget where the look-ahead may still emit the children).
    float refine_above = level + 1u < u_frame.frame.max_level ? 2.0 * budget : budget;
    // Where the children would be checked, a cell that refines on the same-endings bound goes on tracing until
    // the bound also says how many levels below are predicted to refine (predicted_skip): their checks cost more
    // than these traces. `deepest`: the E from which every checked level below is.
    uint below = checked_levels_below(level);
    float deepest = below > 0u ? FE_PREDICT * exp2(float(below - 1u)) * budget : 0.0;
    float stop_above = 1.01 * max(merge_only ? budget : refine_above, deepest);
    uint ok = exact ? DOM_OK : HIT_OK;
    bool mixed = false;
    for (uint j = 0u; j < 4u; j++) {
        uint k = CHILD_ORDER[j];
        uvec2 c = 2u * xy + uvec2(k & 1u, k >> 1);
        vec3 land;
        if (exact) {
            float thr;
            status[k] = child_dominant(level, xy, k, p[k], land, events[k], thr);
            // A path still in the glass after the checks' cap may land anywhere with its dominant flux: it counts
            // as a child that ends differently, carrying that flux (an upper bound on what it deposits).
            bool known = status[k] == DOM_OK || status[k] == DOM_LONG;
            phi[k] = known ? intensity * cell_measure(level + 1u, c) * thr : 0.0;
            if (status[k] == DOM_LONG) mixed = true;
            t_max = max(t_max, thr);
            t_min = min(t_min, thr);
            rest += intensity * cell_measure(level + 1u, c) * (1.0 - thr);
        } else {
            Hit h = trace_cell(level + 1u, c, false);
            status[k] = h.status;
            events[k] = 0u;
            p[k] = h.map_px;
            land = h.pos;
            phi[k] = h.status == HIT_OK ? h.flux : 0.0;
            float full = intensity * cell_measure(level + 1u, c);
            t_max = max(t_max, full > 0.0 ? h.flux / full : 0.0);
        }
        q[k] = p[k];
        seen[k] = status[k] == ok && (!camera || camera_box(land, q[k]));
        // Stop tracing once the verdict can only be REFINE. Both bounds below only grow as children are added:
        // the mixed-endings E (t_max and the landed flux), and, while the children so far all landed, a lower
        // bound on the same-endings E: for any centroid c, |p_a - c|_1 + |p_b - c|_1 >= |p_a - p_b|_1, so
        // E >= 2 min(phi_a, phi_b) min(1, |p_a - p_b|_1 / w) for every pair. A 1% margin keeps rounding (and a
        // compiler's different fusing of the final expressions) from turning an early REFINE into a different
        // verdict: the photons are the same as with four traces.
        if (j == 0u) continue;
        mixed = mixed || status[k] != status[0];
        float partial = phi[0] + phi[1] + phi[2] + phi[3];  // the children not traced yet hold 0
        bool mixed_refines = cell_flux * t_max + partial > 1.01 * budget;
        if (mixed && mixed_refines) {
            skip = predicted_skip_mixed(level, (cell_flux * t_max + partial) / budget);
            return FE_REFINE;
        }
        if (!mixed && status[0] == ok && mixed_refines) {
            float lower = 0.0;
            for (uint i = 0u; i < j; i++) {
                uint b = CHILD_ORDER[i];
                if (!seen[k] || !seen[b]) continue;  // (a pair's bound holds where the image holds both)
                vec2 d = abs(q[k] - q[b]);
                lower = max(lower, 2.0 * min(phi[k], phi[b]) * min(1.0, (d.x + d.y) / w));
            }
            if (lower > stop_above) {
                skip = predicted_skip(level, lower / budget);
                return FE_REFINE;
            }
        }
    }
    bool same = status[0] == status[1] && status[1] == status[2] && status[2] == status[3];
    // All four end the same other way: two-interface drops the cell (it carries nothing to a receiver). Under exact
    // transport the weaker branches, the share 1 - T_k of each child's flux, may still reach one, anywhere: the
    // merged photon's between nothing and I Omega(cell) (1 - T_min), the children's in total `rest`.
    if (same && status[0] != ok && status[0] != DOM_LONG) {
        if (!exact) return FE_DROP;
        float e_weak = cell_flux * (1.0 - t_min) + rest;
        if (e_weak <= budget) return FE_FINAL;
        skip = predicted_skip_mixed(level, e_weak / budget);  // a bound in proportion to the flux, as below
        return FE_REFINE;
    }
    float total = phi[0] + phi[1] + phi[2] + phi[3];
    // Mixed endings: the merged photon deposits between nothing and I Omega(cell) T_max, the children total.
    if (!same || status[0] == DOM_LONG) {
        float e_mixed = cell_flux * t_max + total;
        if (e_mixed <= budget) return FE_FINAL;
        skip = predicted_skip_mixed(level, e_mixed / budget);
        return FE_REFINE;
    }
    vec2 c = total > 0.0 ? (phi[0] * q[0] + phi[1] * q[1] + phi[2] * q[2] + phi[3] * q[3]) / total
                         : 0.25 * (q[0] + q[1] + q[2] + q[3]);
    // Where the camera sees some of the four landings but not all, merging may move each seen child's flux out of
    // its view or across it: the bound is its whole flux, twice. Where it sees none, merging changes nothing it sees.
    bool all_seen = seen[0] && seen[1] && seen[2] && seen[3];
    float e = 0.0, spread = 0.0;
    for (uint k = 0u; k < 4u; k++) {
        vec2 d = abs(q[k] - c);
        if (seen[k]) e += 2.0 * phi[k] * (all_seen ? min(1.0, (d.x + d.y) / w) : 1.0);
        for (uint b = k + 1u; b < 4u; b++) spread = max(spread, distance(p[k], p[b]));
    }
    if (e <= budget) {
        radius = uint(clamp(ceil(spread), 1.0, float(MAX_SPLAT_RADIUS)));
        return FE_FINAL;
    }
    // Look-ahead: where the map is locally linear, each child's own children spread half as far as the children
    // do, with a quarter of the flux each, so a child's error is about e / 8 against a budget of budget / 4. The
    // children are final too when e <= 2 budget: emit them now instead of tracing their sixteen children next.
    if (level + 1u < u_frame.frame.max_level && e <= 2.0 * budget) {
        radius = uint(clamp(ceil(0.5 * spread), 1.0, float(MAX_SPLAT_RADIUS)));
        return FE_CHILDREN;
    }
    // (A bound in proportion to the seen flux does not halve from one level to the next, and the children that lie
    // outside the view need no refinement: where the view holds some of the four, each child is checked.)
    skip = all_seen ? predicted_skip(level, e / budget) : 0u;
    return FE_REFINE;
}

#endif  // TRAVERSE_METRIC == METRIC_FLUX_ERROR

#ifdef TRAVERSE_COOP
// Whether decide() checks `cell` with its four children's dominant paths, by decide's own tests. A cell this missed
// would be traced by decide itself (child_dominant), so the two need to agree only for speed.
bool needs_checks(uint level, uvec2 cell) {
    uvec2 xy = cell_xy(cell);
    if (!transport_exact() || !cell_in_play(level, xy) || level >= u_frame.frame.max_level) return false;
    bool checkable = level >= u_frame.frame.check_level && cell_inside(level, xy);
#if TRAVERSE_METRIC == METRIC_FLUX_ERROR
    if (checkable) return cell_radius(cell) == 0u;  // else predicted to refine: no check
    return look_ahead_level(level) && cell_inside(level, xy);
#else
    return checkable;
#endif
}
#endif

// Decide what happens to one candidate: dropped, emitted as a photon (`out_cell`), or refined (`out_cell`'s radius
// bits are then its children's: how many levels skip their checks, or 0). `no_check`: 1 when a metric's check was
// skipped (predicted), 2 when the candidate could not be checked.
uint decide(uint level, uvec2 cell, out uvec2 out_cell, out uint no_check) {
    uvec2 xy = cell_xy(cell);
    out_cell = pack_cell(level, xy.x, xy.y, 0u);
    no_check = 0u;
    if (!cell_in_play(level, xy)) return ACT_DROP;
    if (level >= u_frame.frame.max_level) {
        // The same test as the dense method, so that max-level traversal emits exactly dense's photons.
        return leaf_emitted(level, xy) ? ACT_EMIT : ACT_DROP;
    }
#ifdef TRAVERSE_MAX_LEVEL
    return ACT_REFINE;
#else
    // Only fully covered cells inside the cone are checked (cell_inside).
    bool checkable = false;
    if (level >= u_frame.frame.check_level) {
        checkable = cell_inside(level, xy);
        if (!checkable) no_check = 2u;
    }
#endif
#if defined(TRAVERSE_METRIC) && TRAVERSE_METRIC == METRIC_FLUX_ERROR
    // The look-ahead starts one level above the check level: a cell there never becomes a photon itself, but when
    // it could merge (e <= its budget; each child is then predicted at an eighth of it, against a quarter) its
    // children are emitted now, without their own checks; otherwise they refine, and skip the checks that its e
    // predicts to refine (predicted_skip). The look-ahead's own band (up to 2 budgets) added more than E to the
    // bunny at level 5 (0.520% at E = 0.005), against 0.474% without this. One call site for the verdict: llvmpipe
    // inlines it, and a second copy slowed every level of this shader.
    bool early = look_ahead_level(level) && cell_inside(level, xy);
    if (checkable || early) {
        uint skip = cell_radius(cell);
        if (checkable && skip != 0u) {
            // Predicted to refine by an ancestor's check: the levels it predicted below this one skip theirs too.
            no_check = 1u;
            out_cell = pack_cell(level, xy.x, xy.y, skip - 1u);
            return ACT_REFINE;
        }
        uint r;
        uint verdict = flux_error_verdict(level, xy, early, r, skip);
        if (early) {
            if (verdict != FE_FINAL) {
                out_cell = pack_cell(level, xy.x, xy.y, skip);
                return ACT_REFINE;
            }
            // The children's splat radius is half the spread: ceil(ceil(s) / 2) = ceil(s / 2); 0 stays 0.
            out_cell = pack_cell(level, xy.x, xy.y, (r + 1u) / 2u);
            return ACT_EMIT_CHILDREN;
        }
        if (verdict == FE_DROP) return ACT_DROP;
        if (verdict == FE_FINAL) {
            out_cell = pack_cell(level, xy.x, xy.y, r);
            return ACT_EMIT;
        }
        if (verdict == FE_CHILDREN) {
            out_cell = pack_cell(level, xy.x, xy.y, r);
            return ACT_EMIT_CHILDREN;
        }
        // Children that will be checked (not the last level's) skip their check when it is predicted to refine.
        out_cell = pack_cell(level, xy.x, xy.y, skip);
    }
#elif defined(TRAVERSE_METRIC) && TRAVERSE_METRIC == METRIC_MAX_ERROR
    if (checkable) {
        uint r = children_verdict(level, xy);
        if (r == CHILDREN_DROP) return ACT_DROP;
        if (r != CHILDREN_REFINE) {
            out_cell = pack_cell(level, xy.x, xy.y, r);
            return ACT_EMIT;
        }
    }
#endif
    return ACT_REFINE;
}

// The work group's reservation (its first invocation's): one for all its photons and children, against two bounds:
// the batch's entries (state.capacity) and its photons alone (u_frame.frame.batch_photons). On overflow the batch is
// aborted (and later split) or, with batching off, the group's entries are dropped and counted; either way nothing
// is written past the buffer. Without batching state.capacity is traversal.w itself, and the photons, counted in
// `used` too, cannot exceed it, so only the first bound can fail there.
void reserve() {
    uint entries = s_emit_n + 4u * s_child_n;
    s_reserved = false;
    if (entries > 0u) {
        uint base = atomicAdd(state.used, entries);
        bool fits = base + entries <= state.capacity;
        if (fits) {
            s_emit_base = atomicAdd(state.emit_count, s_emit_n);
            fits = s_emit_base + s_emit_n <= u_frame.frame.batch_photons;
        }
        if (fits) {
            s_reserved = true;
            s_child_base = atomicAdd(state.write_count, 4u * s_child_n);
        } else if (state.batching != 0u) {
            atomicExchange(state.aborted, 1u);
        } else {
            atomicAdd(state.used, 0u - entries);
            atomicAdd(state.overflow_dropped, entries);
        }
    }
}

// A candidate's outputs into the reserved entries: its photon (with its weak-branch siblings), its four children
// as photons, the fused last level's leaves, or its four children as the next level's candidates.
void write_outputs(uint action, uvec2 out_cell, uint slot, uint siblings, uint leaves, uint level) {
    if (action == ACT_EMIT) {
        photons[state.capacity - 1u - (s_emit_base + slot)] = with_siblings(out_cell, siblings);
    } else if (action == ACT_EMIT_CHILDREN) {
        uvec2 xy = cell_xy(out_cell);
        uint r = cell_radius(out_cell);
        for (uint k = 0u; k < 4u; k++) {
            uvec2 c = pack_cell(level + 1u, 2u * xy.x + (k & 1u), 2u * xy.y + (k >> 1), r);
            photons[state.capacity - 1u - (s_emit_base + slot + k)] =
                weak_by_siblings(level + 1u) ? with_siblings(c, 7u) : c;
        }
    } else if (action == ACT_EMIT_LEAVES) {
        uvec2 xy = cell_xy(out_cell);
        uint j = 0u;
        for (uint k = 0u; k < 4u; k++) {
            if ((leaves & (1u << k)) != 0u) {
                photons[state.capacity - 1u - (s_emit_base + slot + j)] =
                    pack_cell(level + 1u, 2u * xy.x + (k & 1u), 2u * xy.y + (k >> 1), 0u);
                j++;
            }
        }
    } else if (action == ACT_REFINE) {
        uvec2 xy = cell_xy(out_cell);
        uint r = cell_radius(out_cell);
        uint base = state.read_offset + state.read_count + s_child_base + 4u * slot;
        for (uint k = 0u; k < 4u; k++) {
            photons[base + k] = pack_cell(level + 1u, 2u * xy.x + (k & 1u), 2u * xy.y + (k >> 1), r);
        }
    }
}

void main() {
    uint lid = gl_LocalInvocationIndex;
    if (lid == 0u) {
        s_emit_n = 0u;
        s_child_n = 0u;
        s_dropped = 0u;
        s_leaf_cells = 0u;
        s_leaf_emit = 0u;
        s_skipped = 0u;
        s_unchecked = 0u;
    }
    barrier();
    uint per_group = TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE / LANES;
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint lane = lid % LANES, me = lid / LANES;  // me: the candidate's index in the work group
    uint i = group * per_group + me;
    uint level = pc.level;
    uint action = ACT_DROP;
    uvec2 out_cell = uvec2(0u);
    uint slot = 0u;
    uint leaves = 0u;
    bool have = state.aborted == 0u && i < state.read_count;
    uvec2 cell = have ? photons[state.read_offset + i] : uvec2(0u);
#ifdef TRAVERSE_COOP
    {
        // Lane k traces child k's dominant path when the candidate will be checked.
        g_cand = me;
        bool traced = have && needs_checks(cell_level(cell), cell);
        if (traced) {
            uvec2 c = 2u * cell_xy(cell) + uvec2(lane & 1u, lane >> 1);
            uint j = LANES * me + lane;
            s_dom_status[j] = trace_dominant(cell_level(cell) + 1u, c, s_dom_p[j], s_dom_land[j], s_dom_events[j], s_dom_thr[j]);
        }
        if (lane == 0u) s_dom_ok[me] = traced;
        barrier();
    }
#endif
    if (have && lane == 0u) {
        uint no_check;
        action = decide(cell_level(cell), cell, out_cell, no_check);
        // The last level fused into the one before: a cell of level L - 1 that refines emits those of its four
        // children that dense emission would emit, instead of appending them as candidates of level L, whose
        // traversal then has nothing to do.
        if (action == ACT_REFINE && level + 1u == u_frame.frame.max_level) {
            for (uint k = 0u; k < 4u; k++) {
                if (leaf_emitted(level + 1u, 2u * cell_xy(cell) + uvec2(k & 1u, k >> 1))) leaves |= 1u << k;
            }
            action = ACT_EMIT_LEAVES;
        }
#ifndef TRAVERSE_MAX_LEVEL
        if (no_check == 1u) atomicAdd(s_skipped, 1u);
        if (no_check == 2u) atomicAdd(s_unchecked, 1u);
#endif
        if (action == ACT_EMIT) slot = atomicAdd(s_emit_n, 1u);
        if (action == ACT_EMIT_CHILDREN) slot = atomicAdd(s_emit_n, 4u);
        if (action == ACT_EMIT_LEAVES) {
            uint n = bitCount(leaves);
            slot = atomicAdd(s_emit_n, n);
            atomicAdd(s_leaf_cells, 1u);
            atomicAdd(s_leaf_emit, n);
        }
        if (action == ACT_REFINE) slot = atomicAdd(s_child_n, 1u);
        if (action == ACT_DROP) atomicAdd(s_dropped, 1u);
    }
#if !defined(TRAVERSE_MAX_LEVEL) && TRAVERSE_WG_SIDE >= 2
    if (lane == 0u) s_act[me] = action;
#endif
    barrier();
    // Weak-branch siblings (glsl/common/types.glsl, wave.comp): a photon too large for the maximal level's weak-branch
    // blocks shares its weak branches with its three siblings when each of them is a photon of its level too, or
    // covers nothing. Candidates below the tile's first level come in groups of four siblings (a refined cell's
    // children, appended together, aligned to four in the work group); a look-ahead's four photons are such a group
    // by construction.
    // (A work group of one candidate, `--traverse-wg 1`, cannot see its siblings: its clusters share nothing.)
    uint siblings = 0u;
#if !defined(TRAVERSE_MAX_LEVEL) && TRAVERSE_WG_SIDE >= 2
    if (action == ACT_EMIT && level > state.start_level && weak_by_siblings(level)) {
        uint g = me & ~3u, self = me & 3u, j = 0u;
        bool whole = true;
        for (uint k = 0u; k < 4u; k++) {
            if (k == self) continue;
            uint a = s_act[g + k];
            if (a == ACT_EMIT) siblings |= 1u << j;
            else if (a != ACT_DROP) whole = false;
            j++;
        }
        if (!whole) siblings = 0u;
    }
#endif
    if (lid == 0u) reserve();
    barrier();
    if (s_reserved) write_outputs(action, out_cell, slot, siblings, leaves, level);
    if (lid == 0u) {
        // One atomic per work group instead of one per invocation.
        uint refined = s_child_n + s_leaf_cells, emitted = s_emit_n - s_leaf_emit;
        if (s_reserved && refined > 0u) atomicAdd(state.batch_levels[level].refined, refined);
        if (s_reserved && emitted > 0u) atomicAdd(state.batch_levels[level].emitted, emitted);
        if (s_dropped > 0u) atomicAdd(state.batch_levels[level].dropped, s_dropped);
        if (s_reserved && s_skipped > 0u) atomicAdd(state.batch_levels[level].checks_skipped, s_skipped);
        if (s_reserved && s_unchecked > 0u) atomicAdd(state.batch_levels[level].unchecked, s_unchecked);
        if (s_reserved && s_leaf_cells > 0u) {
            // The fused last level's counts, as if its candidates had been traversed there.
            atomicAdd(state.batch_levels[level + 1u].candidates, 4u * s_leaf_cells);
            if (s_leaf_emit > 0u) atomicAdd(state.batch_levels[level + 1u].emitted, s_leaf_emit);
            if (4u * s_leaf_cells > s_leaf_emit) atomicAdd(state.batch_levels[level + 1u].dropped, 4u * s_leaf_cells - s_leaf_emit);
        }
    }
}
