// The eye deposit (docs/design.md "The eye deposit", "Emitters and deposits"): caustic flux per eye sample, W, in
// three planes (red, green, blue), of the landings that no light map holds, where the camera sees them (as AAPS
// deposits in screen space). Its parts:
// - project: eye_project, whether the camera sees a landing, and where in its samples;
// - footprint: eye_footprint, the ray differentials projected into the eye's image;
// - splat: eye_splat (glsl/splat.comp, records of negated shape), over the samples that see the same surface;
// - resolve: none, the lookup divides;
// - lookup: eye_deposit_irradiance, a sample's flux over the receiver area it covers (glsl/eye_shade.comp, and
//   glsl/glass.comp where an eye ray reaches a point the samples see directly).
// Needs the buffer eye_flux; its photon half (project, footprint, splat) also the receivers' eye g-buffer t_eye.
#ifndef DEPOSIT_EYE_GLSL
#define DEPOSIT_EYE_GLSL
#include "common/view.glsl"
#include "common/gbuffer.glsl"

// The flux of eye sample q, of an eye image of `size` samples: the mean over a progressive accumulation's photon
// sets, whose flux the store sums (1 / their count, as FrameUniforms::set_weight).
vec3 eye_deposit_flux(ivec2 q, ivec2 size) {
    uint i = uint(q.y * size.x + q.x), plane = uint(size.x * size.y);
    return vec3(eye_flux[i], eye_flux[i + plane], eye_flux[i + 2u * plane]) * (1.0 / float(u_frame.frame.sample_index + 1u));
}

// The eye deposit's irradiance at sample q (W/m^2), on a receiver of normal n at distance `dist` along the sample's
// ray: its flux over the receiver area the sample covers, so that sum E A keeps the deposited flux.
vec3 eye_deposit_irradiance(GpuView cam, ivec2 q, ivec2 size, vec3 n, float dist) {
    return eye_deposit_flux(q, size) / view_texel_area(cam, q, n, dist);
}

// Camera-driven refinement (`--refine camera`): every landing the camera sees goes to the eye deposit before the
// light's map (common/deposit.glsl), so the receiver points the eye's samples see read the eye deposit alone (the
// light's map holds there only the tents of landings beyond the view's edges).
bool eye_deposit_first() { return u_frame.frame.eye_deposit != 0u && u_frame.frame.refine == REFINE_CAMERA; }

// An eye record's radii are in 1/EYE_SUBSAMPLE samples.
const float EYE_SUBSAMPLE = 8.0;

#ifdef PHOTON_BINDINGS_GLSL
// Whether the camera sees a landing at p arriving along rd (its receivers' eye g-buffer sees p, on the side rd
// arrives on). uv: p's uv in the eye's image.
bool eye_project(vec3 p, vec3 rd, out vec2 uv) {
    GpuView cam = u_frame.frame.camera;
    if (!receiver_seen(cam, t_eye, p, uv)) return false;
    ivec2 size = textureSize(t_eye, 0);
    ivec2 q = clamp(ivec2(uv * vec2(size)), ivec2(0), size - 1);
    vec3 n = geo_fetch(t_eye, q).xyz;
    return dot(rd, n) * dot(view_dir_to(cam, p), n) > 0.0;  // else it lands on the side the eye does not see
}

