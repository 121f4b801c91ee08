#version 460
// Coverage pyramid (DESIGN.md step 1): mip 0 marks the refractor front buffer's covered texels; each coarser mip
// takes the max (bit 0, "any covered": a conservative test for traversal) and the min (bit 1, "all covered":
// max-error clusters must be fully covered) of its 2x2 children.
#include "common/types.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = 1) buffer CoverageBuf { uint coverage[]; };
layout(set = 0, binding = 2) uniform sampler2D t_front;

layout(push_constant) uniform Push {
    uint mip;        // mip to build
    uint src_offset; // start of mip - 1
    uint dst_offset; // start of mip
    uint dst_res;    // side of mip
} pc;

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.dst_res || p.y >= pc.dst_res) return;
    uint bits;
    if (pc.mip == 0u) {
        bits = texelFetch(t_front, ivec2(p), 0).w > 0.0 ? 3u : 0u;
    } else {
        uint src_res = pc.dst_res * 2u;
        uint any = 0u, all = 2u;
        for (uint k = 0u; k < 4u; k++) {
            uvec2 q = 2u * p + uvec2(k & 1u, k >> 1);
            uint c = coverage[pc.src_offset + q.y * src_res + q.x];
            any |= c & 1u;
            all &= c & 2u;
        }
        bits = any | all;
    }
    coverage[pc.dst_offset + p.y * pc.dst_res + p.x] = bits;
}
