#version 460
// A sheared tent of integer radii (rx, ry; glsl/common/photon_bindings.glsl, SplatShape): each row's (column's) tent
// of integer radius sums to exactly its radius over the texel lattice wherever the shear centres it, so with
// splat.vert's normalization each photon deposits exactly its flux (W) into the caustic map (additive blending);
// at an edge splat.vert has scaled the flux up by what the map clips away. The point is a square over the tent's
// extent; the fragments outside the tent weigh 0.
layout(location = 0) flat in float v_flux;
layout(location = 1) flat in vec4 v_splat;
layout(location = 2) flat in vec2 v_shear;
layout(location = 0) out vec4 o_flux;

void main() {
    vec2 r = v_splat.zw;
    vec2 d = gl_FragCoord.xy - v_splat.xy;
    d = v_shear.y > 0.5 ? vec2(d.x, d.y - v_shear.x * d.x) : vec2(d.x - v_shear.x * d.y, d.y);
    vec2 w = max(vec2(0.0), 1.0 - abs(d) / r);
    o_flux = vec4(v_flux * (w.x * w.y));
}
