#version 460
// Init (Piao's initialization shader). INIT_FRAME, once per frame: clear the counters and push the root tile (the
// whole 64^2 level-0 grid). INIT_BATCH, once per batch: pop a tile, write its level-0 candidates (or its one cell),
// and write the first level's dispatch-indirect arguments and an empty draw-indirect command. INIT_DENSE: a dense band.
#include "common/photon_bindings.glsl"
layout(push_constant) uniform InitPushBlock { InitPush pc; };

layout(local_size_x = 256) in;

shared uint s_count;
shared ivec4 s_tile;

void main() {
    uint tid = gl_LocalInvocationIndex;
    if (pc.mode == INIT_FRAME || pc.mode == INIT_DENSE) {
        if (tid == 0u) {
            // The frame-start clear of the whole state is a vkCmdFillBuffer; here only the non-zero fields.
            state.batching = u_frame.frame.batching;
            // A batching traversal may fill the whole buffer, its photons within traversal.w (traverse.comp checks
            // both); dense bands, and traversal without batching, use traversal.w entries at most.
            state.capacity = pc.mode == INIT_FRAME && state.batching != 0u ? u_frame.frame.record_capacity : u_frame.frame.batch_photons;
            state.start_level = MAX_LEVELS;
            state.stack_size = 0u;
            state.emit_count = 0u;
            state.used = 0u;
            state.aborted = 0u;
            if (pc.mode == INIT_FRAME) {
                state.stack[0] = ivec4(-6, 0, 0, 0);  // 2^6 = 64: the whole level-0 grid
                state.stack_size = 1u;
            }
            for (uint l = 0u; l < MAX_LEVELS; l++) dispatch_cmd(l) = uvec4(0u, 0u, 1u, 0u);
            set_emitted(0u, state.capacity);
        }
        return;
    }
    if (tid == 0u) {
        state.read_offset = 0u;
        state.write_count = 0u;
        state.emit_count = 0u;
        state.aborted = 0u;
        for (uint l = 0u; l < MAX_LEVELS; l++) {
            state.batch_levels[l] = LevelCounters(0u, 0u, 0u, 0u, 0u, 0u);
            dispatch_cmd(l) = uvec4(0u, 0u, 1u, 0u);
        }
        set_emitted(0u, state.capacity);
        if (state.stack_size == 0u) {
            s_tile = ivec4(0, 0, 0, -1);
            s_count = 0u;
            state.start_level = MAX_LEVELS;
            state.read_count = 0u;
            state.used = 0u;
        } else {
            state.stack_size -= 1u;
            ivec4 t = state.stack[state.stack_size];
            uint count = t.x < 0 ? (1u << uint(-2 * t.x)) : 1u;
            uint start = uint(max(t.x, 0));
            state.tile = t;
            state.start_level = start;
            state.read_count = count;
            state.used = count;
            state.slots_used += 1u;
            if (count > state.capacity) {
                // Not even the tile's own candidates fit: split it right away.
                state.aborted = 1u;
                count = 0u;
            } else {
                dispatch_cmd(start) = dispatch_groups(count, pc.wg_side * pc.wg_side);
            }
            s_tile = t;
            s_count = count;
        }
    }
    barrier();
    ivec4 t = s_tile;
    uint count = s_count;
    if (t.x < 0) {
        uint side = 1u << uint(-t.x);
        for (uint i = tid; i < count; i += 256u) {
            uint x = uint(t.y) * side + (i % side);
            uint y = uint(t.z) * side + (i / side);
            photons[i] = pack_cell(0u, x, y, 0u);
        }
    } else if (tid == 0u && count == 1u) {
        photons[0] = pack_cell(uint(t.x), uint(t.y), uint(t.z), 0u);
    }
}
