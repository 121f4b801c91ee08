#version 460
#include "generated/gpu_structs.glsl"
// Coverage pyramid (docs/design.md step 2): mip 0 marks the refractor front buffer's covered texels (those whose
// surface is in the light: a receiver between the light and the glass shadows it); each coarser mip
// takes the max (bit 0, "any covered": a conservative test for traversal) and the min (bit 1, "all covered":
// max-error clusters must be fully covered) of its 2x2 children.
#include "common/types.glsl"
#include "common/march.glsl"

layout(std140, set = 0, binding = CV_FRAME) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = CV_COVERAGE) buffer CoverageBuf { uint coverage[]; };
layout(set = 0, binding = CV_FRONT) uniform usampler2D t_front;
layout(set = 0, binding = CV_RECEIVERS) uniform usampler2D t_recv;  // receivers from the light

// Is the refractor surface at this texel in the light, or does a receiver stand between them?
bool lit(ivec2 p, vec4 front) {
    GpuView v = u_frame.light.photon_view;
    GpuView rv = u_frame.light.receiver_view;
    vec2 uv = (vec2(p) + 0.5) / vec2(textureSize(t_front, 0));
    vec3 ro, rd;
    view_ray(v, uv, ro, rd);
    vec3 p1 = ro + rd * front.w;
    vec2 ruv = view_uv(rv, p1);
    float d;
    return !(uv_inside(ruv) && dist_sample(t_recv, ruv, d) && d < view_dist(rv, p1) * (1.0 - 1e-3));
}

// Specialization constant 0: the pipeline builds mip 0 from the g-buffers (else a coarser mip from the one below).
// A CPU driver runs both sides of a branch, so each pipeline holds only its own side.
layout(constant_id = COVERAGE_MIP0_ID) const bool COVERAGE_MIP0 = true;

layout(push_constant) uniform CoveragePushBlock { CoveragePush pc; };

layout(local_size_x = TILE_WG, local_size_y = TILE_WG) in;

void main() {
    uvec2 p = gl_GlobalInvocationID.xy;
    if (p.x >= pc.dst_res || p.y >= pc.dst_res) return;
    uint bits;
    if (COVERAGE_MIP0) {
        vec4 front = geo_fetch(t_front, ivec2(p));
        bits = front.w > 0.0 && lit(ivec2(p), front) ? 3u : 0u;
        if (bits == 0u && u_frame.frame.exact != 0u) {
            // Exact transport traces each cell's own ray, so a cell whose texel center misses the glass may still
            // hit it: dilate "any" by one texel so that silhouette cells are emitted (the ray decides; a miss
            // becomes direct light in the energy account).
            // The 3x3 texels around p in four gathers of the distances, one at each of its corners (each the 2x2
            // texels around that corner; the sampler clamps to the edge). A corner is as far as can be from where
            // a gather's texels change, and each gather is one fetch call on a CPU driver, where nine were.
            vec2 size = vec2(textureSize(t_front, 0));
            for (int k = 0; k < 4; k++) {
                vec2 corner = (vec2(p) + vec2(k & 1, k >> 1)) / size;
                if (any(greaterThan(uintBitsToFloat(textureGather(t_front, corner, 0)), vec4(0.0)))) bits = 1u;
            }
        }
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
