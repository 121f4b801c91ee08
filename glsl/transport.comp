#version 460
// The exact transport's bookkeeping (one invocation; docs/design.md step 4): TRANSPORT_BEGIN_DENSE or _ADAPTIVE
// begins a batch's waves (adaptive: nothing when the batch has no tile or aborted), TRANSPORT_AFTER_WAVE follows each
// wave (the appended children become the next wave, with its dispatch-indirect arguments), TRANSPORT_COMMIT commits
// the batch (its energy account joins the frame's and the splat draws its records) unless it aborted, in which case
// traversal's commit splits its tile. After a wave, `next_wave` is the wave it prepares (its rays count to
// wave_rays there; the rays past the last wave are none: paths end at the cap).
#include "common/photon_bindings.glsl"
layout(push_constant) uniform TransportPushBlock { TransportPush pc; };

layout(local_size_x = 1) in;

void main() {
    bool aborted = state.aborted != 0u && state.batching != 0u;
    if (pc.mode == TRANSPORT_BEGIN_DENSE || pc.mode == TRANSPORT_BEGIN_ADAPTIVE) {
        bool none = pc.mode == TRANSPORT_BEGIN_ADAPTIVE && (state.start_level >= MAX_LEVELS || aborted);
        tstate.in_count = none ? 0u : min(state.emit_count, state.capacity);
        tstate.out_count = 0u;
        tstate.out_reserved = 0u;
        tstate.records = 0u;
        tstate.records_reserved = 0u;
        tstate.queue_capacity = u_frame.frame.queue_rays;
        tstate.record_capacity = u_frame.frame.record_capacity;
        for (uint k = 0u; k < ACC_TERMS; k++) tstate.batch_account[k] = uvec2(0u);
        wave_cmd = dispatch_groups(tstate.in_count, LINEAR_WG);
        if (tstate.in_count > 0u) tstate.waves += 1u;
        tstate.wave_rays_pairs[0].x += tstate.in_count;
        set_draw(0u, 0u);
    } else if (pc.mode == TRANSPORT_AFTER_WAVE) {
        tstate.in_count = aborted && pc.may_abort != 0u ? 0u : tstate.out_count;
        tstate.out_count = 0u;
        tstate.out_reserved = 0u;
        wave_cmd = dispatch_groups(tstate.in_count, LINEAR_WG);
        if (tstate.in_count > 0u) tstate.waves += 1u;
        uint w = min(pc.next_wave, MAX_INTERACTIONS);
        tstate.wave_rays_pairs[w >> 1u][w & 1u] += tstate.in_count;
    } else {
        tstate.in_count = 0u;
        wave_cmd = uvec4(0u, 0u, 1u, 0u);
        if (aborted && pc.may_abort != 0u) {
            set_draw(0u, 0u);
            return;
        }
        for (uint k = 0u; k < ACC_TERMS; k++) {
            uvec2 a = tstate.account[k], b = tstate.batch_account[k];
            uint lo = a.x + b.x;
            tstate.account[k] = uvec2(lo, a.y + b.y + (lo < a.x ? 1u : 0u));
        }
        uint n = min(tstate.records, tstate.record_capacity);
        tstate.records_total += n;
        set_draw(n, 0u);
    }
}
