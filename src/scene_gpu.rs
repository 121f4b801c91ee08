//! The scene's triangles on the GPU: one vertex buffer and one index buffer in world space, receivers first, then
//! refractors, for rasterization, with the same vertices and indices in each object's own space, from which the
//! frame's scene update (src/passes/scene_update.rs) places a moved object; and the scene BVH (src/bvh/) for
//! exact transport, built when a frame first needs it.

use crate::bvh::{BvhLayout, BvhObject, GpuInstance, SceneBvh};
use crate::gpu_types::{GpuPointNormal, GpuWaveRecord, Vertex};
use crate::gpu_types::{MorphPush, SceneUpdatePush, WaterPush};
use crate::scene::{Material, Mesh, Scene};
use crate::vk::{cmd::upload_buffer, cmd::upload_image, Buffer, Device, Image, Recorder, Sampler, VkResult};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

/// The scene's objects as meshes and instances: per object (in the scene's order), the mesh it instances, in
/// object space, and its transform (object → world) ([`crate::renderer`]'s `Instances::of` says how a loaded
/// scene's objects become them).
pub(crate) struct SceneInstances<'a> {
    pub meshes: &'a [Arc<Mesh>],
    /// (index into `meshes`, transform), one per scene object.
    pub objects: &'a [(usize, Mat4)],
    /// Per mesh: the object-space box a deforming mesh (water) stays in (its BVH is refit on the GPU).
    pub deforming: &'a [Option<(glam::Vec3, glam::Vec3)>],
}

/// One object's vertices and indices in the scene's buffers.
#[derive(Clone, Copy, Debug, Default)]
pub struct ObjectRange {
    pub first_vertex: u32,
    pub vertex_count: u32,
    pub first_index: u32,
    pub index_count: u32,
}

/// How an object deforms on the GPU: the scene update displaces its raster vertices and its BVH triangles, and
/// refits its BVH.
#[derive(Clone, Copy, Debug)]
pub enum Deformer {
    /// Water: its waves, and its simulated surface.
    Water(WaterRange),
    /// Morph targets.
    Morph(MorphRange),
}

/// A water object's part of `SceneBuffers::waves` and `heights`.
#[derive(Clone, Copy, Debug)]
pub struct WaterRange {
    /// Its first wave record ([`GpuWaveRecord`]) and how many waves.
    pub first_wave: u32,
    pub wave_count: u32,
    /// Its first vertex in `SceneBuffers::displaced`.
    pub first_displaced: u32,
    /// Its simulated surface: the first of its heights' two slots of nodes² floats in `SceneBuffers::heights`,
    /// and its step (its nodes and spacing are also in `waves`, the record after its waves).
    pub simulation: Option<(u32, crate::scene::water::StepCoefficients)>,
}

/// Where a simulated water surface stands on the GPU: steps taken since rest, and the slot holding its heights
/// now. The scene update steps it to the frame's time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SimulationState {
    pub steps: u64,
    pub slot: u32,
}

/// What the deforming objects upload: water's waves and the size of its heights, and the morph targets and
/// the count of their weights.
#[derive(Default)]
struct DeformData {
    waves: Vec<GpuWaveRecord>,
    heights: u32,
    displaced: u32,
    morphs: Vec<GpuPointNormal>,
    weights: u32,
}

impl DeformData {
    /// Water `w` (`vertices` vertices): its waves, its simulated surface's record and heights, and its displaced
    /// vertices.
    fn water(&mut self, w: &crate::scene::water::Water, vertices: u32) -> WaterRange {
        let first_displaced = self.displaced;
        self.displaced += vertices;
        let first_wave = self.waves.len() as u32;
        for wave in &w.waves {
            let k = std::f32::consts::TAU / wave.wavelength;
            self.waves.push(GpuWaveRecord {
                a: [wave.direction.x, wave.direction.y, k, k * wave.speed],
                b: [wave.amplitude, 0.0, 0.0, 0.0],
            });
        }
        let simulation = w.step_coefficients().map(|k| {
            self.waves.push(GpuWaveRecord { a: [f32::from_bits(k.nodes), 0.5 / k.dx, 0.5 / k.dz, 0.0], b: [0.0; 4] });
            let base = self.heights;
            self.heights += 2 * k.nodes * k.nodes;
            (base, k)
        });
        WaterRange { first_wave, wave_count: w.waves.len() as u32, first_displaced, simulation }
    }

    /// A morphing mesh's base (`base`, object space) and targets.
    fn morph(&mut self, base: &crate::scene::Mesh, m: &crate::scene::morph::Morph) -> MorphRange {
        let range = MorphRange {
            first: self.morphs.len() as u32,
            vertices: base.positions.len() as u32,
            targets: m.targets.len() as u32,
            first_weight: self.weights,
        };
        let v4 = |v: &glam::Vec3| [v.x, v.y, v.z, 0.0];
        for (p, n) in base.positions.iter().zip(&base.normals) {
            self.morphs.push(GpuPointNormal { position: v4(p), normal: v4(n) });
        }
        for t in &m.targets {
            for (k, p) in t.positions.iter().enumerate() {
                self.morphs.push(GpuPointNormal { position: v4(p), normal: t.normals.get(k).map_or([0.0; 4], v4) });
            }
        }
        self.weights += range.targets;
        range
    }
}

