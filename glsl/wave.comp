#version 460
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
// One wave of exact photon transport (docs/design.md step 4, `--transport exact`), dispatched indirectly with the
// arguments the transport shader wrote after the previous wave. Wave 0 turns each emitted photon into a ray from
// the light through its cell's center; wave k > 0 traces the rays wave k - 1 appended (rays_in: the two queues
// swap bindings from wave to wave). At a dielectric the Fresnel split appends the reflected and refracted
// children (each above the flux threshold) to rays_out; at a diffuse
// receiver a path with one or more specular interactions becomes a splat record; a miss escapes. Every
// invocation's flux goes to exactly one account term, summed per work group and added in fixed point.
// Appends reserve once per work group. A reservation that does not fit aborts the batch (batching splits its
// tile, as traversal overflow does) or, without batching, is dropped and counted as overflow.
#if defined(BVH_LAYOUT_WIDE)
// The layout CPU devices trace: the photons, the coverage pyramid and the rays in are read as texels too.
#define WAVE_TEXELS 1
#endif
#include "common/photon_bindings.glsl"
layout(push_constant) uniform WavePushBlock { WavePush pc; };
#include "common/coverage.glsl"
#include "common/photon.glsl"
#include "common/transport.glsl"
#include "common/deposit.glsl"

layout(local_size_x = LINEAR_WG) in;

// Specialization constants (src/passes/photons.rs, wave_spec): wave 0, whose rays start at the photons' cells, or
// a bounce wave, which reads its rays from a queue; and whether the rays carry ray differentials (`--footprint
// differential`, docs/design.md step 5). The driver folds them before it compiles, so each wave holds only the
// code it runs: a CPU driver such as lavapipe runs both sides of every branch under a mask.
layout(constant_id = WAVE_PRIMARY_ID) const bool WAVE_PRIMARY = false;
layout(constant_id = WAVE_DIFFERENTIAL_ID) const bool WAVE_DIFFERENTIAL = false;
// The rays carry the medium they travel in and the volumes they are inside (the scene has absorbing or overlapping
// media, docs/design.md "Media"): a segment is attenuated by its medium's absorption whatever it meets. Without media
// nothing absorbs and every surface is an explicit interface.
layout(constant_id = WAVE_MEDIA_ID) const bool WAVE_MEDIA = false;
// Color photons (with WAVE_MEDIA; docs/design.md "Color"): a ray carries its color as a tint (tint_pack, in its
// medium word), absorption takes each channel's share, and a record carries the ray's color (splat_tints). The
// throughput is the channels' mean weight, so the account and the flux threshold see the mean.
layout(constant_id = WAVE_COLOR_ID) const bool WAVE_COLOR = false;
// Spectral photons (some glass disperses; docs/design.md "Color"): each photon traces one wavelength, stratified
// over the cells (photon_wavelength, glsl/common/spectrum.glsl), at which every IOR and absorption coefficient
// is taken, and a record carries it (splat_tints) for the splat to turn into RGB.
layout(constant_id = WAVE_SPECTRAL_ID) const bool WAVE_SPECTRAL = false;
// The most subgroups a work group can have on this device (LINEAR_WG over its least subgroup size).
layout(constant_id = WAVE_SUBGROUPS_ID) const uint WAVE_SUBGROUPS = LINEAR_WG;

// Each subgroup's sums of the account's terms, then of the flux whose term depends on the reservation verdict:
// children to append, records, the records' one-interaction part and their eye deposit's part (rows
// ACC_TERMS + PEND_*).
const uint PEND_CHILD = 0u, PEND_REC = 1u, PEND_ONE = 2u, PEND_EYE = 3u;
shared float s_acc[ACC_TERMS + 4u][LINEAR_WG];
// The work group's children that travel inside glass, those outside it, and its records, counted in three 10-bit
// fields of one word (each at most 2 LINEAR_WG; src/passes/photons.rs asserts it), so that an invocation takes all
// its slots with one shared atomic: a CPU driver runs each atomic as a loop over the SIMD group's lanes.
shared uint s_slots;
const uint SLOT_BITS = 10u, SLOT_MASK = (1u << SLOT_BITS) - 1u;
const uint SLOT_INSIDE = 1u, SLOT_OUTSIDE = 1u << SLOT_BITS, SLOT_REC = 1u << (2u * SLOT_BITS);

