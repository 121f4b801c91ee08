// The binding layout shared by every photon pass (init, traverse, stats, dense emit, trace, transport, wave, the
// splats and their collapse).
// Each binding's index is a constant of src/shader_consts.rs (PB_*), which src/passes/photons.rs binds by too.
#ifndef PHOTON_BINDINGS_GLSL
#define PHOTON_BINDINGS_GLSL
#include "common/types.glsl"

layout(std140, set = 0, binding = PB_FRAME) uniform FrameUbo { FrameData u_frame; };
layout(std430, set = 0, binding = PB_STATE) buffer StateBuf { TraversalState state; };
// The wave's read-only inputs (the photons, the coverage pyramid) are texel buffers where it reads the BVH as texels
// (WAVE_TEXELS, glsl/wave.comp; common/bvh_types.glsl says why).
#ifdef WAVE_TEXELS
layout(set = 0, binding = PB_PHOTONS) uniform usamplerBuffer photon_texels;
uvec2 photon_at(uint i) { return texelFetch(photon_texels, int(i)).xy; }
#else
layout(std430, set = 0, binding = PB_PHOTONS) buffer PhotonBuf { uvec2 photons[]; };
uvec2 photon_at(uint i) { return photons[i]; }
#endif
// Indirect commands: dispatch[level] (x, y, z, pad) for each traversal level, the photon trace's dispatch, then
// the splat's draw command (vertexCount, instanceCount, firstVertex, firstInstance).
// Exact transport adds the current wave's dispatch.
layout(std430, set = 0, binding = PB_INDIRECT) buffer IndirectBuf { IndirectCommand indirect_cmd[INDIRECT_COMMANDS]; };
#define dispatch_cmd(level) indirect_cmd[level].args
#define trace_cmd indirect_cmd[INDIRECT_TRACE].args
#define draw_cmd indirect_cmd[INDIRECT_DRAW].args
#define wave_cmd indirect_cmd[INDIRECT_WAVE].args
#define splat_cmd indirect_cmd[INDIRECT_SPLAT].args
#ifdef WAVE_TEXELS
layout(set = 0, binding = PB_COVERAGE) uniform usamplerBuffer coverage_texels;
uint coverage_at(uint i) { return texelFetch(coverage_texels, int(i)).x; }
#else
layout(std430, set = 0, binding = PB_COVERAGE) readonly buffer CoverageBuf { uint coverage[]; };
uint coverage_at(uint i) { return coverage[i]; }
#endif
layout(set = 0, binding = PB_FRONT) uniform usampler2D t_front;     // refractor front: normal, distance (0: none; common/gbuffer.glsl)
layout(set = 0, binding = PB_FRONT_AUX) uniform sampler2D t_front_aux;  // refractor front: index of refraction
layout(set = 0, binding = PB_BACK) uniform usampler2D t_back;      // refractor back: normal, distance
layout(set = 0, binding = PB_RECEIVERS) uniform usampler2D t_recv;      // receivers from the light: normal, distance
// Debug photon dump (tests): a header (count, capacity) and a GpuDebugPhoton per splatted photon.
layout(std430, set = 0, binding = PB_DEBUG) buffer DebugBuf { uvec4 debug_header; GpuDebugPhoton debug_photons[]; };
// Splat records (GpuSplat). A record's shape (0: the photon did not land) is an exact integer below 2^24 in a
// float (splat_pack): radii rx (bits 0-6) and ry (bits 7-13, 0 meaning ry = rx, so a plain radius r is the
// isotropic tent of radius r), a shear s in [-1, 1] in 1/255 steps (bits 14-22, two's complement) and its axis
// (bit 23).
// The raster splat only reads them (SPLAT_RECORDS_READ_ONLY), as its pass declares (src/passes/photons.rs).
#ifdef SPLAT_RECORDS_READ_ONLY
layout(std430, set = 0, binding = PB_SPLATS) readonly buffer SplatBuf { GpuSplat splats[]; };
#else
layout(std430, set = 0, binding = PB_SPLATS) buffer SplatBuf { GpuSplat splats[]; };
#endif
// A record's tent: integer radii r (texels) and a shear. Row by row (columns by column when shear_y), the tent
// across the rows is centred s texels further per texel of distance along them, so its weight at offset d from
// the record's center is tent(d.x - s d.y, rx) tent(d.y, ry) (d.y - s d.x and d.x when shear_y).
struct SplatShape {
    vec2 r;
    float s;
    bool shear_y;
};
float splat_pack(uvec2 r, float s, bool shear_y) {
    uint q = uint(int(round(s * 255.0))) & 0x1FFu;
    return float(r.x | (r.y << 7) | (q << 14) | (shear_y ? 1u << 23 : 0u));
}
SplatShape splat_shape(float w) {
    uint b = uint(w);
    uint rx = b & 0x7Fu, ry = (b >> 7) & 0x7Fu;
    int q = int(b << 9) >> 23;  // bits 14-22, sign-extended
    return SplatShape(vec2(float(rx), float(ry == 0u ? rx : ry)), float(q) / 255.0, (b & (1u << 23)) != 0u);
}
// The half-widths of the box that holds a shape's taps.
vec2 splat_extent(SplatShape k) {
    return k.shear_y ? vec2(k.r.x, k.r.y + abs(k.s) * k.r.x) : vec2(k.r.x + abs(k.s) * k.r.y, k.r.y);
}
// The weight of texel x (its center x + 0.5) in a tent of radius r centred at c, before normalization (splat.frag
// weighs its fragments the same way).
float tent(int x, float c, float r) {
    return max(0.0, 1.0 - abs(float(x) + 0.5 - c) / r);
}
// The weight of texel p in a shape centred at c, before normalization: over the whole lattice they sum to exactly
// rx ry for integer radii (each row's tent sums to rx wherever the shear puts it).
float splat_weight(ivec2 p, vec2 c, SplatShape k) {
    vec2 d = vec2(p) + 0.5 - c;
    return k.shear_y ? tent(p.x, c.x, k.r.x) * tent(p.y, c.y + k.s * d.x, k.r.y)
                     : tent(p.x, c.x + k.s * d.y, k.r.x) * tent(p.y, c.y, k.r.y);
}
// The sum over the texel centers of a map n texels wide (0 <= x < n) of tent(x, c, r): exactly r for an integer r
// whose tent lies inside the map, less where it reaches past an edge.
float tent_sum(float c, float r, int n) {
    int lo = max(int(ceil(c - r - 0.5)), 0), hi = min(int(floor(c + r - 0.5)), n - 1);
    float s = 0.0;
    for (int x = lo; x <= hi; x++) s += tent(x, c, r);
    return s;
}
// The sum of a shape's weights over the texels of a map of the given size, row by row (column by column).
float splat_sum(vec2 c, SplatShape k, ivec2 size) {
    vec2 e = splat_extent(k);
    float sum = 0.0;
    if (k.shear_y) {
        int lo = max(int(ceil(c.x - e.x - 0.5)), 0), hi = min(int(floor(c.x + e.x - 0.5)), size.x - 1);
        for (int x = lo; x <= hi; x++) {
            float wx = tent(x, c.x, k.r.x);
            if (wx > 0.0) sum += wx * tent_sum(c.y + k.s * (float(x) + 0.5 - c.x), k.r.y, size.y);
        }
    } else {
        int lo = max(int(ceil(c.y - e.y - 0.5)), 0), hi = min(int(floor(c.y + e.y - 0.5)), size.y - 1);
        for (int y = lo; y <= hi; y++) {
            float wy = tent(y, c.y, k.r.y);
            if (wy > 0.0) sum += wy * tent_sum(c.x + k.s * (float(y) + 0.5 - c.y), k.r.x, size.x);
        }
    }
    return sum;
}
// The taps of a shape centred at c along its line j (a row, or a column when shear_y), within [lo, hi] along it:
// where the line's tent, shifted by the shear, can be nonzero, with a texel to spare on each side for rounding (a
// zero weight is skipped). A sheared shape's lines are narrower than the box that holds them all.
ivec2 splat_line(vec2 c, SplatShape k, int j, ivec2 lo_hi) {
    float center = k.shear_y ? c.y + k.s * (float(j) + 0.5 - c.x) : c.x + k.s * (float(j) + 0.5 - c.y);
    float r = k.shear_y ? k.r.y : k.r.x;
    return ivec2(max(int(ceil(center - r - 0.5)) - 1, lo_hi.x), min(int(floor(center + r - 0.5)) + 1, lo_hi.y));
}
// The factor that makes the on-map weights of a splat of integer radii centred at c (texels) sum to exactly 1:
// 1 / (rx ry) for a tent inside the map; at an edge the taps that would fall off it are given back to the ones on
// it, so a record whose center lands on the map deposits all its flux there, however wide its tent.
float splat_norm(vec2 c, SplatShape k, ivec2 size) {
    vec2 e = splat_extent(k);
    if (all(greaterThanEqual(c - e, vec2(0.0))) && all(lessThanEqual(c + e, vec2(size)))) return 1.0 / (k.r.x * k.r.y);
    float on_map = splat_sum(c, k, size);
    return on_map > 0.0 ? 1.0 / on_map : 0.0;
}

