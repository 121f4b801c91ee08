//! The eye-view composite: the glass over the receivers (traced through the scene BVH under exact transport, the
//! papers' two-surface deferred refraction otherwise), the supersamples averaged, and tone mapping into the
//! beauty image.

use super::groups_2d;
use crate::scene_gpu::BvhBuffers;
use crate::shaders;
use crate::shaders::consts::*;
use crate::vk::pipeline::{kinds, ordered, with_texels, LazyPipeline};
use crate::vk::{Bind, BindKind, Buffer, Device, Image, Sampler, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct CompositePass {
    device: Arc<Device>,
    /// The two-interface deferred refraction.
    pipeline: LazyPipeline,
    /// The eye-ray tracer through the BVH (`--transport exact`).
    exact: LazyPipeline,
    /// The same two with one eye sample per pixel (`--aa 1`, the viewer's previews): kernels without the
    /// averaging loop, which costs a CPU driver such as lavapipe even when it runs once.
    single: LazyPipeline,
    exact_single: LazyPipeline,
    /// Exact transport, before the composite: the glass's radiance per eye sample under every light and the
    /// environment, into the glass image.
    glass: LazyPipeline,
    /// The glass pass walking the wide layout (where the waves trace it; the others walk the pair layout).
    /// The wide layout's glass pass, with the pair fallback and without it.
    glass_wide: [LazyPipeline; 2],
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CompositePush {
    /// The glass pass: how many lights' maps are bound.
    lights: u32,
    /// The glass pass: add to what an earlier pass wrote.
    add: u32,
}
const _: () = assert!(std::mem::size_of::<CompositePush>() == 8);

/// One light's uniforms and maps, as the glass pass reads them.
#[derive(Clone, Copy)]
pub struct LightMaps<'a> {
    pub ubo: &'a Buffer,
    pub shadow: &'a Image,
    pub irradiance: &'a Image,
    pub recv: &'a Image,
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
    pub images: &'a crate::scene_gpu::SceneImages,
    pub nearest: &'a Sampler,
    pub linear: &'a Sampler,
    /// The glass's radiance per eye sample (exact transport: the glass pass writes it, the composite reads it).
    pub glass: &'a Image,
    /// The glass pass's second and third lights' maps (its first is `ubo`, `shadow`, `irradiance`, `recv`).
    pub more_lights: &'a [LightMaps<'a>],
    /// Trace the glass through the BVH.
    pub exact: bool,
    /// Trace it through the wide layout (uploaded: the waves trace it), else the pair layout.
    pub wide: bool,
}

/// The composite's bindings (glsl/composite.comp declares each with the same constant).
const LAYOUT: [(u32, BindKind); CB_COUNT as usize] = [
    (CB_FRAME, BindKind::Uniform),
    (CB_RADIANCE, BindKind::Sampled),
    (CB_FRONT, BindKind::Sampled),
    (CB_FRONT_AUX, BindKind::Sampled),
    (CB_BACK, BindKind::Sampled),
    (CB_RADIANCE_LINEAR, BindKind::Sampled),
    (CB_BEAUTY, BindKind::StorageImage),
    (CB_HDR, BindKind::StorageImage),
    (CB_SHADOW, BindKind::Sampled),
    (CB_IRRADIANCE, BindKind::Sampled),
    (CB_RECEIVERS, BindKind::Sampled),
    (CB_BVH_PAIR, BindKind::Storage),
    (CB_BVH_TRIS, BindKind::Storage),
    (CB_BVH_NORMALS, BindKind::Storage),
    (CB_BVH_INSTANCES, BindKind::Storage),
    (CB_ALBEDO_TEXTURES, BindKind::Sampled),
    (CB_ENV, BindKind::Sampled),
    (CB_ENV_IRRADIANCE, BindKind::Sampled),
    (CB_GLASS, BindKind::StorageImage),
    (CB_LIGHT1, BindKind::Uniform),
    (CB_SHADOW1, BindKind::Sampled),
    (CB_IRRADIANCE1, BindKind::Sampled),
    (CB_RECEIVERS1, BindKind::Sampled),
    (CB_LIGHT2, BindKind::Uniform),
    (CB_SHADOW2, BindKind::Sampled),
    (CB_IRRADIANCE2, BindKind::Sampled),
    (CB_RECEIVERS2, BindKind::Sampled),
    (CB_BVH_WIDE, BindKind::Storage),
    (CB_BVH_WIDE_PRIMS, BindKind::Storage),
];
const _: () = assert!(crate::vk::pipeline::bindings_in_order(&LAYOUT));

