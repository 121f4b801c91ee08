// Push constants of the photon passes.
#ifndef PHOTON_PUSH_GLSL
#define PHOTON_PUSH_GLSL
#include "generated/gpu_structs.glsl"
layout(push_constant) uniform PhotonPushBlock { PhotonPush pc; };
#endif
