//! The eye view of the receivers: radiance, caustic and direct irradiance (the AOVs).

use super::{begin_rendering_with, DEPTH_FORMAT, HDR_FORMAT};
use crate::gpu_types::Vertex;
use crate::scene_gpu::SceneBuffers;
use crate::shaders;
use crate::vk::{Bind, BindKind, Blend, Buffer, ColorTarget, Device, GraphicsDesc, Image, Pipeline, Sampler, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct EyePass {
    device: Arc<Device>,
    pipeline: Pipeline,
    /// A further light: adds its radiance and irradiances to the targets (depth loaded and tested, not written).
    add: Pipeline,
}

pub struct EyeInputs<'a> {
    pub ubo: &'a Buffer,
    pub shadow: &'a Image,
    pub irradiance: &'a Image,
    pub recv: &'a Image,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
}

impl EyePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let make = |name: &str, blend: Blend, depth: (vk::CompareOp, bool)| {
            let hdr = || ColorTarget { format: HDR_FORMAT, blend };
            Pipeline::graphics(
                device,
                name,
                &GraphicsDesc {
                    vertex: shaders::EYE_RECEIVER_VERT.words(),
                    fragment: shaders::EYE_RECEIVER_FRAG.words(),
                    binds: &[BindKind::Uniform, BindKind::Sampled, BindKind::Sampled, BindKind::Sampled],
                    push_size: 0,
                    vertex_attributes: &[
                        (vk::Format::R32G32B32A32_SFLOAT, 0),
                        (vk::Format::R32G32B32A32_SFLOAT, 16),
                        (vk::Format::R32G32B32A32_SFLOAT, 32),
                    ],
                    vertex_stride: std::mem::size_of::<Vertex>() as u32,
                    topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                    cull: vk::CullModeFlags::NONE,
                    depth: Some((DEPTH_FORMAT, depth.0, depth.1)),
                    colors: &[hdr(), hdr(), hdr()],
                },
            )
        };
        let pipeline = make("eye receivers", Blend::None, (vk::CompareOp::LESS, true))?;
        let add = make("eye receivers (a further light)", Blend::AddRgb, (vk::CompareOp::LESS_OR_EQUAL, false))?;
        Ok(EyePass { device: device.clone(), pipeline, add })
    }

    /// Draw the receivers into radiance, caustics and direct (and depth); `add`: add to what an earlier light's
    /// pass drew instead of clearing.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        scene: &SceneBuffers,
        i: &EyeInputs,
        colors: [&Image; 3],
        depth: &Image,
        add: bool,
    ) {
        let d = &self.device;
        begin_rendering_with(d, cmd, depth.extent, &colors, !add, Some(depth), !add);
        let pipeline = if add { &self.add } else { &self.pipeline };
        pipeline.bind(
            cmd,
            &[
                Bind::Uniform(i.ubo),
                Bind::Sampled(i.shadow, i.nearest),
                Bind::Sampled(i.irradiance, i.linear),
                Bind::Sampled(i.recv, i.nearest),
            ],
        );
        unsafe {
            d.cmd_bind_vertex_buffers(cmd, 0, &[scene.vertices.raw], &[0]);
            d.cmd_bind_index_buffer(cmd, scene.indices.raw, 0, vk::IndexType::UINT32);
            if scene.receivers.index_count > 0 {
                d.cmd_draw_indexed(cmd, scene.receivers.index_count, 1, scene.receivers.first_index, 0, 0);
            }
            d.cmd_end_rendering(cmd);
        }
    }
}
