//! Building the scene's BVH: one bottom-level tree per distinct mesh (obvhs' PLOC builder), flattened into the
//! layouts, and one instance per object.

use super::*;

impl SceneBvh {
    /// [`SceneBvh::build_cached`] without a cache: every mesh's tree is built.
    #[cfg(test)]
    pub fn build(meshes: &[&Mesh], objects: &[BvhObject], deforming: &[Option<(Vec3, Vec3)>]) -> SceneBvh {
        Self::build_with(meshes, objects, deforming, &mut |_, tris| Cow::Owned(build_tree(tris)))
    }

    /// One bottom-level BVH per distinct mesh the objects instance (in its object space), and one instance per
    /// object with its transform and material. [`SceneBvh::set_transform`] moves an object without a rebuild. A
    /// mesh with `deforming[m]` bounds (the box it stays in, in object space, whatever its vertices do) is built at
    /// rest with the data the GPU refit needs, and its instances carry those bounds. Each mesh's tree comes from
    /// `cache` when it holds one; the trees built are kept there, and `blas_builds` counts only those.
    pub fn build_cached(
        meshes: &[Arc<Mesh>],
        objects: &[BvhObject],
        deforming: &[Option<(Vec3, Vec3)>],
        cache: &mut BlasCache,
    ) -> SceneBvh {
        let start = Instant::now();
        let refs: Vec<&Mesh> = meshes.iter().map(|m| &**m).collect();
        let mut built = 0;
        for (m, mesh) in meshes.iter().enumerate() {
            // Only the instanced meshes with triangles are built; the rest are never asked for.
            if objects.iter().any(|o| o.mesh == m) && !cache.trees.contains_key(&BlasCache::key(mesh)) {
                let (tris, _) = valid_triangles(mesh);
                if !tris.is_empty() {
                    cache.trees.insert(BlasCache::key(mesh), (mesh.clone(), build_tree(&tris)));
                    built += 1;
                }
            }
        }
        let trees = &cache.trees;
        let mut bvh = Self::build_with(&refs, objects, deforming, &mut |m, _| {
            Cow::Borrowed(&trees[&BlasCache::key(&meshes[m])].1)
        });
        bvh.blas_builds = built;
        bvh.build_ms = start.elapsed().as_secs_f64() * 1e3;
        bvh
    }