/// A morphing object's part of `SceneBuffers::morphs` and `morph_weights`.
#[derive(Clone, Copy, Debug, Default)]
pub struct MorphRange {
    /// Its base vertices ([`GpuPointNormal`]), each target's displacements `vertices` further on.
    pub first: u32,
    pub vertices: u32,
    pub targets: u32,
    /// Its first weight.
    pub first_weight: u32,
}

#[derive(Clone, Copy, Debug, Default)]
pub struct DrawRange {
    pub first_index: u32,
    pub index_count: u32,
}

pub struct SceneBuffers {
    /// World space: what the rasterizer draws (the scene update rewrites a moved object's).
    pub vertices: Buffer,
    pub indices: Buffer,
    /// The same in each object's own space (what the scene update transforms).
    pub object_vertices: Buffer,
    pub object_indices: Buffer,
    /// Per scene object, in order: its range in both.
    pub objects: Vec<ObjectRange>,
    pub receivers: DrawRange,
    pub refractors: DrawRange,
    /// The IOR every refractor's vertices carry, when they all carry the same ([`shared_ior`]).
    pub shared_ior: Option<f32>,
    pub bvh: BvhBuffers,
    /// Every water object's waves, and after a simulated one's, its surface's record ([`GpuWaveRecord`]).
    pub waves: Buffer,
    /// Every simulated water surface's heights (m), two slots each ([`WaterRange::simulation`]).
    pub heights: Buffer,
    /// Every water object's vertices displaced to the frame's time, in object space ([`GpuPointNormal`]), written
    /// with its raster vertices and read by its BVH triangles (each vertex displaced once).
    pub displaced: Buffer,
    /// Per scene object: where its simulated surface stands on the GPU (what the recorded frames stepped it to).
    pub simulations: Vec<Option<SimulationState>>,
    /// Every morphing object's base vertices and morph targets (glsl/morph.comp), and their weights (the frame's
    /// scene update writes them).
    pub morphs: Buffer,
    pub morph_weights: Buffer,
    /// Per scene object: how it deforms on the GPU, if it does.
    pub deformers: Vec<Option<Deformer>>,
    /// The albedo textures and the environment.
    pub images: SceneImages,
}

/// The scene's sampled images, uploaded once and never written again (so no frame declares them to the
/// tracker): the receivers' albedo textures as the layers of one array, and the environment map with its
/// irradiance map.
pub struct SceneImages {
    /// Layer i: the scene's texture i, resized to a common square size with its full mip chain (16-bit linear
    /// reflectance; a white texel when the scene has none).
    pub albedo: Image,
    /// The environment's radiance (map units, RGBA32F; one black texel for the procedural sky).
    pub environment: Image,
    /// Its irradiance per normal direction, same layout (docs/design.md "Environment").
    pub environment_irradiance: Image,
    /// Trilinear, repeating (the albedo textures).
    pub repeat: Sampler,
    /// Bilinear, wrapping in longitude, clamped in latitude (the environment maps).
    pub equirect: Sampler,
    /// The scene has albedo textures (else `albedo` is the one white texel, and no receiver reads it).
    pub textured: bool,
}

impl SceneImages {
    fn new(device: &Arc<Device>, recorder: &mut Recorder, scene: &Scene) -> VkResult<Self> {
        use crate::scene::texture::MAX_TEXTURE_SIZE;
        let side = scene.textures.iter().map(|t| t.width.max(t.height)).max().unwrap_or(1).min(MAX_TEXTURE_SIZE);
        let mut levels: Vec<Vec<[u16; 4]>> = Vec::new();
        for t in &scene.textures {
            for (l, mip) in t.mip_chain(side).into_iter().enumerate() {
                if levels.len() <= l {
                    levels.push(Vec::new());
                }
                levels[l].extend(mip);
            }
        }
        if levels.is_empty() {
            levels.push(vec![[u16::MAX; 4]]);
        }
        let extent = vk::Extent2D { width: side, height: side };
        let layers = scene.textures.len().max(1) as u32;
        let albedo = upload_image(
            device,
            recorder,
            "albedo textures",
            vk::Format::R16G16B16A16_UNORM,
            extent,
            Some(layers),
            &levels,
        )?;
        // The environment map and its irradiance map (one black texel each for the procedural sky).
        let black = [[0.0f32; 3]];
        let w = crate::scene::environment::IRRADIANCE_WIDTH;
        let (map, map_size, irr, irr_size) = match &scene.environment {
            Some(e) => (&e.map.texels[..], (e.map.width, e.map.height), e.map.irradiance_map(), (w, w / 2)),
            None => (&black[..], (1, 1), &black[..], (1, 1)),
        };
        let mut equirect = |name: &str, (width, height): (u32, u32), texels: &[[f32; 3]]| {
            let rgba: Vec<[f32; 4]> = texels.iter().map(|c| [c[0], c[1], c[2], 1.0]).collect();
            let f32x4 = vk::Format::R32G32B32A32_SFLOAT;
            upload_image(device, recorder, name, f32x4, vk::Extent2D { width, height }, None, &[rgba])
        };
        let environment = equirect("environment", map_size, map)?;
        let environment_irradiance = equirect("environment irradiance", irr_size, irr)?;
        Ok(SceneImages {
            albedo,
            environment,
            environment_irradiance,
            repeat: Sampler::repeating(device, true)?,
            equirect: Sampler::repeating(device, false)?,
            textured: !scene.textures.is_empty(),
        })
    }
}

