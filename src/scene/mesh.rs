//! Triangle meshes: procedural shapes (plane, icosphere, cube) and OBJ files, in world space.
//! The GPU rasterizer and the CPU reference see exactly these triangles and these per-vertex normals.

use glam::{Mat3, Mat4, Vec2, Vec3};

#[derive(Clone, Debug, Default, PartialEq)]
/// Triangles: positions, one normal per position, and indices (three per triangle).
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Vertex normals (unit length).
    pub normals: Vec<Vec3>,
    /// Three indices per triangle, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Texture coordinates, one per position, or none (src/scene/texture.rs has their convention).
    pub uvs: Vec<Vec2>,
}

impl Mesh {
    /// Triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// The mesh placed by `m` (normals by its inverse transpose; a mirroring `m` keeps the winding outward).
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

    /// Bounds of the positions.
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

/// The eight corners of the box `(lo, hi)`: bit 0 of the index picks x's end, bit 1 y's, bit 2 z's.
pub fn box_corners((lo, hi): (Vec3, Vec3)) -> [Vec3; 8] {
    std::array::from_fn(|k| Vec3::new([lo.x, hi.x][k & 1], [lo.y, hi.y][(k >> 1) & 1], [lo.z, hi.z][k >> 2]))
}

/// The xz-plane at the origin, facing +y, `sx` by `sz`.
pub fn plane(sx: f32, sz: f32) -> Mesh {
    let (x, z) = (sx * 0.5, sz * 0.5);
    Mesh {
        positions: vec![Vec3::new(-x, 0.0, -z), Vec3::new(-x, 0.0, z), Vec3::new(x, 0.0, z), Vec3::new(x, 0.0, -z)],
        normals: vec![Vec3::Y; 4],
        indices: vec![0, 1, 2, 0, 2, 3],
        // u along +x, v along +z: seen from above with -z up, the image stands upright.
        uvs: vec![Vec2::new(0.0, 0.0), Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0)],
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
            // Each face holds the whole texture.
            m.uvs.push(Vec2::new((su + 1.0) * 0.5, (1.0 - sv) * 0.5));
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
    let mesh = Mesh {
        positions: verts.iter().map(|v| *v * radius).collect(),
        normals: verts,
        indices: tris.into_iter().flatten().collect(),
        uvs: Vec::new(),
    };
    mesh
}

/// Latitude-longitude texture coordinates about the y axis (u = longitude / 2π from -z, v = colatitude / π),
/// with the vertices on the seam duplicated so that no triangle's u wraps across the whole texture. For a textured
/// sphere only: the duplicates split the mesh along the seam (glass needs its closed topology).
pub fn spherical_uvs(m: &mut Mesh) {
    let uv_of = |n: Vec3| {
        let u = 0.5 + n.x.atan2(-n.z) / std::f32::consts::TAU;
        Vec2::new(u, n.y.clamp(-1.0, 1.0).acos() / std::f32::consts::PI)
    };
    m.uvs = m.normals.iter().map(|n| uv_of(*n)).collect();
    let mut wrapped = std::collections::HashMap::new();
    for t in 0..m.indices.len() / 3 {
        let tri = [m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]];
        let us = tri.map(|i| m.uvs[i as usize].x);
        if us.iter().cloned().fold(f32::MIN, f32::max) - us.iter().cloned().fold(f32::MAX, f32::min) <= 0.5 {
            continue;
        }
        for (k, &i) in tri.iter().enumerate() {
            if us[k] < 0.5 {
                let j = *wrapped.entry(i).or_insert_with(|| {
                    m.positions.push(m.positions[i as usize]);
                    m.normals.push(m.normals[i as usize]);
                    m.uvs.push(m.uvs[i as usize] + Vec2::X);
                    (m.positions.len() - 1) as u32
                });
                m.indices[3 * t + k] = j;
            }
        }
    }
}

/// Largest vertex coordinate accepted (meters, in the OBJ file and in world space): squared distances and the
/// light-view products of such coordinates stay finite in f32.
pub const MAX_COORDINATE: f32 = 1e9;

