//! The scene's triangles as a two-level BVH for exact photon transport on the GPU (glsl/common/bvh.glsl).
//!
//! Each scene object is one instance: a bottom-level BVH over its mesh's triangles in object space (one per
//! distinct mesh, built on the host with obvhs' PLOC builder, then flattened) and an affine transform from world
//! space into the mesh's space. Moving a rigid object only rewrites its instance (the frame's scene update writes
//! it on the GPU); a bottom-level BVH is built only when a mesh is new. The few instances of a scene are tested
//! linearly against their world-space bounds, so there is no top-level tree to rebuild.
//!
//! Node layout ("pair", after Aila and Laine 2009): an inner node holds both children's boxes, so one node fetch
//! tests two boxes and the traversal descends into the nearer child. A child is either another inner node or a
//! leaf of up to [`MAX_LEAF_TRIS`] consecutive triangles. Two other layouts are built beside it: "single", one box
//! per node as obvhs keeps it, and "threaded", one box per node in depth-first order with escape links for a
//! stackless walk. A fourth, "wide", collapses the tree into compressed 8-wide nodes (Ylitie, Karras and Laine
//! 2017): one 80-byte node holds eight children's boxes quantized to a byte per plane, and the walk visits the
//! children nearest first in the ray's octant order. The layouts are uploaded as frames need them;
//! `--bvh-layout` picks the one the waves trace (`auto`: single on GPUs, wide on CPU devices, the faster on each
//! in docs/experiments.md, "BVH layouts"). The eye view's glass pass and exact transport's traversal checks walk
//! the wide layout where the waves do and the pair layout otherwise; the wide layout's shaders read the BVH
//! through texel views of its buffers (docs/design.md, "4. Transport").
//! A deforming mesh's layouts are refit on the GPU every frame it deforms: the binary ones' boxes bottom-up, then
//! its wide nodes requantized over the new boxes and its wide triangle list rewritten (glsl/refit_wide.comp).
//!
//! Triangles are stored in leaf order with their positions (the watertight test reads only these) and, separately,
//! their per-vertex normals (read once per closest hit). Degenerate triangles are dropped, as in the CPU reference.

use crate::scene::{Material, Mesh};
use glam::{Mat4, Vec3, Vec3A, Vec4};
use obvhs::bvh2::Bvh2;
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::borrow::Cow;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::Instant;

mod build;
mod records;
mod refit;
#[cfg(test)]
mod walk;
mod wide;

pub use crate::settings::BvhLayout;
use build::row;
pub use records::*;

/// Leaves hold at most this many triangles (obvhs collapses small subtrees into leaves up to this size).
pub const MAX_LEAF_TRIS: u32 = 4;

/// A child slot that holds nothing (a BVH whose root is a leaf has one).
const EMPTY: u32 = u32::MAX;

/// A deforming mesh's part of the refit arrays and of the triangles.
#[derive(Clone, Copy, Debug, Default)]
pub struct RefitMesh {
    /// Its nodes by height: `refit_levels[first_level..first_level + levels]`, each a run of `refit_order`.
    pub first_level: u32,
    pub levels: u32,
    /// Its wide nodes by height: `wide_refit_levels[wide_first_level..wide_first_level + wide_levels]`.
    pub wide_first_level: u32,
    pub wide_levels: u32,
    /// Its first node in the refit arrays.
    pub first_node: u32,
    /// Its triangles in the BVH's triangles (leaf order) and, at rest, in `rest_tris`.
    pub first_tri: u32,
    pub rest_first: u32,
    pub tri_count: u32,
}