/// The scene BVH in storage buffers: the node layouts frames have traced with, triangles, their vertex normals,
/// and the instances. Built on the host when the first exact-transport frame needs it (the two-interface model
/// reads none of it); until then, and for the layouts no frame has used, each binding holds a one-element buffer.
pub struct BvhBuffers {
    pub pair_nodes: Buffer,
    pub single_nodes: Buffer,
    pub threaded_nodes: Buffer,
    /// The wide layout's nodes and its triangle list (indices into `triangles`).
    pub wide_nodes: Buffer,
    pub wide_prims: Buffer,
    pub triangles: Buffer,
    pub normals: Buffer,
    pub instances: Buffer,
    /// The deforming meshes' refit nodes, leaves, box scratch (two vec4 per node), arrival counters (one per
    /// node), and triangles at rest (positions, vertex normals).
    pub refit_nodes: Buffer,
    pub refit_order: Buffer,
    pub refit_boxes: Buffer,
    /// The deforming meshes' wide nodes by height, and a box scratch for them (two vec4 per wide node).
    pub wide_refit_order: Buffer,
    pub wide_refit_boxes: Buffer,
    pub rest_tris: Buffer,
    pub rest_normals: Buffer,
    /// Per rest triangle, its vertices' indices in its mesh (three u32).
    pub rest_corners: Buffer,
    /// The deforming meshes' triangles and boxes on the GPU are the rest ones (just built or a layout just
    /// uploaded from the host copy): the next frame displaces and refits them whatever moved.
    pub stale_deform: bool,
    /// The layout the frames trace (None before an exact-transport frame): a deforming mesh's refit keeps only
    /// the nodes they read current ([`BvhBuffers::trace_with`]).
    traced: Option<BvhLayout>,
    /// The host BVH once built (the layouts not uploaded yet come from it).
    host: Option<SceneBvh>,
    /// Which layouts are uploaded: pair, single, threaded, wide.
    uploaded: [bool; 4],
    /// Host build time of this BVH (ms), the bottom-level BVHs built, node counts and triangle count.
    pub build_ms: f64,
    pub blas_builds: usize,
    pub pair_node_count: usize,
    pub single_node_count: usize,
    pub threaded_node_count: usize,
    pub wide_node_count: usize,
    pub triangle_count: usize,
    pub instance_count: usize,
}

/// The texel formats the wide layout's variants read the BVH as (glsl/common/bvh.glsl): four 32-bit floats (a
/// triangle's vertex, a normal row, a twelfth of an instance) or four 32-bit unsigned integers (a fifth of a wide
/// node, a vertex of the wide triangle list with the triangle's index).
const FLOAT4: (vk::Format, u64) = (vk::Format::R32G32B32A32_SFLOAT, 16);
const UINT4: (vk::Format, u64) = (vk::Format::R32G32B32A32_UINT, 16);

/// A BVH buffer with the texel view those variants read it through.
fn texels(buffer: Buffer, (format, bytes): (vk::Format, u64)) -> VkResult<Buffer> {
    buffer.with_texel_view(format, bytes)
}

/// Empty lists still need a buffer to bind: one zeroed element.
fn nonempty<T: bytemuck::Pod + Default>(v: &[T]) -> Vec<T> {
    if v.is_empty() {
        vec![T::default()]
    } else {
        v.to_vec()
    }
}

/// An instance whose bounds nothing enters (what an empty scene binds).
fn no_instance() -> GpuInstance {
    GpuInstance {
        lo: [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0],
        hi: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0],
        ..GpuInstance::default()
    }
}

