#version 460
// Eye view of the receivers (docs/design.md step 6): their direct light and caustic irradiance, the AOVs.
#include "common/types.glsl"

layout(std140, set = 0, binding = 0) uniform FrameUbo { FrameData u_frame; };

layout(location = 0) in vec4 a_position;
layout(location = 1) in vec4 a_normal;
layout(location = 2) in vec4 a_material;  // rgb albedo

layout(location = 0) out vec3 v_world;
layout(location = 1) out vec3 v_normal;
layout(location = 2) flat out vec3 v_albedo;

void main() {
    v_world = a_position.xyz;
    v_normal = a_normal.xyz;
    v_albedo = a_material.rgb;
    gl_Position = u_frame.camera.view_proj * vec4(a_position.xyz, 1.0);
}
