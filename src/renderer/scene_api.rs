//! The scene in code: meshes in object space, instances of them with a transform and a material, and the lights.
//! A scene loaded from a file is the same thing: a TOML scene's still objects are each a mesh with the identity
//! transform; an animated object, and every glTF object, its object-space mesh with its placement.
//!
//! The renderer keeps the instances' world-space triangles in its [`Scene`] (what the light views, the reference
//! tracer and the stats read). Moving an instance rebuilds nothing: the next frame's scene update places its
//! vertices on the GPU from the object-space copy and writes its BVH instance record, without a wait. Adding an
//! instance or changing a material rebuilds the scene's GPU buffers (and its BVH, once a frame needs it) before the
//! next frame; the meshes' own data is kept, so a mesh is never read from its file again.

use super::{check_media, check_transport, Renderer};
use crate::error::{Error, Result};
use crate::scene::{mesh::MAX_COORDINATE, Material, Mesh, Object};
use crate::scene_gpu::SceneInstances;
use glam::Mat4;
use std::sync::Arc;

/// A mesh the renderer holds ([`Renderer::add_mesh`]; a loaded scene's objects have one each).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshId(u32);

/// An instance of a mesh in the scene: one of the scene's objects, in their order ([`Renderer::add_instance`]
/// appends one).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct InstanceId(u32);

impl InstanceId {
    /// The instance that is the scene's object `index`.
    pub fn from_index(index: usize) -> InstanceId {
        InstanceId(index as u32)
    }

    /// Its index among the scene's objects.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// The meshes and, per scene object, which mesh and transform it is.
pub(super) struct Instances {
    meshes: Vec<Arc<Mesh>>,
    /// (mesh index, object → world transform), one per scene object, in order.
    of_object: Vec<(usize, Mat4)>,
    /// Objects moved since the last frame recorded (its scene update places them), in index order.
    moved: std::collections::BTreeSet<usize>,
    /// Per mesh: the object-space box a deforming mesh (water) stays in.
    deforming: Vec<Option<(glam::Vec3, glam::Vec3)>>,
    /// Water objects whose time changed since the last frame recorded (its scene update displaces them).
    deformed: std::collections::BTreeSet<usize>,
}

impl Instances {
    /// A loaded scene: a still TOML object is its own mesh (its world-space triangles) with the identity transform.
    /// An object placed from its own space (animated, or glTF) instances its object-space mesh, placed where it
    /// stands at the scene's time; objects of the same mesh that does not deform (a glTF mesh under several
    /// nodes) share it, and so its bottom-level BVH.
    pub fn of(scene: &crate::scene::Scene) -> Instances {
        let mut meshes: Vec<Arc<Mesh>> = Vec::new();
        let mut deforming: Vec<Option<(glam::Vec3, glam::Vec3)>> = Vec::new();
        let mut shared: std::collections::HashMap<u64, Vec<usize>> = Default::default();
        let mut of_object = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            let (mesh, transform, deform) = match &o.animation {
                Some(a) => (&a.mesh, a.transform_at(scene.time), a.deform_bounds()),
                None => (&o.mesh, Mat4::IDENTITY, None),
            };
            // Only meshes that do not deform are shared (a deforming one is deformed and refit per object).
            let same = |k: &usize| meshes[*k].as_ref() == mesh;
            let key = deform.is_none().then(|| content_hash(mesh));
            let found = key.and_then(|h| shared.get(&h).and_then(|ks| ks.iter().copied().find(same)));
            let index = found.unwrap_or_else(|| {
                meshes.push(Arc::new(mesh.clone()));
                deforming.push(deform);
                if let Some(h) = key {
                    shared.entry(h).or_default().push(meshes.len() - 1);
                }
                meshes.len() - 1
            });
            of_object.push((index, transform));
        }
        Instances { meshes, of_object, moved: Default::default(), deforming, deformed: Default::default() }
    }

