//! The scene's triangles on the GPU: one vertex buffer and one index buffer, receivers first, then refractors.

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
    pub all: DrawRange,
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
                    Material::Dielectric { ior } => [ior, 0.0, 0.0, 1.0],
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
        let all = DrawRange { first_index: 0, index_count: indices.len() as u32 };
        let vertices =
            upload_buffer(device, recorder, "scene vertices", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER)?;
        let indices = upload_buffer(device, recorder, "scene indices", &indices, vk::BufferUsageFlags::INDEX_BUFFER)?;
        Ok(SceneBuffers { vertices, indices, receivers, refractors, all })
    }
}
