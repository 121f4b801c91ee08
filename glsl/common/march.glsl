// Searches along rays against view-space distance buffers (light-view refractor and receiver buffers, and the
// eye's). Every search is bracketed and capped, so it can miss but never diverge. The buffers hold
// (normal.xyz, distance along the view ray) with distance 0 where there is no geometry.
#ifndef MARCH_GLSL
#define MARCH_GLSL
#include "common/view.glsl"

bool uv_inside(vec2 uv) { return all(greaterThanEqual(uv, vec2(0.0))) && all(lessThanEqual(uv, vec2(1.0))); }

// Coverage-weighted bilinear sample: empty texels get no weight, so silhouettes do not blend with the
// background. False if all four taps are empty. The normal is renormalized.
bool geo_sample(sampler2D tex, vec2 uv, out vec4 v) {
    ivec2 size = textureSize(tex, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st));
    vec2 f = st - vec2(i0);
    vec4 acc = vec4(0.0);
    float wsum = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        ivec2 t = clamp(i0 + o, ivec2(0), size - 1);
        vec4 s = texelFetch(tex, t, 0);
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

// The same, for the distance channel only (.w), of buffers whose rgb is not a normal.
bool dist_sample(sampler2D tex, vec2 uv, out float d) {
    ivec2 size = textureSize(tex, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st));
    vec2 f = st - vec2(i0);
    float acc = 0.0, wsum = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        float s = texelFetch(tex, clamp(i0 + o, ivec2(0), size - 1), 0).w;
        float w = (o.x == 1 ? f.x : 1.0 - f.x) * (o.y == 1 ? f.y : 1.0 - f.y);
        if (s > 0.0 && w > 0.0) {
            acc += w * s;
            wsum += w;
        }
    }
    if (wsum <= 0.0) return false;
    d = acc / wsum;
    return true;
}

// Gap to the back surface: > 0 while p is in front of it (inside the refractor). -1e30 where the back buffer is
// empty (outside the refractor's silhouette), with `n` unset.
float back_gap(View v, sampler2D back, vec3 p, out vec3 n) {
    vec2 uv = view_uv(v, p);
    vec4 b;
    if (!uv_inside(uv) || !geo_sample(back, uv, b)) return -1e30;
    n = b.xyz;
    return b.w - view_dist(v, p);
}

// The exit point on the back surface along p1 + t*dir (p1 on the front surface), by a bracketed secant search:
// bracket the first sign change of back_gap with steps extrapolated from its slope (each at most 3x the last,
// so a thin part is not jumped over carelessly), then Illinois regula falsi to a residual of 1e-5 times the thickness
// (bisection while an end lies outside the silhouette). At most 20 + 12 samples; typically 4-6. The exit normal is the back
// normal there.
bool find_exit(View v, sampler2D back, float diameter, vec3 p1, vec3 dir, out vec3 p2, out vec3 n2) {
    vec3 n;
    float f0 = back_gap(v, back, p1, n);
    if (f0 < -1e29) return false;
    vec3 n_in = n;
    float a = 0.0, fa = max(f0, 0.0);
    float c = -1.0, fc = 0.0;
    // Piao's first guess is the front-to-back thickness along the light ray.
    float h = max(0.8 * fa, diameter / 256.0);
    for (int i = 0; i < 20; i++) {
        float t = a + h;
        float f = back_gap(v, back, p1 + t * dir, n);
        if (f <= 0.0) {
            c = t;
            fc = f;
            break;
        }
        float slope = (fa - f) / h;
        float predicted = slope > 0.0 ? 1.2 * f / slope : 3.0 * h;
        a = t;
        fa = f;
        n_in = n;
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
        float f = back_gap(v, back, p1 + m * dir, n);
        if (abs(f) < tol || w < tol) {
            t = m;
        } else if (f > 0.0) {
            a = m;
            fa = f;
            n_in = n;
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
    if (back_gap(v, back, p2, n) > -1e29) n_in = n;
    n2 = n_in;
    return true;
}

// Distance to where the ray leaves the box [lo, hi].
float ray_box_exit(vec3 o, vec3 d, vec3 lo, vec3 hi) {
    vec3 inv = 1.0 / d;
    vec3 t0 = (lo - o) * inv, t1 = (hi - o) * inv;
    vec3 tmax = max(t0, t1);
    return max(min(min(tmax.x, tmax.y), tmax.z), 0.0);
}

// g = surface distance - point distance in `v`; > 0 while the ray is in front of the surfaces. Empty texels count
// as far away (1e30). Leaving the map sets `in_map` false.
float surface_gap(View v, sampler2D surf, vec3 p, out bool in_map) {
    vec2 uv = view_uv(v, p);
    in_map = uv_inside(uv);
    float d;
    if (!in_map || !dist_sample(surf, uv, d)) return 1e30;
    return d - view_dist(v, p);
}

// The first surface hit along o + t*dir, t in (0, tmax], by a bracketed secant search: steps extrapolated from
// the gap's slope (the first from the gap and the rate at which the ray recedes from the view's origin; each at
// most 3x the last) bracket the first sign change, then Illinois regula falsi (bisection across empty texels) refines
// it to a residual of 1e-6 tmax. At most 24 + 12 samples; a planar receiver takes about 4.
bool find_surface(View v, sampler2D surf, vec3 o, vec3 dir, float tmax, out vec3 hit) {
    if (tmax <= 0.0) return false;
    bool in_map;
    float a = 0.0, ga = surface_gap(v, surf, o, in_map);
    if (ga <= 0.0) return false;
    float c = -1.0, gc = 0.0;
    float recede = dot(dir, view_dir_to(v, o));
    float h = ga < 1e29 ? 1.1 * ga / max(recede, 0.05) : tmax / 16.0;
    h = clamp(h, tmax / 512.0, tmax);
    for (int i = 0; i < 24; i++) {
        float t = min(a + h, tmax);
        float g = surface_gap(v, surf, o + t * dir, in_map);
        if (g <= 0.0) {
            c = t;
            gc = g;
            break;
        }
        if (!in_map || t >= tmax) return false;
        float predicted = (ga < 1e29 && g < 1e29 && ga > g) ? 1.2 * g * (t - a) / (ga - g) : 2.0 * h;
        h = clamp(predicted, 0.5 * h, 3.0 * h);
        a = t;
        ga = g;
    }
    if (c < 0.0) return false;
    float tol = 1e-6 * tmax;
    float t = -1.0;
    int side = 0;
    for (int i = 0; i < 12 && t < 0.0; i++) {
        float w = c - a;
        float m = ga < 1e29 ? clamp((a * gc - c * ga) / (gc - ga), a + 1e-3 * w, c - 1e-3 * w) : 0.5 * (a + c);
        float g = surface_gap(v, surf, o + m * dir, in_map);
        if (abs(g) < tol || w < tol) {
            t = m;
        } else if (g > 0.0) {
            a = m;
            ga = g;
            if (side == 1) gc *= 0.5;
            side = 1;
        } else {
            c = m;
            gc = g;
            if (side == -1 && ga < 1e29) ga *= 0.5;
            side = -1;
        }
    }
    if (t < 0.0) t = ga < 1e29 ? (a * gc - c * ga) / (gc - ga) : c;
    hit = o + t * dir;
    return true;
}

#endif