// Exact transport (src/bvh/, glsl/common/bvh.glsl): the wave state, two ray queues, and the scene BVH.
// A queue entry is a GpuRay's words, then the parts the frame adds (GpuRay says which). The ray's photon index
// points into the photon buffer, whose cell gives the flux and footprint.
layout(std430, set = 0, binding = PB_TRANSPORT) buffer TransportBuf { TransportState tstate; };
// The two ray queues swap bindings from wave to wave (src/passes/photons.rs, PhotonPasses::wave): a wave reads
// rays_in and appends to rays_out, with no branch on which queue is which.
#ifdef WAVE_TEXELS
layout(set = 0, binding = PB_RAYS_IN) uniform usamplerBuffer rays_in_texels;
uvec4 ray_word_in(uint k) { return texelFetch(rays_in_texels, int(k)); }
#else
layout(std430, set = 0, binding = PB_RAYS_IN) readonly buffer RaysIn { uvec4 rays_in[]; };
uvec4 ray_word_in(uint k) { return rays_in[k]; }
#endif
layout(std430, set = 0, binding = PB_RAYS_OUT) writeonly buffer RaysOut { uvec4 rays_out[]; };
#include "common/bvh_types.glsl"
layout(std430, set = 0, binding = PB_BVH_PAIR) readonly buffer BvhPair { PairNode bvh_nodes[]; };
layout(std430, set = 0, binding = PB_BVH_SINGLE) readonly buffer BvhSingle { SingleNode bvh_nodes_single[]; };
#ifdef BVH_TEXELS
layout(set = 0, binding = PB_BVH_TRIS) uniform samplerBuffer bvh_tri_texels;       // 3 per triangle
layout(set = 0, binding = PB_BVH_NORMALS) uniform samplerBuffer bvh_normal_texels; // 3 per triangle
layout(set = 0, binding = PB_BVH_INSTANCES) uniform samplerBuffer bvh_instance_texels;  // 12 per instance
#else
layout(std430, set = 0, binding = PB_BVH_TRIS) readonly buffer BvhTris { vec4 bvh_tris[]; };          // 3 per triangle
layout(std430, set = 0, binding = PB_BVH_NORMALS) readonly buffer BvhNormals { vec4 bvh_normal_rows[]; }; // 3 per triangle
layout(std430, set = 0, binding = PB_BVH_INSTANCES) readonly buffer BvhInstances { GpuInstance bvh_instances[]; };
#endif

