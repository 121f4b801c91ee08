#version 460
#include "generated/gpu_structs.glsl"
// Rasterize scene triangles into a view's g-buffer (light-view refractor front/back, receivers from the light,
// shadow depth, eye-view refractor front/back). The distance written is along the view ray (see view.glsl).
layout(location = 0) in vec4 a_position;  // xyz; w: texture u
layout(location = 1) in vec4 a_normal;    // xyz; w: texture v
layout(location = 2) in vec4 a_material;  // x: index of refraction (dielectric) or albedo r; w: kind (a receiver:
                                          // -(albedo texture layer + 1), 0 for none)

layout(push_constant) uniform GeometryPushBlock { GeometryPush pc; };

// Variants: WITH_AUX passes the material parameter (index of refraction); WITH_ALBEDO the rgb albedo (the eye's
// receiver g-buffer); DEPTH_ONLY passes nothing.
#ifndef DEPTH_ONLY
layout(location = 0) out vec3 v_world;
layout(location = 1) out vec3 v_normal;
#endif
#ifdef WITH_AUX
layout(location = 2) flat out float v_param;
#endif
#ifdef WITH_ALBEDO
layout(location = 2) flat out vec4 v_albedo;  // rgb: albedo factor; w: texture layer (-1: none)
layout(location = 3) out vec2 v_uv;
#endif

void main() {
#ifndef DEPTH_ONLY
    v_world = a_position.xyz;
    v_normal = a_normal.xyz;
#endif
#ifdef WITH_AUX
    v_param = a_material.x;
#endif
#ifdef WITH_ALBEDO
    v_albedo = vec4(a_material.rgb, -a_material.w - 1.0);
    v_uv = vec2(a_position.w, a_normal.w);
#endif
    gl_Position = pc.view_proj * vec4(a_position.xyz, 1.0);
}
