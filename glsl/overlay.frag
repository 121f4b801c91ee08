#version 460
// The viewer's overlay (glsl/overlay.vert): the vertex color times the texture's, both premultiplied and
// sRGB-encoded; the pipeline blends them over the target (ONE, ONE_MINUS_SRC_ALPHA).
layout(set = 0, binding = OV_TEXTURE) uniform sampler2D t_texture;
layout(location = 0) in vec2 v_uv;
layout(location = 1) in vec4 v_color;
layout(location = 0) out vec4 o_color;

void main() {
    o_color = v_color * texture(t_texture, v_uv);
}
