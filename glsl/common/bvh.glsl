// Closest-hit queries against the scene's two-level BVH (src/bvh/ builds it): the instances are tested
// linearly against their world bounds, the ray is moved into each instance's BVH space, and its bottom-level tree
// is walked with a short stack. Triangles use the watertight test of Woop, Benthin and Wald (JCGT 2013), as the
// CPU reference does (there in f64): a ray cannot slip between two triangles that share an edge.
// Needs photon_bindings (bindings 14-18, 20-22). BVH_LAYOUT_SINGLE selects the one-box-per-node layout,
// BVH_LAYOUT_THREADED the stackless one with escape links, BVH_LAYOUT_WIDE the compressed 8-wide one; the default
// is the pair layout.
#ifndef BVH_GLSL
#define BVH_GLSL

// The triangles' vertices and vertex-normal rows (3 each per triangle), and the wide layout's nodes and triangle
// list, from texel buffers or storage buffers (BVH_TEXELS, common/bvh_types.glsl).
#ifdef BVH_TEXELS
vec4 bvh_tri(uint k) { return texelFetch(bvh_tri_texels, int(k)); }
vec4 bvh_normal_row(uint k) { return texelFetch(bvh_normal_texels, int(k)); }
// An instance is 12 texels, in the struct's order (the compiler drops the fetches of members a caller never reads).
GpuInstance bvh_instance(uint i) {
    int k = 12 * int(i);
    vec4 t[12];
    for (int j = 0; j < 12; j++) t[j] = texelFetch(bvh_instance_texels, k + j);
    return GpuInstance(vec4[3](t[0], t[1], t[2]), vec4[3](t[3], t[4], t[5]), t[6], t[7], t[8], t[9], t[10], t[11]);
}
uint bvh_instance_count() { return uint(textureSize(bvh_instance_texels)) / 12u; }
#else
vec4 bvh_tri(uint k) { return bvh_tris[k]; }
vec4 bvh_normal_row(uint k) { return bvh_normal_rows[k]; }
GpuInstance bvh_instance(uint i) { return bvh_instances[i]; }
uint bvh_instance_count() { return uint(bvh_instances.length()); }
#endif
#if defined(BVH_LAYOUT_WIDE)
WideNode bvh_wide_node(uint i) {
#ifdef BVH_TEXELS
    int k = 5 * int(i);
    return WideNode(texelFetch(bvh_wide_texels, k), texelFetch(bvh_wide_texels, k + 1),
                       texelFetch(bvh_wide_texels, k + 2), texelFetch(bvh_wide_texels, k + 3),
                       texelFetch(bvh_wide_texels, k + 4));
#else
    return bvh_nodes_wide[i];
#endif
}
// Texel k of the wide triangle list (entry k / 3's vertex k % 3; the first's w: the triangle's index).
uvec4 bvh_wide_prim(uint k) {
#ifdef BVH_TEXELS
    return texelFetch(bvh_wide_prim_texels, int(k));
#else
    return bvh_wide_prims[k];
#endif
}
#endif

const uint BVH_EMPTY = 0xFFFFFFFFu;
const uint BVH_STACK = 64u;

struct SceneHit {
    float t;
    uint inst;
    uint tri;
    vec3 bary;  // weights of p0, p1, p2
};

vec3 bvh_xform(vec4 r0, vec4 r1, vec4 r2, vec3 v, float w) {
    vec4 h = vec4(v, w);
    return vec3(dot(r0, h), dot(r1, h), dot(r2, h));
}

// Entry distance of the ray into [lo, hi], or +inf when it misses or enters beyond tmax.
float bvh_slab(vec3 lo, vec3 hi, vec3 o, vec3 inv_d, float tmax) {
    vec3 t0 = (lo - o) * inv_d, t1 = (hi - o) * inv_d;
    vec3 tn = min(t0, t1), tf = max(t0, t1);
    float near = max(max(tn.x, tn.y), max(tn.z, 0.0));
    float far = min(min(tf.x, tf.y), min(tf.z, tmax));
    return near <= far ? near : 1.0 / 0.0;
}

