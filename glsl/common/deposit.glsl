// The deposit interface (docs/design.md "Emitters and deposits"): where a photon's landing on a diffuse receiver is
// kept until the eye view reads it. Each kind of deposit is its own file, with the same parts: project (whether it
// holds a landing at p arriving along rd, and where in its store), footprint (a record's tent there, from the
// ray differentials), splat (the record into its store, glsl/splat.comp), resolve, and lookup (the receivers'
// shading). A record (GpuSplat) says its deposit by its shape's sign: positive, the light map's; negated, the
// eye's.
// The kinds, in the order a landing tries them (src/frame/deposit.rs DEPOSITS; the first that holds it takes it):
// - common/deposit_light_map.glsl: the light view's caustic map, the papers' deposit and the fast path;
// - common/deposit_eye.glsl: the eye's samples, where the camera sees a landing no light map holds.
// What none holds is ACC_UNSEEN in the energy account. Needs the photon bindings and common/transport.glsl.
#ifndef DEPOSIT_GLSL
#define DEPOSIT_GLSL
#include "common/deposit_light_map.glsl"
#include "common/deposit_eye.glsl"

// A landing at p (geometric normal ng) arriving along rd, of flux `flux` (W), whose photon's cell has the splat
// radius r_cell (caustic-map texels) and the ray differentials rdf (`differential`), and a sun's jitter (m,
// light_map_footprint): its record in the first deposit that holds it. Returns false where none does.
bool deposit_landing(vec3 p, vec3 ng, vec3 rd, RayDiff rdf, uint r_cell, bool differential, float jitter, float flux,
                     out GpuSplat record) {
    GpuView rv = u_frame.light.receiver_view;
    vec2 uv;
    // Camera-driven refinement refines as finely as the camera's image needs, which the light's map may not
    // resolve: what the camera sees goes to the eye deposit first.
    bool eye = u_frame.frame.eye_deposit != 0u, eye_first = eye_deposit_first();
    if (eye_first && eye_project(p, rd, uv)) {
        record = GpuSplat(uv * vec2(textureSize(t_eye, 0)), flux, -eye_footprint(p, rdf, differential, jitter));
        return true;
    }
    if (light_map_project(rv, t_recv, p, ng, rd, uv)) {
        record = GpuSplat(uv * rv.extent.xy, flux, light_map_footprint(rv, p, rdf, r_cell, differential, jitter));
        return true;
    }
    if (eye && !eye_first && eye_project(p, rd, uv)) {
        record = GpuSplat(uv * vec2(textureSize(t_eye, 0)), flux, -eye_footprint(p, rdf, differential, jitter));
        return true;
    }
    return false;
}

#endif
