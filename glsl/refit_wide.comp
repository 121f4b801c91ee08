#version 460
#include "generated/gpu_structs.glsl"
// The wide layout's part of a deforming mesh's GPU refit (src/bvh/refit.rs), after refit.comp bounded its binary
// nodes and the frame displaced its triangles: one height of its wide nodes per dispatch, lowest first. Each node
// bounds its children anew (a leaf child its triangles, whose copies in the wide triangle list it rewrites; an inner
// child the box an earlier dispatch wrote to the scratch), then requantizes their planes against the union, as the
// build does (Ylitie, Karras and Laine 2017; obvhs' conversion): origin at the union's low corner, a power-of-two
// scale per axis with 255 steps over the union's extent, each child's low planes rounded down and its high planes
// up. Its meta bytes, inner-child mask and child and triangle bases are kept: the tree's shape does not change.
layout(local_size_x = LINEAR_WG) in;

layout(std430, set = 0, binding = RW_ORDER) readonly buffer Order { uint order[]; };
layout(std430, set = 0, binding = RW_BOXES) buffer Boxes { vec4 boxes[]; };
layout(std430, set = 0, binding = RW_TRIS) readonly buffer Tris { vec4 tris[]; };
// A wide node's five words (src/bvh/records.rs, WideNode); a wide triangle-list entry is three uvec4 (its vertices'
// bits, the first's w the triangle's index in `tris`).
layout(std430, set = 0, binding = RW_NODES) buffer Nodes { WideNode nodes[]; };
layout(std430, set = 0, binding = RW_PRIMS) buffer Prims { uvec4 prims[]; };

layout(push_constant) uniform RefitPushBlock { RefitPush pc; };

// The per-axis scale exponent: the least power of two s with extent / s <= 255, as its biased exponent byte.
uint scale_byte(float extent) {
    float x = max(extent, 1e-20) / 255.0;
    int e;
    float m = frexp(x, e);  // x = m 2^e, m in [0.5, 1): 2^e >= x, and 2^(e-1) >= x only when m is 0.5
    if (m == 0.5) e -= 1;
    if (max(extent, 1e-20) * exp2(float(-e)) > 255.0) e += 1;
    return uint(clamp(e + 127, 1, 254));
}

// A child's quantized planes along one axis: low rounded down, high up, each checked against the plane it
// decodes to (p + q s) so that rounding in the subtraction never shrinks the box.
uvec2 quantize(float lo, float hi, float p, float s) {
    float ql = clamp(floor((lo - p) / s), 0.0, 255.0);
    if (ql > 0.0 && p + ql * s > lo) ql -= 1.0;
    float qh = clamp(ceil((hi - p) / s), 0.0, 255.0);
    if (qh < 255.0 && p + qh * s < hi) qh += 1.0;
    return uvec2(ql, qh);
}

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    if (i >= pc.count) return;
    uint k = order[pc.first + i];
    uvec4 w0 = nodes[k].w0, w1 = nodes[k].w1;
    uint imask = w0.w >> 24;
    vec3 clo[8], chi[8];
    vec3 lo = vec3(1e30), hi = vec3(-1e30);
    for (uint c = 0u; c < 8u; c++) {
        uint meta = (w1[2u + (c >> 2)] >> (8u * (c & 3u))) & 0xFFu;
        vec3 a = vec3(1e30), b = vec3(-1e30);
        if (meta == 0u) {
            // An empty slot.
        } else if ((imask & (1u << c)) != 0u) {
            uint child = w1.x + bitCount(imask & ((1u << c) - 1u));
            a = boxes[2u * child].xyz;
            b = boxes[2u * child + 1u].xyz;
        } else {
            // A leaf: its triangles' run of the list (offset in the low five bits, count in unary above them).
            uint first = w1.y + (meta & 0x1Fu), count = bitCount(meta >> 5);
            for (uint j = 0u; j < count; j++) {
                uint e = 3u * (first + j);
                uint t = prims[e].w;
                for (uint v = 0u; v < 3u; v++) {
                    vec3 q = tris[3u * t + v].xyz;
                    prims[e + v].xyz = floatBitsToUint(q);
                    a = min(a, q);
                    b = max(b, q);
                }
            }
        }
        clo[c] = a;
        chi[c] = b;
        lo = min(lo, a);
        hi = max(hi, b);
    }
    uvec3 eb = uvec3(scale_byte(hi.x - lo.x), scale_byte(hi.y - lo.y), scale_byte(hi.z - lo.z));
    vec3 s = uintBitsToFloat(eb << 23);
    // Planes: x in the third uvec4, y in the fourth, z in the fifth; each low bytes (.xy) then high bytes (.zw),
    // slots 0-3 in the first word of a pair and 4-7 in the second. Empty slots keep theirs.
    uvec4 planes[3] = uvec4[3](nodes[k].w2, nodes[k].w3, nodes[k].w4);
    for (uint c = 0u; c < 8u; c++) {
        if (clo[c].x > chi[c].x) continue;
        uint word = c >> 2, shift = 8u * (c & 3u), keep = ~(0xFFu << shift);
        for (uint axis = 0u; axis < 3u; axis++) {
            uvec2 q = quantize(clo[c][axis], chi[c][axis], lo[axis], s[axis]);
            planes[axis][word] = (planes[axis][word] & keep) | (q.x << shift);
            planes[axis][2u + word] = (planes[axis][2u + word] & keep) | (q.y << shift);
        }
    }
    nodes[k].w0 = uvec4(floatBitsToUint(lo), eb.x | (eb.y << 8) | (eb.z << 16) | (imask << 24));
    nodes[k].w2 = planes[0];
    nodes[k].w3 = planes[1];
    nodes[k].w4 = planes[2];
    boxes[2u * k] = vec4(lo, 0.0);
    boxes[2u * k + 1u] = vec4(hi, 0.0);
}
