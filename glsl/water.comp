#version 460
#include "generated/gpu_structs.glsl"
// Water (src/scene/water.rs, which runs the same formula on the host): displace a water object's vertices to
// the frame's time, adding its simulated surface's heights (glsl/water_step.comp) where it has one. The plain build
// displaces each vertex once, in object space (from the object-space rest copies), keeps it in `displaced`, and
// writes its raster vertex in world space through the instance's transform; the WATER_BVH build then gathers each
// BVH triangle's corners (in leaf order, by their vertex indices in `rest_corners`) from `displaced`, and the
// refit (refit.comp) bounds them. A vertex at y = 0 rises to
//   h = sum_i a_i sin(k_i (d_i . (x, z)) - w_i t) (+ the simulated height at its node),
// and where its rest normal is +y (the surface, not the walls' top edges) its normal becomes
// normalize(-dh/dx, 1, -dh/dz).
layout(local_size_x = LINEAR_WG) in;

#ifdef WATER_BVH
layout(std430, set = 0, binding = WA_BVH_DISPLACED) readonly buffer BvhDisplaced { GpuPointNormal displaced[]; };
layout(std430, set = 0, binding = WA_REST_CORNERS) readonly buffer RestCorners { uint rest_corners[]; };
layout(std430, set = 0, binding = WA_BVH_TRIS) writeonly buffer BvhTris { vec4 bvh_tris[]; };
layout(std430, set = 0, binding = WA_BVH_NORMALS) writeonly buffer BvhNormals { vec4 bvh_normals[]; };
#else
// Two per wave: (direction x, direction z, k, omega), (amplitude, 0, 0, 0).
layout(std430, set = 0, binding = WA_WAVES) readonly buffer Waves { GpuWaveRecord waves[]; };
layout(std430, set = 0, binding = WA_OBJECT_VERTICES) readonly buffer ObjectVertices { Vertex object_vertices[]; };
layout(std430, set = 0, binding = WA_WORLD_VERTICES) writeonly buffer WorldVertices { Vertex world_vertices[]; };
layout(std430, set = 0, binding = WA_HEIGHTS) readonly buffer Heights { float heights[]; };
layout(std430, set = 0, binding = WA_DISPLACED) writeonly buffer Displaced { GpuPointNormal displaced[]; };
#endif

layout(push_constant) uniform WaterPushBlock { WaterPush pc; };

#ifndef WATER_BVH
void displace(inout vec3 p, inout vec3 n) {
    if (p.y != 0.0) return;
    float h = 0.0;
    vec2 g = vec2(0.0);
    for (uint w = 0u; w < pc.wave_count; w++) {
        vec4 a = waves[pc.first_wave + w].a;
        float amp = waves[pc.first_wave + w].b.x;
        float phase = a.z * (a.x * p.x + a.y * p.z) - a.w * pc.time;
        h += amp * sin(phase);
        g += a.xy * (amp * a.z * cos(phase));
    }
    if (pc.heights != 0u) {
        // The simulated surface at the nearest node (src/scene/water.rs Water::node), its gradient by central
        // differences, zero across a wall (HeightField::at).
        vec4 r = waves[pc.first_wave + pc.wave_count].a;
        uint nodes = floatBitsToUint(r.x);
        float cells = float(nodes - 1u);
        uint i = uint(clamp(round(p.x * 2.0 * r.y + 0.5 * cells), 0.0, cells));
        uint j = uint(clamp(round(p.z * 2.0 * r.z + 0.5 * cells), 0.0, cells));
        uint at = pc.heights - 1u + j * nodes + i;
        h += heights[at];
        if (i > 0u && i + 1u < nodes) g.x += (heights[at + 1u] - heights[at - 1u]) * r.y;
        if (j > 0u && j + 1u < nodes) g.y += (heights[at + nodes] - heights[at - nodes]) * r.z;
    }
    p.y = h;
    if (n == vec3(0.0, 1.0, 0.0)) n = normalize(vec3(-g.x, 1.0, -g.y));
}

#endif

void main() {
    uint i = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    if (i >= pc.count) return;
#ifndef WATER_BVH
    {
        Vertex v = object_vertices[pc.src + i];
        vec3 p = v.position.xyz, n = v.normal.xyz;
        displace(p, n);
        displaced[pc.displaced + i] = GpuPointNormal(vec4(p, 0.0), vec4(n, 0.0));
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
            uint k = pc.displaced + rest_corners[t];
            // The w lanes hold texture coordinates, which water's meshes have none of (src/scene/water.rs).
            bvh_tris[3u * (pc.dst + i) + c] = vec4(displaced[k].position.xyz, 0.0);
            bvh_normals[3u * (pc.dst + i) + c] = vec4(displaced[k].normal.xyz, 0.0);
        }
    }
#endif
}