// The watertight test's per-ray shear (dimension order k, shear s).
struct Shear {
    uvec3 k;
    vec3 s;
};

Shear bvh_shear(vec3 d) {
    vec3 a = abs(d);
    uint kz = (a.x >= a.y && a.x >= a.z) ? 0u : (a.y >= a.z ? 1u : 2u);
    uint kx = (kz + 1u) % 3u, ky = (kx + 1u) % 3u;
    if (d[kz] < 0.0) { uint t = kx; kx = ky; ky = t; }
    Shear sh;
    sh.k = uvec3(kx, ky, kz);
    sh.s = vec3(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]);
    return sh;
}

// Watertight ray/triangle test of the triangle (p0, p1, p2): t and the barycentric weights of the hit, if
// 0 < t < tmax.
bool bvh_triangle_of(Shear sh, vec3 o, vec3 p0, vec3 p1, vec3 p2, float tmax, out float t, out vec3 bary) {
    vec3 a = p0 - o, b = p1 - o, c = p2 - o;
    uint kx = sh.k.x, ky = sh.k.y, kz = sh.k.z;
    float ax = a[kx] - sh.s.x * a[kz], ay = a[ky] - sh.s.y * a[kz];
    float bx = b[kx] - sh.s.x * b[kz], by = b[ky] - sh.s.y * b[kz];
    float cx = c[kx] - sh.s.x * c[kz], cy = c[ky] - sh.s.y * c[kz];
    float u = cx * by - cy * bx;
    float v = ax * cy - ay * cx;
    float w = bx * ay - by * ax;
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    float det = u + v + w;
    if (det == 0.0) return false;
    t = (u * a[kz] + v * b[kz] + w * c[kz]) * sh.s.z / det;
    bary = vec3(u, v, w) / det;
    return t > 0.0 && t < tmax;
}

bool bvh_triangle(Shear sh, vec3 o, uint tri, float tmax, out float t, out vec3 bary) {
    return bvh_triangle_of(sh, o, bvh_tri(3u * tri).xyz, bvh_tri(3u * tri + 1u).xyz, bvh_tri(3u * tri + 2u).xyz,
                           tmax, t, bary);
}

#if defined(BVH_LAYOUT_WIDE)
// The same for the wide layout's triangle-list entry starting at texel e, which holds the vertices themselves;
// tri: the triangle's index (the first texel's w).
bool bvh_wide_triangle(Shear sh, vec3 o, uint e, float tmax, out float t, out vec3 bary, out uint tri) {
    uvec4 v0 = bvh_wide_prim(e);
    tri = v0.w;
    return bvh_triangle_of(sh, o, uintBitsToFloat(v0.xyz), uintBitsToFloat(bvh_wide_prim(e + 1u).xyz),
                           uintBitsToFloat(bvh_wide_prim(e + 2u).xyz), tmax, t, bary);
}
#endif

void bvh_leaf(Shear sh, vec3 o, uint first, uint count, uint inst, inout SceneHit hit, inout bool found) {
    for (uint k = first; k < first + count; k++) {
        float t;
        vec3 bary;
        if (bvh_triangle(sh, o, k, hit.t, t, bary)) {
            hit.t = t;
            hit.inst = inst;
            hit.tri = k;
            hit.bary = bary;
            found = true;
        }
    }
}

// The walks of one instance's bottom-level tree, in its BVH space (o, d, inv = 1/d, the watertight shear sh):
// each lowers hit.t to its closest hit.