impl CompositePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let binds = kinds(&LAYOUT);
        let push = std::mem::size_of::<CompositePush>() as u32;
        let lazy = |name: &str, spv: &'static [u32]| LazyPipeline::compute(device, name, spv, &binds, push);
        let pipeline = lazy("composite", shaders::COMPOSITE_COMP.words());
        let exact = lazy("composite exact", shaders::COMPOSITE_COMP_EXACT.words());
        let single = lazy("composite, one sample", shaders::COMPOSITE_COMP_SINGLE.words());
        let exact_single = lazy("composite exact, one sample", shaders::COMPOSITE_COMP_EXACT_SINGLE.words());
        let glass = lazy("eye glass", shaders::COMPOSITE_COMP_GLASS.words());
        // Read as texels there (glsl/common/bvh.glsl, `BVH_TEXELS`).
        let texel_binds =
            with_texels(binds, &[CB_BVH_TRIS, CB_BVH_NORMALS, CB_BVH_INSTANCES, CB_BVH_WIDE, CB_BVH_WIDE_PRIMS]);
        // Compiled with the wide walk's pair fallback (some mesh deforms) and without it (glsl/common/bvh.glsl,
        // `BVH_PAIR_FALLBACK`), as the waves are.
        let glass_wide = [1, 0].map(|fallback| {
            LazyPipeline::compute_specialized(
                device,
                if fallback == 1 { "eye glass (wide BVH nodes, pair fallback)" } else { "eye glass (wide BVH nodes)" },
                shaders::COMPOSITE_COMP_GLASS_WIDE.words(),
                &texel_binds,
                push,
                &[(crate::passes::photons::BVH_PAIR_FALLBACK_ID, fallback)],
            )
        });
        Ok(CompositePass { device: device.clone(), pipeline, exact, single, exact_single, glass, glass_wide })
    }

    /// Exact transport: the glass's radiance per eye sample under the lights of `i` (at most [`GLASS_LIGHTS`]),
    /// into `i.glass`; `add`: onto what an earlier pass wrote.
    pub fn record_glass(&self, cmd: vk::CommandBuffer, i: &CompositeInputs, add: bool) -> VkResult<()> {
        assert!(i.more_lights.len() < GLASS_LIGHTS as usize, "a glass pass shades with {GLASS_LIGHTS} lights");
        let pipeline = if i.wide { &self.glass_wide[usize::from(!i.bvh.deforms())] } else { &self.glass }.get()?;
        self.bind(cmd, pipeline, i)?;
        pipeline.push(cmd, &CompositePush { lights: 1 + i.more_lights.len() as u32, add: add as u32 });
        let (gx, gy) = groups_2d(i.glass.extent.width, i.glass.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }

    pub fn record(&self, cmd: vk::CommandBuffer, i: &CompositeInputs) -> VkResult<()> {
        let single = i.radiance.extent.width == i.beauty.extent.width;
        let pipeline = match (i.exact, single) {
            (true, true) => &self.exact_single,
            (true, false) => &self.exact,
            (false, true) => &self.single,
            (false, false) => &self.pipeline,
        }
        .get()?;
        self.bind(cmd, pipeline, i)?;
        pipeline.push(cmd, &CompositePush { lights: 1, add: 0 });
        let (gx, gy) = groups_2d(i.beauty.extent.width, i.beauty.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }

    fn bind(&self, cmd: vk::CommandBuffer, pipeline: &crate::vk::Pipeline, i: &CompositeInputs) -> VkResult<()> {
        // Lights the scene lacks bind the first light's maps (the shader reads only `lights` of them).
        let first = LightMaps { ubo: i.ubo, shadow: i.shadow, irradiance: i.irradiance, recv: i.recv };
        let l = |k: usize| i.more_lights.get(k).copied().unwrap_or(first);
        let (l1, l2) = (l(0), l(1));
        pipeline.bind_checked(
            cmd,
            &ordered([
                (CB_FRAME, Bind::Uniform(i.ubo)),
                (CB_RADIANCE, Bind::Sampled(i.radiance, i.nearest)),
                (CB_FRONT, Bind::Sampled(i.front, i.nearest)),
                (CB_FRONT_AUX, Bind::Sampled(i.front_aux, i.nearest)),
                (CB_BACK, Bind::Sampled(i.back, i.nearest)),
                (CB_RADIANCE_LINEAR, Bind::Sampled(i.radiance, i.linear)),
                (CB_BEAUTY, Bind::StorageImage(i.beauty)),
                (CB_HDR, Bind::StorageImage(i.hdr)),
                (CB_SHADOW, Bind::Sampled(i.shadow, i.nearest)),
                (CB_IRRADIANCE, Bind::Sampled(i.irradiance, i.linear)),
                (CB_RECEIVERS, Bind::Sampled(i.recv, i.nearest)),
                (CB_BVH_PAIR, Bind::Storage(&i.bvh.pair_nodes)),
                (CB_BVH_TRIS, Bind::Storage(&i.bvh.triangles)),
                (CB_BVH_NORMALS, Bind::Storage(&i.bvh.normals)),
                (CB_BVH_INSTANCES, Bind::Storage(&i.bvh.instances)),
                (CB_ALBEDO_TEXTURES, Bind::Sampled(&i.images.albedo, &i.images.repeat)),
                (CB_ENV, Bind::Sampled(&i.images.environment, &i.images.equirect)),
                (CB_ENV_IRRADIANCE, Bind::Sampled(&i.images.environment_irradiance, &i.images.equirect)),
                (CB_GLASS, Bind::StorageImage(i.glass)),
                (CB_LIGHT1, Bind::Uniform(l1.ubo)),
                (CB_SHADOW1, Bind::Sampled(l1.shadow, i.nearest)),
                (CB_IRRADIANCE1, Bind::Sampled(l1.irradiance, i.linear)),
                (CB_RECEIVERS1, Bind::Sampled(l1.recv, i.nearest)),
                (CB_LIGHT2, Bind::Uniform(l2.ubo)),
                (CB_SHADOW2, Bind::Sampled(l2.shadow, i.nearest)),
                (CB_IRRADIANCE2, Bind::Sampled(l2.irradiance, i.linear)),
                (CB_RECEIVERS2, Bind::Sampled(l2.recv, i.nearest)),
                (CB_BVH_WIDE, Bind::Storage(&i.bvh.wide_nodes)),
                (CB_BVH_WIDE_PRIMS, Bind::Storage(&i.bvh.wide_prims)),
            ]),
        )
    }
}
