#version 460
#include "common/gbuffer.glsl"
layout(push_constant) uniform Push {
    mat4 view_proj;
    vec4 origin;
    vec4 forward;
} pc;

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
#ifdef WITH_AUX
layout(location = 2) flat in float v_param;
#endif
#ifdef WITH_ALBEDO
layout(location = 2) flat in vec3 v_albedo;
#endif

layout(location = 0) out uvec2 o_geo;  // normal (interpolated, as the reference sees it), distance: common/gbuffer.glsl
#ifdef WITH_AUX
layout(location = 1) out float o_aux;  // index of refraction
#endif
#ifdef WITH_ALBEDO
layout(location = 1) out vec4 o_albedo;  // rgb albedo (RGBA8)
#endif

void main() {
    vec3 d = v_world - pc.origin.xyz;
    float dist = pc.origin.w > 0.5 ? dot(d, pc.forward.xyz) : length(d);
    // geo_pack needs no unit normal: the octahedral map divides by the L1 norm.
    o_geo = geo_pack(v_normal, max(dist, 1e-6));
#ifdef WITH_AUX
    o_aux = v_param;
#endif
#ifdef WITH_ALBEDO
    o_albedo = vec4(v_albedo, 1.0);
#endif
}