// Pair layout: both children's boxes in the parent; leaves tested as met, inner children visited nearer first.
void bvh_walk_pair(uint root, uint ii, vec3 o, vec3 inv, Shear sh, inout SceneHit hit, inout bool found) {
    uint stack[BVH_STACK];
    uint sp = 0u;
    uint node = root;
    while (true) {
        PairNode n = bvh_nodes[node];
        float t0 = bvh_slab(n.lo0.xyz, n.hi0.xyz, o, inv, hit.t);
        float t1 = bvh_slab(n.lo1.xyz, n.hi1.xyz, o, inv, hit.t);
        uint i0 = floatBitsToUint(n.lo0.w), c0 = floatBitsToUint(n.hi0.w);
        uint i1 = floatBitsToUint(n.lo1.w), c1 = floatBitsToUint(n.hi1.w);
        if (i1 == BVH_EMPTY) t1 = 1.0 / 0.0;
        if (!isinf(t0) && c0 > 0u) { bvh_leaf(sh, o, i0, c0, ii, hit, found); t0 = 1.0 / 0.0; }
        if (!isinf(t1) && c1 > 0u) { bvh_leaf(sh, o, i1, c1, ii, hit, found); t1 = 1.0 / 0.0; }
        // hit.t may have shrunk: a child entered beyond it is skipped.
        if (t0 > hit.t) t0 = 1.0 / 0.0;
        if (t1 > hit.t) t1 = 1.0 / 0.0;
        bool go0 = !isinf(t0), go1 = !isinf(t1);
        if (go0 && go1) {
            uint near = t0 <= t1 ? i0 : i1, far = t0 <= t1 ? i1 : i0;
            if (sp < BVH_STACK) stack[sp++] = far;
            node = near;
        } else if (go0) {
            node = i0;
        } else if (go1) {
            node = i1;
        } else {
            if (sp == 0u) break;
            node = stack[--sp];
        }
    }
}

#if defined(BVH_LAYOUT_THREADED)
// Threaded layout, stackless: a hit inner node continues at its first child (the next node), a miss or a
// finished leaf at its escape link.
void bvh_walk_threaded(uint root, uint ii, vec3 o, vec3 inv, Shear sh, inout SceneHit hit, inout bool found) {
    uint n = root;
    while (n != BVH_EMPTY) {
        SingleNode nd = bvh_nodes_threaded[n];
        uint escape = floatBitsToUint(nd.lo.w);
        if (!isinf(bvh_slab(nd.lo.xyz, nd.hi.xyz, o, inv, hit.t))) {
            uint info = floatBitsToUint(nd.hi.w);
            uint count = info >> 29;
            if (count > 0u) {
                bvh_leaf(sh, o, info & 0x1FFFFFFFu, count, ii, hit, found);
                n = escape;
            } else {
                n = n + 1u;
            }
        } else {
            n = escape;
        }
    }
}
#endif

#if defined(BVH_LAYOUT_SINGLE)
// Single layout: one box per node, children adjacent; the nearer child is pushed last, so it is visited first
// and shrinks hit.t for the other.
void bvh_walk_single(uint root, uint ii, vec3 o, vec3 inv, Shear sh, inout SceneHit hit, inout bool found) {
    uint stack[BVH_STACK];
    uint sp = 0u;
    stack[sp++] = root;
    while (sp > 0u) {
        SingleNode n = bvh_nodes_single[stack[--sp]];
        if (isinf(bvh_slab(n.lo.xyz, n.hi.xyz, o, inv, hit.t))) continue;
        uint first = floatBitsToUint(n.lo.w), count = floatBitsToUint(n.hi.w);
        if (count > 0u) {
            bvh_leaf(sh, o, first, count, ii, hit, found);
        } else if (sp + 2u <= BVH_STACK) {
            SingleNode c0 = bvh_nodes_single[first], c1 = bvh_nodes_single[first + 1u];
            float t0 = bvh_slab(c0.lo.xyz, c0.hi.xyz, o, inv, hit.t);
            float t1 = bvh_slab(c1.lo.xyz, c1.hi.xyz, o, inv, hit.t);
            if (t0 <= t1) {
                if (!isinf(t1)) stack[sp++] = first + 1u;
                if (!isinf(t0)) stack[sp++] = first;
            } else {
                if (!isinf(t0)) stack[sp++] = first;
                stack[sp++] = first + 1u;
            }
        }
    }
}
#endif

