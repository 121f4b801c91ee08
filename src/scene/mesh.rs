//! Triangle meshes: procedural shapes (plane, icosphere, cube) and OBJ files, in world space.
//! The GPU rasterizer and the CPU reference see exactly these triangles and these per-vertex normals.

use glam::{Mat3, Mat4, Vec3};

#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub indices: Vec<u32>,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn transformed(mut self, m: Mat4) -> Mesh {
        let n = Mat3::from_mat4(m).inverse().transpose();
        let flip = Mat3::from_mat4(m).determinant() < 0.0;
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        for v in &mut self.normals {
            *v = (n * *v).normalize_or_zero();
        }
        if flip {
            // A mirroring transform turns outward counter-clockwise winding inside out; restore it.
            for t in self.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
        }
        self
    }

    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &self.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        (lo, hi)
    }

    /// Area-weighted vertex normals, for meshes without their own.
    pub fn compute_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for t in self.indices.chunks_exact(3) {
            let (a, b, c) =
                (self.positions[t[0] as usize], self.positions[t[1] as usize], self.positions[t[2] as usize]);
            let n = (b - a).cross(c - a); // length = 2 * area
            for &i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc.into_iter().map(|n| n.normalize_or_zero()).collect();
    }
}

/// The xz-plane at the origin, facing +y, `sx` by `sz`.
pub fn plane(sx: f32, sz: f32) -> Mesh {
    let (x, z) = (sx * 0.5, sz * 0.5);
    Mesh {
        positions: vec![Vec3::new(-x, 0.0, -z), Vec3::new(-x, 0.0, z), Vec3::new(x, 0.0, z), Vec3::new(x, 0.0, -z)],
        normals: vec![Vec3::Y; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
    }
}

/// An axis-aligned box centered at the origin with flat (sharp-edged) faces.
pub fn cube(size: Vec3) -> Mesh {
    let h = size * 0.5;
    let mut m = Mesh::default();
    // Each face: normal, and two in-plane axes u, v with u x v = normal (counter-clockwise seen from outside).
    let faces = [
        (Vec3::X, Vec3::Y, Vec3::Z),
        (Vec3::NEG_X, Vec3::Z, Vec3::Y),
        (Vec3::Y, Vec3::Z, Vec3::X),
        (Vec3::NEG_Y, Vec3::X, Vec3::Z),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    for (n, u, v) in faces {
        let base = m.positions.len() as u32;
        for (su, sv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push((n + u * su + v * sv) * h);
            m.normals.push(n);
        }
        m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
    }
    m
}

/// A geodesic sphere: an icosahedron subdivided `subdivisions` times (20·4^s triangles), with exact sphere
/// normals at the vertices.
pub fn icosphere(radius: f32, subdivisions: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut verts: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..subdivisions {
        let mut mid = std::collections::HashMap::new();
        let mut midpoint = |a: u32, b: u32, verts: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                // Normalizing in f64 keeps shared vertices bit-identical whichever triangle creates them.
                let pa = verts[a as usize].as_dvec3();
                let pb = verts[b as usize].as_dvec3();
                verts.push(((pa + pb) * 0.5).normalize().as_vec3());
                (verts.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut verts);
            let bc = midpoint(b, c, &mut verts);
            let ca = midpoint(c, a, &mut verts);
            next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    Mesh {
        positions: verts.iter().map(|v| *v * radius).collect(),
        normals: verts,
        indices: tris.into_iter().flatten().collect(),
    }
}

/// Load an OBJ (all models merged), triangulated, with its normals when it has them for every vertex.
pub fn load_obj(path: &std::path::Path) -> Result<Mesh, String> {
    let opts = tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    let (models, _) = tobj::load_obj(path, &opts).map_err(|e| e.to_string())?;
    let mut mesh = Mesh::default();
    let mut all_normals = true;
    for m in &models {
        let base = mesh.positions.len() as u32;
        let p = &m.mesh.positions;
        if p.len() % 3 != 0 {
            return Err("position data is not a multiple of 3".into());
        }
        for v in p.chunks_exact(3) {
            mesh.positions.push(Vec3::new(v[0], v[1], v[2]));
        }
        if m.mesh.normals.len() == p.len() {
            for v in m.mesh.normals.chunks_exact(3) {
                mesh.normals.push(Vec3::new(v[0], v[1], v[2]).normalize_or_zero());
            }
        } else {
            all_normals = false;
        }
        let count = (p.len() / 3) as u32;
        for &i in &m.mesh.indices {
            if i >= count {
                return Err(format!("face index {} out of range ({} vertices)", i + 1, count));
            }
            mesh.indices.push(base + i);
        }
    }
    if mesh.indices.is_empty() {
        return Err("no triangles".into());
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err("non-finite vertex position".into());
    }
    if !all_normals || mesh.normals.iter().any(|n| *n == Vec3::ZERO || !n.is_finite()) {
        mesh.compute_normals();
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_is_closed_and_outward() {
        let m = icosphere(0.3, 3);
        assert_eq!(m.triangle_count(), 20 * 64);
        // Closed: the signed volume equals that of an inscribed polyhedron, slightly below the sphere's.
        let mut vol = 0.0f64;
        for t in m.indices.chunks_exact(3) {
            let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
            vol += a.as_dvec3().dot(b.as_dvec3().cross(c.as_dvec3())) / 6.0;
            let n = (b - a).cross(c - a);
            assert!(n.dot(a + b + c) > 0.0, "triangle winding must face outward");
        }
        let sphere = 4.0 / 3.0 * std::f64::consts::PI * 0.027;
        assert!(vol > 0.97 * sphere && vol < sphere, "volume {vol} vs {sphere}");
    }

    #[test]
    fn cube_faces_outward() {
        let m = cube(Vec3::ONE);
        for t in m.indices.chunks_exact(3) {
            let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
            let n = (b - a).cross(c - a).normalize();
            assert!((n - m.normals[t[0] as usize]).length() < 1e-6);
        }
    }

    #[test]
    fn plane_faces_up() {
        let m = plane(2.0, 2.0);
        for t in m.indices.chunks_exact(3) {
            let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }
}