/// The first `v` line of OBJ text with a coordinate that is not finite or exceeds [`MAX_COORDINATE`], as
/// `LINE: message` (tobj would accept `nan` and `inf` and lose the line).
fn check_obj_vertices(text: &str) -> Result<(), String> {
    let mut vertex = 0usize;
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        vertex += 1;
        for w in words.take(3) {
            match w.parse::<f32>() {
                Ok(x) if !x.is_finite() => {
                    return Err(format!("{}: vertex {vertex} has a non-finite coordinate `{w}`", i + 1))
                }
                Ok(x) if x.abs() > MAX_COORDINATE => {
                    return Err(format!(
                        "{}: vertex {vertex} has a coordinate beyond ±{MAX_COORDINATE:e} (`{w}`)",
                        i + 1
                    ))
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// Load an OBJ (all models merged), triangulated, with its normals when it has them for every vertex.
/// Errors start with the file's path, and its line (`PATH:LINE: message`) when they concern one line.
pub fn load_obj(path: &std::path::Path) -> Result<Mesh, String> {
    Ok(load_obj_report(path)?.0)
}

/// [`load_obj`], then [`sanitize`]: the mesh and what was repaired or found.
pub fn load_obj_report(path: &std::path::Path) -> Result<(Mesh, MeshReport), String> {
    let file = path.display();
    let start = std::time::Instant::now();
    let bytes = read_obj(path)?;
    let out = load_obj_bytes(&bytes).map_err(|e| format!("{file}: {e}"))?;
    log::info!(
        "{file}: {} triangles, read and repaired in {:.0} ms",
        out.0.triangle_count(),
        start.elapsed().as_secs_f64() * 1e3
    );
    Ok(out)
}

/// An OBJ file's bytes, once its `v` lines are checked ([`check_obj_vertices`]); errors start with its path.
fn read_obj(path: &std::path::Path) -> Result<Vec<u8>, String> {
    let file = path.display();
    let bytes = std::fs::read(path).map_err(|e| format!("{file}: cannot read: {e}"))?;
    check_obj_vertices(&String::from_utf8_lossy(&bytes)).map_err(|e| format!("{file}:{e}"))?;
    Ok(bytes)
}

/// Parse OBJ bytes (see [`load_obj_report`]; errors without the path, and no line check).
fn load_obj_bytes(bytes: &[u8]) -> Result<(Mesh, MeshReport), String> {
    // Materials are not used: every `mtllib` resolves to nothing, so no other file is ever opened.
    let (models, _) =
        tobj::load_obj_buf(&mut std::io::Cursor::new(bytes), &OBJ_OPTIONS, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| e.to_string())?;
    merge_models(&models.iter().collect::<Vec<_>>())
}

const OBJ_OPTIONS: tobj::LoadOptions =
    tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };

/// One mesh of OBJ models (repaired by [`sanitize`]), with their normals when every vertex has one and their
/// texture coordinates when every vertex has one.
fn merge_models(models: &[&tobj::Model]) -> Result<(Mesh, MeshReport), String> {
    let mut mesh = Mesh::default();
    let mut all_normals = true;
    let all_uvs = models.iter().all(|m| m.mesh.texcoords.len() * 3 == m.mesh.positions.len() * 2);
    for m in models {
        if all_uvs {
            // OBJ's v runs up the image; ours runs down.
            mesh.uvs.extend(m.mesh.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])));
        }
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
    let computed = !all_normals || mesh.normals.iter().any(|n| *n == Vec3::ZERO || !n.is_finite());
    if computed {
        mesh.compute_normals();
    }
    let report = sanitize(&mut mesh, computed);
    if mesh.indices.is_empty() {
        return Err(format!("no triangles with a non-zero area ({} degenerate)", report.degenerate_removed));
    }
    Ok((mesh, report))
}

/// An OBJ's triangles split by the MTL material their faces use.
#[derive(Debug)]
pub struct ObjParts {
    /// Every material of its `mtllib` files, in the order they were defined.
    pub materials: Vec<super::mtl::MtlMaterial>,
    /// Per material used (in the order of first use): its index in `materials` (None: faces before any
    /// `usemtl`, or after one naming no material of the files), its mesh and what was repaired in it.
    pub parts: Vec<(Option<usize>, Mesh, MeshReport)>,
}

/// Load an OBJ with its `mtllib` materials (relative to the OBJ), one mesh per material used. Errors start with
/// the file's path and line (`PATH:LINE: message`), an MTL file's too.
pub fn load_obj_parts(path: &std::path::Path) -> Result<ObjParts, String> {
    let file = path.display();
    let bytes = read_obj(path)?;
    let text = String::from_utf8_lossy(&bytes);
    let dir = path.parent().unwrap_or(std::path::Path::new(""));
    // Each `mtllib` file, parsed here (tobj is given only the names, to resolve `usemtl`).
    let mut materials = Vec::new();
    let mut by_file: std::collections::HashMap<String, Vec<String>> = Default::default();
    for (i, line) in text.lines().enumerate() {
        let Some(name) = line.trim_start().strip_prefix("mtllib").filter(|r| r.starts_with(char::is_whitespace)) else {
            continue;
        };
        let name = name.trim().to_string();
        let full = dir.join(&name);
        let mtl = std::fs::read(&full)
            .map_err(|e| format!("{file}:{}: mtllib `{name}`: cannot read {}: {e}", i + 1, full.display()))?;
        let parsed = super::mtl::parse(&String::from_utf8_lossy(&mtl), &full.display().to_string())?;
        by_file.insert(name, parsed.iter().map(|m| m.name.clone()).collect());
        materials.extend(parsed);
    }
    if materials.is_empty() {
        return Err(format!("{file}: the OBJ names no MTL materials (`mtllib`), or its files define none"));
    }
    let (models, names) = tobj::load_obj_buf(&mut std::io::Cursor::new(&bytes[..]), &OBJ_OPTIONS, |p| {
        let names = by_file.get(&p.display().to_string()).cloned().unwrap_or_default();
        let map = names.iter().enumerate().map(|(k, n)| (n.clone(), k)).collect();
        Ok((names.into_iter().map(|name| tobj::Material { name, ..Default::default() }).collect(), map))
    })
    .map_err(|e| format!("{file}: {e}"))?;
    let names = names.map_err(|e| format!("{file}: {e}"))?;
    // Each model's material, by name (the last definition of a name wins, as tobj's map has it).
    let of = |m: &tobj::Model| {
        let name = &names.get(m.mesh.material_id?)?.name;
        materials.iter().rposition(|x: &super::mtl::MtlMaterial| &x.name == name)
    };
    let mut used: Vec<Option<usize>> = Vec::new();
    for m in &models {
        if !used.contains(&of(m)) {
            used.push(of(m));
        }
    }
    let mut parts = Vec::new();
    for u in used {
        let group: Vec<&tobj::Model> = models.iter().filter(|m| of(m) == u).collect();
        if group.iter().all(|m| m.mesh.indices.is_empty()) {
            continue;
        }
        let (mesh, report) = merge_models(&group).map_err(|e| match u {
            Some(k) => format!("{file}: the faces of material `{}`: {e}", materials[k].name),
            None => format!("{file}: the faces without a material: {e}"),
        })?;
        parts.push((u, mesh, report));
    }
    if parts.is_empty() {
        return Err(format!("{file}: no triangles"));
    }
    Ok(ObjParts { materials, parts })
}

/// [`sanitize`]'s first steps: each vertex's welded id (equal positions share one), and the triangles left once
/// those with a zero area and those repeating an earlier one's corners are gone (counted in `report`).
fn weld_and_cull(mesh: &Mesh, report: &mut MeshReport) -> (Vec<u32>, Vec<[u32; 3]>) {
    use rayon::prelude::*;
    // Welded ids: equal positions (0.0 and -0.0 alike) share one, numbered along the vertices sorted by their bits
    // (sorting, in parallel, rather than hashing: a million-triangle mesh is repaired in a fraction of a second).
    let keys: Vec<[u32; 3]> =
        mesh.positions.par_iter().map(|p| (*p + Vec3::ZERO).to_array().map(f32::to_bits)).collect(); // + 0: -0.0 and 0.0 weld
    let mut order: Vec<u32> = (0..keys.len() as u32).collect();
    order.par_sort_unstable_by_key(|&i| keys[i as usize]);
    let mut ids = vec![0u32; keys.len()];
    let mut id = 0u32;
    for (k, &i) in order.iter().enumerate() {
        if k > 0 && keys[i as usize] != keys[order[k - 1] as usize] {
            id += 1;
        }
        ids[i as usize] = id;
    }
    let faces = mesh.indices.len() / 3;
    let corners = |f: usize| [mesh.indices[3 * f], mesh.indices[3 * f + 1], mesh.indices[3 * f + 2]];
    let degenerate: Vec<bool> = (0..faces)
        .into_par_iter()
        .map(|f| {
            let t = corners(f);
            let w = t.map(|i| ids[i as usize]);
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let area2 = (b - a).as_dvec3().cross((c - a).as_dvec3()).length();
            w[0] == w[1] || w[1] == w[2] || w[0] == w[2] || area2 == 0.0 || !area2.is_finite()
        })
        .collect();
    // A triangle repeating an earlier one's corners (in either winding): the later ones go.
    let mut same: Vec<([u32; 3], u32)> = (0..faces)
        .filter(|&f| !degenerate[f])
        .map(|f| {
            let mut key = corners(f).map(|i| ids[i as usize]);
            key.sort_unstable();
            (key, f as u32)
        })
        .collect();
    same.par_sort_unstable();
    let mut duplicate = vec![false; faces];
    for k in 1..same.len() {
        if same[k].0 == same[k - 1].0 {
            duplicate[same[k].1 as usize] = true;
        }
    }
    report.degenerate_removed = degenerate.iter().filter(|&&d| d).count();
    report.duplicate_removed = duplicate.iter().filter(|&&d| d).count();
    let tris: Vec<[u32; 3]> = (0..faces).filter(|&f| !degenerate[f] && !duplicate[f]).map(corners).collect();
    (ids, tris)
}

/// The half-edges of `tris` (3 · triangle + corner: from corner k to k + 1, by welded id) sorted by their undirected
/// edge, so that each edge's users are one run; per half-edge, its run (start, length); and the runs.
#[allow(clippy::type_complexity)]
fn edge_runs(
    tris: &[[u32; 3]],
    welded: impl Fn(&[u32; 3]) -> [u32; 3],
) -> (Vec<(u64, u32)>, Vec<(u32, u32)>, Vec<(usize, usize)>) {
    use rayon::prelude::*;
    let edge_key = |a: u32, b: u32| ((a.min(b) as u64) << 32) | a.max(b) as u64;
    let mut half: Vec<(u64, u32)> = Vec::with_capacity(3 * tris.len());
    for (f, t) in tris.iter().enumerate() {
        let w = welded(t);
        for k in 0..3 {
            half.push((edge_key(w[k], w[(k + 1) % 3]), (3 * f + k) as u32));
        }
    }
    half.par_sort_unstable();
    let mut run_of = vec![(0u32, 0u32); half.len()];
    let mut runs = Vec::new();
    let mut s = 0;
    while s < half.len() {
        let e = s + half[s..].iter().take_while(|h| h.0 == half[s].0).count();
        for h in &half[s..e] {
            run_of[h.1 as usize] = (s as u32, (e - s) as u32);
        }
        runs.push((s, e - s));
        s = e;
    }
    (half, run_of, runs)
}

/// What [`sanitize`] found in a mesh and did about it.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MeshReport {
    /// Triangles removed for a zero area (two corners at the same position, or three collinear corners).
    pub degenerate_removed: usize,
    /// Triangles removed for repeating an earlier triangle's three corners (in either winding).
    pub duplicate_removed: usize,
    /// Edges of only one triangle: the mesh is open there.
    pub boundary_edges: usize,
    /// Edges shared by more than two triangles.
    pub nonmanifold_edges: usize,
    /// Triangles whose winding was reversed to agree with their neighbours across shared edges.
    pub reoriented: usize,
    /// Edges whose two triangles still disagree after re-orientation (a non-orientable surface).
    pub inconsistent_edges: usize,
    /// A closed mesh enclosing a negative volume: every winding was reversed (it was inside out).
    pub inverted: bool,
    /// A closed mesh whose own normals pointed inward (against its outward winding): they were negated.
    pub normals_negated: bool,
}

