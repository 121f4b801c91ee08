//! World-space triangles of every scene object in one BVH (obvhs' compressed wide BVH8), with the GPU's
//! barycentric-interpolated per-vertex normals.
//!
//! The BVH only culls nodes; each candidate triangle is tested here in f64 with the watertight ray/triangle test
//! of Woop, Benthin and Wald (JCGT 2013). Two triangles sharing an edge compute that edge's function from the
//! same transformed vertices with the operands swapped, so its value is exactly negated: a ray can neither slip
//! through a shared edge nor be lost between neighbours. Degenerate (zero-area) triangles are dropped; they cover
//! no area, so dropping them opens no gap.

use crate::scene::Scene;
use glam::{DVec3, Vec3A};
use obvhs::cwbvh::CwBvh;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;

#[derive(Clone, Copy, Debug)]
pub(crate) struct Tri {
    pub p: [DVec3; 3],
    pub n: [DVec3; 3],
    /// Unit geometric normal, (p1 − p0) × (p2 − p0): outward for counter-clockwise (outward) winding.
    pub ng: DVec3,
    pub object: u32,
    pub receiver: bool,
}

#[derive(Clone, Copy, Debug)]
pub(crate) struct Hit {
    /// Index of the triangle in BVH order (what `skip` takes).
    pub prim: u32,
    pub pos: DVec3,
    pub ng: DVec3,
    /// Interpolated, normalized vertex normal (falls back to `ng` where it is degenerate).
    pub ns: DVec3,
    pub object: u32,
    pub receiver: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Filter {
    All,
    ReceiversOnly,
}

pub(crate) struct Geometry {
    tris: Vec<Tri>,
    bvh: CwBvh,
}

/// The watertight test's per-ray shear constants.
struct ShearedRay {
    o: DVec3,
    k: [usize; 3],
    s: DVec3,
}

impl ShearedRay {
    fn new(o: DVec3, d: DVec3) -> Self {
        let a = d.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        ShearedRay { o, k: [kx, ky, kz], s: DVec3::new(d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]) }
    }

    /// (t, barycentric weights of p0, p1, p2), if the ray hits the triangle.
    #[inline]
    fn intersect(&self, p: &[DVec3; 3]) -> Option<(f64, [f64; 3])> {
        let [kx, ky, kz] = self.k;
        let a = p[0] - self.o;
        let b = p[1] - self.o;
        let c = p[2] - self.o;
        let (ax, ay) = (a[kx] - self.s.x * a[kz], a[ky] - self.s.y * a[kz]);
        let (bx, by) = (b[kx] - self.s.x * b[kz], b[ky] - self.s.y * b[kz]);
        let (cx, cy) = (c[kx] - self.s.x * c[kz], c[ky] - self.s.y * c[kz]);
        let u = cx * by - cy * bx;
        let v = ax * cy - ay * cx;
        let w = bx * ay - by * ax;
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t = (u * a[kz] + v * b[kz] + w * c[kz]) * self.s.z / det;
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        Some((t, [u / det, v / det, w / det]))
    }
}