// The count of children inside glass (else outside it) in a word of s_slots.
uint slot_run(uint word, bool inside) { return (word >> (inside ? 0u : SLOT_BITS)) & SLOT_MASK; }
shared uint s_ray_base;  // where the work group's children go in rays_out, or NO_BASE
shared uint s_rec_base;  // where its records go in splats, or NO_BASE
const uint NO_BASE = 0xFFFFFFFFu;

// A child ray: the ray, its differentials, and whether it travels inside glass (else outside it). The work group
// appends the two kinds as two runs, so that neighbouring rays of the next wave tend to take the same way through
// the BVH (a SIMD group of a CPU driver, or a GPU's, walks as long as its longest ray).
struct Child {
    GpuRay ray;
    RayDiff diff;
    bool inside;
    uint medium;  // the medium it travels in (WAVE_MEDIA)
    uvec2 nested; // the volumes with a priority it is inside (WAVE_MEDIA; glsl/common/interface.glsl)
    vec3 tint;    // its color (WAVE_COLOR)
};

// What one invocation produces: up to two child rays and one splat record. The children are named, not an array:
// a CPU driver stores an element of a local array indexed per invocation lane by lane. Child 0 is the reflected
// branch when it is traced, else the refracted one; child 1 the refracted one when both are.
struct Outcome {
    uint n_child;
    Child c0, c1;
    bool rec;          // a splat record
    GpuSplat record;
    uint rec_tint;     // its color, packed (WAVE_COLOR)
    float rec_flux;    // its flux, relative to the light's intensity (the account's unit)
    bool one_event;    // its path met exactly one interaction
    bool eye;          // the record is the eye deposit's (in eye samples, its shape negated)
};

// The ray an invocation traces, and its photon.
struct Traced {
    GpuRay ray;
    RayDiff diff;
    uint pidx;    // the photon's entry; a ray carries it counted from the buffer's top (the batch's photons fill it
                  // from there down), which a 24-bit field holds for any batch (Settings::batch_photons)
    uvec2 cell;   // the photon's cell, read once
    float phi;    // the photon's flux / intensity
    float side;   // the photon's cell side: the scale of its packed differentials
    uint depth;   // the ray's interactions so far: the wave's own index, since wave k traces what wave k - 1
                  // appended (wave 0 the photons), so every ray of a wave has the same
    bool lod;     // a weak branch carried for the photon's block
    uint medium;  // the medium it travels in (WAVE_MEDIA; wave 0's rays start in air)
    uvec2 nested; // the volumes with a priority it is inside (WAVE_MEDIA)
    vec3 tint;    // its color (WAVE_COLOR; white at the light)
};

// The invocation's shares of the account's terms (ACC_*), summed per work group at the end.
float acc[ACC_TERMS];

// A queue entry (GpuRay, src/gpu_types.rs): the ray's words, then with differential footprints their packed
// word (diff_pack, glsl/common/transport.glsl), then with media its GpuRayMedium, last.
void store_ray(uint k, uint stride, Child c, float side) {
    uint b = stride * k;
    uvec4 w0, w1;
    GpuRay_to_words(c.ray, w0, w1);
    rays_out[b] = w0;
    rays_out[b + 1u] = w1;
    if (WAVE_DIFFERENTIAL) rays_out[b + 2u] = diff_pack(c.diff, c.ray.dir, side);
    if (WAVE_MEDIA) {
        uvec4 m;
        GpuRayMedium_to_words(GpuRayMedium(c.nested, WAVE_COLOR ? tint_pack(c.tint) : 0u, c.medium), m);
        rays_out[b + stride - 1u] = m;
    }
}

// Weak branches (`--weak-branches`, docs/design.md step 4): a Fresnel branch below u_frame.frame.weak_fraction of its
// photon's flux is traced once per block instead of by each photon in the block. At a split of depth d the block's
// members take turns (member d mod n of the n, in raster order): the photon whose turn it is traces the weak branch
// carrying the block's share (its weight times `scale`, the block's solid angle over its own), flagged LOD_RAY so
// that it splats as wide as the block; the others leave it (ACC_WEAK_LEFT), and the extra weight the one carries is
// ACC_WEAK_CARRIED, so the account still closes exactly. Two kinds of blocks, so that the turns never depend on
// which photons another batch made:
// - the maximal level's blocks, weak_block() of its cells a side, whose members are those cells that pass dense's
//   test: the turn goes to the photon that contains the member, so photons of different levels (dense's and
//   max-level's cells, and under the merging metrics a refined cell's children, look-ahead children and clusters
//   smaller than the block) share a block consistently;
// - a larger photon (a cluster) shares with its three siblings when traversal found each of them a photon of its
//   level too, or empty (cell_siblings, glsl/common/types.glsl); otherwise it traces its own weak branches.
// The meta bit of a weak branch carried for its block (the depth stays in the 6 bits above PHOTON_INDEX_BITS).
const uint LOD_RAY = 0x80000000u;