    /// The view the scene's GPU buffers are built from.
    pub fn view(&self) -> SceneInstances<'_> {
        SceneInstances { meshes: &self.meshes, objects: &self.of_object, deforming: &self.deforming }
    }

    /// Every object's transform, in order (what the caustic maps depend on besides the meshes).
    pub fn transforms(&self) -> Vec<Mat4> {
        self.of_object.iter().map(|&(_, m)| m).collect()
    }

    /// The objects moved since the last call, with their transforms.
    pub fn take_moved(&mut self) -> Vec<(usize, Mat4)> {
        std::mem::take(&mut self.moved).into_iter().map(|i| (i, self.of_object[i].1)).collect()
    }

    /// The water objects displaced since the last call.
    pub fn take_deformed(&mut self) -> Vec<usize> {
        std::mem::take(&mut self.deformed).into_iter().collect()
    }

    /// Mesh `m`.
    pub fn mesh_at(&self, m: usize) -> &Arc<Mesh> {
        &self.meshes[m]
    }

    /// Deform object `i` again in the next frame's scene update.
    pub fn mark_deformed(&mut self, i: usize) {
        self.deformed.insert(i);
    }

    /// Object `i`'s transform.
    pub fn transform_of(&self, i: usize) -> Mat4 {
        self.of_object[i].1
    }

    /// The mesh object `i` instances.
    pub fn mesh_of(&self, i: usize) -> usize {
        self.of_object[i].0
    }

    /// Forget the moves and deformations (the scene's buffers were rebuilt from the current scene).
    pub fn clear_moved(&mut self) {
        self.moved.clear();
        self.deformed.clear();
    }
}

/// A hash of a mesh's data (equal meshes hash alike).
fn content_hash(m: &Mesh) -> u64 {
    use std::hash::{Hash, Hasher};
    let mut h = std::collections::hash_map::DefaultHasher::new();
    let floats = |v: &[glam::Vec3]| v.iter().flat_map(|p| p.to_array()).map(f32::to_bits).collect::<Vec<u32>>();
    floats(&m.positions).hash(&mut h);
    floats(&m.normals).hash(&mut h);
    m.indices.hash(&mut h);
    m.uvs.iter().flat_map(|p| p.to_array()).map(f32::to_bits).collect::<Vec<u32>>().hash(&mut h);
    h.finish()
}

/// A mesh a renderer can draw: indices in range and a multiple of three, one normal per position, every coordinate
/// finite and within ±1e9.
fn check_mesh(mesh: &Mesh) -> Result<()> {
    let bad = |m: String| Err(Error::BadInput(format!("add_mesh: {m}")));
    if mesh.indices.is_empty() || !mesh.indices.len().is_multiple_of(3) {
        return bad(format!("{} indices: must be a positive multiple of 3", mesh.indices.len()));
    }
    if mesh.normals.len() != mesh.positions.len() {
        return bad(format!("{} normals for {} positions: one per position", mesh.normals.len(), mesh.positions.len()));
    }
    if let Some(i) = mesh.indices.iter().find(|&&i| i as usize >= mesh.positions.len()) {
        return bad(format!("index {i} is past the {} positions", mesh.positions.len()));
    }
    if let Some(p) = mesh.positions.iter().find(|p| !(p.is_finite() && p.abs().max_element() <= MAX_COORDINATE)) {
        return bad(format!("position {p}: must be finite and within ±1e9"));
    }
    if let Some(n) = mesh.normals.iter().find(|n| !n.is_finite()) {
        return bad(format!("normal {n}: must be finite"));
    }
    Ok(())
}

fn check_transform(m: &Mat4) -> Result<()> {
    let det = glam::Mat3::from_mat4(*m).determinant();
    if !(m.is_finite() && det.is_finite() && det.abs() > 1e-12) {
        return Err(Error::BadInput(format!("transform {m}: must be finite and invertible")));
    }
    Ok(())
}

