#version 460
// Compute splat (docs/design.md step 5, `--splat compute`), dispatched indirectly over the records the draw would
// draw: the same sheared tent of integer radii (glsl/common/photon_bindings.glsl, SplatShape) as splat.frag,
// evaluated at the same texel centers, each tap added to the flux map with a float atomic. The weights of a record
// sum to exactly 1 over the map's texels (at an edge they are renormalized over the taps on the map, splat_norm),
// so flux is conserved as by the point draw; only the order of the float additions differs. As with points, a
// record whose center lies outside the map is dropped (a point primitive is clipped by its vertex).
//
// SPLAT_TILED (the default variant): contention control. Neighbouring records come from neighbouring cells, so a
// work group's records mostly land in a small window of the map, and where light focuses many land on the same
// texels. The group first adds its taps into a SPLAT_TILE² window in shared memory (placed over the group's
// footprint, or centred on its first record when the footprint is wider), then adds each touched window texel to
// the map with one global atomic. Taps outside the window go straight to the map.
//
// Under differential footprints a tent wider than SPLAT_FINE_RADIUS goes to a coarse level of the flux texels
// instead (glsl/common/splat_levels.glsl), at most SPLAT_FINE_RADIUS wide there, with its weights normalized to
// sum to 1; splat_collapse.comp adds the levels back into the map. So a record costs at most about (2
// SPLAT_FINE_RADIUS + 1)² taps, where a 64-texel tent took 129².
//
// SPLAT_COLOR (docs/design.md "Color"): SPLAT_TINT, color photons: a record's flux is its channels' mean and its
// tint their ratios to it (splat_tints); SPLAT_WAVELENGTH, spectral photons: a record's word is its wavelength, whose RGB (spectrum_rgb)
// times the light's color at it (spectral_tint) the flux is spread over. Either way each tap adds its share of each channel to that channel's plane of the texels.
//
// A record whose shape is negated is the eye deposit's (docs/design.md "The eye deposit"; common/deposit.glsl):
// its center is in eye samples, and it is added into the eye's flux (common/deposit_eye.glsl eye_splat), not the
// map.
#extension GL_EXT_shader_atomic_float : require
#include "common/photon_bindings.glsl"
#include "common/splat_levels.glsl"
#include "common/spectrum.glsl"
#include "common/view.glsl"
#include "common/gbuffer.glsl"
#define DEPOSIT_SPLAT
#include "common/deposit_eye.glsl"

layout(local_size_x = LINEAR_WG) in;

layout(constant_id = SPLAT_COLOR_ID) const uint SPLAT_COLOR = SPLAT_GRAY;
const bool SPLAT_RGB = SPLAT_COLOR != SPLAT_GRAY;
const uint SPLAT_PLANES = SPLAT_RGB ? 3u : 1u;

// Add v (W) to flux texel k, tinted: each channel's share to its plane (`plane` texels apart).
// A spectral photon's RGB per watt: its wavelength's, times the pass's light color as a spectrum there (white:
// 1; LightUniforms.light_spectrum_c*, src/spectrum.rs RgbSpectrum), so that its mean over the wavelengths is that color.
vec3 spectral_tint(float nm) {
    vec3 color = u_frame.light.light_intensity > 0.0 ? u_frame.light.light_power / u_frame.light.light_intensity : vec3(0.0);
    vec3 c = vec3(u_frame.light.light_spectrum_c0, u_frame.light.light_spectrum_c1, u_frame.light.light_spectrum_c2);
    return spectrum_rgb(nm) * rgb_spectrum(color, c, nm);
}

void flux_add(uint k, float v, vec3 tint, uint plane) {
    if (SPLAT_RGB) {
        atomicAdd(flux_texels[k], v * tint.r);
        atomicAdd(flux_texels[k + plane], v * tint.g);
        atomicAdd(flux_texels[k + 2u * plane], v * tint.b);
    } else {
        atomicAdd(flux_texels[k], v);
    }
}

