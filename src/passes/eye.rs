//! The eye view of the receivers, deferred: a raster pass writes their eye-view g-buffer (normal and distance,
//! albedo), then a compute pass shades each pixel under each light into the radiance and, when the frame reads
//! one back, the caustics and direct AOVs.

use super::{groups_2d, DEPTH_FORMAT, GEO_FORMAT};
use crate::gpu_types::{GeometryPush, GpuView, ShadePush, Vertex};
use crate::scene_gpu::SceneBuffers;
use crate::shaders;
use crate::shaders::consts::*;
use crate::vk::pipeline::{ordered, LazyPipeline};
use crate::vk::{
    Bind, Blend, Buffer, ColorTarget, Device, GraphicsDesc, Image, Pipeline, Raster, Sampler, Target, Tracker, Use,
    VkResult,
};
use ash::vk;
use std::sync::Arc;

/// The receivers' albedo in the eye g-buffer (albedos lie in [0, 1]). 16 bits a channel: an albedo (a texture's
/// texel, decoded from sRGB, or a material's factor) comes back within 8e-6, and dark ones keep their precision.
pub const ALBEDO_FORMAT: vk::Format = vk::Format::R16G16B16A16_UNORM;

pub struct EyePass {
    device: Arc<Device>,
    /// The receivers' eye-view g-buffer: normal and distance, albedo (and depth).
    gbuffer: Pipeline,
    /// Shading: [the radiance alone, the radiance and the caustics and direct AOVs].
    shade: [LazyPipeline; 2],
}

pub struct EyeInputs<'a> {
    pub ubo: &'a Buffer,
    pub shadow: &'a Image,
    pub irradiance: &'a Image,
    pub recv: &'a Image,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
    pub images: &'a crate::scene_gpu::SceneImages,
    /// The eye deposit's flux (docs/design.md "The eye deposit").
    pub eye_flux: &'a Buffer,
}

/// The eye g-buffer of the receivers.
pub struct EyeGbuffer<'a> {
    pub geo: &'a Image,
    pub albedo: &'a Image,
    pub depth: &'a Image,
}

impl EyePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let gbuffer = Pipeline::graphics(
            device,
            "eye receivers g-buffer",
            &GraphicsDesc {
                vertex: shaders::GEOMETRY_VERT_ALBEDO.words(),
                fragment: shaders::GEOMETRY_FRAG_ALBEDO.words(),
                vertex_attributes: &[
                    (vk::Format::R32G32B32A32_SFLOAT, 0),
                    (vk::Format::R32G32B32A32_SFLOAT, 16),
                    (vk::Format::R32G32B32A32_SFLOAT, 32),
                ],
                vertex_stride: std::mem::size_of::<Vertex>() as u32,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                cull: vk::CullModeFlags::NONE,
                depth: Some((DEPTH_FORMAT, vk::CompareOp::LESS, true)),
                colors: &[
                    ColorTarget { format: GEO_FORMAT, blend: Blend::None },
                    ColorTarget { format: ALBEDO_FORMAT, blend: Blend::None },
                ],
            },
        )?;
        let shade = [
            LazyPipeline::compute(device, "eye shade", shaders::EYE_SHADE_COMP.words()),
            LazyPipeline::compute(device, "eye shade (AOVs)", shaders::EYE_SHADE_COMP_AOVS.words()),
        ];
        Ok(EyePass { device: device.clone(), gbuffer, shade })
    }

    /// Rasterize the receivers seen from `camera` into the g-buffer (once per frame, whatever the lights).
    pub fn record_gbuffer(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        scene: &SceneBuffers,
        camera: &GpuView,
        g: &EyeGbuffer,
    ) -> VkResult<()> {
        let images = &scene.images;
        let raster = Raster {
            colors: &[Target::Clear(g.geo), Target::Clear(g.albedo)],
            depth: Some(Target::Clear(g.depth)),
            vertices: Some(&scene.vertices),
            indices: Some(&scene.indices),
            uses: &ordered([(GE_ALBEDO_TEXTURES, Use::Fixed(Bind::Sampled(&images.albedo, &images.repeat)))]),
        };
        self.gbuffer.begin_raster(cmd, sync, &raster)?;
        self.gbuffer.push(cmd, &GeometryPush::from_view(camera));
        if scene.receivers.index_count > 0 {
            let r = scene.receivers;
            unsafe { self.device.cmd_draw_indexed(cmd, r.index_count, 1, r.first_index, 0, 0) };
        }
        raster.end(&self.device, cmd);
        Ok(())
    }

    /// Shade the g-buffer under one light into `out`: the radiance, or the radiance, caustics and direct. `add`:
    /// add to what an earlier light's dispatch wrote instead of writing.
    pub fn record_shade(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        i: &EyeInputs,
        g: &EyeGbuffer,
        out: &[&Image],
        add: bool,
    ) -> VkResult<()> {
        let pipeline = self.shade[(out.len() > 1) as usize].get()?;
        let mut uses = vec![
            (EB_FRAME, Use::Uniform(i.ubo)),
            (EB_SHADOW, Use::Sampled(i.shadow, i.nearest)),
            (EB_IRRADIANCE, Use::Sampled(i.irradiance, i.linear)),
            (EB_RECEIVERS, Use::Sampled(i.recv, i.nearest)),
            (EB_EYE, Use::Sampled(g.geo, i.nearest)),
            (EB_ALBEDO, Use::Sampled(g.albedo, i.nearest)),
            (EB_ENV, Use::Fixed(Bind::Sampled(&i.images.environment, &i.images.equirect))),
            (EB_ENV_IRRADIANCE, Use::Fixed(Bind::Sampled(&i.images.environment_irradiance, &i.images.equirect))),
            (EB_EYE_FLUX, Use::Read(i.eye_flux)),
        ];
        // A further light adds to what the last one wrote, pixel by pixel.
        let write = |img| if add { Use::ImageWrite(img) } else { Use::ImageOverwrite(img) };
        uses.extend(out.iter().zip([EB_RADIANCE, EB_CAUSTICS, EB_DIRECT]).map(|(img, b)| (b, write(img))));
        assert!(crate::vk::pipeline::bindings_in_order(&uses), "the eye shading's bindings out of order");
        let uses: Vec<Use> = uses.into_iter().map(|(_, u)| u).collect();
        pipeline.bind_uses(cmd, sync, &uses)?;
        pipeline.push(cmd, &ShadePush { add: add as u32 });
        let (gx, gy) = groups_2d(out[0].extent.width, out[0].extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }
}