/// A textured material's texture must be one the scene holds, and its mesh must carry texture coordinates.
fn check_map(scene: &crate::scene::Scene, material: &Material, mesh: &Mesh) -> Result<()> {
    if let Material::Diffuse { map: Some(m), .. } = material {
        if m.texture >= scene.textures.len() {
            return Err(Error::BadInput(format!(
                "albedo texture {} does not exist (the scene has {}; Renderer::add_texture adds one)",
                m.texture,
                scene.textures.len()
            )));
        }
        if mesh.uvs.len() != mesh.positions.len() {
            return Err(Error::BadInput("a textured material needs a mesh with texture coordinates".into()));
        }
        if !m.uv_transform.iter().flatten().all(|x| x.is_finite()) {
            return Err(Error::BadInput("the uv transform must be finite".into()));
        }
    }
    Ok(())
}

impl Renderer {
    /// Add an albedo texture; a diffuse material names it by the index returned ([`crate::scene::AlbedoMap`]).
    /// The textures are uploaded again before the next frame.
    pub fn add_texture(&mut self, texture: crate::scene::Texture) -> Result<usize> {
        if texture.width == 0
            || texture.height == 0
            || texture.texels.len() != (texture.width * texture.height) as usize
        {
            return Err(Error::BadInput(format!(
                "texture `{}`: {}x{} with {} texels",
                texture.name,
                texture.width,
                texture.height,
                texture.texels.len()
            )));
        }
        self.scene.textures.push(Arc::new(texture));
        self.geometry_dirty = true;
        Ok(self.scene.textures.len() - 1)
    }

    /// Add a mesh (object space) the scene can then instance any number of times.
    pub fn add_mesh(&mut self, mesh: Mesh) -> Result<MeshId> {
        check_mesh(&mesh)?;
        self.instances.meshes.push(Arc::new(mesh));
        self.instances.deforming.push(None);
        Ok(MeshId(self.instances.meshes.len() as u32 - 1))
    }

    /// Add an instance of `mesh` to the scene: a new object named `name` with `material`, placed by `transform`
    /// (object → world). Refused, with the scene unchanged, where the transport cannot render the material.
    pub fn add_instance(
        &mut self,
        mesh: MeshId,
        name: &str,
        material: Material,
        transform: Mat4,
    ) -> Result<InstanceId> {
        let m = self.mesh(mesh)?.clone();
        check_transform(&transform)?;
        check_map(&self.scene, &material, &m)?;
        self.scene.objects.push(Object::new(name, material, (*m).clone().transformed(transform)));
        if let Err(e) = check_transport(&self.scene, &self.config).and_then(|_| check_media(&self.scene)) {
            self.scene.objects.pop();
            return Err(e);
        }
        self.instances.of_object.push((mesh.0 as usize, transform));
        self.geometry_dirty = true;
        Ok(InstanceId(self.scene.objects.len() as u32 - 1))
    }

    /// Place instance `id` by `transform` (object → world, replacing its last one). Nothing is rebuilt and nothing
    /// waits: the next frame's scene update moves it on the GPU (its report's `scene` counts what that cost).
    pub fn set_transform(&mut self, id: InstanceId, transform: Mat4) -> Result<()> {
        check_transform(&transform)?;
        self.instance(id)?;
        self.place_host(id.index(), transform);
        self.instances.of_object[id.index()].1 = transform;
        self.instances.moved.insert(id.index());
        Ok(())
    }

    /// The host copy of object `i` (its world-space triangles) placed by `transform`: its mesh, deformed to the
    /// scene's time when morph targets deform it (water's stays at rest: its heights live on the GPU).
    fn place_host(&mut self, i: usize, transform: Mat4) {
        let m = self.instances.meshes[self.instances.of_object[i].0].clone();
        let o = &mut self.scene.objects[i];
        o.mesh = match o.animation.as_ref() {
            Some(a) if a.deforms() && a.water.is_none() => a.local_mesh_at(self.scene.time).transformed(transform),
            _ => (*m).clone().transformed(transform),
        };
    }

