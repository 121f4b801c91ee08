#version 460
// Traverse one level of the photon quadtree (Wyman & Nichols sec. 3.2, Piao's traversal shader). Each invocation
// takes one candidate cell: a cell that covers no refractor (or lies outside the spot cone) is dropped; a final
// cell is emitted as a photon; otherwise its four children are appended to the photon buffer with atomicAdd.
// A cell is final at the maximal level, or, under the max-error metric, when its 2x2 children land within the
// error bound of one another in the caustic map: then one photon carries the whole cell's flux.
#include "common/photon_bindings.glsl"
#include "common/photon_push.glsl"
#include "common/coverage.glsl"
#include "common/photon.glsl"

#ifndef TRAVERSE_WG_SIDE
#define TRAVERSE_WG_SIDE TRAVERSE_WG
#endif
layout(local_size_x = TRAVERSE_WG_SIDE, local_size_y = TRAVERSE_WG_SIDE) in;

shared uint s_refined;
shared uint s_emitted;
shared uint s_dropped;

// Reserve k entries of the photon buffer. On overflow the batch is aborted (and later split), or, with batching
// off, the entries are dropped and counted. Either way nothing is written past the buffer.
bool reserve(uint k) {
    uint base = atomicAdd(state.used, k);
    if (base + k <= state.capacity) return true;
    if (state.batching != 0u) {
        atomicExchange(state.aborted, 1u);
    } else {
        // Give the entries back so that smaller requests (single photons) can still fit; meanwhile a concurrent
        // request may fail spuriously, which only drops (and counts) more work.
        atomicAdd(state.used, 0u - k);
        atomicAdd(state.overflow_dropped, k);
    }
    return false;
}

void emit(uvec2 cell) {
    if (!reserve(1u)) return;
    uint i = atomicAdd(state.emit_count, 1u);
    photons[state.capacity - 1u - i] = cell;
    atomicAdd(s_emitted, 1u);
}

const uint CHILDREN_REFINE = 0xFFFFFFFFu;
const uint CHILDREN_DROP = 0xFFFFFFFEu;

// Max-error metric: trace the cell's four children. Returns the splat radius (texels) of the converged cluster,
// CHILDREN_DROP when all four fail the same way (all escape the receivers, all meet total internal reflection, ...:
// the cluster carries nothing to a receiver, so refining it would only multiply photons that get discarded), or
// CHILDREN_REFINE.
uint children_verdict(uint level, uvec2 xy) {
    vec2 p[4];
    uint status[4];
    bool all_ok = true;
    for (uint k = 0u; k < 4u; k++) {
        Hit h = trace_cell(level + 1u, 2u * xy + uvec2(k & 1u, k >> 1));
        status[k] = h.status;
        all_ok = all_ok && h.status == HIT_OK;
        p[k] = h.map_px;
    }
    if (!all_ok) {
        bool same = status[0] == status[1] && status[1] == status[2] && status[2] == status[3];
        return same ? CHILDREN_DROP : CHILDREN_REFINE;
    }
    float spread = 0.0;
    for (uint a = 0u; a < 4u; a++)
        for (uint b = a + 1u; b < 4u; b++) spread = max(spread, distance(p[a], p[b]));
    if (spread > u_frame.params.x) return CHILDREN_REFINE;
    return uint(clamp(ceil(spread), 1.0, float(MAX_SPLAT_RADIUS)));
}

void process(uint level, uvec2 cell) {
    uvec2 xy = cell_xy(cell);
    View v = u_frame.photon_view;
    float side = cell_side(level);
    vec2 lo = v.window.xy + vec2(xy) * side;
    vec2 hi = lo + side;
    if (!cell_any_covered(level, xy) || !view_rect_touches_cone(v, lo, hi)) {
        atomicAdd(s_dropped, 1u);
        return;
    }
    uint max_level = u_frame.traversal.x;
    if (level >= max_level) {
        // The same test as the dense method, so that max-level traversal emits exactly dense's photons.
        if (leaf_covered(level, xy) && view_in_cone(v, 0.5 * (lo + hi))) {
            emit(cell);
        } else {
            atomicAdd(s_dropped, 1u);
        }
        return;
    }
    bool max_error = (u_frame.traversal.y & 0xFFu) == 1u;
    if (max_error && level >= u_frame.traversal.z && cell_all_covered(level, xy) && view_rect_inside_cone(v, lo, hi)) {
        // Only fully covered cells inside the cone may converge: then the cluster's flux I*Omega(cell) equals the
        // sum over the leaves that max-level traversal would have emitted.
        uint r = children_verdict(level, xy);
        if (r == CHILDREN_DROP) {
            atomicAdd(s_dropped, 1u);
            return;
        }
        if (r != CHILDREN_REFINE) {
            emit(pack_cell(level, xy.x, xy.y, r));
            return;
        }
    }
    if (!reserve(4u)) return;
    uint i = atomicAdd(state.write_count, 4u);
    uint base = state.read_offset + state.read_count + i;
    for (uint k = 0u; k < 4u; k++) {
        photons[base + k] = pack_cell(level + 1u, 2u * xy.x + (k & 1u), 2u * xy.y + (k >> 1), 0u);
    }
    atomicAdd(s_refined, 1u);
}

void main() {
    if (gl_LocalInvocationIndex == 0u) {
        s_refined = 0u;
        s_emitted = 0u;
        s_dropped = 0u;
    }
    barrier();
    uint per_group = TRAVERSE_WG_SIDE * TRAVERSE_WG_SIDE;
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint i = group * per_group + gl_LocalInvocationIndex;
    if (state.aborted == 0u && i < state.read_count) {
        uvec2 cell = photons[state.read_offset + i];
        process(cell_level(cell), cell);
    }
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        // One atomic per work group instead of one per invocation.
        uint l = pc.level;
        if (s_refined > 0u) atomicAdd(state.batch_levels[l].refined, s_refined);
        if (s_emitted > 0u) atomicAdd(state.batch_levels[l].emitted, s_emitted);
        if (s_dropped > 0u) atomicAdd(state.batch_levels[l].dropped, s_dropped);
    }
}