impl BvhBuffers {
    /// Placeholders: one element per binding, no BVH built.
    pub fn placeholders(device: &Arc<Device>, recorder: &mut Recorder) -> VkResult<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let readable = storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let zeros = [[0u32; 4]; 4];
        Ok(BvhBuffers {
            pair_nodes: upload_buffer(device, recorder, "bvh pair nodes (none)", &zeros, storage)?,
            single_nodes: upload_buffer(device, recorder, "bvh single nodes (none)", &zeros, storage)?,
            threaded_nodes: upload_buffer(device, recorder, "bvh threaded nodes (none)", &zeros, storage)?,
            wide_nodes: texels(
                upload_buffer(device, recorder, "bvh wide nodes (none)", &[[0u32; 20]], readable)?,
                UINT4,
            )?,
            wide_prims: texels(upload_buffer(device, recorder, "bvh wide triangles (none)", &zeros, readable)?, UINT4)?,
            triangles: texels(upload_buffer(device, recorder, "bvh triangles (none)", &zeros, readable)?, FLOAT4)?,
            normals: texels(upload_buffer(device, recorder, "bvh normals (none)", &zeros, readable)?, FLOAT4)?,
            instances: texels(
                upload_buffer(device, recorder, "bvh instances (none)", &[no_instance()], readable)?,
                FLOAT4,
            )?,
            refit_nodes: upload_buffer(device, recorder, "refit nodes (none)", &zeros, storage)?,
            refit_order: upload_buffer(device, recorder, "refit order (none)", &zeros, storage)?,
            refit_boxes: upload_buffer(device, recorder, "refit boxes (none)", &zeros, storage)?,
            wide_refit_order: upload_buffer(device, recorder, "wide refit order (none)", &zeros, storage)?,
            wide_refit_boxes: upload_buffer(device, recorder, "wide refit boxes (none)", &zeros, storage)?,
            rest_tris: upload_buffer(device, recorder, "rest triangles (none)", &zeros, storage)?,
            rest_normals: upload_buffer(device, recorder, "rest normals (none)", &zeros, storage)?,
            rest_corners: upload_buffer(device, recorder, "rest corners (none)", &zeros, storage)?,
            stale_deform: false,
            traced: None,
            host: None,
            uploaded: [false; 4],
            build_ms: 0.0,
            blas_builds: 0,
            pair_node_count: 0,
            single_node_count: 0,
            threaded_node_count: 0,
            wide_node_count: 0,
            triangle_count: 0,
            instance_count: 0,
        })
    }

    /// Whether the BVH has been built.
    pub fn is_built(&self) -> bool {
        self.host.is_some()
    }

    /// Whether the BVH is built and `layout`'s nodes (with the pair layout's) are on the GPU.
    pub fn has(&self, layout: BvhLayout) -> bool {
        self.host.is_some() && self.uploaded[0] && self.uploaded[Self::slot(layout)]
    }

    /// The layout's slot in `uploaded`.
    fn slot(layout: BvhLayout) -> usize {
        match layout {
            BvhLayout::Pair | BvhLayout::Auto => 0,
            BvhLayout::Single => 1,
            BvhLayout::Threaded => 2,
            BvhLayout::Wide => 3,
        }
    }

    /// The node count of `layout` (the pair layout's for `auto`).
    pub fn node_count(&self, layout: BvhLayout) -> usize {
        match layout {
            BvhLayout::Pair | BvhLayout::Auto => self.pair_node_count,
            BvhLayout::Single => self.single_node_count,
            BvhLayout::Threaded => self.threaded_node_count,
            BvhLayout::Wide => self.wide_node_count,
        }
    }

    /// Build the BVH if no frame has needed it yet, and upload the nodes of `layout` (and the pair layout, which
    /// the eye view's glass tracing reads) if they are not on the GPU yet. The buffers it replaces must not be in
    /// use by a frame in flight.
    pub(crate) fn ensure(
        &mut self,
        device: &Arc<Device>,
        recorder: &mut Recorder,
        scene: &Scene,
        instances: &SceneInstances,
        layout: BvhLayout,
        cache: &mut crate::bvh::BlasCache,
    ) -> VkResult<()> {
        // (Transfer source: tests read the refit BVH back.)
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_SRC;
        let readable = storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        if self.host.is_none() {
            let objects: Vec<BvhObject> = instances
                .objects
                .iter()
                .zip(&scene.objects)
                .map(|(&(mesh, transform), o)| BvhObject { mesh, transform, material: &o.material })
                .collect();
            cache.retain(instances.meshes);
            let mut bvh = SceneBvh::build_cached(instances.meshes, &objects, instances.deforming, cache);
            bvh.set_media((0..scene.objects.len()).map(|i| (scene.outside_of(i), scene.objects[i].priority)));
            log::info!("scene BVH: {} triangles, built in {:.0} ms", bvh.triangles.len(), bvh.build_ms);
            let tris = upload_buffer(device, recorder, "bvh triangles", &nonempty(&bvh.triangles), readable)?;
            self.triangles = texels(tris, FLOAT4)?;
            let normals = upload_buffer(device, recorder, "bvh normals", &nonempty(&bvh.normals), readable)?;
            self.normals = texels(normals, FLOAT4)?;
            let instances = if bvh.instances.is_empty() { vec![no_instance()] } else { bvh.instances.clone() };
            self.instances = texels(upload_buffer(device, recorder, "bvh instances", &instances, readable)?, FLOAT4)?;
            if !bvh.refit_nodes.is_empty() {
                let n = bvh.refit_nodes.len();
                self.refit_nodes = upload_buffer(device, recorder, "refit nodes", &bvh.refit_nodes, storage)?;
                self.refit_order = upload_buffer(device, recorder, "refit order", &bvh.refit_order, storage)?;
                let boxes = vec![[0f32; 4]; 2 * n];
                self.refit_boxes = upload_buffer(device, recorder, "refit boxes", &boxes, storage)?;
                let order = &bvh.wide_refit_order;
                self.wide_refit_order = upload_buffer(device, recorder, "wide refit order", order, storage)?;
                let boxes = vec![[0f32; 4]; 2 * bvh.wide_nodes.len()];
                self.wide_refit_boxes = upload_buffer(device, recorder, "wide refit boxes", &boxes, storage)?;
                self.rest_tris = upload_buffer(device, recorder, "rest triangles", &bvh.rest_tris, storage)?;
                self.rest_normals = upload_buffer(device, recorder, "rest normals", &bvh.rest_normals, storage)?;
                self.rest_corners = upload_buffer(device, recorder, "rest corners", &bvh.rest_corners, storage)?;
            }
            self.build_ms = bvh.build_ms;
            self.blas_builds += bvh.blas_builds;
            self.pair_node_count = bvh.pair_nodes.len();
            self.single_node_count = bvh.single_nodes.len();
            self.threaded_node_count = bvh.threaded_nodes.len();
            self.wide_node_count = bvh.wide_nodes.len();
            self.triangle_count = bvh.triangles.len();
            self.instance_count = bvh.instances.len();
            self.host = Some(bvh);
        }
        let bvh = self.host.as_ref().expect("built");
        let mut wanted = [true, false, false, false];
        wanted[Self::slot(layout)] = true;
        if wanted[0] && !self.uploaded[0] {
            self.pair_nodes = upload_buffer(device, recorder, "bvh pair nodes", &nonempty(&bvh.pair_nodes), storage)?;
        }
        if wanted[1] && !self.uploaded[1] {
            self.single_nodes =
                upload_buffer(device, recorder, "bvh single nodes", &nonempty(&bvh.single_nodes), storage)?;
        }
        if wanted[2] && !self.uploaded[2] {
            self.threaded_nodes =
                upload_buffer(device, recorder, "bvh threaded nodes", &nonempty(&bvh.threaded_nodes), storage)?;
        }
        if wanted[3] && !self.uploaded[3] {
            let nodes = upload_buffer(device, recorder, "bvh wide nodes", &nonempty(&bvh.wide_nodes), readable)?;
            self.wide_nodes = texels(nodes, UINT4)?;
            let records = nonempty(&bvh.wide_triangle_records());
            let prims = upload_buffer(device, recorder, "bvh wide triangles", &records, readable)?;
            self.wide_prims = texels(prims, UINT4)?;
        }
        let new_layout = self.uploaded.iter().zip(wanted).any(|(&u, w)| w && !u);
        for (u, w) in self.uploaded.iter_mut().zip(wanted) {
            *u |= w;
        }
        // Uploaded from the host copy, a deforming mesh's boxes and triangles are its rest ones.
        if new_layout && !bvh.refit_nodes.is_empty() {
            self.stale_deform = true;
        }
        Ok(())
    }
}

