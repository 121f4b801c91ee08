// Searches along rays against view-space distance buffers (light-view refractor and receiver buffers, and the
// eye's). Every search is bracketed and capped, so it can miss but never diverge. The g-buffers hold the normal
// and the distance along the view ray, 0 where there is no geometry (common/gbuffer.glsl).
#ifndef MARCH_GLSL
#define MARCH_GLSL
#include "common/view.glsl"
#include "common/gbuffer.glsl"

bool uv_inside(vec2 uv) { return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0))); }

// Coverage-weighted bilinear sample: empty texels get no weight, so silhouettes do not blend with the
// background. False if all four taps are empty. The normal is renormalized.
bool geo_sample(usampler2D tex, vec2 uv, out vec4 v) {
    ivec2 size = textureSize(tex, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st));
    vec2 f = st - vec2(i0);
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 t = clamp(i0 + o, ivec2(0), size - 1);
        vec4 s = geo_fetch(tex, t);
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        if (s.w > 0.0 && w > 0.0) {
            acc += w * s;
            wsum += w;
        }
    }
    if (wsum <= 0.0) return false;
    v = acc / wsum;
    v.xyz = normalize(v.xyz);
    return true;
}

// The surface searches, for g-buffers (usampler2D) and for float buffers with the distance in .w (sampler2D).
#define SURF_T usampler2D
#include "common/march_surface.glsl"
#undef SURF_T
#define SURF_T sampler2D
#include "common/march_surface.glsl"
#undef SURF_T

// Gap to the back surface: > 0 while p is in front of it (inside the refractor). -1e30 where the back buffer is
// empty (outside the refractor's silhouette). The distance alone: the search needs the normal only where it ends.
float back_gap(GpuView v, usampler2D back, vec3 p) {
    vec2 uv = view_uv(v, p);
    float d;
    if (!uv_inside(uv) || !dist_sample(back, uv, d)) return -1e30;
    return d - view_dist(v, p);
}

// The back surface's normal at p's texel position; false outside the silhouette.
bool back_normal(GpuView v, usampler2D back, vec3 p, out vec3 n) {
    vec2 uv = view_uv(v, p);
    vec4 b;
    if (!uv_inside(uv) || !geo_sample(back, uv, b)) return false;
    n = b.xyz;
    return true;
}

// The exit point on the back surface along p1 + t*dir (p1 on the front surface), by a bracketed secant search:
// bracket the first sign change of back_gap with steps extrapolated from its slope (each at most 3x the last,
// so a thin part is not jumped over carelessly), then Illinois regula falsi to a residual of 1e-5 times the thickness
// (bisection while an end lies outside the silhouette). At most 20 + 12 samples; typically 4-6. The exit normal is the back
// normal there.
bool find_exit(GpuView v, usampler2D back, float diameter, vec3 p1, vec3 dir, out vec3 p2, out vec3 n2) {
    float f0 = back_gap(v, back, p1);
    if (f0 < -1e29) return false;
    float t_in = 0.0;  // the last sample inside the silhouette and in front of the back surface
    float a = 0.0, fa = max(f0, 0.0);
    float c = -1.0, fc = 0.0;
    // Piao's first guess is the front-to-back thickness along the light ray.
    float h = max(0.8 * fa, diameter / 256.0);
    for (int i = 0; i < 20; i++) {
        float t = a + h;
        float f = back_gap(v, back, p1 + t * dir);
        if (f <= 0.0) {
            c = t;
            fc = f;
            break;
        }
        float slope = (fa - f) / h;
        float predicted = slope > 0.0 ? 1.2 * f / slope : 3.0 * h;
        a = t;
        fa = f;
        t_in = t;
        h = clamp(predicted, 0.5 * h, 3.0 * h);
        if (a > 2.0 * diameter) return false;
    }
    if (c < 0.0) return false;
    // Illinois: regula falsi that halves a stale end's value, so the bracket shrinks from both sides. The
    // tolerance follows the local thickness, so thin refractors in large scenes are resolved as finely.
    float tol = 1e-5 * max(f0, diameter / 1024.0);
    float t = -1.0;
    int side = 0;
    for (int i = 0; i < 12 && t < 0.0; i++) {
        float w = c - a;
        float m = fc > -1e29 ? clamp((a * fc - c * fa) / (fc - fa), a + 1e-3 * w, c - 1e-3 * w) : 0.5 * (a + c);
        float f = back_gap(v, back, p1 + m * dir);
        if (abs(f) < tol || w < tol) {
            t = m;
        } else if (f > 0.0) {
            a = m;
            fa = f;
            t_in = m;
            if (side == 1) fc *= 0.5;
            side = 1;
        } else {
            c = m;
            fc = f;
            if (side == -1 && fc > -1e29) fa *= 0.5;
            side = -1;
        }
    }
    if (t < 0.0) t = fc > -1e29 ? (a * fc - c * fa) / (fc - fa) : a;
    p2 = p1 + t * dir;
    // The exit normal: the back surface's at p2, else (p2 just outside the silhouette) at the last inside sample.
    if (!back_normal(v, back, p2, n2)) back_normal(v, back, p1 + t_in * dir, n2);
    return true;
}

// Distance to where the ray leaves the box [lo, hi].
float ray_box_exit(vec3 o, vec3 d, vec3 lo, vec3 hi) {
    vec3 inv = 1.0 / d;
    vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
    vec3 tmax = max(t0, t1);
    return max(min(min(tmax.x, tmax.y), tmax.z), 0.0);
}

#endif
