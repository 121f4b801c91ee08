//! Caustic flux (W per texel) to caustic irradiance (W/m²).

use super::groups_2d;
use crate::shaders;
use crate::vk::{Bind, BindKind, Buffer, Device, Image, Pipeline, Sampler, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct ResolvePass {
    device: Arc<Device>,
    pipeline: Pipeline,
}

impl ResolvePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let pipeline = Pipeline::compute(
            device,
            "resolve",
            shaders::RESOLVE_COMP.words(),
            &[BindKind::Uniform, BindKind::Sampled, BindKind::Sampled, BindKind::StorageImage],
            4,
        )?;
        Ok(ResolvePass { device: device.clone(), pipeline })
    }

    /// Resolve `flux` into `out` (its channel, for a color pass); `add`: add to what `out` holds instead (the rest of
    /// a frame's batches, traced after the first submission ran out of batch slots).
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        ubo: &Buffer,
        flux: &Image,
        recv: &Image,
        out: &Image,
        s: &Sampler,
        add: bool,
    ) {
        self.pipeline
            .bind(cmd, &[Bind::Uniform(ubo), Bind::Sampled(flux, s), Bind::Sampled(recv, s), Bind::StorageImage(out)]);
        self.pipeline.push(cmd, &(add as u32));
        let (gx, gy) = groups_2d(out.extent.width, out.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
    }
}