// Whether the photon shares the maximal level's blocks (else its siblings, if traversal marked any).
bool weak_fine(uvec2 cell) { return !weak_by_siblings(cell_level(cell)); }

bool weak_branches_apply(uvec2 cell) {
    return u_frame.frame.weak_fraction > 0.0 && (weak_fine(cell) || cell_siblings(cell) != 0u);
}

// The block's side over the photon's cell's: how much wider a carried branch is than the photon's own.
float weak_widen(uvec2 cell) {
    return weak_fine(cell) ? exp2(float(weak_block_shift()) - float(u_frame.frame.max_level - cell_level(cell))) : 2.0;
}

// Whether this photon (`own`: its cell's measure, the photon's phi) carries its block's weak branches at `depth`,
// and the weight factor when it does.
bool weak_carrier(uvec2 cell, float own, uint depth, out float scale) {
    uvec2 xy = cell_xy(cell);
    if (!weak_fine(cell)) {
        // Siblings: the members are the photon and those of its three siblings the mask names, in raster order.
        uint level = cell_level(cell), mask = cell_siblings(cell);
        uint self_k = (xy.x & 1u) | ((xy.y & 1u) << 1);
        float total = 0.0;
        uint n = 0u, self_i = 0u, j = 0u;
        for (uint k = 0u; k < 4u; k++) {
            if (k == self_k) {
                self_i = n++;
                total += own;
            } else if ((mask & (1u << j++)) != 0u) {
                total += cell_measure(level, (xy & ~uvec2(1u)) + uvec2(k & 1u, k >> 1));
                n++;
            }
        }
        scale = total / own;
        return depth % n == self_i;
    }
    uint top = u_frame.frame.max_level;
    uint up = top - cell_level(cell);  // the photon's cell is 2^up cells of the maximal level a side
    uint side = weak_block(), shift = weak_block_shift();
    uvec2 b = (xy << up) & ~uvec2(side - 1u);
    float total = 0.0;
    uint n = 0u, counted = 0u, mine = 0u;
    for (uint k = 0u; k < side * side; k++) {
        // side is a power of two: a CPU driver would divide lane by lane.
        uvec2 c = b + uvec2(k & (side - 1u), k >> shift);
        if (!leaf_emitted(top, c)) continue;
        counted |= 1u << k;
        if (all(equal(c >> up, xy))) mine |= 1u << k;
        total += cell_measure(top, c);
        n++;
    }
    scale = total / own;
    if (mine == 0u) return false;
    for (uint t = depth % n; t > 0u; t--) counted &= counted - 1u;  // drop the turns before this depth's
    return (mine & (1u << findLSB(counted))) != 0u;
}

// The terms a photon rarely meets (the interaction cap, a numerical dead end): an invocation adds its own to the
// account, without a work-group sum.
bool rare_term(uint k) { return k == ACC_CAP || k == ACC_LOST; }

// Whether a wave of this kind sums row k of s_acc: the terms its invocations can add to, but for the rare ones, and
// the records' rows (wave 0's rays reach a receiver only directly, a bounce wave's only after an interaction). The
// other rows are neither summed nor read: on a CPU driver each sum is a loop over the lanes.
bool wave_row(uint k) {
    if (k == ACC_CAUSTIC || k == ACC_OVERFLOW || k == ACC_ONE_EVENT || k == ACC_EYE) return false;  // the pending rows hold them
    if (rare_term(k)) return false;
    if (k == ACC_ABSORBED) return WAVE_MEDIA;
    if (k == ACC_EMITTED || k == ACC_DIRECT) return WAVE_PRIMARY;
    if (k == ACC_UNSEEN) return !WAVE_PRIMARY;
    if (k == ACC_TERMS + PEND_REC || k == ACC_TERMS + PEND_ONE || k == ACC_TERMS + PEND_EYE) return !WAVE_PRIMARY;
    return true;
}

// The work group's sum of row `row` of s_acc, over its subgroups (at most WAVE_SUBGROUPS: the loop has a constant
// bound, so the driver unrolls it and every address is the same for all invocations).
float wave_sum(uint row) {
    float s = 0.0;
    for (uint k = 0u; k < WAVE_SUBGROUPS; k++) {
        float x = s_acc[row][k];
        s += k < gl_NumSubgroups ? x : 0.0;
    }
    return s;
}