/// The host side of the scene BVH: everything the GPU buffers hold, plus build statistics.
#[derive(Clone, Debug, Default)]
pub struct SceneBvh {
    pub pair_nodes: Vec<PairNode>,
    pub single_nodes: Vec<SingleNode>,
    pub threaded_nodes: Vec<ThreadedNode>,
    pub wide_nodes: Vec<WideNode>,
    /// The wide layout's triangle list: each entry the index of a triangle in `triangles` (the wide nodes' leaves
    /// are runs of this list, in an order of their own).
    pub wide_prims: Vec<u32>,
    /// One per scene object with triangles, in order.
    pub instances: Vec<GpuInstance>,
    /// Per scene object: its instance (None: it has no triangle).
    object_instance: Vec<Option<usize>>,
    pub triangles: Vec<GpuTriangle>,
    /// Per-vertex normals of each triangle (same order as `triangles`).
    pub normals: Vec<GpuTriangle>,
    /// Each instance's bounds in its BVH space.
    local_bounds: Vec<(Vec3, Vec3)>,
    /// Bottom-level BVHs built (one per distinct mesh).
    pub blas_builds: usize,
    /// The deforming meshes' trees, for the GPU refit: nodes, their indices by height (each height a run, `[first,
    /// count]` in `refit_levels`), and their triangles at rest (positions and vertex normals, in leaf order).
    pub refit_nodes: Vec<RefitNode>,
    pub refit_order: Vec<u32>,
    pub refit_levels: Vec<[u32; 2]>,
    /// The deforming meshes' wide nodes by height, as `refit_order` and `refit_levels` hold their binary nodes.
    pub wide_refit_order: Vec<u32>,
    pub wide_refit_levels: Vec<[u32; 2]>,
    pub rest_tris: Vec<GpuTriangle>,
    pub rest_normals: Vec<GpuTriangle>,
    /// Per rest triangle: the indices of its vertices in its mesh (a morphing mesh's triangles are read by them).
    pub rest_corners: Vec<[u32; 3]>,
    /// Per mesh passed to [`SceneBvh::build`]: its refit data when it deforms.
    pub refit_meshes: Vec<Option<RefitMesh>>,
    pub build_ms: f64,
}

/// A mesh's bottom-level BVH: its roots in the four layouts (pair, single, threaded, wide) and its object-space
/// bounds.
#[derive(Clone, Copy)]
struct Blas {
    roots: [u32; 4],
    lo: Vec3,
    hi: Vec3,
}

/// One scene object as the BVH sees it: which of the meshes it instances, where, and of what.
pub struct BvhObject<'a> {
    /// Index into the meshes passed to [`SceneBvh::build`].
    pub mesh: usize,
    /// Object → world.
    pub transform: Mat4,
    pub material: &'a Material,
}

/// A triangle's three vertices (or vertex normals), each with a texture coordinate in w.
type Corners = [Vec4; 3];

impl SceneBvh {
    #[cfg(test)]
    /// [`SceneBvh::build`] for a scene's objects as they are: each its own mesh with the identity transform.
    pub fn of_scene(scene: &crate::scene::Scene) -> SceneBvh {
        let meshes: Vec<&Mesh> = scene.objects.iter().map(|o| &o.mesh).collect();
        let objects: Vec<BvhObject> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| BvhObject { mesh: i, transform: Mat4::IDENTITY, material: &o.material })
            .collect();
        SceneBvh::build(&meshes, &objects, &[])
    }

    /// Each dielectric's media: the medium beyond its surface (`Object::outside`: an object index, None for air)
    /// into its instance's `sigma_rgb.w`, the outside object's instance + 1, 0 for air; and its priority
    /// (`Object::priority`) into `material.w` (glsl/common/interface.glsl). An outside object without triangles
    /// has no instance: its medium is then air's.
    pub fn set_media(&mut self, media: impl Iterator<Item = (Option<usize>, u32)>) {
        for (object, (o, priority)) in media.enumerate() {
            let Some(i) = self.object_instance.get(object).copied().flatten() else { continue };
            let m = o.and_then(|j| self.object_instance.get(j).copied().flatten()).map_or(0, |k| k + 1);
            self.instances[i].sigma_rgb[3] = m as f32;
            if self.instances[i].material[1] == 1.0 {
                self.instances[i].material[3] = priority as f32;
            }
        }
    }

    /// Move object `object` rigidly: `world_from_object` maps its BVH space (its mesh's object space) to world. Its
    /// instance's world bounds become the transformed corners of its BVH-space box (the identity keeps them
    /// exact). An object with no triangle has no instance to move.
    pub fn set_transform(&mut self, object: usize, world_from_object: Mat4) {
        let Some(i) = self.object_instance[object] else {
            return;
        };
        let (wlo, whi) = crate::scene::mesh::box_corners(self.local_bounds[i])
            .into_iter()
            .map(|c| world_from_object.transform_point3(c))
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| (a.min(p), b.max(p)));
        let inst = &mut self.instances[i];
        let inv = world_from_object.inverse();
        inst.world_from_object = [row(&world_from_object, 0), row(&world_from_object, 1), row(&world_from_object, 2)];
        inst.object_from_world = [row(&inv, 0), row(&inv, 1), row(&inv, 2)];
        inst.lo = [wlo.x, wlo.y, wlo.z, inst.lo[3]];
        inst.hi = [whi.x, whi.y, whi.z, inst.hi[3]];
    }
}

/// Where [`SceneBvh::build`] gets mesh `m`'s tree over its valid triangles: built, or borrowed from a cache.
type TreeFor<'a, 't> = dyn FnMut(usize, &[[Vec4; 3]]) -> Cow<'t, Bvh2> + 'a;

