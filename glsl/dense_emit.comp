#version 460
// Dense photon emission: every cell of the 64*2^L grid whose center sees a refractor (and lies inside the cone)
// is emitted, one band of rows at a time. The draw count that follows is written by stats (mode 2), so dense
// and adaptive feed the same indirect splat.
#include "common/photon_bindings.glsl"
layout(push_constant) uniform DenseEmitPushBlock { DenseEmitPush pc; };
#include "common/coverage.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

shared uint s_emitted;
shared uint s_base;
shared bool s_reserved;

void main() {
    uint lid = gl_LocalInvocationIndex;
    if (lid == 0u) {
        s_emitted = 0u;
    }
    barrier();
    uint level = pc.level;
    uint n = LEVEL0_RES << level;
    uvec2 xy = uvec2(gl_GlobalInvocationID.x, pc.row0 + gl_GlobalInvocationID.y);
    bool emit = false;
    if (xy.x < n && gl_GlobalInvocationID.y < pc.rows && xy.y < n) {
        emit = leaf_emitted(level, xy);
    }
    // Every invocation takes its slot with one atomic outside any branch (adding 0 when it emits nothing): a CPU
    // driver runs each atomic as a loop over the SIMD group's lanes, whichever are active.
    uint slot = atomicAdd(s_emitted, emit ? 1u : 0u);
    // The work group's candidates, its invocations inside the grid and the band, counted from its place; those
    // not emitted are dropped.
    uvec2 g0 = gl_WorkGroupID.xy * uint(TILE_WG);
    uint rows = pc.row0 < n ? min(pc.rows, n - pc.row0) : 0u;
    uint cand = (n > g0.x ? min(uint(TILE_WG), n - g0.x) : 0u) * (rows > g0.y ? min(uint(TILE_WG), rows - g0.y) : 0u);
    barrier();
    if (lid == 0u) {
        // One reservation per work group.
        s_reserved = false;
        if (s_emitted > 0u) {
            uint base = atomicAdd(state.used, s_emitted);
            if (base + s_emitted <= state.capacity) {
                s_reserved = true;
                s_base = atomicAdd(state.emit_count, s_emitted);
            } else {
                atomicAdd(state.used, 0u - s_emitted);
                atomicAdd(state.overflow_dropped, s_emitted);
            }
        }
    }
    barrier();
    if (emit && s_reserved) {
        photons[state.capacity - 1u - (s_base + slot)] = pack_cell(level, xy.x, xy.y, 0u);
    }
    if (lid == 0u) {
        if (cand > 0u) atomicAdd(state.levels[level].candidates, cand);
        if (s_reserved) atomicAdd(state.levels[level].emitted, s_emitted);
        if (cand > s_emitted) atomicAdd(state.levels[level].dropped, cand - s_emitted);
    }
}