void subgroup_sum(uint row, float v) {
    float s = subgroupAdd(v);
    // Every invocation reaches the sums (none returns early), so invocation 0 of each subgroup is active: on a CPU
    // driver subgroupElect() would be a loop over the lanes.
    if (gl_SubgroupInvocationID == 0u) s_acc[row][gl_SubgroupID] = s;
}

// Add a non-negative value to a (lo, hi) fixed-point pair of the batch account.
void account_add(uint term, float v) {
    if (!(v > 0.0)) return;
    float x = v * exp2(float(ACCOUNT_SHIFT));
    uint hi = uint(x * exp2(-32.0));
    uint lo = uint(x - float(hi) * exp2(32.0));
    uint old = atomicAdd(tstate.batch_account[term].x, lo);
    uint carry = old + lo < old ? 1u : 0u;
    if (hi + carry != 0u) atomicAdd(tstate.batch_account[term].y, hi + carry);
}

// The ray invocation i traces: wave 0 makes it from its photon's cell, a bounce wave reads it from the queue.
Traced traced_ray(uint i, uint stride, uint in_count, uint capacity) {
    const bool diff = WAVE_DIFFERENTIAL;
    Traced t;
    t.diff.dpx = t.diff.dpy = t.diff.ddx = t.diff.ddy = vec3(0.0);
    t.lod = false;
    t.medium = AIR;
    t.nested = uvec2(0u);
    t.tint = vec3(1.0);
    if (WAVE_PRIMARY) {
        t.pidx = capacity - in_count + i;
        t.cell = photon_at(t.pidx);
        cell_ray(cell_level(t.cell), cell_xy(t.cell), t.ray.origin, t.ray.dir);
        if (diff) t.diff = cell_ray_diff(cell_level(t.cell), cell_xy(t.cell), t.ray.dir);
        t.ray.throughput = 1.0;
        t.ray.meta = 0u;
        t.depth = 0u;
    } else {
        t.ray = GpuRay_from_words(ray_word_in(stride * i), ray_word_in(stride * i + 1u));
        uint m = t.ray.meta;
        t.pidx = capacity - 1u - (m & ((1u << PHOTON_INDEX_BITS) - 1u));
        t.depth = (m >> PHOTON_INDEX_BITS) & 0x3Fu;
        t.lod = (m & LOD_RAY) != 0u;
        t.cell = photon_at(t.pidx);
        if (WAVE_MEDIA) {
            GpuRayMedium m = GpuRayMedium_from_words(ray_word_in(stride * i + stride - 1u));
            t.medium = m.medium;
            t.nested = m.inside;
            if (WAVE_COLOR) t.tint = tint_unpack(m.tint);
        }
    }
    t.phi = cell_measure(cell_level(t.cell), cell_xy(t.cell));
    t.side = diff ? cell_side(cell_level(t.cell)) : 1.0;
    if (diff && !WAVE_PRIMARY) t.diff = diff_unpack(ray_word_in(stride * i + 2u), t.ray.dir, t.side);
    return t;
}

// A ray of a bounce wave reaches a diffuse receiver at p along rd: its splat record in the first deposit that holds
// it (common/deposit.glsl: the light's map where its view sees p, else the eye's samples where the camera sees it),
// else no deposit of the frame can hold it (ACC_UNSEEN). (Wave 0's rays have met nothing yet.) ng: the receiver's
// geometric normal at p, for the side rd arrives on.
void record_at(Traced t, RayDiff rdf, vec3 p, vec3 ng, vec3 rd, float flux, inout Outcome o) {
    // A cluster (max-error, flux-error) takes its own cell's footprint too, clamped around the radius traversal
    // gave it (its children's spread): the parallelogram the whole cell covers where it lands, which a round splat
    // of the spread fits only where that is round.
    uint r = t.lod ? side_splat_radius(weak_widen(t.cell) * cell_side(cell_level(t.cell))) : cell_splat_radius(t.cell);
    // A sun's photon takes one direction of its disk (common/emitter.glsl): where it lands scatters by the disk's
    // image over the ray's last segment.
    float jitter = u_frame.light.beam_spread * distance(p, t.ray.origin);
    if (!deposit_landing(p, ng, rd, rdf, r, WAVE_DIFFERENTIAL, jitter, flux * u_frame.light.light_intensity, o.record)) {
        acc[ACC_UNSEEN] += flux;
        return;
    }
    o.rec_tint = WAVE_COLOR ? tint_pack(t.tint) : WAVE_SPECTRAL ? floatBitsToUint(ray_nm) : 0u;
    o.rec = true;
    o.rec_flux = flux;
    o.one_event = t.depth == 1u;
    if (o.record.shape < 0.0) o.eye = true;
}

