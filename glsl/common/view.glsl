// GpuView math shared by every pass: image-plane coordinates, uv, rays and ray distances.
#ifndef VIEW_GLSL
#define VIEW_GLSL
#include "common/types.glsl"

bool view_is_ortho(GpuView v) { return v.origin.w > 0.5; }

// Image-plane point and depth along forward.
vec3 view_image(GpuView v, vec3 p) {
    vec3 d = p - v.origin.xyz;
    float a = dot(d, v.right.xyz), b = dot(d, v.down.xyz), c = dot(d, v.forward.xyz);
    return view_is_ortho(v) ? vec3(a, b, c) : vec3(a / c, b / c, c);
}

vec2 view_uv(GpuView v, vec3 p) {
    vec3 xyz = view_image(v, p);
    return (xyz.xy - v.window.xy) / v.window.zw;
}

vec2 view_xy_of_uv(GpuView v, vec2 uv) { return v.window.xy + uv * v.window.zw; }

// Ray through an image-plane point.
void view_ray_xy(GpuView v, vec2 xy, out vec3 ro, out vec3 rd) {
    if (view_is_ortho(v)) {
        ro = v.origin.xyz + xy.x * v.right.xyz + xy.y * v.down.xyz;
        rd = v.forward.xyz;
    } else {
        ro = v.origin.xyz;
        rd = normalize(xy.x * v.right.xyz + xy.y * v.down.xyz + v.forward.xyz);
    }
}

void view_ray(GpuView v, vec2 uv, out vec3 ro, out vec3 rd) { view_ray_xy(v, view_xy_of_uv(v, uv), ro, rd); }

// The distance stored in g-buffers: along the view ray from its origin.
float view_dist(GpuView v, vec3 p) {
    vec3 d = p - v.origin.xyz;
    return view_is_ortho(v) ? dot(d, v.forward.xyz) : length(d);
}

// The side (m) of one of the view's samples (texels, pixels) at distance `dist` along its ray: its window's side per
// sample, times the distance for a perspective view.
float view_sample_side(GpuView v, float dist) { return v.window.z * v.extent.z * (view_is_ortho(v) ? 1.0 : dist); }

// Direction of the view ray through p (from the origin towards p).
vec3 view_dir_to(GpuView v, vec3 p) {
    return view_is_ortho(v) ? v.forward.xyz : normalize(p - v.origin.xyz);
}

// Solid angle (perspective) or area (orthographic) of a square image-plane cell of side d centered at xy:
// docs/design.md's midpoint formula d^2 / (1 + x^2 + y^2)^(3/2).
float view_cell_measure(GpuView v, vec2 xy, float d) {
    if (view_is_ortho(v)) return d * d;
    float q = 1.0 + dot(xy, xy);
    return d * d / (q * sqrt(q));
}

// The receiver area (m^2) that texel q of view v covers on a surface of normal n at distance `dist` along the
// texel's ray: Omega d^2 / |cos| (perspective) or side^2 / |cos| (orthographic), |cos| at least 0.02. Flux in
// the texel over it is irradiance (the resolve's caustic map, the eye deposit's samples).
float view_texel_area(GpuView v, ivec2 q, vec3 n, float dist) {
    vec2 xy = view_xy_of_uv(v, (vec2(q) + 0.5) * v.extent.zw);
    vec3 ro, rd;
    view_ray_xy(v, xy, ro, rd);
    float cos_t = max(abs(dot(normalize(n), rd)), 0.02);
    float area = view_cell_measure(v, xy, v.window.z * v.extent.z) / cos_t;
    if (!view_is_ortho(v)) area *= dist * dist;
    return area;
}

bool uv_inside_strict(vec2 uv) { return all(greaterThan(uv, vec2(0.0))) && all(lessThan(uv, vec2(1.0))); }

#endif