impl Geometry {
    pub fn new(scene: &Scene) -> Self {
        let mut tris = Vec::with_capacity(scene.triangle_count());
        for (oi, obj) in scene.objects.iter().enumerate() {
            let m = &obj.mesh;
            for t in m.indices.chunks_exact(3) {
                let p = [0, 1, 2].map(|k| m.positions[t[k] as usize].as_dvec3());
                let ng = (p[1] - p[0]).cross(p[2] - p[0]);
                let len = ng.length();
                if !(len > 0.0 && len.is_finite()) {
                    continue;
                }
                let n = [0, 1, 2].map(|k| m.normals.get(t[k] as usize).map(|v| v.as_dvec3()).unwrap_or(DVec3::ZERO));
                tris.push(Tri { p, n, ng: ng / len, object: oi as u32, receiver: !obj.is_refractor() });
            }
        }
        let boxes: Vec<Triangle> = tris
            .iter()
            .map(|t| Triangle { v0: t.p[0].as_vec3a(), v1: t.p[1].as_vec3a(), v2: t.p[2].as_vec3a() })
            .collect();
        if boxes.is_empty() {
            return Geometry { tris, bvh: CwBvh::default() };
        }
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &boxes,
            BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        // Without spatial splits the BVH's primitive list is a permutation: store the triangles in that order so
        // the traversal callback indexes them directly.
        let tris = bvh.primitive_indices.iter().map(|&i| tris[i as usize]).collect();
        Geometry { tris, bvh }
    }

    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Closest hit along `o + t·d` (unit `d`) with 0 < t < `tmax`, ignoring triangle `skip`.
    pub fn intersect(&self, o: DVec3, d: DVec3, tmax: f64, skip: Option<u32>, filter: Filter) -> Option<Hit> {
        if self.tris.is_empty() {
            return None;
        }
        let sr = ShearedRay::new(o, d);
        // obvhs picks the child order from `dir < 0` but inverts −0.0 to −1/ε, so a −0.0 component (the top
        // camera's (−0, 1, −0), for one) makes every node test fail. Adding +0 turns −0.0 into +0.0.
        let dir = d.as_vec3a() + Vec3A::ZERO;
        let ray = Ray::new(o.as_vec3a(), dir, 0.0, if tmax.is_finite() { tmax as f32 } else { f32::INFINITY });
        let mut best: Option<(f64, u32, [f64; 3])> = None;
        let mut best_t = tmax;
        let mut rh = RayHit::none();
        self.bvh.ray_traverse(ray, &mut rh, |_, id| {
            let tri = &self.tris[id];
            if (filter == Filter::ReceiversOnly && !tri.receiver) || skip == Some(id as u32) {
                return f32::INFINITY;
            }
            match sr.intersect(&tri.p) {
                Some((t, b)) if t < best_t => {
                    best_t = t;
                    best = Some((t, id as u32, b));
                    // The BVH culls nodes beyond this distance in f32: round up so that culling stays conservative.
                    (t * (1.0 + 1e-6)) as f32
                }
                _ => f32::INFINITY,
            }
        });
        let (_, prim, b) = best?;
        let tri = &self.tris[prim as usize];
        let pos = tri.p[0] * b[0] + tri.p[1] * b[1] + tri.p[2] * b[2];
        let ns = (tri.n[0] * b[0] + tri.n[1] * b[1] + tri.n[2] * b[2]).normalize_or_zero();
        let ns = if ns == DVec3::ZERO || !ns.is_finite() { tri.ng } else { ns };
        Some(Hit { prim, pos, ng: tri.ng, ns, object: tri.object, receiver: tri.receiver })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edge_is_watertight() {
        // Two triangles of a unit square share the diagonal; rays straight at the diagonal hit exactly one or both.
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let t1 = [p[0], p[2], p[1]];
        let t2 = [p[0], p[3], p[2]];
        for i in 0..1000 {
            let s = i as f64 / 999.0;
            let o = DVec3::new(s, 1.0, s);
            let d = DVec3::new(1e-3 * (s - 0.5), -1.0, 0.0).normalize();
            let r = ShearedRay::new(o, d);
            let hit = r.intersect(&t1).is_some() || r.intersect(&t2).is_some();
            let inside = {
                let x = s + d.x / -d.y;
                (0.0..=1.0).contains(&x)
            };
            assert!(hit || !inside, "ray {i} slipped through the shared edge");
        }
    }

    #[test]
    fn negative_zero_directions_hit() {
        // A unit square at y = 0.3 and rays straight up whose x and z components are −0.0 or +0.0.
        let mut mesh = crate::scene::mesh::plane(1.0, 1.0);
        mesh = mesh.transformed(glam::Mat4::from_translation(glam::Vec3::new(0.0, 0.3, 0.0)));
        let obj = crate::scene::Object::new("p", crate::scene::Material::diffuse(glam::Vec3::ONE), mesh);
        let mut scene = Scene::new(vec![], vec![]);
        scene.objects.push(obj);
        let g = Geometry::new(&scene);
        for d in [DVec3::new(-0.0, 1.0, -0.0), DVec3::new(0.0, 1.0, -0.0), DVec3::Y, -DVec3::NEG_Y] {
            let h = g.intersect(DVec3::new(0.1, 0.0, 0.2), d, 1.0, None, Filter::All);
            assert!(h.is_some_and(|h| (h.pos.y - 0.3).abs() < 1e-6), "{d:?}");
        }
    }

    #[test]
    fn barycentrics_reconstruct_the_hit() {
        let tri = [DVec3::new(-1.0, 0.2, -1.0), DVec3::new(1.0, 0.1, -1.0), DVec3::new(0.0, 0.3, 1.0)];
        let o = DVec3::new(0.1, 2.0, 0.05);
        let d = DVec3::new(0.05, -1.0, 0.02).normalize();
        let (t, b) = ShearedRay::new(o, d).intersect(&tri).unwrap();
        let p = tri[0] * b[0] + tri[1] * b[1] + tri[2] * b[2];
        assert!((p - (o + t * d)).length() < 1e-12);
        assert!((b.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    }
}