// Whether a Fresnel branch of weight wb is traced: cut below the flux threshold, left to its block's carrier when
// it is weak (`weak`: the weak fraction) and this photon does not carry it, else kept. Both tests weigh its
// brightest channel (`bright`: that channel's weight over the mean, 1 without color), so a color photon keeps a
// branch as long as its brightest channel's own pass would; the account takes the mean weight.
bool branch_kept(float phi, float wb, float bright, float cut, float weak, bool carrier, float scale) {
    if (!(wb > 0.0)) return false;
    float wm = wb * bright;
    if (wm < cut) {
        acc[ACC_THRESHOLD] += phi * wb;
        return false;
    }
    if (wm < weak && !carrier) {
        acc[ACC_WEAK_LEFT] += phi * wb;
        return false;
    }
    if (wm < weak) acc[ACC_WEAK_CARRIED] += phi * wb * (scale - 1.0);
    return true;
}

// The brightest channel's weight over the mean (tint_unpack's ratios): 1 without color.
float brightest(Traced t) { return WAVE_COLOR ? max(t.tint.r, max(t.tint.g, t.tint.b)) : 1.0; }

// The flux threshold a child of the ray t is cut below: a carried weak branch holds its block's share, so it is cut
// where its siblings' would be.
float child_cut(Traced t) {
    float widen = weak_widen(t.cell);
    return u_frame.frame.flux_threshold * (t.lod ? widen * widen : 1.0);
}

// A child's meta word (GpuRay.meta): its photon's entry, one interaction more, and the ray's weak-branch flag.
uint child_meta(Traced t, uint capacity) {
    return (capacity - 1u - t.pidx) | ((t.depth + 1u) << PHOTON_INDEX_BITS) | (t.lod ? LOD_RAY : 0u);
}

// A volume's surface inside one of higher priority (WAVE_MEDIA): no interface, so the ray t (weight w) goes on as one
// child on the surface's other side, unbent, inside the volumes beyond it; cut below the flux threshold.
void pass_through(Traced t, RayDiff rdf, vec3 p, vec3 ng, float w, uint capacity, Crossing x, inout Outcome o) {
    if (w * brightest(t) < child_cut(t)) {
        acc[ACC_THRESHOLD] += t.phi * w;
        return;
    }
    vec3 rd = t.ray.dir;
    uint meta = child_meta(t, capacity);
    vec3 beyond = dot(rd, ng) > 0.0 ? ng : -ng;
    o.n_child = 1u;
    o.c0 = Child(GpuRay(offset_ray(p, beyond), w, rd, meta), rdf, dot(rd, ng) < 0.0, x.m_refr, x.l_refr, t.tint);
}