/// The meshes' trees already built, so that building the scene's BVH again (an object added, a material changed)
/// builds only the meshes it has not built before. A mesh is keyed by its address; the entry holds the mesh's
/// `Arc`, so no other mesh can take that address while the entry lives. [`BlasCache::retain`] drops the meshes a
/// scene no longer instances.
#[derive(Default)]
pub struct BlasCache {
    trees: HashMap<usize, (Arc<Mesh>, Bvh2)>,
}

impl BlasCache {
    fn key(mesh: &Arc<Mesh>) -> usize {
        Arc::as_ptr(mesh) as usize
    }

    /// Keep only the trees of these meshes.
    pub fn retain(&mut self, meshes: &[Arc<Mesh>]) {
        let live: std::collections::HashSet<usize> = meshes.iter().map(Self::key).collect();
        self.trees.retain(|k, _| live.contains(k));
    }
}

#[cfg(test)]
mod tests {
    use super::walk::watertight;
    use super::*;
    use crate::scene::Scene;

    fn brute(bvh: &SceneBvh, o: Vec3, d: Vec3) -> Option<(f32, u32)> {
        let mut best: Option<(f32, u32)> = None;
        for (i, t) in bvh.triangles.iter().enumerate() {
            let p = t.p.map(|v| Vec3::from_slice(&v[..3]));
            if let Some(t) = watertight(o, d, &p) {
                if best.is_none_or(|(b, _)| t < b) {
                    best = Some((t, i as u32));
                }
            }
        }
        best
    }