#ifdef TRANSPORT_GLSL
// A record's shape in eye samples: the ray differentials projected into the eye's image (`differential`), its
// radius at most EYE_SPLAT_RADIUS, else one sample. `jitter` (m) widens it (footprint_widening).
float eye_footprint(vec3 p, RayDiff rdf, bool differential, float jitter) {
    if (!differential) return EYE_SUBSAMPLE;  // one sample
    GpuView cam = u_frame.frame.camera;
    vec2 mx = view_px_diff(cam, p, rdf.dpx), my = view_px_diff(cam, p, rdf.dpy);
    if (jitter > 0.0) {
        float f = footprint_widening(jitter / view_sample_side(cam, view_dist(cam, p)), sqrt(abs(mx.x * my.y - mx.y * my.x)));
        mx *= f;
        my *= f;
    }
    // In eighths of a sample (EYE_SUBSAMPLE: eye_splat divides), so that the tents of a lattice of photons a few
    // samples apart tile it: radii rounded to whole samples leave a moiré of their rounding.
    float k = set_narrowing() * EYE_SUBSAMPLE;
    mx *= k;
    my *= k;
    uint r = uint(clamp(round(sqrt(abs(mx.x * my.y - mx.y * my.x))), EYE_SUBSAMPLE, EYE_SUBSAMPLE * float(EYE_SPLAT_RADIUS)));
    return footprint_radii(mx, my, r);
}
#endif

#ifdef DEPOSIT_SPLAT
// (The splat's half: splat.comp defines DEPOSIT_SPLAT, with float atomics enabled.)
// Where eye sample q's ray meets the receiver it sees (`dist`: its g-buffer distance along the ray).
vec3 eye_point(GpuView cam, ivec2 q, float dist) {
    vec3 ro, rd;
    view_ray(cam, (vec2(q) + 0.5) * cam.extent.zw, ro, rd);
    return ro + rd * dist;
}

// The eye deposit's record s (its shape negated), each watt adding `rgb`: its tent (radii at most
// EYE_SPLAT_RADIUS) over the eye samples that see the surface its center sees (on that surface's tangent plane
// within the tent's reach, facing the same way), its weights normalized over them, so that it deposits all its
// flux on the receiver it landed on and none across an edge. At the image's edges it keeps its flux on the samples
// inside: a landing outside the image deposits nothing here, so one inside keeps all of its flux in view, as the
// reference counts the landings inside the view.
void eye_splat(GpuSplat s, vec3 rgb) {
    GpuView cam = u_frame.frame.camera;
    ivec2 size = textureSize(t_eye, 0);
    ivec2 c = clamp(ivec2(floor(s.texel)), ivec2(0), size - 1);
    vec4 g0 = geo_fetch(t_eye, c);
    if (!(g0.w > 0.0)) return;  // the wave saw a receiver there
    vec3 p0 = eye_point(cam, c, g0.w);
    SplatShape k = splat_shape(-s.shape);
    k.r = clamp(k.r / EYE_SUBSAMPLE, vec2(1.0), vec2(float(EYE_SPLAT_RADIUS)));  // (a narrower tent may miss every sample)
    vec2 e = splat_extent(k);
    ivec2 lo = max(ivec2(ceil(s.texel - e - 0.5)), ivec2(0)), hi = min(ivec2(floor(s.texel + e - 0.5)), size - 1);
    float sample_side = view_sample_side(cam, g0.w);
    float reach = (max(k.r.x, k.r.y) + 1.0) * sample_side;
    float sum = 0.0;
    for (int pass = 0; pass < 2; pass++) {
        vec3 add = (pass == 0 ? 0.0 : s.flux / sum) * rgb;
        for (int y = lo.y; y <= hi.y; y++) {
            for (int x = lo.x; x <= hi.x; x++) {
                ivec2 q = ivec2(x, y);
                float w = splat_weight(q, s.texel, k);
                if (w == 0.0) continue;
                vec4 g = geo_fetch(t_eye, q);
                if (!(g.w > 0.0) || dot(g.xyz, g0.xyz) < 0.9) continue;
                if (abs(dot(eye_point(cam, q, g.w) - p0, g0.xyz)) > reach) continue;
                if (pass == 0) {
                    sum += w;
                } else {
                    uint i = uint(q.y * size.x + q.x), plane = uint(size.x * size.y);
                    atomicAdd(eye_flux[i], w * add.r);
                    atomicAdd(eye_flux[i + plane], w * add.g);
                    atomicAdd(eye_flux[i + 2u * plane], w * add.b);
                }
            }
        }
        if (!(sum > 0.0)) return;
    }
}
#endif
#endif

#endif
