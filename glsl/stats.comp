#version 460
// Stats (Piao's post-traversal statistics shader), one invocation after each traversal level: count the level's
// candidates, move the read window onto the children just appended, and write the next level's
// dispatch-indirect arguments. After the last level (STATS_COMMIT) it commits the batch: on success the batch's counts
// join the frame's and the draw-indirect command is set to the emitted photons; after an overflow the batch's
// tile is split into four tiles pushed on the tile stack, and nothing is drawn.
#include "common/photon_bindings.glsl"
layout(push_constant) uniform StatsPushBlock { StatsPush pc; };

layout(local_size_x = 1) in;

void commit() {
    bool split = state.aborted != 0u && state.batching != 0u;
    if (state.start_level >= MAX_LEVELS) {
        set_emitted(0u, state.capacity);
        return;
    }
    if (split) {
        ivec4 t = state.tile;
        state.batches_aborted += 1u;
        if (t.x >= 0) {
            // The tile's own cell was refined (its subtree overflowed): count it once, here.
            uint l = uint(t.x);
            state.levels[l].candidates += 1u;
            state.levels[l].refined += 1u;
        }
        if (t.x < int(MAX_LEVELS) - 1 && state.stack_size + 4u <= TILE_STACK) {
            for (int k = 3; k >= 0; k--) {
                state.stack[state.stack_size] = ivec4(t.x + 1, 2 * t.y + (k & 1), 2 * t.z + (k >> 1), 0);
                state.stack_size += 1u;
            }
        } else {
            state.overflow_dropped += 1u;
        }
        set_emitted(0u, state.capacity);
        return;
    }
    for (uint l = 0u; l < MAX_LEVELS; l++) {
        LevelCounters b = state.batch_levels[l];
        state.levels[l].candidates += b.candidates;
        state.levels[l].refined += b.refined;
        state.levels[l].emitted += b.emitted;
        state.levels[l].dropped += b.dropped;
        state.levels[l].checks_skipped += b.checks_skipped;
        state.levels[l].unchecked += b.unchecked;
    }
    uint n = min(state.emit_count, state.capacity);
    state.batches_committed += 1u;
    state.photons_total += n;
    set_emitted(n, state.capacity);
}

void main() {
    uint l = pc.level;
    if (pc.mode == STATS_DENSE) {
        // Dense: the band's photons are all emitted; draw them.
        uint n = min(state.emit_count, state.capacity);
        state.photons_total += n;
        state.peak_used = max(state.peak_used, n);
        state.batches_committed += 1u;
        set_emitted(n, state.capacity);
        return;
    }
    if (state.start_level < MAX_LEVELS && l >= state.start_level) {
        state.batch_levels[l].candidates += state.read_count;
        state.peak_used = max(state.peak_used, min(state.used, state.capacity));
        state.read_offset += state.read_count;
        state.read_count = state.write_count;
        state.write_count = 0u;
        if (l + 1u < MAX_LEVELS) {
            bool stop = state.aborted != 0u && state.batching != 0u;
            dispatch_cmd(l + 1u) = stop ? uvec4(0u, 0u, 1u, 0u) : dispatch_groups(state.read_count, pc.wg_side * pc.wg_side);
        }
    }
    if (pc.mode == STATS_COMMIT) commit();
}