impl MeshReport {
    /// Whether every edge is shared by exactly two triangles.
    pub fn closed(&self) -> bool {
        self.boundary_edges == 0 && self.nonmanifold_edges == 0
    }

    /// One line per finding, for warnings.
    pub fn findings(&self) -> Vec<String> {
        let mut out = Vec::new();
        if self.degenerate_removed > 0 {
            out.push(format!("removed {} degenerate (zero-area) triangles", self.degenerate_removed));
        }
        if self.duplicate_removed > 0 {
            out.push(format!("removed {} duplicated triangles", self.duplicate_removed));
        }
        if self.reoriented > 0 {
            out.push(format!("reversed the winding of {} triangles to agree with their neighbours", self.reoriented));
        }
        if self.normals_negated {
            out.push("the closed mesh's normals pointed inward: negated them".into());
        }
        if self.inverted {
            out.push("the closed mesh was inside out (negative volume): reversed every winding".into());
        }
        if self.boundary_edges > 0 {
            out.push(format!("open mesh: {} boundary edges (rendered as surfaces)", self.boundary_edges));
        }
        if self.nonmanifold_edges > 0 {
            out.push(format!(
                "non-manifold: {} edges shared by more than two triangles (rendered as surfaces)",
                self.nonmanifold_edges
            ));
        }
        if self.inconsistent_edges > 0 {
            out.push(format!(
                "non-orientable: {} edges between triangles of opposite winding",
                self.inconsistent_edges
            ));
        }
        out
    }
}

