#version 460
// A separable tent of integer radii (rx, ry): on each axis the sum over the texel lattice of (1/r)(1 - |d|/r) is
// exactly 1 for any center, so each photon deposits exactly its flux (W) into the caustic map (additive blending);
// at an edge splat.vert has scaled the flux up by what the map clips away (splat_edge_norm).
// The point is a square of side 2 max(rx, ry); the narrower axis's weights are 0 beyond its radius.
layout(location = 0) flat in float v_flux;
layout(location = 1) flat in vec4 v_splat;
layout(location = 0) out vec4 o_flux;

void main() {
    vec2 r = v_splat.zw;
    vec2 d = abs(gl_FragCoord.xy - v_splat.xy);
    vec2 w = max(vec2(0.0), 1.0 - d / r) / r;
    o_flux = vec4(v_flux * (w.x * w.y));
}