// The RGB an eye-deposit record's watt adds: its tint (a spectral record's already holds its light's color) times
// its light's color, which the resolve applies to the map's records; a one-channel pass adds its channel alone.
vec3 eye_tint(vec3 tint) {
    if (SPLAT_COLOR == SPLAT_WAVELENGTH) return tint;
    vec3 color = u_frame.light.light_intensity > 0.0 ? u_frame.light.light_power / u_frame.light.light_intensity : vec3(0.0);
    uint c = u_frame.pass.channel;
    if (c >= 1u && c <= 3u) color *= vec3(equal(uvec3(1u, 2u, 3u), uvec3(c)));
    return tint * color;
}

#ifdef SPLAT_TILED
// The window, one plane after another.
shared float s_tile[SPLAT_TILE * SPLAT_TILE * SPLAT_PLANES];
shared int s_lo_x, s_lo_y, s_hi_x, s_hi_y;
shared ivec2 s_first;

// Add v to window texel b, tinted, as flux_add does to the map.
void tile_add(uint b, float v, vec3 tint) {
    if (SPLAT_RGB) {
        atomicAdd(s_tile[b], v * tint.r);
        atomicAdd(s_tile[b + SPLAT_TILE * SPLAT_TILE], v * tint.g);
        atomicAdd(s_tile[b + 2u * SPLAT_TILE * SPLAT_TILE], v * tint.b);
    } else {
        atomicAdd(s_tile[b], v);
    }
}
#endif

// The coarse level a record of the given extent (half-widths, texels) splats at: the first where both are at most
// SPLAT_FINE_RADIUS texels (the coarsest if none), or 0 for a record splatted as it is.
uint splat_level(vec2 e, ivec2 size) {
    if (u_frame.frame.differential == 0u) return 0u;
    float w = max(e.x, e.y);
    uint top = splat_levels(size), m = 0u;
    while (m < top && w > float(SPLAT_FINE_RADIUS << m)) m++;
    return m;
}

// A record's tent centred at c0 (texels of level 0), at coarse level m: radii r / 2^m (at least 1) and the same
// shear, its weights over the level's texels normalized to sum to 1 (radii that are not integers do not sum to it
// by themselves, and at an edge the taps off the map are given back to the ones on it, as at level 0).
void splat_coarse(vec2 c0, float flux, vec3 tint, SplatShape k0, ivec2 size, uint m) {
    float scale = exp2(-float(m));
    vec2 c = c0 * scale;
    SplatShape k = SplatShape(max(k0.r * scale, vec2(1.0)), k0.s, k0.shear_y);
    ivec2 n = size >> m;
    float sum = splat_sum(c, k, n);
    if (!(sum > 0.0)) return;
    float f = flux / sum;
    uint base = splat_level_offset(size, m), plane = flux_plane(size);
    vec2 e = splat_extent(k);
    ivec2 lo = max(ivec2(ceil(c - e - 0.5)), ivec2(0)), hi = min(ivec2(floor(c + e - 0.5)), n - 1);
    // Line by line (rows, or columns when the shear runs along y), each over its own taps.
    bool sy = k.shear_y;
    for (int j = sy ? lo.x : lo.y; j <= (sy ? hi.x : hi.y); j++) {
        ivec2 line = splat_line(c, k, j, sy ? ivec2(lo.y, hi.y) : ivec2(lo.x, hi.x));
        for (int i = line.x; i <= line.y; i++) {
            ivec2 q = sy ? ivec2(j, i) : ivec2(i, j);
            float w = splat_weight(q, c, k);
            if (w != 0.0) flux_add(base + uint(q.y * n.x + q.x), f * w, tint, plane);
        }
    }
}