/// Repair what has one right answer and measure the rest: drop zero-area and duplicated triangles, make the
/// winding consistent across shared edges (breadth-first over edges of exactly two triangles), and turn a closed
/// mesh of negative volume outward. Vertices are welded by exact position for the topology (OBJ files split
/// vertices at normal and texture seams). `normals_from_winding`: the normals were computed from the winding,
/// so they are recomputed after a change; normals from the file are kept, negated when the mesh is turned
/// inside out.
pub fn sanitize(mesh: &mut Mesh, normals_from_winding: bool) -> MeshReport {
    let mut report = MeshReport::default();
    let (ids, mut tris) = weld_and_cull(mesh, &mut report);
    let welded = |t: &[u32; 3]| t.map(|i| ids[i as usize]);
    let (half, run_of, runs) = edge_runs(&tris, welded);
    report.boundary_edges = runs.iter().filter(|r| r.1 == 1).count();
    report.nonmanifold_edges = runs.iter().filter(|r| r.1 > 2).count();
    // Whether triangle t traverses a -> b (else b -> a).
    let forward = |t: &[u32; 3], a: u32, b: u32| {
        let w = welded(t);
        (0..3).any(|k| w[k] == a && w[(k + 1) % 3] == b)
    };
    let mut flipped = vec![false; tris.len()];
    let mut visited = vec![false; tris.len()];
    for start in 0..tris.len() {
        if visited[start] {
            continue;
        }
        visited[start] = true;
        let mut component = vec![start];
        let mut queue = std::collections::VecDeque::from([start]);
        while let Some(f) = queue.pop_front() {
            let w = welded(&tris[f]);
            for k in 0..3 {
                let (a, b) = (w[k], w[(k + 1) % 3]);
                let (s, len) = run_of[3 * f + k];
                if len != 2 {
                    continue;
                }
                let (s, me) = (s as usize, (3 * f + k) as u32);
                let other = if half[s].1 == me { half[s + 1].1 } else { half[s].1 };
                let g = other as usize / 3;
                if visited[g] {
                    continue;
                }
                visited[g] = true;
                // f (as oriented now) goes a -> b, or b -> a when flipped; g must go the other way.
                let f_ab = !flipped[f];
                let g_ab = forward(&tris[g], a, b);
                flipped[g] = g_ab == f_ab;
                component.push(g);
                queue.push_back(g);
            }
        }
        // The seed's winding is arbitrary: keep whichever orientation most of the component already has.
        if 2 * component.iter().filter(|&&f| flipped[f]).count() > component.len() {
            for &f in &component {
                flipped[f] = !flipped[f];
            }
        }
    }
    for (t, &f) in tris.iter_mut().zip(&flipped) {
        if f {
            t.swap(1, 2);
            report.reoriented += 1;
        }
    }
    report.inconsistent_edges = runs
        .iter()
        .filter(|r| r.1 == 2)
        .filter(|&&(s, _)| {
            let (a, b) = ((half[s].0 >> 32) as u32, half[s].0 as u32);
            let (f, g) = (half[s].1 as usize / 3, half[s + 1].1 as usize / 3);
            forward(&tris[f], a, b) == forward(&tris[g], a, b)
        })
        .count();
    if report.closed() && report.inconsistent_edges == 0 {
        let volume: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        if volume < 0.0 {
            report.inverted = true;
            for t in &mut tris {
                t.swap(1, 2);
            }
        }
        // The file's normals must face out as the (now outward) winding does: a closed mesh whose normals mostly
        // point against its faces (an inside-out file, or normals and winding that disagree) gets them negated.
        if !normals_from_winding && mesh.normals.len() == mesh.positions.len() {
            let agreement: f64 = tris
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3());
                    let n = t.iter().map(|&i| mesh.normals[i as usize].as_dvec3()).sum::<glam::DVec3>();
                    (b - a).cross(c - a).dot(n)
                })
                .sum();
            if agreement < 0.0 {
                report.normals_negated = true;
                for n in &mut mesh.normals {
                    *n = -*n;
                }
            }
        }
    }
    let changed = report.degenerate_removed + report.duplicate_removed + report.reoriented > 0 || report.inverted;
    if changed {
        mesh.indices = tris.into_iter().flatten().collect();
        if normals_from_winding {
            mesh.compute_normals();
        }
    }
    report
}

