#version 460
// The viewer's overlay (src/passes/overlay.rs): 2D triangles in points, (0, 0) at the target's top left, with a
// texture coordinate and a premultiplied color whose bytes are sRGB-encoded. The target holds sRGB-encoded bytes in
// a UNORM format (the tone-mapped beauty image), so the colors and their blending stay in that encoding, as the
// triangles' author (egui) expects of such a target.
#include "common/types.glsl"
layout(push_constant) uniform OverlayPushBlock { OverlayPush pc; };

layout(location = 0) in vec2 a_pos;
layout(location = 1) in vec2 a_uv;
layout(location = 2) in vec4 a_color;
layout(location = 0) out vec2 v_uv;
layout(location = 1) out vec4 v_color;

void main() {
    gl_Position = vec4(2.0 * a_pos / pc.size - 1.0, 0.0, 1.0);
    v_uv = a_uv;
    v_color = a_color;
}
