//! The eye-view composite: the glass over the receivers (traced through the scene BVH under exact transport, the
//! papers' two-surface deferred refraction otherwise), the supersamples averaged, and tone mapping into the
//! beauty image.

use super::groups_2d;
use crate::scene_gpu::BvhBuffers;
use crate::shaders;
use crate::vk::{Bind, BindKind, Buffer, Device, Image, Pipeline, Sampler, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct CompositePass {
    device: Arc<Device>,
    /// The two-interface deferred refraction.
    pipeline: Pipeline,
    /// The eye-ray tracer through the BVH (`--transport exact`).
    exact: Pipeline,
    /// The same two with one eye sample per pixel (`--aa 1`, the viewer's previews): kernels without the
    /// averaging loop, which costs a CPU driver such as lavapipe even when it runs once.
    single: Pipeline,
    exact_single: Pipeline,
}

pub struct CompositeInputs<'a> {
    pub ubo: &'a Buffer,
    pub radiance: &'a Image,
    pub front: &'a Image,
    pub front_aux: &'a Image,
    pub back: &'a Image,
    pub beauty: &'a Image,
    pub hdr: &'a Image,
    pub shadow: &'a Image,
    pub irradiance: &'a Image,
    pub recv: &'a Image,
    pub bvh: &'a BvhBuffers,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
    /// Trace the glass through the BVH.
    pub exact: bool,
}

impl CompositePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        use BindKind::*;
        let binds = [
            Uniform,
            Sampled,
            Sampled,
            Sampled,
            Sampled,
            Sampled,
            StorageImage,
            StorageImage,
            Sampled,
            Sampled,
            Sampled,
            Storage,
            Storage,
            Storage,
            Storage,
        ];
        let pipeline = Pipeline::compute(device, "composite", shaders::COMPOSITE_COMP.words(), &binds, 0)?;
        let exact = Pipeline::compute(device, "composite exact", shaders::COMPOSITE_COMP_EXACT.words(), &binds, 0)?;
        let single =
            Pipeline::compute(device, "composite, one sample", shaders::COMPOSITE_COMP_SINGLE.words(), &binds, 0)?;
        let exact_single = Pipeline::compute(
            device,
            "composite exact, one sample",
            shaders::COMPOSITE_COMP_EXACT_SINGLE.words(),
            &binds,
            0,
        )?;
        Ok(CompositePass { device: device.clone(), pipeline, exact, single, exact_single })
    }

    pub fn record(&self, cmd: vk::CommandBuffer, i: &CompositeInputs) {
        let single = i.radiance.extent.width == i.beauty.extent.width;
        let pipeline = match (i.exact, single) {
            (true, true) => &self.exact_single,
            (true, false) => &self.exact,
            (false, true) => &self.single,
            (false, false) => &self.pipeline,
        };
        pipeline.bind(
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
                Bind::Sampled(i.shadow, i.nearest),
                Bind::Sampled(i.irradiance, i.linear),
                Bind::Sampled(i.recv, i.nearest),
                Bind::Storage(&i.bvh.pair_nodes),
                Bind::Storage(&i.bvh.triangles),
                Bind::Storage(&i.bvh.normals),
                Bind::Storage(&i.bvh.instances),
            ],
        );
        let (gx, gy) = groups_2d(i.beauty.extent.width, i.beauty.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
    }
}