#if defined(BVH_LAYOUT_WIDE)
const uint BVH_WIDE_STACK = 32u;

// The children of wide node n that the ray enters before tmax, as the hit mask of Ylitie, Karras and Laine
// (2017): an inner child sets bit 24 + (slot ^ oct) (so the highest set bit is the child nearest in the ray's
// octant order), a leaf its triangles' bits (offsets from the node's first triangle-list entry) in the low 24.
// inv is the ray's inverse direction kept finite, oct the octant code (0-7, one bit set per positive axis).
uint bvh_wide_hits(WideNode n, vec3 o, vec3 inv, uint oct, float tmax) {
    vec3 e = uintBitsToFloat((uvec3(n.w0.w, n.w0.w >> 8, n.w0.w >> 16) & 0xFFu) << 23);
    // A plane q of a child sits at p + e q, the ray there at t = q s + b.
    vec3 s = e * inv, b = (uintBitsToFloat(n.w0.xyz) - o) * inv;
    // The near planes: the low ones along an axis the ray goes up, the high ones where it goes down.
    bvec3 down = lessThan(inv, vec3(0.0));
    uvec2 nx = down.x ? n.w2.zw : n.w2.xy, fx = down.x ? n.w2.xy : n.w2.zw;
    uvec2 ny = down.y ? n.w3.zw : n.w3.xy, fy = down.y ? n.w3.xy : n.w3.zw;
    uvec2 nz = down.z ? n.w4.zw : n.w4.xy, fz = down.z ? n.w4.xy : n.w4.zw;
    uint hits = 0u;
    for (uint c = 0u; c < 8u; c++) {
        uint word = c >> 2, shift = 8u * (c & 3u);
        uint meta = (n.w1[2u + word] >> shift) & 0xFFu;
        if (meta == 0u) continue;
        vec3 qn = vec3((uvec3(nx[word], ny[word], nz[word]) >> shift) & 0xFFu);
        vec3 qf = vec3((uvec3(fx[word], fy[word], fz[word]) >> shift) & 0xFFu);
        vec3 tn = qn * s + b, tf = qf * s + b;
        float near = max(max(tn.x, tn.y), max(tn.z, 0.0));
        float far = min(min(tf.x, tf.y), min(tf.z, tmax));
        if (near <= far) {
            // An inner child's meta is 0b001_11sss (24 + its slot): bits 3 and 4 are both set only there.
            bool inner = (meta & (meta << 1) & 0x10u) != 0u;
            uint index = inner ? ((meta ^ oct) & 0x1Fu) : (meta & 0x1Fu);
            hits |= ((meta >> 5) & 7u) << index;
        }
    }
    return hits;
}

