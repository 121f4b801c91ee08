// Included twice by march.glsl, with SURF_T = usampler2D (g-buffers) and sampler2D (float buffers with the
// distance in .w): GLSL overloads the functions on the sampler type. No include guard, on purpose.

// Coverage-weighted bilinear sample of the distance alone (see geo_sample). False if all four taps are empty.
bool dist_sample(SURF_T tex, vec2 uv, out float d) {
    ivec2 size = textureSize(tex, 0);
    vec2 st = uv * vec2(size) - 0.5;
    ivec2 i0 = ivec2(floor(st));
    vec2 f = st - vec2(i0);
    float acc = 0.0, wsum = 0.0;
    for (int k = 0; k < 4; k++) {
        ivec2 o = ivec2(k & 1, k >> 1);
        float s = geo_dist(tex, clamp(i0 + o, ivec2(0), size - 1));
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

// g = surface distance - point distance in `v`; > 0 while the ray is in front of the surfaces. Empty texels count
// as far away (1e30). Leaving the map sets `in_map` false.
float surface_gap(GpuView v, SURF_T surf, vec3 p, out bool in_map) {
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
bool find_surface(GpuView v, SURF_T surf, vec3 o, vec3 dir, float tmax, out vec3 hit) {
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