// The Fresnel split of the ray t (weight w) at a dielectric hit at p: its reflected and refracted children, each
// traced, cut, or left to its block's carrier (a carried one holds its block's share).
void split_at(Traced t, RayDiff rdf, SceneHit hit, vec3 p, vec3 ng, vec3 ns, float w, uint capacity,
              inout Outcome o) {
    const bool diff = WAVE_DIFFERENTIAL;
    vec3 rd = t.ray.dir;
    Crossing x = crossing_at(hit.inst, dot(rd, ng) < 0.0, t.medium, t.nested, color_channel(), WAVE_MEDIA);
    if (WAVE_MEDIA && x.through) {
        pass_through(t, rdf, p, ng, w, capacity, x, o);
        return;
    }
    Split s = split_interface(rd, p, ng, ns, x.n_in, x.n_out, inst_is_mirror(hit.inst));
    if (!s.ok) {
        acc[ACC_LOST] += t.phi * w;
        return;
    }
    float wr = w * s.F, wt = w * (1.0 - s.F);
    float widen = weak_widen(t.cell), cut = child_cut(t);
    float weak = !t.lod && weak_branches_apply(t.cell) ? u_frame.frame.weak_fraction : 0.0;
    float scale = 1.0, bright = brightest(t);
    float br = wr * bright, bt = wt * bright;
    bool carrier = (br >= cut && br < weak) || (bt >= cut && bt < weak) ? weak_carrier(t.cell, t.phi, t.depth, scale)
                                                                         : false;
    uint meta = child_meta(t, capacity);
    bool keep_r = branch_kept(t.phi, wr, bright, cut, weak, carrier, scale);
    bool keep_t = branch_kept(t.phi, wt, bright, cut, weak, carrier, scale);
    bool carried_r = br < weak, carried_t = bt < weak;
    uint m_r = carried_r ? meta | LOD_RAY : meta, m_t = carried_t ? meta | LOD_RAY : meta;
    // The reflection stays in the ray's medium; the refraction crosses the surface.
    Child r = Child(GpuRay(s.p_refl, carried_r ? wr * scale : wr, normalize(s.refl), m_r), rdf, false, t.medium,
                    t.nested, t.tint);
    Child tr = Child(GpuRay(s.p_refr, carried_t ? wt * scale : wt, normalize(s.refr), m_t), rdf, false, x.m_refr,
                     x.l_refr, t.tint);
    if (diff) {
        // Both children inherit dP; their dD follow their branch, with the interpolated normal's derivative where
        // the branch used it.
        vec3 dnx = vec3(0.0), dny = vec3(0.0);
        if (s.k_refl != 0.0 || s.k_refr != 0.0) bvh_shading_dn(hit, ns, rdf.dpx, rdf.dpy, dnx, dny);
        r.diff.ddx = diff_reflect(rd, rdf.ddx, s.n_refl, s.k_refl * dnx);
        r.diff.ddy = diff_reflect(rd, rdf.ddy, s.n_refl, s.k_refl * dny);
        if (carried_r) diff_scale(r.diff, widen);
        tr.diff.ddx = diff_refract(rd, rdf.ddx, s.n_refr, s.k_refr * dnx, tr.ray.dir, s.eta);
        tr.diff.ddy = diff_refract(rd, rdf.ddy, s.n_refr, s.k_refr * dny, tr.ray.dir, s.eta);
        if (carried_t) diff_scale(tr.diff, widen);
    }
    // ng faces out of the glass.
    r.inside = dot(r.ray.dir, ng) < 0.0;
    tr.inside = dot(tr.ray.dir, ng) < 0.0;
    o.n_child = uint(keep_r) + uint(keep_t);
    o.c0 = keep_r ? r : tr;
    o.c1 = tr;
}

// Trace the ray t: it escapes, reaches a receiver (a record in a bounce wave), meets the interaction cap, or splits
// at a dielectric; absorption in the ray's medium first takes its share of the segment.
void interact(Traced t, uint capacity, inout Outcome o) {
    const bool diff = WAVE_DIFFERENTIAL;
    vec3 ro = t.ray.origin, rd = t.ray.dir;
    float w = t.ray.throughput;
    RayDiff rdf = t.diff;
    SceneHit hit;
    if (!bvh_closest(ro, rd, 1.0 / 0.0, hit)) {
        acc[ACC_ESCAPED] += t.phi * w;
        return;
    }
    vec3 p = bvh_hit_point(hit);
    bool specular = inst_is_dielectric(hit.inst);
    // The normals, once: the interface, the differentials and a landing's side need them.
    vec3 ng = vec3(0.0), ns = vec3(0.0);
    if (specular || !WAVE_PRIMARY) bvh_normals(hit, ng, ns);
    // The differentials move to the hit, in the plane of its triangle.
    if (diff) diff_transfer(rdf, rd, dot(p - ro, rd), ng);
    if (WAVE_COLOR) {
        // Each channel keeps its own share (Beer–Lambert, exactly); the throughput becomes their mean and the tint
        // their ratios to it.
        vec3 sigma = medium_sigma_rgb(t.medium);
        if (any(greaterThan(sigma, vec3(0.0)))) {
            vec3 c = w * t.tint * exp(-sigma * distance(p, ro));
            float kept = (c.r + c.g + c.b) / 3.0;
            acc[ACC_ABSORBED] += t.phi * (w - kept);
            t.tint = kept > 0.0 ? c / kept : vec3(1.0);
            w = kept;
        }
    } else {
        float sigma = WAVE_MEDIA ? medium_sigma_in(t.medium, color_channel()) : 0.0;
        if (sigma > 0.0) {
            // The segment ran through an absorbing medium: Beer–Lambert attenuation, exactly (no sampling).
            float keep = exp(-sigma * distance(p, ro));
            acc[ACC_ABSORBED] += t.phi * w * (1.0 - keep);
            w *= keep;
        }
    }
    if (!specular) {
        if (WAVE_PRIMARY) {
            acc[ACC_DIRECT] += t.phi * w;
        } else {
            record_at(t, rdf, p, ng, rd, t.phi * w, o);
        }
    } else if (t.depth >= MAX_INTERACTIONS) {
        acc[ACC_CAP] += t.phi * w;
    } else {
        split_at(t, rdf, hit, p, ng, ns, w, capacity, o);
    }
}

