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
    /// Radiance, caustics and direct: the first light clears and writes them, a further light adds to them
    /// (depth loaded and tested, not written).
    aovs: [Pipeline; 2],
    /// The radiance alone, for frames that read back neither AOV: [first light, a further light].
    radiance: [Pipeline; 2],
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
        let make = |name: &str, fragment: &[u32], targets: usize, blend: Blend, depth: (vk::CompareOp, bool)| {
            let hdr = ColorTarget { format: HDR_FORMAT, blend };
            Pipeline::graphics(
                device,
                name,
                &GraphicsDesc {
                    vertex: shaders::EYE_RECEIVER_VERT.words(),
                    fragment,
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
                    colors: &[hdr; 3][..targets],
                },
            )
        };
        let (first, further) = ((vk::CompareOp::LESS, true), (vk::CompareOp::LESS_OR_EQUAL, false));
        let (full, rad) = (shaders::EYE_RECEIVER_FRAG.words(), shaders::EYE_RECEIVER_FRAG_RADIANCE.words());
        Ok(EyePass {
            device: device.clone(),
            aovs: [
                make("eye receivers", full, 3, Blend::None, first)?,
                make("eye receivers (a further light)", full, 3, Blend::AddRgb, further)?,
            ],
            radiance: [
                make("eye receivers, radiance", rad, 1, Blend::None, first)?,
                make("eye receivers, radiance (a further light)", rad, 1, Blend::AddRgb, further)?,
            ],
        })
    }

    /// Draw the receivers into `colors`: radiance, caustics and direct, or the radiance alone (and depth); `add`:
    /// add to what an earlier light's pass drew instead of clearing.
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        scene: &SceneBuffers,
        i: &EyeInputs,
        colors: &[&Image],
        depth: &Image,
        add: bool,
    ) {
        let d = &self.device;
        begin_rendering_with(d, cmd, depth.extent, colors, !add, Some(depth), !add);
        let set = if colors.len() == 1 { &self.radiance } else { &self.aovs };
        let pipeline = &set[add as usize];
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