    /// Give instance `id` another material. Refused, with the material unchanged, where the transport cannot
    /// render it (a mirror or absorbing or dispersive glass under the two-interface model).
    pub fn set_material(&mut self, id: InstanceId, material: Material) -> Result<()> {
        self.instance(id)?;
        check_map(&self.scene, &material, self.instances.mesh_at(self.instances.mesh_of(id.index())))?;
        let old = std::mem::replace(&mut self.scene.objects[id.index()].material, material);
        if let Err(e) = check_transport(&self.scene, &self.config).and_then(|_| check_media(&self.scene)) {
            self.scene.objects[id.index()].material = old;
            return Err(e);
        }
        self.geometry_dirty = true;
        Ok(())
    }

    /// Move the scene's animated objects to where they stand at time `t` (s), as [`Renderer::set_transform`]
    /// would: the next frame's scene update places them on the GPU (and deforms the water and the morphing
    /// meshes). Objects that do not animate stay where they are (an animated object moved by `set_transform` goes
    /// back on its animation here). Animated cameras and lights move too.
    pub fn set_time(&mut self, t: f32) -> Result<()> {
        if !t.is_finite() {
            return Err(Error::BadInput(format!("time {t}: must be finite")));
        }
        let old = std::mem::replace(&mut self.scene.time, t);
        for i in 0..self.scene.objects.len() {
            let Some(a) = self.scene.objects[i].animation.clone().filter(|a| a.changes()) else { continue };
            let m = a.transform_at(t);
            let current = self.instances.of_object[i].1;
            if a.deforms() && t != old {
                // Deformed on the GPU by the next frame. The host copy of a morphing mesh follows (views, bounds);
                // water's stays at rest, and the light views fit its block's bounds (views.rs): no O(vertices) work
                // per frame for it.
                self.instances.deformed.insert(i);
                if m == current && a.water.is_none() {
                    self.place_host(i, current);
                }
            }
            if m != current {
                self.set_transform(InstanceId::from_index(i), m)
                    .map_err(|e| Error::BadInput(format!("object `{}` at {t} s: {e}", self.scene.objects[i].name)))?;
            }
        }
        // Animated materials (a glass's IOR) change the scene's materials: its buffers and BVH are rebuilt.
        let animates = |p: &crate::scene::PropertyTrack| matches!(p, crate::scene::PropertyTrack::ObjectIor(..));
        let before: Option<Vec<Material>> =
            self.scene.properties.iter().any(animates).then(|| self.scene.objects.iter().map(|o| o.material).collect());
        self.scene.place_movers();
        if before.is_some_and(|b| self.scene.objects.iter().zip(&b).any(|(o, m)| o.material != *m)) {
            self.geometry_dirty = true;
        }
        Ok(())
    }

    /// The time (s) the animated objects stand at.
    pub fn time(&self) -> f32 {
        self.scene.time
    }

    /// The transform instance `id` was placed with (for a loaded scene's objects: a glTF node's world transform,
    /// an animated object's at the scene's time, the identity for a TOML scene's still objects).
    pub fn transform(&self, id: InstanceId) -> Result<Mat4> {
        Ok(self.instance(id)?.1)
    }

    fn instance(&self, id: InstanceId) -> Result<(MeshId, Mat4)> {
        self.instances.of_object.get(id.index()).map(|&(m, t)| (MeshId(m as u32), t)).ok_or_else(|| {
            Error::BadInput(format!("instance {}: the scene has {} objects", id.0, self.scene.objects.len()))
        })
    }

    fn mesh(&self, id: MeshId) -> Result<&Arc<Mesh>> {
        self.instances
            .meshes
            .get(id.0 as usize)
            .ok_or_else(|| Error::BadInput(format!("mesh {}: {} meshes were added", id.0, self.instances.meshes.len())))
    }
}