// Wide layout: a stack of node groups (the first inner child of a node, and the mask of its children still to
// visit in the high byte with the inner-child mask in the low byte); the nearest child in octant order first, and
// a node's leaf triangles tested before its inner children are entered.
void bvh_walk_wide(uint root, uint ii, vec3 o, vec3 d, Shear sh, inout SceneHit hit, inout bool found) {
    // A zero component becomes a tiny one of its sign (-0 counts as positive, as the octant does).
    vec3 tiny = mix(vec3(1e-30), vec3(-1e-30), lessThan(d, vec3(0.0)));
    vec3 inv = 1.0 / mix(d, tiny, lessThanEqual(abs(d), vec3(1e-30)));
    uint oct = (inv.x < 0.0 ? 0u : 4u) | (inv.y < 0.0 ? 0u : 2u) | (inv.z < 0.0 ? 0u : 1u);
    uvec2 stack[BVH_WIDE_STACK];
    uint sp = 0u;
    // The root as the only inner child of a virtual parent.
    uvec2 group = uvec2(root, 0x80000000u);
    uvec2 tris = uvec2(0u);
    // The nearest hit's triangle-list texel: the loop keeps only its distance and where it is, and its weights and
    // index are read once the walk ends (a CPU driver would otherwise blend every field of the hit into place
    // under a mask, and spill them around each texel fetch, at every triangle of every lane).
    uint best = BVH_EMPTY;
    while (true) {
        while (tris.y != 0u) {
            uint k = uint(findMSB(tris.y));
            tris.y &= ~(1u << k);
            // The entry holds the triangle's vertices, so the test reads no index first.
            uint e = 3u * (tris.x + k);
            float t;
            vec3 bary;
            uint tri;
            if (bvh_wide_triangle(sh, o, e, hit.t, t, bary, tri)) {
                hit.t = t;
                best = e;
            }
        }
        if ((group.y & 0xFF000000u) != 0u) {
            uint mask = group.y;
            uint bit = uint(findMSB(mask));
            group.y &= ~(1u << bit);
            if ((group.y & 0xFF000000u) != 0u && sp < BVH_WIDE_STACK) stack[sp++] = group;
            // The child's slot, and its rank among the node's inner children (which are stored in slot order).
            uint slot = (bit - 24u) ^ oct;
            uint child = group.x + bitCount(mask & ~(0xFFFFFFFFu << slot));
            WideNode n = bvh_wide_node(child);
            uint hits = bvh_wide_hits(n, o, inv, oct, hit.t);
            group = uvec2(n.w1.x, (hits & 0xFF000000u) | (n.w0.w >> 24));
            tris = uvec2(n.w1.y, hits & 0x00FFFFFFu);
        } else {
            group = uvec2(0u);
        }
        if (tris.y == 0u && (group.y & 0xFF000000u) == 0u) {
            if (sp == 0u) break;
            group = stack[--sp];
        }
    }
    if (best != BVH_EMPTY) {
        // The same test of the same triangle gives the same weights (bounded by +inf: hit.t is its own t now).
        float t;
        vec3 bary = vec3(1.0 / 3.0), b;
        if (bvh_wide_triangle(sh, o, best, 1.0 / 0.0, t, b, hit.tri)) bary = b;
        hit.inst = ii;
        hit.bary = bary;
        found = true;
    }
}
#endif

// Closest hit along ro + t*rd (0 < t < tmax) over every instance.
bool bvh_closest(vec3 ro, vec3 rd, float tmax, out SceneHit hit) {
    hit.t = tmax;
    hit.inst = 0u;
    hit.tri = 0u;
    hit.bary = vec3(0.0);
    bool found = false;
    vec3 inv_wd = 1.0 / rd;
    for (uint ii = 0u; ii < bvh_instance_count(); ii++) {
        GpuInstance I = bvh_instance(ii);
        if (isinf(bvh_slab(I.lo.xyz, I.hi.xyz, ro, inv_wd, hit.t))) continue;
        vec3 o = bvh_xform(I.object_from_world[0], I.object_from_world[1], I.object_from_world[2], ro, 1.0);
        vec3 d = bvh_xform(I.object_from_world[0], I.object_from_world[1], I.object_from_world[2], rd, 0.0);
        Shear sh = bvh_shear(d);
#if defined(BVH_LAYOUT_THREADED)
        bvh_walk_threaded(floatBitsToUint(I.pad.x), ii, o, 1.0 / d, sh, hit, found);
#elif defined(BVH_LAYOUT_SINGLE)
        bvh_walk_single(floatBitsToUint(I.hi.w), ii, o, 1.0 / d, sh, hit, found);
#elif defined(BVH_LAYOUT_WIDE)
        bvh_walk_wide(floatBitsToUint(I.ior_rgb.w), ii, o, d, sh, hit, found);
#else
        bvh_walk_pair(floatBitsToUint(I.lo.w), ii, o, 1.0 / d, sh, hit, found);
#endif
    }
    return found;
}