// The compute splat's target: the caustic flux map as one float per texel (row-major), added to atomically, then
// copied into the flux image that the resolve reads.
layout(std430, set = 0, binding = PB_FLUX_TEXELS) buffer FluxBuf { float flux_texels[]; };
// Photons that carry their color: each splat record's color (tint_pack, glsl/common/types.glsl) or wavelength (its
// float bits), at its record's index.
layout(std430, set = 0, binding = PB_SPLAT_TINTS) buffer SplatTintBuf { uint splat_tints[]; };
// The eye deposit (docs/design.md "The eye deposit"): the receivers seen from the eye (normal, distance; 0: none;
// common/gbuffer.glsl), which the waves test a landing against, and the caustic flux per eye sample, W, in three
// planes (red, green, blue), which the compute splats add a negated-shape record's taps into.
layout(set = 0, binding = PB_EYE) uniform usampler2D t_eye;
layout(std430, set = 0, binding = PB_EYE_FLUX) buffer EyeFluxBuf { float eye_flux[]; };
// The threaded layout (src/bvh/): depth-first nodes with escape links; lo.w: escape, hi.w: count << 29 | first.
layout(std430, set = 0, binding = PB_BVH_THREADED) readonly buffer BvhThreaded { SingleNode bvh_nodes_threaded[]; };
// The wide layout (src/bvh/): compressed 8-wide nodes, and its triangle list (each entry its triangle's three
// vertices, the first's w the triangle's index in bvh_tris' triangles).
#ifdef BVH_TEXELS
layout(set = 0, binding = PB_BVH_WIDE) uniform usamplerBuffer bvh_wide_texels;  // 5 per node
layout(set = 0, binding = PB_BVH_WIDE_PRIMS) uniform usamplerBuffer bvh_wide_prim_texels;  // 3 per entry
#else
layout(std430, set = 0, binding = PB_BVH_WIDE) readonly buffer BvhWide { WideNode bvh_nodes_wide[]; };
layout(std430, set = 0, binding = PB_BVH_WIDE_PRIMS) readonly buffer BvhWidePrims { uvec4 bvh_wide_prims[]; };
#endif

// Dispatch arguments for n invocations in groups of `per_group`, 2D because a dimension holds at most 65535
// groups (lavapipe's limit).
uvec4 dispatch_groups(uint n, uint per_group) {
    uint g = (n + per_group - 1u) / per_group;
    uint gx = min(g, 65535u);
    return uvec4(gx, g == 0u ? 0u : (g + gx - 1u) / gx, 1u, 0u);
}

// The splat's draw over records [first, first + n), and the compute splat's dispatch for the same records.
void set_draw(uint n, uint first) {
    draw_cmd = uvec4(n, 1u, first, 0u);
    splat_cmd = dispatch_groups(n, LINEAR_WG);
}

// The emitted photons are [capacity - n, capacity): set the trace dispatch and the splat draw for them.
void set_emitted(uint n, uint capacity) {
    trace_cmd = dispatch_groups(n, LINEAR_WG);
    set_draw(n, capacity - n);
}

#endif
