// The eye view's shared layout (src/passes/composite.rs): the composite (glsl/composite.comp) and the glass pass
// (glsl/glass.comp) bind the same resources at the same CB_* indices.
#ifndef COMPOSITE_BINDINGS_GLSL
#define COMPOSITE_BINDINGS_GLSL
#include "common/types.glsl"
#include "common/view.glsl"
#include "common/optics.glsl"
#include "common/march.glsl"

layout(std140, set = 0, binding = CB_FRAME) uniform FrameUbo { FrameData u_frame; };
layout(set = 0, binding = CB_RADIANCE) uniform sampler2D t_radiance;      // receivers: rgb radiance, a: eye distance
layout(set = 0, binding = CB_FRONT) uniform usampler2D t_front;        // refractor front: normal, eye distance
layout(set = 0, binding = CB_FRONT_AUX) uniform sampler2D t_front_aux;     // refractor front: index of refraction
layout(set = 0, binding = CB_BACK) uniform usampler2D t_back;         // refractor back: normal, eye distance
layout(set = 0, binding = CB_RADIANCE_LINEAR) uniform sampler2D t_radiance_linear;  // the radiance buffer, linear filtering
layout(set = 0, binding = CB_BEAUTY, rgba8) uniform writeonly image2D o_beauty;
layout(set = 0, binding = CB_HDR, rgba32f) uniform writeonly image2D o_hdr;  // linear radiance, before exposure
layout(set = 0, binding = CB_SHADOW) uniform sampler2D t_shadow;        // light depth of all objects
layout(set = 0, binding = CB_IRRADIANCE) uniform sampler2D t_irradiance;    // caustic irradiance, W/m^2 (linear filtering)
layout(set = 0, binding = CB_RECEIVERS) uniform usampler2D t_recv;        // receivers from the light: normal, distance
layout(set = 0, binding = CB_ENV) uniform sampler2D t_env;                 // the environment map
layout(set = 0, binding = CB_ENV_IRRADIANCE) uniform sampler2D t_env_irradiance;  // its irradiance map
layout(set = 0, binding = CB_ALBEDO_TEXTURES) uniform sampler2DArray t_albedo_textures;  // receivers' albedo textures
// Exact transport: the glass's radiance per eye sample under every light, written by the glass pass; the
// composite reads it (and declares it so: the pass declares a read, src/passes/composite.rs).
#ifdef GLASS_READ_ONLY
layout(set = 0, binding = CB_GLASS, rgba32f) uniform readonly image2D o_glass;
#else
layout(set = 0, binding = CB_GLASS, rgba32f) uniform image2D o_glass;
#endif

// The eye deposit (docs/design.md "The eye deposit"): caustic flux per eye sample, W, three planes (red, green,
// blue), every light's; the glass pass adds its irradiance at the receivers it reaches that the eye's samples see.
layout(std430, set = 0, binding = CB_EYE_FLUX) readonly buffer EyeFluxBuf { float eye_flux[]; };

layout(push_constant) uniform CompositePushBlock { CompositePush pc; };
#endif