    pub(super) fn build_with<'t>(
        meshes: &[&Mesh],
        objects: &[BvhObject],
        deforming: &[Option<(Vec3, Vec3)>],
        tree: &mut TreeFor<'_, 't>,
    ) -> SceneBvh {
        let start = Instant::now();
        let mut bvh = SceneBvh { refit_meshes: vec![None; meshes.len()], ..SceneBvh::default() };
        // Per mesh, once built: its roots and object-space bounds, or None when it has no valid triangle.
        let mut blas: Vec<Option<Option<Blas>>> = vec![None; meshes.len()];
        for obj in objects {
            let built = *blas[obj.mesh].get_or_insert_with(|| {
                let (tris, nrms, corners) = valid_triangles_with_corners(meshes[obj.mesh]);
                if tris.is_empty() {
                    return None;
                }
                let threaded_root = bvh.threaded_nodes.len() as u32;
                let deform = deforming.get(obj.mesh).copied().flatten();
                let b2 = tree(obj.mesh, &tris);
                let (pair_root, single_root, wide_root) =
                    bvh.add_blas(&tris, &nrms, deform.is_some().then_some((obj.mesh, &corners[..])), &b2);
                bvh.blas_builds += 1;
                let (lo, hi) = deform.unwrap_or_else(|| {
                    tris.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
                        (a.min(p.truncate()), b.max(p.truncate()))
                    })
                });
                Some(Blas { roots: [pair_root, single_root, threaded_root, wide_root], lo, hi })
            });
            // An object with no triangle has no instance.
            let Some(b) = built else {
                bvh.object_instance.push(None);
                continue;
            };
            let (material, albedo, mut ior_rgb, sigma_rgb) = material_words(obj.material);
            ior_rgb[3] = f32::from_bits(b.roots[3]);
            bvh.instances.push(GpuInstance {
                lo: [0.0, 0.0, 0.0, f32::from_bits(b.roots[0])],
                hi: [0.0, 0.0, 0.0, f32::from_bits(b.roots[1])],
                material,
                pad: [f32::from_bits(b.roots[2]), albedo[0], albedo[1], albedo[2]],
                ior_rgb,
                sigma_rgb,
                ..GpuInstance::default()
            });
            bvh.local_bounds.push((b.lo, b.hi));
            bvh.object_instance.push(Some(bvh.instances.len() - 1));
            bvh.set_transform(bvh.object_instance.len() - 1, obj.transform);
        }
        bvh.build_ms = start.elapsed().as_secs_f64() * 1e3;
        bvh
    }

    /// Add one bottom-level BVH over `tris` from its tree `b2` (all four layouts, and the triangles in leaf
    /// order); with `refit` (the mesh's index), also its refit nodes, its wide nodes by height, and its rest
    /// triangles. Returns the pair, single and wide roots.
    /// `refit`: a deforming mesh's index, with each triangle's vertex indices.
    pub(super) fn add_blas(
        &mut self,
        tris: &[[Vec4; 3]],
        nrms: &[[Vec4; 3]],
        refit: Option<(usize, &[[u32; 3]])>,
        b2: &Bvh2,
    ) -> (u32, u32, u32) {
        // No spatial splits: the primitive list is a permutation, so leaves index the reordered triangles directly.
        let tri_base = self.triangles.len() as u32;
        for &i in &b2.primitive_indices {
            let (t, n) = (&tris[i as usize], &nrms[i as usize]);
            self.triangles.push(GpuTriangle { p: t.map(|p| p.to_array()) });
            self.normals.push(GpuTriangle { p: n.map(|p| p.to_array()) });
        }
        let nodes = &b2.nodes;
        let aabb = |k: usize| {
            let a = &nodes[k].aabb;
            (Vec3::from(a.min), Vec3::from(a.max))
        };
        let b4 = |v: Vec3, w: u32| [v.x, v.y, v.z, f32::from_bits(w)];

        let wide_first = self.wide_nodes.len() as u32;
        let wide_root = self.add_wide(tris, b2, tri_base);

        // Single layout: copy obvhs' nodes (children already adjacent), in the same order.
        let single_base = self.single_nodes.len() as u32;
        for (k, n) in nodes.iter().enumerate() {
            let (lo, hi) = aabb(k);
            let (first, count) = if n.prim_count == 0 {
                (single_base + n.first_index, 0)
            } else {
                (tri_base + n.first_index, n.prim_count)
            };
            self.single_nodes.push(SingleNode { lo: b4(lo, first), hi: b4(hi, count) });
        }

        // Threaded layout: depth-first order, escape = the node after the subtree.
        let threaded_base = self.threaded_nodes.len() as u32;
        let (order, pos, size) = depth_first(nodes);
        for &k in &order {
            let n = &nodes[k];
            let (lo, hi) = aabb(k);
            let next = pos[k] + size[k];
            let escape = if next as usize >= order.len() { EMPTY } else { threaded_base + next };
            let info = if n.prim_count == 0 { 0 } else { (n.prim_count << 29) | (tri_base + n.first_index) };
            self.threaded_nodes.push(ThreadedNode { lo: b4(lo, escape), hi: b4(hi, info) });
        }

        // Pair layout: inner nodes only, depth first (the nearer-first traversal then walks mostly forward).
        let pair_base = self.pair_nodes.len() as u32;
        // Where each node's box sits in the pair layout: its parent's slot (node << 1 | slot).
        let mut pair_slot = vec![EMPTY; nodes.len()];
        if let Some((mesh, corners)) = refit {
            self.add_refit(mesh, b2, tri_base, single_base, threaded_base, &pos);
            self.add_wide_refit(mesh, wide_first);
            self.rest_corners.extend(b2.primitive_indices.iter().map(|&i| corners[i as usize]));
        }
        let child = |k: usize| -> ([f32; 4], [f32; 4], Option<usize>) {
            let n = &nodes[k];
            let (lo, hi) = aabb(k);
            if n.prim_count == 0 {
                (b4(lo, 0), b4(hi, 0), Some(k))
            } else {
                (b4(lo, tri_base + n.first_index), b4(hi, n.prim_count), None)
            }
        };
        if nodes[0].prim_count > 0 {
            // The root is a leaf: one node with that leaf and an empty slot whose box nothing enters.
            let (lo0, hi0, _) = child(0);
            let empty_lo = [f32::INFINITY, f32::INFINITY, f32::INFINITY, f32::from_bits(EMPTY)];
            let empty_hi = [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, f32::from_bits(0)];
            self.pair_nodes.push(PairNode { lo0, hi0, lo1: empty_lo, hi1: empty_hi });
            pair_slot[0] = pair_base << 1;
            self.set_pair_slots(refit.map(|(m, _)| m), &pair_slot);
            return (pair_base, single_base, wide_root);
        }
        let mut stack = vec![(0usize, None::<(usize, usize)>)];
        while let Some((k, parent)) = stack.pop() {
            let me = self.pair_nodes.len();
            if let Some((p, slot)) = parent {
                let node = &mut self.pair_nodes[p];
                let w = f32::from_bits(me as u32);
                if slot == 0 {
                    node.lo0[3] = w;
                } else {
                    node.lo1[3] = w;
                }
            }
            let f = nodes[k].first_index as usize;
            let (lo0, hi0, in0) = child(f);
            let (lo1, hi1, in1) = child(f + 1);
            self.pair_nodes.push(PairNode { lo0, hi0, lo1, hi1 });
            pair_slot[f] = (me as u32) << 1;
            pair_slot[f + 1] = (me as u32) << 1 | 1;
            if let Some(c) = in1 {
                stack.push((c, Some((me, 1))));
            }
            if let Some(c) = in0 {
                stack.push((c, Some((me, 0))));
            }
        }
        self.set_pair_slots(refit.map(|(m, _)| m), &pair_slot);
        (pair_base, single_base, wide_root)
    }
}