// Invocation 0 reserves the work group's children in rays_out and its records in splats (NO_BASE: not reserved).
// A reservation that does not fit is undone and counted as an overflow, and aborts the batch where it may.
void reserve(uint slots, uint depth, uint queue_capacity, uint record_capacity, bool can_abort) {
    uint rays = slot_run(slots, true) + slot_run(slots, false), recs = slots >> (2u * SLOT_BITS);
    uint ray_base = NO_BASE, rec_base = NO_BASE, failed = 0u;
    if (rays > 0u) {
        uint base = atomicAdd(tstate.out_reserved, rays);
        if (base + rays <= queue_capacity) {
            ray_base = atomicAdd(tstate.out_count, rays);
        } else {
            atomicAdd(tstate.out_reserved, 0u - rays);
            failed++;
        }
    }
    if (recs > 0u) {
        // The deepest deposited path: invocation 0 holds the work group's first ray (live whenever the group has
        // records), whose depth is every ray's of the wave. One atomic per work group, not per record.
        atomicMax(tstate.max_depth, depth);
        uint base = atomicAdd(tstate.records_reserved, recs);
        if (base + recs <= record_capacity) {
            rec_base = atomicAdd(tstate.records, recs);
        } else {
            atomicAdd(tstate.records_reserved, 0u - recs);
            failed++;
        }
    }
    if (failed > 0u) {
        atomicAdd(tstate.overflows, failed);
        if (can_abort) atomicExchange(state.aborted, 1u);
    }
    s_ray_base = ray_base;
    s_rec_base = rec_base;
}

// Each subgroup's sums of the invocations' shares, written before the reservation's barrier: the work group adds
// them after it, once the verdict says whether the children and records went out or overflowed (barriers are
// costly on CPU drivers). The rare terms go to the account directly.
void sum_shares(Outcome o, float phi) {
    float pend_child = 0.0;
    if (o.n_child >= 1u) pend_child += phi * o.c0.ray.throughput;
    if (o.n_child == 2u) pend_child += phi * o.c1.ray.throughput;
    for (uint k = 0u; k < ACC_TERMS; k++) {
        if (wave_row(k)) subgroup_sum(k, acc[k]);
        if (rare_term(k)) account_add(k, acc[k]);
    }
    subgroup_sum(ACC_TERMS + PEND_CHILD, pend_child);
    if (wave_row(ACC_TERMS + PEND_REC)) {
        subgroup_sum(ACC_TERMS + PEND_REC, o.rec ? o.rec_flux : 0.0);
        subgroup_sum(ACC_TERMS + PEND_ONE, o.rec && o.one_event ? o.rec_flux : 0.0);
        subgroup_sum(ACC_TERMS + PEND_EYE, o.rec && o.eye ? o.rec_flux : 0.0);
    }
}

// The work group's shares: every invocation reads the subgroups' sums, at the same addresses and outside any branch
// (a CPU driver then loads each once for its SIMD group, where a branch or an address per invocation makes it load
// lane by lane), and invocation `lid` adds term lid in fixed point. What was not appended is overflow.
void add_shares(uint lid, bool rays_ok, bool recs_ok) {
    float child = wave_sum(ACC_TERMS + PEND_CHILD), recs = 0.0, one = 0.0, eye = 0.0;
    if (wave_row(ACC_TERMS + PEND_REC)) {
        recs = wave_sum(ACC_TERMS + PEND_REC);
        one = wave_sum(ACC_TERMS + PEND_ONE);
        eye = wave_sum(ACC_TERMS + PEND_EYE);
    }
    float mine = 0.0;
    for (uint k = 0u; k < ACC_TERMS; k++) {
        float sum = wave_row(k) ? wave_sum(k) : 0.0;
        if (k == ACC_OVERFLOW) sum += (rays_ok ? 0.0 : child) + (recs_ok ? 0.0 : recs);
        if (k == ACC_CAUSTIC) sum += recs_ok ? recs : 0.0;
        if (k == ACC_ONE_EVENT) sum += recs_ok ? one : 0.0;
        if (k == ACC_EYE) sum += recs_ok ? eye : 0.0;
        mine = lid == k ? sum : mine;
    }
    if (lid < ACC_TERMS) account_add(lid, mine);
}