/// The sides of a room, by the direction its wall faces away from the inside.
pub const ROOM_SIDES: [&str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

/// The inside of an axis-aligned box `size` wide, its floor centered at the origin (y from 0 to `size.y`), facing
/// inward, with the sides in `open` (of [`ROOM_SIDES`]: "-y" is the floor, "+y" the ceiling) left out. Each wall
/// holds the whole texture, upright seen from inside.
pub fn room(size: Vec3, open: &[&str]) -> Mesh {
    let h = size * 0.5;
    let c = Vec3::new(0.0, h.y, 0.0);
    let mut m = Mesh::default();
    // Each side: its name, its inward normal, and the directions of texture u (right) and v (down) seen from
    // inside (the floor's as the plane's: u along +x, v along +z).
    let sides = [
        ("+x", Vec3::NEG_X, Vec3::Z, Vec3::NEG_Y),
        ("-x", Vec3::X, Vec3::NEG_Z, Vec3::NEG_Y),
        ("+y", Vec3::NEG_Y, Vec3::X, Vec3::Z),
        ("-y", Vec3::Y, Vec3::X, Vec3::Z),
        ("+z", Vec3::NEG_Z, Vec3::NEG_X, Vec3::NEG_Y),
        ("-z", Vec3::Z, Vec3::X, Vec3::NEG_Y),
    ];
    for (name, n, u, v) in sides {
        if open.contains(&name) {
            continue;
        }
        let base = m.positions.len() as u32;
        for (su, sv) in [(-1.0f32, -1.0f32), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            m.positions.push(c - n * h + (u * su + v * sv) * h);
            m.normals.push(n);
            m.uvs.push(Vec2::new((su + 1.0) * 0.5, (sv + 1.0) * 0.5));
        }
        // Wind each face counter-clockwise seen from its normal's side.
        let (a, b) = (
            m.positions[base as usize + 1] - m.positions[base as usize],
            m.positions[base as usize + 2] - m.positions[base as usize],
        );
        if a.cross(b).dot(n) > 0.0 {
            m.indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        } else {
            m.indices.extend_from_slice(&[base, base + 2, base + 1, base, base + 3, base + 2]);
        }
    }
    m
}

/// Joints of a lathe profile sharper than this (between the two segments' directions) keep a crease: each side
/// has its own normals there.
const CREASE_DEG: f32 = 40.0;

/// A surface of revolution about the y axis: `profile` is a polyline of (radius, height) points, revolved in
/// `segments` steps. The surface faces to the right of the profile's direction in the (r, y) plane: a profile
/// that climbs the outside of a glass faces out, one that runs down the inside of a bowl faces in and up. Normals
/// are smooth along the profile except at creases (over 40°) and exact around the axis; u runs around (from -z,
/// as the sphere's), v along the profile. A closed profile (first point = last) makes a closed surface, and one
/// that starts and ends on the axis (r = 0) a solid.
pub fn lathe(profile: &[Vec2], segments: u32) -> Mesh {
    let mut m = Mesh::default();
    let n = profile.len();
    if n < 2 {
        return m;
    }
    let closed = (profile[0] - profile[n - 1]).length() < 1e-6;
    let seg_dir: Vec<Vec2> = (0..n - 1).map(|i| (profile[i + 1] - profile[i]).normalize_or_zero()).collect();
    let seg_normal = |i: usize| Vec2::new(seg_dir[i].y, -seg_dir[i].x);
    let smooth = |a: usize, b: usize| seg_dir[a].dot(seg_dir[b]) >= CREASE_DEG.to_radians().cos();
    // The normal at each end of segment i: averaged with the neighbor's across a smooth joint.
    let end_normal = |i: usize, start: bool| -> Vec2 {
        let other = match (start, closed) {
            (true, _) if i > 0 => Some(i - 1),
            (true, true) => Some(n - 2),
            (false, _) if i + 2 < n => Some(i + 1),
            (false, true) => Some(0),
            _ => None,
        };
        match other {
            Some(o) if o != i && smooth(i, o) => (seg_normal(i) + seg_normal(o)).normalize_or_zero(),
            _ => seg_normal(i),
        }
    };
    let length: f32 = (0..n - 1).map(|i| (profile[i + 1] - profile[i]).length()).sum::<f32>().max(1e-12);
    let mut along = 0.0f32;
    let segments = segments.max(3);
    for i in 0..n - 1 {
        let (p0, p1) = (profile[i], profile[i + 1]);
        let (n0, n1) = (end_normal(i, true), end_normal(i, false));
        let (v0, v1) = (along / length, (along + (p1 - p0).length()) / length);
        along += (p1 - p0).length();
        let base = m.positions.len() as u32;
        for k in 0..=segments {
            let a = k as f32 / segments as f32 * std::f32::consts::TAU;
            // Around from -z through +x, as the sphere's u.
            let (s, c) = a.sin_cos();
            let dir = Vec3::new(s, 0.0, -c);
            for (p, nn, v) in [(p0, n0, v0), (p1, n1, v1)] {
                m.positions.push(dir * p.x + Vec3::Y * p.y);
                m.normals.push((dir * nn.x + Vec3::Y * nn.y).normalize_or_zero());
                m.uvs.push(Vec2::new(k as f32 / segments as f32, v));
            }
        }
        for k in 0..segments {
            let (a0, a1, b0, b1) = (base + 2 * k, base + 2 * k + 1, base + 2 * k + 2, base + 2 * k + 3);
            for t in [[a0, b0, b1], [a0, b1, a1]] {
                let [p, q, r] = t.map(|x| m.positions[x as usize]);
                let ng = (q - p).cross(r - p);
                if ng.length() <= 1e-12 {
                    continue; // a triangle collapsed on the axis
                }
                // Counter-clockwise seen from the side the profile faces.
                let want = m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
                if ng.dot(want) >= 0.0 {
                    m.indices.extend_from_slice(&t);
                } else {
                    m.indices.extend_from_slice(&[t[0], t[2], t[1]]);
                }
            }
        }
    }
    m
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

    /// An inside-out closed mesh is turned outward, and its own normals end up facing out whether they agreed
    /// with the inside-out winding (inward) or already faced out.
    #[test]
    fn inside_out_meshes_are_turned_and_their_normals_face_out() {
        for normals_inward in [true, false] {
            let mut m = icosphere(0.3, 2);
            for t in m.indices.chunks_exact_mut(3) {
                t.swap(1, 2);
            }
            if normals_inward {
                for n in &mut m.normals {
                    *n = -*n;
                }
            }
            let r = sanitize(&mut m, false);
            assert!(r.inverted, "{r:?}");
            assert_eq!(r.normals_negated, normals_inward, "{r:?}");
            for t in m.indices.chunks_exact(3) {
                let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
                assert!((b - a).cross(c - a).dot(a + b + c) > 0.0, "winding faces out");
                assert!(m.normals[t[0] as usize].dot(a) > 0.0, "normals face out");
            }
        }
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

    /// A room's walls face inward and enclose its size: each face's winding agrees with its normal, the open side
    /// is absent, and every vertex lies on the box.
    #[test]
    fn room_faces_inward() {
        let m = room(Vec3::new(4.0, 2.0, 3.0), &["+z"]);
        assert_eq!(m.triangle_count(), 10);
        for t in m.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
            let n = m.normals[t[0] as usize];
            assert!((b - a).cross(c - a).normalize().dot(n) > 0.999, "winding against the normal");
            // Inward: the room's center lies on the normal's side.
            assert!((Vec3::new(0.0, 1.0, 0.0) - a).dot(n) > 0.0);
        }
        let (lo, hi) = m.bounds();
        assert_eq!((lo, hi), (Vec3::new(-2.0, 0.0, -1.5), Vec3::new(2.0, 2.0, 1.5)));
        assert!(m.normals.iter().all(|n| *n != Vec3::NEG_Z), "the +z wall is open");
    }

    /// A lathe of a closed cylinder profile (axis, bottom rim, top rim, axis) is a solid: its triangles' signed
    /// volume is the cylinder's, its normals point out, and its sides are smooth while the rims keep their creases.
    #[test]
    fn lathe_makes_a_closed_solid() {
        let (r, h) = (0.5f32, 2.0f32);
        let profile = [Vec2::new(0.0, 0.0), Vec2::new(r, 0.0), Vec2::new(r, h), Vec2::new(0.0, h)];
        let m = lathe(&profile, 256);
        let volume: f64 = m
            .indices
            .chunks_exact(3)
            .map(|t| {
                let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize].as_dvec3());
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        let want = std::f64::consts::PI * (r * r * h) as f64;
        // A 256-gon holds (256/2π) sin(2π/256) of the circle's area.
        assert!((volume / want - 1.0).abs() < 2e-4, "volume {volume} vs {want}");
        for (p, n) in m.positions.iter().zip(&m.normals) {
            if p.y > 1e-4 && p.y < h - 1e-4 {
                assert!(
                    (n.y.abs()) < 1e-5 && (Vec2::new(p.x, p.z).normalize().dot(Vec2::new(n.x, n.z)) - 1.0).abs() < 1e-4
                );
            }
        }
        // Caps face down and up, the sides out (the rim is a 90° crease: no averaged normal there).
        assert!(m.normals.iter().all(|n| n.y.abs() > 0.9999 || n.y.abs() < 1e-5));
        assert!(m.uvs.len() == m.positions.len());
    }
}
