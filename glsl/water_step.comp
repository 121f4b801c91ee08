#version 460
#include "generated/gpu_structs.glsl"
// A simulated water surface (src/scene/water.rs, which runs the same on the host): one leapfrog step of the damped
// wave equation over its nodes, with the bodies moving through it (WATER_STEP), or one drop into it (WATER_DROP).
// Each invocation reads and writes its own node of the slot before (the step overwrites it with the next heights)
// and reads its neighbours in the slot now, which nothing writes: the step is free of hazards in place. The step's
// arithmetic is `precise` (no fused multiply-adds), as the host's is, so the two agree to the last bit where the
// drops and bodies (cos, sqrt) do not enter.
layout(local_size_x = LINEAR_WG) in;

layout(std430, set = 0, binding = WS_HEIGHTS) buffer Heights { float heights[]; };

layout(push_constant) uniform WaterStepPushBlock { WaterStepPush pc; };

// Water::coord: the same expression as the host's, so the same floats.
float coord(float s, uint i, uint n) { return -0.5 * s + s * (float(i) / float(n)); }

// water::column_length: the submerged length of sphere c (center, radius) in the column at (x, z).
float column_length(float x, float z, vec4 c) {
    float d2 = (x - c.x) * (x - c.x) + (z - c.z) * (z - c.z);
    float s2 = c.w * c.w - d2;
    if (s2 <= 0.0) return 0.0;
    float s = sqrt(s2);
    return max(min(c.y + s, 0.0) - max(c.y - s, -pc.depth), 0.0);
}

// The mirror of a node outside the grid.
uint mirror(int i, int last) { return uint(clamp(i < 0 ? -i : (i > last ? 2 * last - i : i), 0, last)); }

void main() {
    uint k = gl_GlobalInvocationID.x + gl_GlobalInvocationID.y * gl_NumWorkGroups.x * LINEAR_WG;
    uint nodes = pc.nodes;
    if (k >= nodes * nodes) return;
    uint i = k % nodes, j = k / nodes;
    uint now = pc.base + pc.slot * nodes * nodes;
    uint before = pc.base + (1u - pc.slot) * nodes * nodes;
    float x = coord(pc.size_x, i, nodes - 1u), z = coord(pc.size_z, j, nodes - 1u);
    if (pc.mode == WATER_DROP) {
        float r = sqrt((x - pc.drop.x) * (x - pc.drop.x) + (z - pc.drop.y) * (z - pc.drop.y));
        if (r >= pc.drop.z) return;
        float b = -pc.drop.w * 0.5 * (1.0 + cos(3.14159265 * r / pc.drop.z));
        heights[now + k] = clamp(heights[now + k] + b, -pc.limit, pc.limit);
        heights[before + k] = clamp(heights[before + k] + b, -pc.limit, pc.limit);
        return;
    }
    int last = int(nodes) - 1;
    precise float h = heights[now + k];
    precise float lap_x = heights[now + j * nodes + mirror(int(i) + 1, last)]
        + heights[now + j * nodes + mirror(int(i) - 1, last)] - 2.0 * h;
    precise float lap_z = heights[now + mirror(int(j) + 1, last) * nodes + i]
        + heights[now + mirror(int(j) - 1, last) * nodes + i] - 2.0 * h;
    precise float v = h + pc.keep * (h - heights[before + k]) + pc.cx * lap_x + pc.cz * lap_z;
    for (uint b = 0u; b < pc.body_count; b++) {
        v += column_length(x, z, pc.bodies[2u * b + 1u]) - column_length(x, z, pc.bodies[2u * b]);
    }
    heights[before + k] = clamp(v, -pc.limit, pc.limit);
}
