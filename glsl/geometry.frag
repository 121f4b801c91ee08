#version 460
#include "generated/gpu_structs.glsl"
#include "common/gbuffer.glsl"
layout(push_constant) uniform GeometryPushBlock { GeometryPush pc; };

layout(location = 0) in vec3 v_world;
layout(location = 1) in vec3 v_normal;
#ifdef WITH_AUX
layout(location = 2) flat in float v_param;
#endif
#ifdef WITH_ALBEDO
layout(location = 2) flat in vec4 v_albedo;
layout(location = 3) in vec2 v_uv;
// The receivers' albedo textures, one per layer (linear reflectance, decoded from sRGB on the host), trilinear
// and repeating: albedo(uv) = factor x texture(uv), the texture's mip chosen by the uv's screen-space derivatives.
layout(set = 0, binding = GE_ALBEDO_TEXTURES) uniform sampler2DArray t_albedo_textures;
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
    vec3 albedo = v_albedo.rgb;
    if (v_albedo.w >= 0.0) albedo *= texture(t_albedo_textures, vec3(v_uv, v_albedo.w)).rgb;
    o_albedo = vec4(albedo, 1.0);
#endif
}
