// Exact photon transport (docs/design.md step 5, `--transport exact`): rays through the scene BVH, a deterministic
// Fresnel split at every dielectric interface, and the landing point of a path on the receivers. The wave shader
// follows every branch; the traversal's max-error metric follows each child's dominant branch.
// Needs photon_bindings, photon.glsl and bvh.glsl.
#ifndef TRANSPORT_GLSL
#define TRANSPORT_GLSL
#include "common/bvh.glsl"
#include "common/interface.glsl"


// The photon ray of a cell: from the light through the cell's center.
void cell_ray(uint level, uvec2 xy, out vec3 ro, out vec3 rd) {
    View v = u_frame.photon_view;
    view_ray_xy(v, view_xy_of_uv(v, cell_center_uv(level, xy)), ro, rd);
}

const uint DOM_OK = 0u;       // landed on a receiver after >= 1 specular interaction
const uint DOM_DIRECT = 1u;   // landed on a receiver with none
const uint DOM_ESCAPED = 2u;
const uint DOM_CUT = 3u;      // interaction cap or a dead end

// Follow a cell's dominant path (the larger branch at every interface) to where it ends, for the max-error
// metric: its status, the landing texel of the caustic map, and its interaction count.
uint trace_dominant(uint level, uvec2 xy, out vec2 map_px, out uint events) {
    vec3 ro, rd;
    cell_ray(level, xy, ro, rd);
    map_px = vec2(-1e9);
    events = 0u;
    for (uint k = 0u; k <= MAX_INTERACTIONS; k++) {
        SceneHit hit;
        if (!bvh_closest(ro, rd, 1.0 / 0.0, hit)) return DOM_ESCAPED;
        vec3 p = bvh_hit_point(hit);
        if (!inst_is_dielectric(hit.inst)) {
            View rv = u_frame.receiver_view;
            map_px = view_uv(rv, p) * rv.extent.xy;
            return events == 0u ? DOM_DIRECT : DOM_OK;
        }
        if (k == MAX_INTERACTIONS) break;
        vec3 ng, ns;
        bvh_normals(hit, ng, ns);
        Split s = split_interface(rd, p, ng, ns, inst_ior(hit.inst), inst_is_mirror(hit.inst));
        if (!s.ok) break;
        bool refl = s.F >= 0.5;
        ro = refl ? s.p_refl : s.p_refr;
        rd = normalize(refl ? s.refl : s.refr);
        events++;
    }
    return DOM_CUT;
}

#endif
