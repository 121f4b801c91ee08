// The view-space g-buffers (light-view refractor front and back, receivers from the light, the eye's refractor
// front and back) are R32G32_UINT (GEO_FORMAT in src/passes/mod.rs): x holds the distance along the view ray as
// float bits (0 where there is no geometry), y the unit normal in octahedral form as two snorm16 (an angular error
// below 1e-4 rad). Half the bytes of RGBA32F: on GPUs whose few raster units export 128-bit pixels at a fraction
// of the rate of 64-bit ones, the light view is pixel-bound on these writes.
#ifndef GBUFFER_GLSL
#define GBUFFER_GLSL

vec2 oct_wrap(vec2 v) { return (1.0 - abs(v.yx)) * vec2(v.x >= 0.0 ? 1.0 : -1.0, v.y >= 0.0 ? 1.0 : -1.0); }

vec2 oct_encode(vec3 n) {
    n /= abs(n.x) + abs(n.y) + abs(n.z);
    return n.z >= 0.0 ? n.xy : oct_wrap(n.xy);
}

vec3 oct_decode(vec2 e) {
    vec3 n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    if (n.z < 0.0) n.xy = oct_wrap(n.xy);
    return normalize(n);
}

// n need not be unit length (the octahedral map divides by its L1 norm).
uvec2 geo_pack(vec3 n, float dist) { return uvec2(floatBitsToUint(dist), packSnorm2x16(oct_encode(n))); }

// (normal, distance) of a texel.
vec4 geo_fetch(usampler2D t, ivec2 p) {
    uvec2 g = texelFetch(t, p, 0).xy;
    return vec4(oct_decode(unpackSnorm2x16(g.y)), uintBitsToFloat(g.x));
}

// The distance alone: of a g-buffer, and of a float buffer holding it in .w (the eye's receiver radiance).
float geo_dist(usampler2D t, ivec2 p) { return uintBitsToFloat(texelFetch(t, p, 0).x); }
float geo_dist(sampler2D t, ivec2 p) { return texelFetch(t, p, 0).w; }

// Whether p is the receiver surface that a light of view lv sees at p's texel of its receivers' g-buffer recv (at
// the same distance, within four texels' footprint), so that the light's caustic map, one receiver per texel, holds
// the light that reaches p: the photons deposit only there (glsl/wave.comp, ACC_UNSEEN), and the receivers' shading
// reads only there (common/receiver.glsl). Returns p's uv in the view. Defined where common/view.glsl came first.
#ifdef VIEW_GLSL
// p's uv in view lv, and whether it lies in the window in front of the view (a point behind a perspective view
// projects through its origin into the window).
bool view_holds(GpuView lv, vec3 p, out vec2 uv) {
    vec3 img = view_image(lv, p);
    uv = (img.xy - lv.window.xy) / lv.window.zw;
    return uv_inside_strict(uv) && (view_is_ortho(lv) || img.z > 0.0);
}

// Whether the distance r_dist that lv's texel at p stores is p's own (within four texels' footprint).
bool stored_distance_is(GpuView lv, vec3 p, float r_dist) {
    float d = view_dist(lv, p);
    float texel = view_sample_side(lv, d);
    return r_dist > 0.0 && abs(r_dist - d) < 4.0 * texel + 1e-3 * d;
}

bool receiver_seen(GpuView lv, usampler2D recv, vec3 p, out vec2 uv) {
    if (!view_holds(lv, p, uv)) return false;
    ivec2 size = textureSize(recv, 0);
    return stored_distance_is(lv, p, geo_dist(recv, clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1)));
}

// Whether a ray arriving at p along `arrival` (a photon's, or the eye's) meets the side of the surface there (normal
// n, either way round) that view lv's rays meet: a light's caustic map holds only the side its straight rays reach.
// Where two surfaces meet at an edge the distance test passes for both within four texels: a ledge's underside,
// beside its front, is as far from the light as the front is, but faces away from it, and must neither take the
// front's light nor give its own to it.
bool same_side_as_view(GpuView lv, vec3 p, vec3 n, vec3 arrival) {
    return dot(arrival, n) * dot(view_dir_to(lv, p), n) > 0.0;
}

// The same, where the distance is the .w of a float image (the eye's receiver radiance).
bool receiver_seen(GpuView lv, sampler2D recv, vec3 p, out vec2 uv) {
    if (!view_holds(lv, p, uv)) return false;
    ivec2 size = textureSize(recv, 0);
    return stored_distance_is(lv, p, geo_dist(recv, clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1)));
}
#endif

#endif
