#version 460
#include "generated/gpu_structs.glsl"
// Morph targets (src/scene/morph.rs, which runs the same formula on the host): weight a morphing object's
// vertices to the frame's weights, p = p0 + sum_k w_k dp_k and n = normalize(n0 + sum_k w_k dn_k) (n0 where the sum
// vanishes). The plain build writes its raster vertices in world space (through the instance's transform; the
// texture coordinates and material come from the object-space copies); the MORPH_BVH build writes its BVH
// triangles and vertex normals in object space, in leaf order, each corner read by its vertex index, which the
// refit (refit.comp) then bounds.
layout(local_size_x = LINEAR_WG) in;

// Per morphing object: its base vertices, then each target's displacements, `vertices` apart; two vec4 per
// vertex: (position, 0), (normal, 0).
layout(std430, set = 0, binding = MO_MORPHS) readonly buffer Morphs { GpuPointNormal morph[]; };
layout(std430, set = 0, binding = MO_WEIGHTS) readonly buffer Weights { float weights[]; };
#ifdef MORPH_BVH
layout(std430, set = 0, binding = MO_REST_TRIS) readonly buffer RestTris { vec4 rest_tris[]; };
layout(std430, set = 0, binding = MO_REST_NORMALS) readonly buffer RestNormals { vec4 rest_normals[]; };
layout(std430, set = 0, binding = MO_REST_CORNERS) readonly buffer RestCorners { uint rest_corners[]; };
layout(std430, set = 0, binding = MO_BVH_TRIS) writeonly buffer BvhTris { vec4 bvh_tris[]; };
layout(std430, set = 0, binding = MO_BVH_NORMALS) writeonly buffer BvhNormals { vec4 bvh_normals[]; };
#else
layout(std430, set = 0, binding = MO_OBJECT_VERTICES) readonly buffer ObjectVertices { Vertex object_vertices[]; };
layout(std430, set = 0, binding = MO_WORLD_VERTICES) writeonly buffer WorldVertices { Vertex world_vertices[]; };
#endif

layout(push_constant) uniform MorphPushBlock { MorphPush pc; };

// Vertex v of the object, weighted.
void morphed(uint v, out vec3 p, out vec3 n) {
    uint b = pc.first + v;
    p = morph[b].position.xyz;
    n = morph[b].normal.xyz;
    vec3 n0 = n;
    for (uint k = 0u; k < pc.targets; k++) {
        float w = weights[pc.first_weight + k];
        if (w == 0.0) continue;
        uint j = b + (k + 1u) * pc.vertices;
        p += w * morph[j].position.xyz;
        n += w * morph[j].normal.xyz;
    }
    float len = length(n);
    n = len > 0.0 && !isinf(len) ? n / len : n0;
}

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    if (i >= pc.count) return;
#ifndef MORPH_BVH
    {
        Vertex v = object_vertices[pc.src + i];
        vec3 p, n;
        morphed(i, p, n);
        vec4 q = vec4(p, 1.0);
        v.position.xyz = vec3(dot(pc.rows[0], q), dot(pc.rows[1], q), dot(pc.rows[2], q));
        vec3 m = vec3(dot(pc.nrows[0].xyz, n), dot(pc.nrows[1].xyz, n), dot(pc.nrows[2].xyz, n));
        float len = length(m);
        v.normal.xyz = len > 0.0 && !isinf(len) ? m / len : vec3(0.0);
        world_vertices[pc.dst + i] = v;
    }
#else
    {
        for (uint c = 0u; c < 3u; c++) {
            uint t = 3u * (pc.src + i) + c;
            vec3 p, n;
            morphed(rest_corners[t], p, n);
            bvh_tris[3u * (pc.dst + i) + c] = vec4(p, rest_tris[t].w);
            bvh_normals[3u * (pc.dst + i) + c] = vec4(n, rest_normals[t].w);
        }
    }
#endif
}
