#version 460
#include "generated/gpu_structs.glsl"
// The scene update (src/passes/scene_update.rs): place one moved object's vertices and triangles in the world-space
// buffers the rasterizer draws, from its object-space copies. Positions go through the affine transform, normals
// through its inverse transpose (renormalized; zero where that degenerates, as Mesh::transformed does), and a
// mirroring transform swaps two indices of each triangle so that the winding stays counter-clockwise outside.
layout(local_size_x = LINEAR_WG) in;

layout(std430, set = 0, binding = SU_OBJECT_VERTICES) readonly buffer ObjectVertices { Vertex object_vertices[]; };
layout(std430, set = 0, binding = SU_WORLD_VERTICES) writeonly buffer WorldVertices { Vertex world_vertices[]; };
layout(std430, set = 0, binding = SU_OBJECT_INDICES) readonly buffer ObjectIndices { uint object_indices[]; };
layout(std430, set = 0, binding = SU_WORLD_INDICES) writeonly buffer WorldIndices { uint world_indices[]; };

layout(push_constant) uniform SceneUpdatePushBlock { SceneUpdatePush pc; };

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    if (i < pc.vertex_count) {
        Vertex v = object_vertices[pc.first_vertex + i];
        vec4 p = vec4(v.position.xyz, 1.0);
        v.position.xyz = vec3(dot(pc.rows[0], p), dot(pc.rows[1], p), dot(pc.rows[2], p));
        vec3 n = vec3(dot(pc.nrows[0].xyz, v.normal.xyz), dot(pc.nrows[1].xyz, v.normal.xyz),
                      dot(pc.nrows[2].xyz, v.normal.xyz));
        float len = length(n);
        v.normal.xyz = len > 0.0 && !isinf(len) ? n / len : vec3(0.0);
        world_vertices[pc.first_vertex + i] = v;
    }
    if (3u * i < pc.index_count) {
        uint k = pc.first_index + 3u * i;
        uint a = object_indices[k], b = object_indices[k + 1u], c = object_indices[k + 2u];
        bool mirror = pc.nrows[0].w != 0.0;
        world_indices[k] = a;
        world_indices[k + 1u] = mirror ? c : b;
        world_indices[k + 2u] = mirror ? b : c;
    }
}