/// The nodes of `nodes` in depth-first order (left child first), each node's position in that order, and the size
/// of its subtree (itself included): the threaded layout's order and escape links.
fn depth_first(nodes: &[obvhs::bvh2::node::Bvh2Node]) -> (Vec<usize>, Vec<u32>, Vec<u32>) {
    let mut order = Vec::new();
    let mut st = vec![0usize];
    while let Some(k) = st.pop() {
        order.push(k);
        if nodes[k].prim_count == 0 {
            st.push(nodes[k].first_index as usize + 1);
            st.push(nodes[k].first_index as usize);
        }
    }
    let mut pos = vec![0u32; nodes.len()];
    for (i, &k) in order.iter().enumerate() {
        pos[k] = i as u32;
    }
    let mut size = vec![1u32; nodes.len()];
    for &k in order.iter().rev() {
        if nodes[k].prim_count == 0 {
            let f = nodes[k].first_index as usize;
            size[k] = 1 + size[f] + size[f + 1];
        }
    }
    (order, pos, size)
}

/// Triangles whose nodes all get reinserted; a bigger mesh reinserts this many of its nodes' worth (at least
/// [`MIN_REINSERTION`] of them), so that its build stays a second or so.
pub const REINSERTED_TRIANGLES: usize = 100_000;

/// The smallest share of a big mesh's nodes reinserted (obvhs' own medium build's).
pub const MIN_REINSERTION: f32 = 0.05;

/// A mesh's tree over its valid triangles. obvhs' medium build (PLOC, in parallel) with reinsertion over every node,
/// before and after the collapse to leaves: a tree 1–16% cheaper by the surface-area heuristic (the bunny 6.5%),
/// whose frames trace 5–16% faster on lavapipe (docs/experiments.md, "BVH build quality"), for a build 4–7× longer
/// (the bunny's 3,674 triangles: 6 ms instead of 1.3 ms). Over [`REINSERTED_TRIANGLES`] the share reinserted falls
/// with the size: a million-triangle sphere builds in 1.1 s instead of 3.2 s, its frames 1–6% slower.
pub(super) fn build_tree(tris: &[[Vec4; 3]]) -> Bvh2 {
    let boxes: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: Vec3A::from(t[0].truncate()),
            v1: Vec3A::from(t[1].truncate()),
            v2: Vec3A::from(t[2].truncate()),
        })
        .collect();
    let params = BvhBuildParams {
        max_prims_per_leaf: MAX_LEAF_TRIS,
        reinsertion_batch_ratio: (REINSERTED_TRIANGLES as f32 / tris.len().max(1) as f32).clamp(MIN_REINSERTION, 1.0),
        post_collapse_reinsertion_batch_ratio_multiplier: 1.0,
        ..BvhBuildParams::medium_build()
    };
    obvhs::bvh2::builder::build_bvh2_from_tris(&boxes, params, &mut std::time::Duration::default())
}