impl BvhBuffers {
    /// Move object `i` (once the BVH is built): its instance record on the host, which the frame's scene update
    /// then writes to the GPU. Returns whether there is a BVH to update.
    pub(crate) fn set_transform(&mut self, i: usize, world_from_object: Mat4) -> bool {
        match self.host.as_mut() {
            Some(bvh) => {
                bvh.set_transform(i, world_from_object);
                true
            }
            None => false,
        }
    }

    #[cfg(test)]
    /// The host copy (rest boxes for deforming meshes).
    pub(crate) fn host(&self) -> Option<&SceneBvh> {
        self.host.as_ref()
    }

    #[cfg(test)]
    /// The BVH as the GPU holds it now (after the frames that wrote it have completed): the host copy with the
    /// GPU's nodes of every uploaded layout, triangles, normals and instances.
    pub(crate) fn download(&self, device: &Arc<Device>, recorder: &mut Recorder) -> VkResult<Option<SceneBvh>> {
        use crate::vk::cmd::download_buffer;
        let Some(host) = &self.host else { return Ok(None) };
        let mut b = host.clone();
        b.triangles = download_buffer(device, recorder, &self.triangles, b.triangles.len())?;
        b.normals = download_buffer(device, recorder, &self.normals, b.normals.len())?;
        b.instances = download_buffer(device, recorder, &self.instances, b.instances.len())?;
        if self.uploaded[0] {
            b.pair_nodes = download_buffer(device, recorder, &self.pair_nodes, b.pair_nodes.len())?;
        }
        if self.uploaded[1] {
            b.single_nodes = download_buffer(device, recorder, &self.single_nodes, b.single_nodes.len())?;
        }
        if self.uploaded[3] {
            b.wide_nodes = download_buffer(device, recorder, &self.wide_nodes, b.wide_nodes.len())?;
        }
        Ok(Some(b))
    }

