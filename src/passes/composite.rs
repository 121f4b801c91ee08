//! Deferred refraction of the refractors over the receivers, and tone mapping into the beauty image.

use super::groups_2d;
use crate::shaders;
use crate::vk::{Bind, BindKind, Buffer, Device, Image, Pipeline, Sampler, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct CompositePass {
    device: Arc<Device>,
    pipeline: Pipeline,
}

pub struct CompositeInputs<'a> {
    pub ubo: &'a Buffer,
    pub radiance: &'a Image,
    pub front: &'a Image,
    pub front_aux: &'a Image,
    pub back: &'a Image,
    pub beauty: &'a Image,
    pub hdr: &'a Image,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
}

impl CompositePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        use BindKind::*;
        let pipeline = Pipeline::compute(
            device,
            "composite",
            shaders::COMPOSITE_COMP.words(),
            &[Uniform, Sampled, Sampled, Sampled, Sampled, Sampled, StorageImage, StorageImage],
            0,
        )?;
        Ok(CompositePass { device: device.clone(), pipeline })
    }

    pub fn record(&self, cmd: vk::CommandBuffer, i: &CompositeInputs) {
        self.pipeline.bind(
            cmd,
            &[
                Bind::Uniform(i.ubo),
                Bind::Sampled(i.radiance, i.nearest),
                Bind::Sampled(i.front, i.nearest),
                Bind::Sampled(i.front_aux, i.nearest),
                Bind::Sampled(i.back, i.nearest),
                Bind::Sampled(i.radiance, i.linear),
                Bind::StorageImage(i.beauty),
                Bind::StorageImage(i.hdr),
            ],
        );
        let (gx, gy) = groups_2d(i.beauty.extent.width, i.beauty.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
    }
}