    /// Both flattened layouts find exactly the brute-force closest hit for rays through the bunny scene.
    #[test]
    fn layouts_match_brute_force() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/bunny.toml");
        let scene = Scene::load(&path).expect("scene");
        let bvh = SceneBvh::of_scene(&scene);
        assert_eq!(bvh.instances.len(), scene.objects.len());
        let mut hits = 0;
        let mut state = 12345u32;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state as f32 / u32::MAX as f32
        };
        for _ in 0..3000 {
            let o = Vec3::new(0.0, 2.0, 0.0) + 0.05 * Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
            let target = Vec3::new(0.6 * (rnd() - 0.5), 0.25 + 0.5 * rnd(), 0.6 * (rnd() - 0.5));
            let d = (target - o).normalize();
            let want = brute(&bvh, o, d);
            for layout in [BvhLayout::Pair, BvhLayout::Single, BvhLayout::Threaded, BvhLayout::Wide] {
                let got = bvh.intersect(layout, o, d, f32::INFINITY);
                assert_eq!(got.map(|(t, _, tri)| (t, tri)), want, "{layout:?} ray {o} {d}");
            }
            hits += want.is_some() as u32;
        }
        assert!(hits > 1000, "{hits} hits");
    }

    /// A moved instance is hit where it moved to, without a rebuild.
    /// Surface-area-heuristic cost of a single-layout tree (traversal and triangle tests weighted 1), relative to
    /// its root's area: the expected node and triangle tests of a ray that enters the root.
    fn sah(nodes: &[SingleNode], boxes: &[(Vec3, Vec3)]) -> f64 {
        let area = |(lo, hi): (Vec3, Vec3)| {
            let e = (hi - lo).max(Vec3::ZERO);
            2.0 * (e.x * e.y + e.y * e.z + e.z * e.x) as f64
        };
        let root = area(boxes[0]);
        nodes.iter().zip(boxes).map(|(n, &b)| area(b) * (n.hi[3].to_bits().max(1) as f64)).sum::<f64>() / root
    }

    fn single_boxes(nodes: &[SingleNode]) -> Vec<(Vec3, Vec3)> {
        nodes.iter().map(|n| (Vec3::from_slice(&n.lo[..3]), Vec3::from_slice(&n.hi[..3]))).collect()
    }

    /// The refit: each node's box over `tris` (a deforming mesh's triangles in leaf order), children before
    /// parents (the reverse of a depth-first order from the root), as glsl/refit.comp bounds them.
    fn refit_boxes(built: &SceneBvh, r: &RefitMesh, tris: &[[Vec3; 3]]) -> Vec<(Vec3, Vec3)> {
        let nodes = &built.refit_nodes[r.first_node as usize..];
        let mut boxes = vec![(Vec3::INFINITY, Vec3::NEG_INFINITY); nodes.len()];
        let mut order = vec![0usize];
        let mut k = 0;
        while k < order.len() {
            let n = nodes[order[k]];
            if n.tri_count == 0 {
                order.push((n.left - r.first_node) as usize);
                order.push((n.right - r.first_node) as usize);
            }
            k += 1;
        }
        for &k in order.iter().rev() {
            let n = nodes[k];
            boxes[k] = if n.tri_count > 0 {
                let ts =
                    &tris[(n.first_tri - r.first_tri) as usize..(n.first_tri - r.first_tri + n.tri_count) as usize];
                ts.iter().flatten().fold(boxes[k], |(a, b), p| (a.min(*p), b.max(*p)))
            } else {
                let (a, b) = (boxes[(n.left - r.first_node) as usize], boxes[(n.right - r.first_node) as usize]);
                (a.0.min(b.0), a.1.max(b.1))
            };
        }
        boxes
    }

    /// The refit rule for morph targets, measured on Blender's shape-key export (a slab whose top bulges into a
    /// lens, leaning): built once over the base mesh, refit at every sixth frame of its animation, against a tree
    /// built afresh over the morphed mesh. The morph's triangles are read through their rest corners, as
    /// glsl/morph.comp reads them.
    #[test]
    fn refit_morph_stays_near_a_fresh_build() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/blender/shape_keys.glb");
        let scene = Scene::load(&path).expect("scene");
        let a = scene.objects.iter().find_map(|o| o.animation.as_ref().filter(|a| a.deforms())).expect("a morph");
        let morph = a.morph.as_ref().unwrap();
        let rest = &a.mesh;
        let m = Material::Dielectric { ior: 1.5, absorption: Vec3::ZERO, abbe: 0.0 };
        let object = [BvhObject { mesh: 0, transform: Mat4::IDENTITY, material: &m }];
        let built = SceneBvh::build(&[rest], &object, &[Some(morph.bounds(rest))]);
        let r = built.refit_meshes[0].expect("refit data");
        let corners = &built.rest_corners[r.rest_first as usize..(r.rest_first + r.tri_count) as usize];
        let mut worst = 0.0f64;
        for frame in (1..=48).step_by(6) {
            let morphed = morph.apply(rest, &morph.weights_at(frame as f32 / 24.0));
            let tris: Vec<[Vec3; 3]> = corners.iter().map(|c| c.map(|v| morphed.positions[v as usize])).collect();
            let boxes = refit_boxes(&built, &r, &tris);
            // Every box holds its triangles: the morph bounds them, as the GPU's refit does.
            let (lo, hi) = morph.bounds(rest);
            assert!(boxes[0].0.cmpge(lo).all() && boxes[0].1.cmple(hi).all(), "the root outgrew the morph's bounds");
            let fresh = SceneBvh::build(&[&morphed], &object, &[]);
            let ratio = sah(&built.single_nodes, &boxes) / sah(&fresh.single_nodes, &single_boxes(&fresh.single_nodes));
            worst = worst.max(ratio);
        }
        eprintln!("morph refit SAH / fresh build SAH: worst {worst:.3}");
        assert!(worst < 1.25, "the refit tree degraded past the rebuild threshold: {worst:.3}");
    }

    /// The refit rule, measured: the pool's water (64² cells) built once at rest and refit for 20 s of its
    /// animation at 30 fps, against a tree built afresh over the displaced surface every second. Its cost (SAH) is
    /// what a ray pays; the rebuild threshold it must stay under is docs/design.md's (1.25×).
    #[test]
    fn refit_water_stays_near_a_fresh_build() {
        use crate::scene::water::{Water, Wave};
        let wave = |a: f32, l: f32, deg: f32, c: f32| Wave {
            amplitude: a,
            wavelength: l,
            direction: glam::Vec2::new(deg.to_radians().cos(), deg.to_radians().sin()),
            speed: c,
        };
        let w = Water {
            size: glam::Vec2::splat(1.96),
            depth: 0.42,
            grid: 64,
            waves: vec![wave(0.012, 0.7, 0.0, 0.35), wave(0.007, 0.41, 65.0, 0.28), wave(0.004, 0.23, 140.0, 0.22)],
            simulation: None,
        };
        let rest = w.rest_mesh();
        let m = Material::Dielectric { ior: 1.33, absorption: Vec3::ZERO, abbe: 0.0 };
        let object = [BvhObject { mesh: 0, transform: Mat4::IDENTITY, material: &m }];
        let built = SceneBvh::build(&[&rest], &object, &[Some(w.bounds())]);
        let r = built.refit_meshes[0].expect("refit data");
        let (mut worst, mut sum, mut samples) = (0.0f64, 0.0, 0);
        for frame in 0..600 {
            let t = frame as f32 / 30.0;
            // Displace the rest triangles and refit bottom-up (children before parents: the reverse of a
            // depth-first order from the root).
            let tris: Vec<[Vec3; 3]> = built.rest_tris[r.rest_first as usize..(r.rest_first + r.tri_count) as usize]
                .iter()
                .map(|g| g.p.map(|p| w.displace(Vec3::from_slice(&p[..3]), Vec3::Y, t, None).0))
                .collect();
            let boxes = refit_boxes(&built, &r, &tris);
            if frame % 30 != 0 {
                continue;
            }
            let refit = sah(&built.single_nodes, &boxes);
            let displaced = w.displaced(&rest, t, None);
            let fresh = SceneBvh::build(&[&displaced], &object, &[]);
            let rebuilt = sah(&fresh.single_nodes, &single_boxes(&fresh.single_nodes));
            let ratio = refit / rebuilt;
            worst = worst.max(ratio);
            sum += ratio;
            samples += 1;
        }
        eprintln!("refit SAH / fresh build SAH over 20 s: mean {:.3}, worst {worst:.3}", sum / samples as f64);
        assert!(worst < 1.25, "the refit tree degraded past the rebuild threshold: {worst:.3}");
    }

    /// Building the scene again takes the trees it has built from the cache: the same nodes, no build; a new mesh
    /// is the only one built; a mesh no longer instanced leaves the cache.
    #[test]
    fn cached_trees_are_not_built_again() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/sphere.toml");
        let scene = Scene::load(&path).expect("scene");
        let mut meshes: Vec<Arc<Mesh>> = scene.objects.iter().map(|o| Arc::new(o.mesh.clone())).collect();
        let objects = |n: usize| -> Vec<BvhObject> {
            (0..n)
                .map(|i| BvhObject { mesh: i, transform: Mat4::IDENTITY, material: &scene.objects[i % 2].material })
                .collect()
        };
        let mut cache = BlasCache::default();
        let first = SceneBvh::build_cached(&meshes, &objects(2), &[], &mut cache);
        assert_eq!((first.blas_builds, cache.trees.len()), (2, 2));
        let again = SceneBvh::build_cached(&meshes, &objects(2), &[], &mut cache);
        assert_eq!(again.blas_builds, 0, "both trees come from the cache");
        assert_eq!(bytemuck::cast_slice::<_, u8>(&again.pair_nodes), bytemuck::cast_slice::<_, u8>(&first.pair_nodes));
        assert_eq!(
            bytemuck::cast_slice::<_, u8>(&again.threaded_nodes),
            bytemuck::cast_slice::<_, u8>(&first.threaded_nodes)
        );
        let fresh = SceneBvh::build(&meshes.iter().map(|m| &**m).collect::<Vec<_>>(), &objects(2), &[]);
        assert_eq!(
            bytemuck::cast_slice::<_, u8>(&fresh.single_nodes),
            bytemuck::cast_slice::<_, u8>(&first.single_nodes)
        );
        meshes.push(Arc::new(scene.objects[1].mesh.clone()));
        let added = SceneBvh::build_cached(&meshes, &objects(3), &[], &mut cache);
        assert_eq!((added.blas_builds, cache.trees.len()), (1, 3), "only the added mesh is built");
        meshes.remove(0);
        cache.retain(&meshes);
        assert_eq!(cache.trees.len(), 2, "the dropped mesh's tree leaves the cache");
    }

    #[test]
    fn moved_instance_is_hit() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/scenes/sphere.toml");
        let scene = Scene::load(&path).expect("scene");
        let mut bvh = SceneBvh::of_scene(&scene);
        let glass = scene.objects.iter().position(|o| o.is_refractor()).unwrap();
        let down = Vec3::NEG_Y;
        let before = bvh.intersect(BvhLayout::Pair, Vec3::new(0.0, 2.0, 0.0), down, f32::INFINITY).unwrap();
        assert!((before.0 - 1.2).abs() < 1e-3, "top of the sphere at y = 0.8: t {}", before.0);
        bvh.set_transform(glass, Mat4::from_translation(Vec3::new(0.5, 0.0, 0.0)));
        let nodes = bvh.pair_nodes.len();
        let miss = bvh.intersect(BvhLayout::Pair, Vec3::new(0.0, 2.0, 0.0), down, f32::INFINITY).unwrap();
        assert_ne!(miss.1 as usize, glass, "the sphere moved away from x = 0");
        let moved = bvh.intersect(BvhLayout::Pair, Vec3::new(0.5, 2.0, 0.0), down, f32::INFINITY).unwrap();
        assert_eq!(moved.1 as usize, glass);
        assert!((moved.0 - 1.2).abs() < 1e-3);
        assert_eq!(bvh.pair_nodes.len(), nodes);
    }
}
