//! The scene's triangles on the GPU: one vertex buffer and one index buffer, receivers first, then refractors,
//! for rasterization; and the scene BVH (src/bvh.rs) for exact transport.

use crate::bvh::{GpuInstance, SceneBvh};
use crate::gpu_types::Vertex;
use crate::scene::{Material, Scene};
use crate::vk::{cmd::upload_buffer, Buffer, Device, Recorder, VkResult};
use ash::vk;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, Default)]
pub struct DrawRange {
    pub first_index: u32,
    pub index_count: u32,
}

pub struct SceneBuffers {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub receivers: DrawRange,
    pub refractors: DrawRange,
    /// The IOR every refractor's vertices carry, when they all carry the same ([`shared_ior`]).
    pub shared_ior: Option<f32>,
    pub bvh: BvhBuffers,
}

/// The scene BVH in storage buffers: both node layouts, triangles, their vertex normals, and the instances.
pub struct BvhBuffers {
    pub pair_nodes: Buffer,
    pub single_nodes: Buffer,
    pub threaded_nodes: Buffer,
    pub triangles: Buffer,
    pub normals: Buffer,
    pub instances: Buffer,
    /// Host build time of this BVH (ms), node counts and triangle count.
    pub build_ms: f64,
    pub pair_node_count: usize,
    pub single_node_count: usize,
    pub threaded_node_count: usize,
    pub triangle_count: usize,
    pub instance_count: usize,
}

impl BvhBuffers {
    pub fn new(device: &Arc<Device>, recorder: &mut Recorder, scene: &Scene) -> VkResult<Self> {
        let bvh = SceneBvh::build(scene);
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        // Empty lists still need a buffer to bind: one zeroed element (an instance whose bounds nothing enters).
        fn nonempty<T: bytemuck::Pod + Default>(v: &[T]) -> Vec<T> {
            if v.is_empty() {
                vec![T::default()]
            } else {
                v.to_vec()
            }
        }
        let instances = if bvh.instances.is_empty() {
            vec![GpuInstance {
                lo: [f32::INFINITY, f32::INFINITY, f32::INFINITY, 0.0],
                hi: [f32::NEG_INFINITY, f32::NEG_INFINITY, f32::NEG_INFINITY, 0.0],
                ..GpuInstance::default()
            }]
        } else {
            bvh.instances.clone()
        };
        Ok(BvhBuffers {
            pair_nodes: upload_buffer(device, recorder, "bvh pair nodes", &nonempty(&bvh.pair_nodes), storage)?,
            single_nodes: upload_buffer(device, recorder, "bvh single nodes", &nonempty(&bvh.single_nodes), storage)?,
            threaded_nodes: upload_buffer(
                device,
                recorder,
                "bvh threaded nodes",
                &nonempty(&bvh.threaded_nodes),
                storage,
            )?,
            threaded_node_count: bvh.threaded_nodes.len(),
            triangles: upload_buffer(device, recorder, "bvh triangles", &nonempty(&bvh.triangles), storage)?,
            normals: upload_buffer(device, recorder, "bvh normals", &nonempty(&bvh.normals), storage)?,
            instances: upload_buffer(device, recorder, "bvh instances", &instances, storage)?,
            build_ms: bvh.build_ms,
            pair_node_count: bvh.pair_nodes.len(),
            single_node_count: bvh.single_nodes.len(),
            triangle_count: bvh.triangles.len(),
            instance_count: bvh.instances.len(),
        })
    }
}

/// A refractor's gray index of refraction as the light and eye views' IOR buffers hold it. A negative IOR marks a
/// mirror for the eye view's deferred shading (composite.comp).
fn refractor_ior(m: &Material) -> f32 {
    match *m {
        Material::Dielectric { ior, .. } => ior,
        _ => -1.0,
    }
}

/// The IOR buffer's value when every refractor of the scene has the same one: the frame then passes it in its
/// uniforms and draws no IOR buffer (in the light view that buffer cost a fifth of the front pass on an H200).
pub fn shared_ior(scene: &Scene) -> Option<f32> {
    let mut iors = scene.objects.iter().filter(|o| o.is_refractor()).map(|o| refractor_ior(&o.material));
    let first = iors.next()?;
    iors.all(|x| x == first).then_some(first)
}

impl SceneBuffers {
    pub fn new(device: &Arc<Device>, recorder: &mut Recorder, scene: &Scene) -> VkResult<Self> {
        let mut vertices = Vec::new();
        let mut indices = Vec::new();
        let mut push = |refractors: bool| {
            let start = indices.len() as u32;
            for o in scene.objects.iter().filter(|o| o.is_refractor() == refractors) {
                let base = vertices.len() as u32;
                let material = match o.material {
                    Material::Diffuse { albedo } => [albedo.x, albedo.y, albedo.z, 0.0],
                    _ => [refractor_ior(&o.material), 0.0, 0.0, 1.0],
                };
                for (p, n) in o.mesh.positions.iter().zip(&o.mesh.normals) {
                    vertices.push(Vertex { position: [p.x, p.y, p.z, 1.0], normal: [n.x, n.y, n.z, 0.0], material });
                }
                indices.extend(o.mesh.indices.iter().map(|i| i + base));
            }
            DrawRange { first_index: start, index_count: indices.len() as u32 - start }
        };
        let receivers = push(false);
        let refractors = push(true);
        let vertices =
            upload_buffer(device, recorder, "scene vertices", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let indices = upload_buffer(device, recorder, "scene indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        let bvh = BvhBuffers::new(device, recorder, scene)?;
        Ok(SceneBuffers { vertices, indices, receivers, refractors, shared_ior: shared_ior(scene), bvh })
    }
}
