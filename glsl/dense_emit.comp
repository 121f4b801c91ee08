#version 460
// Dense photon emission: every cell of the 64*2^L grid whose center sees a refractor (and lies inside the cone)
// is emitted, one band of rows at a time. The draw count that follows is written by stats (mode 2), so dense
// and adaptive feed the same indirect splat.
#include "common/photon_bindings.glsl"
#include "common/photon_push.glsl"
#include "common/coverage.glsl"

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

shared uint s_cand;
shared uint s_emitted;
shared uint s_dropped;
shared uint s_base;
shared bool s_reserved;

void main() {
    uint lid = gl_LocalInvocationIndex;
    if (lid == 0u) {
        s_cand = 0u;
        s_emitted = 0u;
        s_dropped = 0u;
    }
    barrier();
    uint level = pc.level;
    uint n = LEVEL0_RES << level;
    uvec2 xy = uvec2(gl_GlobalInvocationID.x, pc.row0 + gl_GlobalInvocationID.y);
    bool emit = false;
    uint slot = 0u;
    if (xy.x < n && gl_GlobalInvocationID.y < pc.rows && xy.y < n) {
        atomicAdd(s_cand, 1u);
        emit = leaf_emitted(level, xy);
        if (emit) {
            slot = atomicAdd(s_emitted, 1u);
        } else {
            atomicAdd(s_dropped, 1u);
        }
    }
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
        if (s_cand > 0u) atomicAdd(state.levels[level].candidates, s_cand);
        if (s_reserved) atomicAdd(state.levels[level].emitted, s_emitted);
        if (s_dropped > 0u) atomicAdd(state.levels[level].dropped, s_dropped);
    }
}
