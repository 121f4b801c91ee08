// The light map deposit (docs/design.md "Emitters and deposits"): the papers' caustic map of a light view, one
// receiver per texel, where the light's straight rays land. It is the fast path, which every landing tries first
// (common/deposit.glsl). Its parts:
// - project: light_map_project, whether the map holds a landing and where;
// - footprint: light_map_footprint, the tent of a record in the map's texels;
// - splat: glsl/splat.comp (records of positive shape; splat.vert and splat.frag under the point draw);
// - resolve: glsl/resolve.comp, flux over the receiver area a texel covers;
// - lookup: light_map_irradiance, the receivers' shading (common/receiver.glsl, glsl/glass.comp).
#ifndef DEPOSIT_LIGHT_MAP_GLSL
#define DEPOSIT_LIGHT_MAP_GLSL
#include "common/view.glsl"
#include "common/gbuffer.glsl"

// Whether light view lv's map, whose receivers' g-buffer is recv, holds a landing at p (normal n, either way round)
// arriving along `arrival` (a photon's direction, or the eye's): the texel at p sees p itself, on the side the
// view's rays reach. uv: p's uv in the map.
bool light_map_project(GpuView lv, usampler2D recv, vec3 p, vec3 n, vec3 arrival, out vec2 uv) {
    return receiver_seen(lv, recv, p, uv) && same_side_as_view(lv, p, n, arrival);
}

#ifdef TRANSPORT_GLSL
// A record's shape in the map (common/photon_bindings.glsl SplatShape): the parallelogram the photon's cell covers
// where it lands, from its ray differentials (`differential`) clamped around the radius r that traversal gave
// it, else the round radius r. `jitter` (m): how far a light with size scatters the photon's landing, which widens
// the footprint (footprint_widening), at a blur well under the light's own.
float light_map_footprint(GpuView lv, vec3 p, RayDiff rdf, uint r, bool differential, float jitter) {
    vec2 mx = view_px_diff(lv, p, rdf.dpx), my = view_px_diff(lv, p, rdf.dpy);
    if (jitter > 0.0) {
        float side = differential ? sqrt(abs(mx.x * my.y - mx.y * my.x)) : float(r);
        float f = footprint_widening(jitter / view_sample_side(lv, view_dist(lv, p)), side);
        mx *= f;
        my *= f;
        r = min(uint(ceil(float(r) * f)), MAX_SPLAT_RADIUS);
    }
    float k = set_narrowing();
    mx *= k;
    my *= k;
    r = set_narrowed_radius(r);
    return differential ? footprint_radii(mx, my, r) : float(r);
}
#endif

// Caustic irradiance (W/m^2) of a light (view lv, caustic map irr, receivers recv) at p (normal n), on the side that
// the eye's ray (direction `eye`) meets, averaged over a footprint in its caustic map spanned by the uv offsets dx,
// dy (up to 8x8 bilinear taps), so that a caustic sharper than the footprint keeps its flux.
vec3 light_map_irradiance(GpuView lv, sampler2D irr, usampler2D recv, vec3 p, vec3 n, vec3 eye, vec2 dx, vec2 dy) {
    vec2 uv;
    // The map holds another receiver's light there, or the light's on the other side.
    if (!light_map_project(lv, recv, p, n, eye, uv)) return vec3(0.0);
    vec2 size = vec2(textureSize(irr, 0));
    int nx = int(clamp(ceil(length(dx * size)), 1.0, 8.0));
    int ny = int(clamp(ceil(length(dy * size)), 1.0, 8.0));
    vec3 e = vec3(0.0);
    for (int j = 0; j < ny; j++) {
        for (int i = 0; i < nx; i++) {
            vec2 o = vec2((float(i) + 0.5) / float(nx) - 0.5, (float(j) + 0.5) / float(ny) - 0.5);
            e += textureLod(irr, uv + o.x * dx + o.y * dy, 0.0).rgb;
        }
    }
    return e / float(nx * ny);
}

#endif