void main() {
    uint lid = gl_LocalInvocationIndex;
    uint i = (gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x) * LINEAR_WG + lid;
    uint stride = (WAVE_DIFFERENTIAL ? RAY_VEC4S_DIFFERENTIAL : RAY_VEC4S_CELL) + (WAVE_MEDIA ? RAY_VEC4S_MEDIUM : 0u);
    bool can_abort = pc.may_abort != 0u;
    // The transport state's scalars, read outside any branch: there a CPU driver loads a storage buffer's word once
    // for the SIMD group, inside a branch lane by lane.
    uint in_count = tstate.in_count, capacity = state.capacity;
    uint queue_capacity = tstate.queue_capacity, record_capacity = tstate.record_capacity;
    bool aborted = state.aborted != 0u;
    if (lid == 0u) s_slots = 0u;
    for (uint k = 0u; k < ACC_TERMS; k++) acc[k] = 0.0;
    barrier();

    RayDiff none;
    none.dpx = none.dpy = none.ddx = none.ddy = vec3(0.0);
    Child no_child = Child(GpuRay(vec3(0.0), 0.0, vec3(0.0), 0u), none, false, AIR, uvec2(0u), vec3(1.0));
    Outcome o = Outcome(0u, no_child, no_child, false, GpuSplat(vec2(0.0), 0.0, 0.0), 0u, 0.0, false, false);
    float phi = 0.0, side = 1.0;
    uint depth = 0u;
    if (i < in_count && !(can_abort && aborted)) {
        Traced t = traced_ray(i, stride, in_count, capacity);
        if (WAVE_SPECTRAL) ray_nm = photon_wavelength(cell_xy(t.cell), cell_level(t.cell) | (u_frame.frame.sample_index << 5u));
        phi = t.phi;
        side = t.side;
        depth = t.depth;
        if (WAVE_PRIMARY) acc[ACC_EMITTED] = t.phi;
        interact(t, capacity, o);
    }
    // The slots, each child's within its run and the record's: child 0's first, then child 1's, then the record's.
    uint take = (o.n_child >= 1u ? (o.c0.inside ? SLOT_INSIDE : SLOT_OUTSIDE) : 0u) +
                (o.n_child == 2u ? (o.c1.inside ? SLOT_INSIDE : SLOT_OUTSIDE) : 0u) + (o.rec ? SLOT_REC : 0u);
    uint taken = take != 0u ? atomicAdd(s_slots, take) : 0u;
    uint c0_slot = slot_run(taken, o.c0.inside);
    uint c1_slot = slot_run(taken, o.c1.inside) + (o.c0.inside == o.c1.inside ? 1u : 0u);
    uint rec_slot = taken >> (2u * SLOT_BITS);
    sum_shares(o, phi);
    barrier();
    // Whatever is read from shared memory is read outside any branch, and the verdicts are the bases themselves: a
    // CPU driver runs a shared access inside a branch as a loop over the lanes, in every SIMD group of the group.
    uint slots = s_slots;
    if (lid == 0u) reserve(slots, depth, queue_capacity, record_capacity, can_abort);
    barrier();
    uint ray_base = s_ray_base, rec_base = s_rec_base;
    bool rays_ok = ray_base != NO_BASE, recs_ok = rec_base != NO_BASE;
    uint inside_n = slot_run(slots, true);
    uint k0 = ray_base + (o.c0.inside ? c0_slot : inside_n + c0_slot);
    uint k1 = ray_base + (o.c1.inside ? c1_slot : inside_n + c1_slot);
    if (rays_ok && o.n_child >= 1u) store_ray(k0, stride, o.c0, side);
    if (rays_ok && o.n_child == 2u) store_ray(k1, stride, o.c1, side);
    if (o.rec && recs_ok) splats[rec_base + rec_slot] = o.record;
    if ((WAVE_COLOR || WAVE_SPECTRAL) && o.rec && recs_ok) splat_tints[rec_base + rec_slot] = o.rec_tint;
    add_shares(lid, rays_ok, recs_ok);
    if (lid == 0u && i < in_count) atomicAdd(tstate.rays_traced, min(LINEAR_WG, in_count - i));
}