void main() {
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * LINEAR_WG + gl_LocalInvocationIndex;
    ivec2 size = ivec2(u_frame.light.receiver_view.extent.xy);
    GpuSplat s = GpuSplat(vec2(0.0), 0.0, 0.0);
    vec3 tint = vec3(1.0);
    uint plane = flux_plane(size);
    bool valid = false;
    if (i < draw_cmd.x) {
        s = splats[draw_cmd.z + i];
        if (SPLAT_RGB) {
            uint w = splat_tints[draw_cmd.z + i];
            tint = SPLAT_COLOR == SPLAT_WAVELENGTH ? spectral_tint(uintBitsToFloat(w)) : tint_unpack(w);
        }
        valid = s.shape > 0.0 && all(greaterThanEqual(s.texel, vec2(0.0))) && all(lessThanEqual(s.texel, vec2(size)));
        if (s.shape < 0.0) eye_splat(s, eye_tint(tint));
    }
    SplatShape k = splat_shape(s.shape);
    vec2 e = splat_extent(k);
    if (valid) {
        uint m = splat_level(e, size);
        if (m > 0u) {
            splat_coarse(s.texel, s.flux, tint, k, size, m);
            valid = false;  // splatted: the level-0 taps (and the tiled window) leave it out
        }
    }
    // Texel centers p + 0.5 with |p + 0.5 - c| < e on each axis.
    ivec2 lo = ivec2(0), hi = ivec2(-1);
    float flux = 0.0;
    if (valid) {
        flux = s.flux * splat_norm(s.texel, k, size);
        lo = max(ivec2(ceil(s.texel - e - 0.5)), ivec2(0));
        hi = min(ivec2(floor(s.texel + e - 0.5)), size - 1);
    }
#ifdef SPLAT_TILED
    uint t = gl_LocalInvocationIndex;
    if (t == 0u) {
        s_lo_x = s_lo_y = 0x7fffffff;
        s_hi_x = s_hi_y = -1;
        s_first = ivec2(-1 << 30);
    }
    for (uint k = t; k < SPLAT_TILE * SPLAT_TILE * SPLAT_PLANES; k += LINEAR_WG) s_tile[k] = 0.0;
    barrier();
    if (valid && hi.x >= lo.x && hi.y >= lo.y) {
        atomicMin(s_lo_x, lo.x);
        atomicMin(s_lo_y, lo.y);
        atomicMax(s_hi_x, hi.x);
        atomicMax(s_hi_y, hi.y);
    }
    if (t == 0u && valid) s_first = ivec2(floor(s.texel)) - SPLAT_TILE / 2;
    barrier();
    if (s_hi_x < 0) return;  // uniform: no record of this group has a tap
    ivec2 glo = ivec2(s_lo_x, s_lo_y), ghi = ivec2(s_hi_x, s_hi_y);
    // The window: over the whole footprint when it fits, else centred on the first record (or on the footprint's
    // corner when the first record is invalid).
    ivec2 org = glo;
    if (any(greaterThanEqual(ghi - glo, ivec2(SPLAT_TILE))) && s_first.x > (-1 << 29)) org = s_first;
    ivec2 wlo = max(org, glo), whi = min(org + SPLAT_TILE - 1, ghi);
#endif
    // Line by line (rows, or columns when the shear runs along y), each over its own taps.
    bool sy = k.shear_y;
    for (int j = sy ? lo.x : lo.y; j <= (sy ? hi.x : hi.y); j++) {
        ivec2 line = splat_line(s.texel, k, j, sy ? ivec2(lo.y, hi.y) : ivec2(lo.x, hi.x));
        for (int i = line.x; i <= line.y; i++) {
            ivec2 p = sy ? ivec2(j, i) : ivec2(i, j);
            float w = splat_weight(p, s.texel, k);
            if (w == 0.0) continue;
            float v = flux * w;
#ifdef SPLAT_TILED
            ivec2 q = p - org;
            if (all(greaterThanEqual(q, ivec2(0))) && all(lessThan(q, ivec2(SPLAT_TILE)))) {
                tile_add(uint(q.y * SPLAT_TILE + q.x), v, tint);
                continue;
            }
#endif
            flux_add(uint(p.y * size.x + p.x), v, tint, plane);
        }
    }
#ifdef SPLAT_TILED
    barrier();
    ivec2 wsz = whi - wlo + 1;
    uint n = uint(max(wsz.x, 0) * max(wsz.y, 0));
    // Plane by plane (a constant count: one loop for gray records).
    for (uint c = 0u; c < SPLAT_PLANES; c++) {
        for (uint k = t; k < n; k += LINEAR_WG) {
            ivec2 p = wlo + ivec2(int(k) % wsz.x, int(k) / wsz.x);
            ivec2 q = p - org;
            float v = s_tile[c * SPLAT_TILE * SPLAT_TILE + uint(q.y * SPLAT_TILE + q.x)];
            if (v != 0.0) atomicAdd(flux_texels[c * plane + uint(p.y * size.x + p.x)], v);
        }
    }
#endif
}
