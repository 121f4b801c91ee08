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
            0,
        )?;
        Ok(ResolvePass { device: device.clone(), pipeline })
    }

    pub fn record(&self, cmd: vk::CommandBuffer, ubo: &Buffer, flux: &Image, recv: &Image, out: &Image, s: &Sampler) {
        self.pipeline
            .bind(cmd, &[Bind::Uniform(ubo), Bind::Sampled(flux, s), Bind::Sampled(recv, s), Bind::StorageImage(out)]);
        let (gx, gy) = groups_2d(out.extent.width, out.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
    }
}