    #[cfg(test)]
    /// The wide triangle list as the GPU holds it now (`SceneBvh::wide_triangle_records`' layout), when uploaded.
    pub(crate) fn download_wide_records(
        &self,
        device: &Arc<Device>,
        recorder: &mut Recorder,
    ) -> VkResult<Option<Vec<[u32; 4]>>> {
        use crate::vk::cmd::download_buffer;
        match &self.host {
            Some(host) if self.uploaded[3] => {
                Ok(Some(download_buffer(device, recorder, &self.wide_prims, 3 * host.wide_prims.len())?))
            }
            _ => Ok(None),
        }
    }

    /// Mesh `mesh`'s refit data, when it deforms and the BVH is built.
    pub(crate) fn refit_mesh(&self, mesh: usize) -> Option<crate::bvh::RefitMesh> {
        self.host.as_ref().and_then(|b| b.refit_meshes.get(mesh).copied().flatten())
    }

    /// The heights of refit mesh `r`'s nodes, lowest first: each `[first, count]` in the refit order.
    pub(crate) fn refit_levels(&self, r: &crate::bvh::RefitMesh) -> Vec<[u32; 2]> {
        let levels = self.host.as_ref().map_or(&[][..], |b| &b.refit_levels[..]);
        levels_of(levels, r.first_level, r.levels)
    }

    /// This frame traces `layout` (exact transport). The refit writes only what such frames read: the wide
    /// layout's nodes when it is traced (the waves, the checks and the glass pass all walk it), else the traced
    /// binary layout's and the pair layout's (the checks and the glass pass walk pair). So when the traced layout
    /// changes, the deforming meshes' nodes it reads may be stale: every one is displaced and refit again.
    pub(crate) fn trace_with(&mut self, layout: BvhLayout) {
        if self.traced.is_some_and(|t| t != layout) && self.deforms() {
            self.stale_deform = true;
        }
        self.traced = Some(layout);
    }

    /// Whether some mesh deforms (is refit on the GPU).
    fn deforms(&self) -> bool {
        self.host.as_ref().is_some_and(|h| !h.refit_order.is_empty())
    }

    /// Whether the refit writes the wide layout: it is on the GPU and traced (or no frame has traced yet).
    fn refits_wide(&self) -> bool {
        self.uploaded[3] && self.traced.is_none_or(|t| t == BvhLayout::Wide)
    }

    /// The heights of refit mesh `r`'s wide nodes, lowest first, when the refit writes the wide layout (else
    /// none): each `[first, count]` in the wide refit order.
    pub(crate) fn wide_refit_levels(&self, r: &crate::bvh::RefitMesh) -> Vec<[u32; 2]> {
        let levels = self.host.as_ref().filter(|_| self.refits_wide()).map_or(&[][..], |b| &b.wide_refit_levels[..]);
        levels_of(levels, r.wide_first_level, r.wide_levels)
    }

    /// The binary layouts the refit writes, as its mask (REFIT_PAIR, REFIT_SINGLE, REFIT_THREADED): those on the GPU that
    /// frames read (none when they trace the wide layout, which has a pass of its own). 0: no binary refit.
    pub(crate) fn layout_mask(&self) -> u32 {
        let read = |k: usize| match self.traced {
            None => true,
            Some(BvhLayout::Wide) => false,
            Some(t) => k == 0 || k == Self::slot(t),
        };
        use crate::shaders::consts::{REFIT_PAIR, REFIT_SINGLE, REFIT_THREADED};
        let bits =
            [(BvhLayout::Pair, REFIT_PAIR), (BvhLayout::Single, REFIT_SINGLE), (BvhLayout::Threaded, REFIT_THREADED)];
        bits.iter()
            .map(|&(l, bit)| (Self::slot(l), bit))
            .filter(|&(k, _)| self.uploaded[k] && read(k))
            .map(|(_, bit)| bit)
            .sum()
    }

    /// The instance records as the GPU buffer holds them (None before the BVH is built).
    pub(crate) fn instance_records(&self) -> Option<&[GpuInstance]> {
        self.host.as_ref().filter(|b| !b.instances.is_empty()).map(|b| &b.instances[..])
    }
}

/// A mesh's run of `count` heights from `first` in a refit's height list (none where the list is empty).
fn levels_of(levels: &[[u32; 2]], first: u32, count: u32) -> Vec<[u32; 2]> {
    levels.get(first as usize..(first + count) as usize).unwrap_or(&[]).to_vec()
}