/// A mesh's triangles with a nonzero, finite area and their vertex normals (degenerate ones are dropped, as in the
/// CPU reference).
/// With the texture coordinates packed in `w`: corner positions carry u, their normals v (see [`GpuTriangle`]).
pub(super) fn valid_triangles(m: &Mesh) -> (Vec<[Vec4; 3]>, Vec<[Vec4; 3]>) {
    let (tris, nrms, _) = valid_triangles_with_corners(m);
    (tris, nrms)
}

/// [`valid_triangles`] with each kept triangle's vertex indices (what a deforming mesh's refit reads its morphed
/// vertices by).
pub(super) fn valid_triangles_with_corners(m: &Mesh) -> (Vec<Corners>, Vec<Corners>, Vec<[u32; 3]>) {
    let mut tris = Vec::new();
    let mut nrms = Vec::new();
    let mut corners = Vec::new();
    for t in m.indices.chunks_exact(3) {
        let p = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
        let ng = (p[1] - p[0]).cross(p[2] - p[0]);
        if !(ng.length() > 0.0 && ng.is_finite()) {
            continue;
        }
        let uv = [0, 1, 2].map(|k| m.uvs.get(t[k] as usize).copied().unwrap_or(glam::Vec2::ZERO));
        let n = [0, 1, 2].map(|k| m.normals.get(t[k] as usize).copied().unwrap_or(Vec3::ZERO).extend(uv[k].y));
        tris.push([0, 1, 2].map(|k| p[k].extend(uv[k].x)));
        nrms.push(n);
        corners.push([t[0], t[1], t[2]]);
    }
    (tris, nrms, corners)
}

/// An instance's material words (`BvhInstance.material`, `.pad.yzw`, `.ior_rgb`, `.sigma_rgb`).
pub(super) fn material_words(m: &Material) -> ([f32; 4], [f32; 3], [f32; 4], [f32; 4]) {
    let (ior_rgb, sigma_rgb) = match *m {
        Material::Dielectric { absorption, .. } => {
            let n = m.ior_rgb();
            ([n[0], n[1], n[2], 0.0], [absorption.x, absorption.y, absorption.z, 0.0])
        }
        _ => ([0.0; 4], [0.0; 4]),
    };
    let material = match *m {
        // The gray pass: the d-line IOR and the channels' mean absorption.
        Material::Dielectric { ior, absorption, .. } => {
            [ior, 1.0, (absorption.x + absorption.y + absorption.z) / 3.0, 0.0]
        }
        Material::Mirror => [0.0, 2.0, 0.0, 0.0],
        // w: the albedo texture's layer + 1 (0: none).
        Material::Diffuse { albedo, map } => {
            [albedo.max_element(), 0.0, 0.0, map.map_or(0.0, |m| m.texture as f32 + 1.0)]
        }
    };
    // A dielectric's absorption as a spectrum, for photons that carry a wavelength: its upsampled coefficients.
    let albedo = match *m {
        Material::Diffuse { albedo, .. } => albedo.to_array(),
        Material::Dielectric { absorption, .. } => {
            crate::spectrum::RgbSpectrum::fit_f32(absorption.to_array()).coeffs_f32()
        }
        _ => [0.0; 3],
    };
    // A textured receiver's uv transform rows, in the words a dielectric's IORs and absorption take.
    let (ior_rgb, sigma_rgb) = match *m {
        Material::Diffuse { map: Some(map), .. } => {
            let [a, b] = map.uv_transform;
            ([a[0], a[1], a[2], 0.0], [b[0], b[1], b[2], 0.0])
        }
        _ => (ior_rgb, sigma_rgb),
    };
    (material, albedo, ior_rgb, sigma_rgb)
}

pub(super) fn row(m: &Mat4, r: usize) -> [f32; 4] {
    m.row(r).to_array()
}