// World-space geometric normal (unit; counter-clockwise winding faces it) and interpolated shading normal (unit,
// falling back to the geometric one where the interpolation degenerates), as src/reference/geometry.rs computes.
void bvh_normals(SceneHit hit, out vec3 ng, out vec3 ns) {
    GpuInstance I = bvh_instance(hit.inst);
    vec3 p0 = bvh_tri(3u * hit.tri).xyz, p1 = bvh_tri(3u * hit.tri + 1u).xyz, p2 = bvh_tri(3u * hit.tri + 2u).xyz;
    vec3 n = bvh_normal_row(3u * hit.tri).xyz * hit.bary.x + bvh_normal_row(3u * hit.tri + 1u).xyz * hit.bary.y
        + bvh_normal_row(3u * hit.tri + 2u).xyz * hit.bary.z;
    // Normals transform with the inverse transpose: the transpose of object_from_world's 3x3 part (whose rows are
    // the columns GLSL's mat3 constructor takes).
    mat3 m = mat3(I.object_from_world[0].xyz, I.object_from_world[1].xyz, I.object_from_world[2].xyz);
    ng = normalize(m * cross(p1 - p0, p2 - p0));
    float len = length(n);
    ns = len > 0.0 && !isnan(len) && !isinf(len) ? normalize(m * n) : ng;
}

// Derivatives of the world-space shading normal `ns` (as bvh_normals computes it) along two world offsets dpx, dpy in
// the triangle's plane (ray differentials): the barycentric gradients of the world-space triangle (b1 = dp.(e2 x n)/|n|^2,
// b2 = dp.(n x e1)/|n|^2 with n = e1 x e2), the vertex normals' differences through the normal matrix, and the
// derivative of the normalization, (dm - ns (ns.dm)) / |m|.
void bvh_shading_dn(SceneHit hit, vec3 ns, vec3 dpx, vec3 dpy, out vec3 dnx, out vec3 dny) {
    dnx = dny = vec3(0.0);
    GpuInstance I = bvh_instance(hit.inst);
    vec3 q0 = bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2],
                        bvh_tri(3u * hit.tri).xyz, 1.0);
    vec3 q1 = bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2],
                        bvh_tri(3u * hit.tri + 1u).xyz, 1.0);
    vec3 q2 = bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2],
                        bvh_tri(3u * hit.tri + 2u).xyz, 1.0);
    vec3 e1 = q1 - q0, e2 = q2 - q0, n = cross(e1, e2);
    float nn = dot(n, n);
    if (!(nn > 0.0)) return;
    vec3 g1 = cross(e2, n) / nn, g2 = cross(n, e1) / nn;
    vec3 n0 = bvh_normal_row(3u * hit.tri).xyz, n1 = bvh_normal_row(3u * hit.tri + 1u).xyz;
    vec3 n2 = bvh_normal_row(3u * hit.tri + 2u).xyz;
    mat3 m = mat3(I.object_from_world[0].xyz, I.object_from_world[1].xyz, I.object_from_world[2].xyz);
    float len = length(m * (n0 * hit.bary.x + n1 * hit.bary.y + n2 * hit.bary.z));
    if (!(len > 0.0) || isinf(len)) return;
    vec3 d1 = m * (n1 - n0), d2 = m * (n2 - n0);
    vec3 dm = d1 * dot(dpx, g1) + d2 * dot(dpx, g2);
    dnx = (dm - ns * dot(ns, dm)) / len;
    dm = d1 * dot(dpy, g1) + d2 * dot(dpy, g2);
    dny = (dm - ns * dot(ns, dm)) / len;
    if (any(isnan(dnx)) || any(isinf(dnx))) dnx = vec3(0.0);
    if (any(isnan(dny)) || any(isinf(dny))) dny = vec3(0.0);
}

// World-space hit point from the barycentric weights (more precise than ro + t*rd far from the origin).
vec3 bvh_hit_point(SceneHit hit) {
    GpuInstance I = bvh_instance(hit.inst);
    vec3 p = bvh_tri(3u * hit.tri).xyz * hit.bary.x + bvh_tri(3u * hit.tri + 1u).xyz * hit.bary.y
        + bvh_tri(3u * hit.tri + 2u).xyz * hit.bary.z;
    return bvh_xform(I.world_from_object[0], I.world_from_object[1], I.world_from_object[2], p, 1.0);
}

#endif