/// A refractor's gray index of refraction as the light and eye views' IOR buffers hold it. A negative IOR marks a
/// mirror for the eye view's deferred shading (composite.comp).
fn refractor_ior(m: &Material) -> f32 {
    match *m {
        Material::Dielectric { ior, .. } => ior,
        _ => -1.0,
    }
}

/// The scene's triangles as the GPU holds them: the receivers' draw range, then the refractors', in world space
/// and (for the scene update's refits and deformers) in object space, with each object's ranges.
struct Geometry {
    vertices: Vec<Vertex>,
    indices: Vec<u32>,
    object_vertices: Vec<Vertex>,
    object_indices: Vec<u32>,
    objects: Vec<ObjectRange>,
    receivers: DrawRange,
    refractors: DrawRange,
}

impl Geometry {
    fn gather(scene: &Scene, instances: &SceneInstances) -> Self {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut object_vertices = Vec::new();
        let mut object_indices = Vec::new();
        let mut objects = vec![ObjectRange::default(); scene.objects.len()];
        let mut push = |refractors: bool| {
            let start = indices.len() as u32;
            for (i, o) in scene.objects.iter().enumerate().filter(|(_, o)| o.is_refractor() == refractors) {
                let base = vertices.len() as u32;
                // A receiver's w: -(its albedo texture's layer + 1), 0 for none; a refractor's 1.
                let (material, map) = match o.material {
                    Material::Diffuse { albedo, map } => {
                        ([albedo.x, albedo.y, albedo.z, map.map_or(0.0, |m| -(m.texture as f32) - 1.0)], map)
                    }
                    _ => ([refractor_ior(&o.material), 0.0, 0.0, 1.0], None),
                };
                // The texture coordinates, through the material's uv transform, in the position's and the
                // normal's w.
                let vertex = |p: &glam::Vec3, n: &glam::Vec3, uv: glam::Vec2| {
                    let uv = map.map_or(uv, |m| m.apply(uv));
                    Vertex { position: [p.x, p.y, p.z, uv.x], normal: [n.x, n.y, n.z, uv.y], material }
                };
                let uv = |m: &Mesh, k: usize| m.uvs.get(k).copied().unwrap_or(glam::Vec2::ZERO);
                objects[i] = ObjectRange {
                    first_vertex: base,
                    vertex_count: o.mesh.positions.len() as u32,
                    first_index: indices.len() as u32,
                    index_count: o.mesh.indices.len() as u32,
                };
                vertices.extend(
                    o.mesh
                        .positions
                        .iter()
                        .zip(&o.mesh.normals)
                        .enumerate()
                        .map(|(k, (p, n))| vertex(p, n, uv(&o.mesh, k))),
                );
                indices.extend(o.mesh.indices.iter().map(|i| i + base));
                let local = &instances.meshes[instances.objects[i].0];
                object_vertices.extend(
                    local
                        .positions
                        .iter()
                        .zip(&local.normals)
                        .enumerate()
                        .map(|(k, (p, n))| vertex(p, n, uv(local, k))),
                );
                object_indices.extend(local.indices.iter().map(|i| i + base));
            }
            DrawRange { first_index: start, index_count: indices.len() as u32 - start }
        };
        let receivers = push(false);
        let refractors = push(true);
        Geometry { vertices, indices, object_vertices, object_indices, objects, receivers, refractors }
    }
}

