#version 460
// Compute splat (docs/design.md step 5, `--splat compute`), dispatched indirectly over the records the draw would
// draw: the same separable integer-radius tent (radii rx, ry) as splat.frag, evaluated at the same texel centers, each tap added
// to the flux map with a float atomic. The weights of a record sum to exactly 1 over the texel lattice, so flux is
// conserved as by the point draw; only the order of the float additions differs. As with points, a record whose
// center lies outside the map is dropped (a point primitive is clipped by its vertex).
//
// SPLAT_TILED (the default variant): contention control. Neighbouring records come from neighbouring cells, so a
// work group's records mostly land in a small window of the map, and where light focuses many land on the same
// texels. The group first adds its taps into a SPLAT_TILE² window in shared memory (placed over the group's
// footprint, or centred on its first record when the footprint is wider), then adds each touched window texel to
// the map with one global atomic. Taps outside the window go straight to the map.
#extension GL_EXT_shader_atomic_float : require
#include "common/photon_bindings.glsl"

layout(local_size_x = LINEAR_WG) in;

#ifdef SPLAT_TILED
shared float s_tile[SPLAT_TILE * SPLAT_TILE];
shared int s_lo_x, s_lo_y, s_hi_x, s_hi_y;
shared ivec2 s_first;
#endif

void main() {
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * LINEAR_WG + gl_LocalInvocationIndex;
    ivec2 size = ivec2(u_frame.receiver_view.extent.xy);
    vec4 s = vec4(0.0);
    bool valid = false;
    if (i < draw_cmd.x) {
        s = splats[draw_cmd.z + i];
        valid = s.w > 0.0 && s.x >= 0.0 && s.y >= 0.0 && s.x <= float(size.x) && s.y <= float(size.y);
    }
    vec2 r = splat_radii(s.w);
    // Texel centers p + 0.5 with |p + 0.5 - c| < r on each axis.
    ivec2 lo = ivec2(0), hi = ivec2(-1);
    if (valid) {
        lo = max(ivec2(ceil(s.xy - r - 0.5)), ivec2(0));
        hi = min(ivec2(floor(s.xy + r - 0.5)), size - 1);
    }
#ifdef SPLAT_TILED
    uint t = gl_LocalInvocationIndex;
    if (t == 0u) {
        s_lo_x = s_lo_y = 0x7fffffff;
        s_hi_x = s_hi_y = -1;
        s_first = ivec2(-1 << 30);
    }
    for (uint k = t; k < SPLAT_TILE * SPLAT_TILE; k += LINEAR_WG) s_tile[k] = 0.0;
    barrier();
    if (valid && hi.x >= lo.x && hi.y >= lo.y) {
        atomicMin(s_lo_x, lo.x);
        atomicMin(s_lo_y, lo.y);
        atomicMax(s_hi_x, hi.x);
        atomicMax(s_hi_y, hi.y);
    }
    if (t == 0u && valid) s_first = ivec2(floor(s.xy)) - SPLAT_TILE / 2;
    barrier();
    if (s_hi_x < 0) return;  // uniform: no record of this group has a tap
    ivec2 glo = ivec2(s_lo_x, s_lo_y), ghi = ivec2(s_hi_x, s_hi_y);
    // The window: over the whole footprint when it fits, else centred on the first record (or on the footprint's
    // corner when the first record is invalid).
    ivec2 org = glo;
    if (any(greaterThanEqual(ghi - glo, ivec2(SPLAT_TILE))) && s_first.x > (-1 << 29)) org = s_first;
    ivec2 wlo = max(org, glo), whi = min(org + SPLAT_TILE - 1, ghi);
#endif
    for (int y = lo.y; y <= hi.y; y++) {
        float wy = max(0.0, 1.0 - abs(float(y) + 0.5 - s.y) / r.y) / r.y;
        if (wy == 0.0) continue;
        for (int x = lo.x; x <= hi.x; x++) {
            float wx = max(0.0, 1.0 - abs(float(x) + 0.5 - s.x) / r.x) / r.x;
            if (wx == 0.0) continue;
            float v = s.z * (wx * wy);
#ifdef SPLAT_TILED
            ivec2 q = ivec2(x, y) - org;
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(SPLAT_TILE)))) {
                atomicAdd(s_tile[q.y * SPLAT_TILE + q.x], v);
                continue;
            }
#endif
            atomicAdd(flux_texels[y * size.x + x], v);
        }
    }
#ifdef SPLAT_TILED
    barrier();
    ivec2 wsz = whi - wlo + 1;
    uint n = uint(max(wsz.x, 0) * max(wsz.y, 0));
    for (uint k = t; k < n; k += LINEAR_WG) {
        ivec2 p = wlo + ivec2(int(k) % wsz.x, int(k) / wsz.x);
        ivec2 q = p - org;
        float v = s_tile[q.y * SPLAT_TILE + q.x];
        if (v != 0.0) atomicAdd(flux_texels[p.y * size.x + p.x], v);
    }
#endif
}
