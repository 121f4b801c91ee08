//! Caustic flux (W per texel) to caustic irradiance (W/m²).

use super::groups_2d;
use crate::gpu_types::ResolvePush;
use crate::shaders::{self, consts::*};
use crate::vk::pipeline::{ordered, LazyPipeline};
use crate::vk::{Buffer, Device, Image, Pipeline, Sampler, Tracker, Use, VkResult};
use ash::vk;
use std::sync::Arc;

/// Where the resolve reads the frame's flux.
pub enum FluxSource<'a> {
    /// The flux image: the raster splat's target, or the compute splat's level 0 copied into it.
    Image(&'a Image),
    /// The compute splat's flux texels through their texel view, once the coarse levels from 2 up are collapsed:
    /// the resolve adds level 1's share itself (glsl/resolve.comp, `RESOLVE_TEXELS`).
    Texels(&'a Buffer),
    /// The same in three planes, red, green and blue: the records of color photons.
    ColorTexels(&'a Buffer),
}

pub struct ResolvePass {
    device: Arc<Device>,
    pipeline: Pipeline,
    /// Gray flux texels, then three planes (RESOLVE_COLOR).
    texels: [LazyPipeline; 2],
}

impl ResolvePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let pipeline = Pipeline::compute(device, "resolve", shaders::RESOLVE_COMP.words())?;
        let texels = [false, true].map(|color| {
            LazyPipeline::compute_specialized(
                device,
                if color { "resolve (flux texels, color)" } else { "resolve (flux texels)" },
                shaders::RESOLVE_COMP_TEXELS.words(),
                &[(RESOLVE_COLOR_ID, color as u32)],
            )
        });
        Ok(ResolvePass { device: device.clone(), pipeline, texels })
    }

    /// Resolve `flux` into `out` (its channel, for a color pass); `keep`: keep what `out` holds (a light's later
    /// channel passes); `blend`: how the flux's irradiance joins what `out` holds (written, added to it, or
    /// averaged into it; [`ResolvePush`]).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        ubo: &Buffer,
        flux: FluxSource,
        recv: &Image,
        out: &Image,
        s: &Sampler,
        keep: bool,
        blend: ResolvePush,
    ) -> VkResult<()> {
        let out_use = if keep { Use::ImageWrite(out) } else { Use::ImageOverwrite(out) };
        let (pipeline, flux_use) = match flux {
            FluxSource::Image(img) => (&self.pipeline, Use::Sampled(img, s)),
            FluxSource::Texels(buf) | FluxSource::ColorTexels(buf) => {
                (self.texels[matches!(flux, FluxSource::ColorTexels(_)) as usize].get()?, Use::Read(buf))
            }
        };
        let uses = ordered([
            (RS_FRAME, Use::Uniform(ubo)),
            (RS_FLUX, flux_use),
            (RS_RECEIVERS, Use::Sampled(recv, s)),
            (RS_IRRADIANCE, out_use),
        ]);
        pipeline.bind_uses(cmd, sync, &uses)?;
        pipeline.push(cmd, &blend);
        let (gx, gy) = groups_2d(out.extent.width, out.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }
}