impl SceneBuffers {
    pub(crate) fn new(
        device: &Arc<Device>,
        recorder: &mut Recorder,
        scene: &Scene,
        instances: &SceneInstances,
    ) -> VkResult<Self> {
        let Geometry { vertices, indices, object_vertices, object_indices, objects, receivers, refractors } =
            Geometry::gather(scene, instances);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let vertices = upload_buffer(
            device,
            recorder,
            "scene vertices",
            &vertices,
            vk::BufferUsageFlags::VERTEX_BUFFER | storage,
        )?;
        let indices =
            upload_buffer(device, recorder, "scene indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER | storage)?;
        let object_vertices =
            upload_buffer(device, recorder, "scene vertices (object space)", &object_vertices, storage)?;
        let object_indices = upload_buffer(device, recorder, "scene indices (object space)", &object_indices, storage)?;
        let bvh = BvhBuffers::placeholders(device, recorder)?;
        let mut data = DeformData::default();
        let deformers: Vec<Option<Deformer>> = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let a = o.animation.as_ref()?;
                if let Some(w) = &a.water {
                    let vertices = instances.meshes[instances.objects[i].0].positions.len() as u32;
                    return Some(Deformer::Water(data.water(w, vertices)));
                }
                let m = a.morph.as_ref().filter(|m| m.is_animated())?;
                // The mesh the GPU holds for it: its base, in object space.
                Some(Deformer::Morph(data.morph(&instances.meshes[instances.objects[i].0], m)))
            })
            .collect();
        let DeformData { waves, heights, displaced, morphs, weights } = data;
        let displaced = vec![GpuPointNormal::default(); displaced.max(1) as usize];
        let displaced = upload_buffer(device, recorder, "water vertices (displaced)", &displaced, storage)?;
        let waves = upload_buffer(device, recorder, "water waves", &nonempty(&waves), storage)?;
        let simulations = deformers
            .iter()
            .map(|d| match d {
                Some(Deformer::Water(w)) if w.simulation.is_some() => Some(SimulationState::default()),
                _ => None,
            })
            .collect();
        let heights = vec![0f32; heights.max(1) as usize];
        let heights = upload_buffer(
            device,
            recorder,
            "water heights",
            &heights,
            storage | vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
        )?;
        let morphs = upload_buffer(device, recorder, "morph targets", &nonempty(&morphs), storage)?;
        let weights = vec![0f32; weights.max(1) as usize];
        let morph_weights =
            upload_buffer(device, recorder, "morph weights", &weights, storage | vk::BufferUsageFlags::TRANSFER_DST)?;
        let images = SceneImages::new(device, recorder, scene)?;
        Ok(SceneBuffers {
            images,
            waves,
            heights,
            displaced,
            simulations,
            morphs,
            morph_weights,
            deformers,
            vertices,
            indices,
            object_vertices,
            object_indices,
            objects,
            receivers,
            refractors,
            shared_ior: scene.shared_ior(),
            bvh,
        })
    }
}

// The push constants that place and deform the scene's objects, from its ranges (src/gpu_types.rs holds only
// the data).

impl SceneUpdatePush {
    /// Object `range` placed by `world_from_object`.
    pub fn new(world_from_object: glam::Mat4, range: &crate::scene_gpu::ObjectRange) -> Self {
        let m3 = glam::Mat3::from_mat4(world_from_object);
        let n = m3.inverse().transpose();
        let mut nrows = [0, 1, 2].map(|r| n.row(r).extend(0.0).to_array());
        nrows[0][3] = if m3.determinant() < 0.0 { 1.0 } else { 0.0 };
        SceneUpdatePush {
            rows: [0, 1, 2].map(|r| world_from_object.row(r).to_array()),
            nrows,
            first_vertex: range.first_vertex,
            vertex_count: range.vertex_count,
            first_index: range.first_index,
            index_count: range.index_count,
        }
    }
}

impl WaterPush {
    /// The raster vertices of object `range` placed by `world_from_object`, at `time`, with `water`'s waves and
    /// its simulated surface's heights now (the first float of `heights`, when it has one).
    pub fn raster(
        world_from_object: glam::Mat4,
        range: &crate::scene_gpu::ObjectRange,
        time: f32,
        water: &crate::scene_gpu::WaterRange,
        heights: Option<u32>,
    ) -> Self {
        let place = SceneUpdatePush::new(world_from_object, range);
        WaterPush {
            rows: place.rows,
            nrows: place.nrows,
            time,
            heights: heights.map_or(0, |h| h + 1),
            first_wave: water.first_wave,
            wave_count: water.wave_count,
            displaced: water.first_displaced,
            src: range.first_vertex,
            dst: range.first_vertex,
            count: range.vertex_count,
        }
    }

    /// The BVH triangles of a water mesh (`r`), from its vertices displaced by the raster job before.
    pub fn bvh(r: &crate::bvh::RefitMesh, water: &crate::scene_gpu::WaterRange) -> Self {
        WaterPush {
            displaced: water.first_displaced,
            src: r.rest_first,
            dst: r.first_tri,
            count: r.tri_count,
            ..WaterPush::default()
        }
    }
}

impl MorphPush {
    /// The raster vertices of object `range` placed by `world_from_object`, morphed as `morph` says.
    pub fn raster(
        world_from_object: glam::Mat4,
        range: &crate::scene_gpu::ObjectRange,
        morph: &crate::scene_gpu::MorphRange,
    ) -> Self {
        let place = SceneUpdatePush::new(world_from_object, range);
        MorphPush {
            rows: place.rows,
            nrows: place.nrows,
            first: morph.first,
            vertices: morph.vertices,
            targets: morph.targets,
            first_weight: morph.first_weight,
            src: range.first_vertex,
            dst: range.first_vertex,
            count: range.vertex_count,
        }
    }

    /// The BVH triangles of a morphing mesh (`r`).
    pub fn bvh(r: &crate::bvh::RefitMesh, morph: &crate::scene_gpu::MorphRange) -> Self {
        MorphPush {
            first: morph.first,
            vertices: morph.vertices,
            targets: morph.targets,
            first_weight: morph.first_weight,
            src: r.rest_first,
            dst: r.first_tri,
            count: r.tri_count,
            ..MorphPush::default()
        }
    }
}
