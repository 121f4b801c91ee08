#version 460
#include "generated/gpu_structs.glsl"
// The GPU refit of a deforming mesh's bottom-level BVH (src/bvh/ builds its tree once, at rest), one height per
// dispatch, lowest first (src/bvh/refit.rs groups the nodes by height): a leaf bounds its triangles, an inner node
// unions its children's boxes, bounded by an earlier dispatch. Each box is written to the scratch (read by the
// parent) and into every layout on the GPU: its single and threaded node, and its slot in its parent's pair node.
#include "common/bvh_types.glsl"
layout(local_size_x = LINEAR_WG) in;

const uint NONE = 0xffffffffu;
layout(std430, set = 0, binding = RF_NODES) readonly buffer Nodes { RefitNode nodes[]; };
layout(std430, set = 0, binding = RF_ORDER) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = RF_BOXES) buffer Boxes { vec4 boxes[]; };
layout(std430, set = 0, binding = RF_TRIS) readonly buffer Tris { vec4 tris[]; };
layout(std430, set = 0, binding = RF_PAIR) buffer Pair { PairNode pair_nodes[]; };
layout(std430, set = 0, binding = RF_SINGLE) buffer Single { SingleNode single_nodes[]; };
layout(std430, set = 0, binding = RF_THREADED) buffer Threaded { SingleNode threaded_nodes[]; };

layout(push_constant) uniform RefitPushBlock { RefitPush pc; };

void store(uint k, RefitNode n, vec3 lo, vec3 hi) {
    boxes[2u * k] = vec4(lo, 0.0);
    boxes[2u * k + 1u] = vec4(hi, 0.0);
    if ((pc.layouts & REFIT_SINGLE) != 0u) {
        single_nodes[n.single].lo.xyz = lo;
        single_nodes[n.single].hi.xyz = hi;
    }
    if ((pc.layouts & REFIT_THREADED) != 0u) {
        threaded_nodes[n.threaded].lo.xyz = lo;
        threaded_nodes[n.threaded].hi.xyz = hi;
    }
    if ((pc.layouts & REFIT_PAIR) != 0u && n.pair != NONE) {
        uint p = n.pair >> 1u;
        if ((n.pair & 1u) == 0u) {
            pair_nodes[p].lo0.xyz = lo;
            pair_nodes[p].hi0.xyz = hi;
        } else {
            pair_nodes[p].lo1.xyz = lo;
            pair_nodes[p].hi1.xyz = hi;
        }
    }
}

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    if (i >= pc.count) return;
    uint k = order[pc.first + i];
    RefitNode n = nodes[k];
    vec3 lo = vec3(1e30), hi = vec3(-1e30);
    if (n.tri_count > 0u) {
        for (uint t = n.first_tri; t < n.first_tri + n.tri_count; t++) {
            for (uint c = 0u; c < 3u; c++) {
                vec3 p = tris[3u * t + c].xyz;
                lo = min(lo, p);
                hi = max(hi, p);
            }
        }
    } else {
        lo = min(boxes[2u * n.left].xyz, boxes[2u * n.right].xyz);
        hi = max(boxes[2u * n.left + 1u].xyz, boxes[2u * n.right + 1u].xyz);
    }
    store(k, n, lo, hi);
}
