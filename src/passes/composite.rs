//! The eye-view composite: the glass over the receivers (traced through the scene BVH under exact transport, the
//! papers' two-surface deferred refraction otherwise), the supersamples averaged, and tone mapping into the
//! beauty image.

use super::groups_2d;
use crate::gpu_types::CompositePush;
use crate::scene_gpu::BvhBuffers;
use crate::shaders;
use crate::shaders::consts::*;
use crate::vk::pipeline::{ordered, LazyPipeline};
use crate::vk::{Bind, Buffer, Device, Image, Sampler, Tracker, Use, VkResult};
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
    /// environment, into the glass image. One pipeline per [`GlassKey`] (built when a frame first needs it).
    glass: Vec<LazyPipeline>,
}

/// What a glass pass's pipeline is specialized for (glsl/glass.comp's specialization constants, src/shader_consts.rs). A CPU
/// driver runs both sides of every branch under a mask, so the pass compiles no code for what the frame lacks:
/// a second or third light, dispersion (three traces per sample), an environment map, albedo textures, absorbing or
/// overlapping media.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GlassKey {
    /// Walk the wide layout (else the pair layout).
    pub wide: bool,
    /// The pass's lights, 1 to [`GLASS_LIGHTS`].
    pub lights: u32,
    pub dispersive: bool,
    pub environment: bool,
    pub textured: bool,
    /// The scene has absorbing or overlapping media: the trace follows the medium each branch is in.
    pub media: bool,
}

impl GlassKey {
    const COUNT: usize = 2 * GLASS_LIGHTS as usize * 2 * 2 * 2 * 2;

    fn index(self) -> usize {
        let bits = [self.wide, self.dispersive, self.environment, self.textured, self.media];
        let flags = bits.iter().fold(0, |k, &b| 2 * k + usize::from(b));
        flags * GLASS_LIGHTS as usize + (self.lights as usize - 1)
    }

    fn of_index(k: usize) -> GlassKey {
        let (flags, lights) = (k / GLASS_LIGHTS as usize, k % GLASS_LIGHTS as usize);
        let bit = |i: usize| flags >> (4 - i) & 1 == 1;
        GlassKey {
            wide: bit(0),
            lights: lights as u32 + 1,
            dispersive: bit(1),
            environment: bit(2),
            textured: bit(3),
            media: bit(4),
        }
    }

    fn spec(self) -> [(u32, u32); 5] {
        [
            (GLASS_LIGHT_COUNT_ID, self.lights),
            (GLASS_DISPERSIVE_ID, self.dispersive as u32),
            (GLASS_ENVIRONMENT_ID, self.environment as u32),
            (GLASS_TEXTURED_ID, self.textured as u32),
            (GLASS_MEDIA_ID, self.media as u32),
        ]
    }
}

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
    /// The eye deposit's flux (docs/design.md "The eye deposit").
    pub eye_flux: &'a Buffer,
    /// The glass pass's second and third lights' maps (its first is `ubo`, `shadow`, `irradiance`, `recv`).
    pub more_lights: &'a [LightMaps<'a>],
    /// Trace the glass through the BVH.
    pub exact: bool,
    /// Trace it through the wide layout (uploaded: the waves trace it), else the pair layout.
    pub wide: bool,
    /// Some glass disperses (`FrameUniforms.disperses`): the glass pass traces each channel.
    pub dispersive: bool,
    /// The scene has an environment map (`FrameUniforms.environment`).
    pub environment: bool,
    /// The scene has absorbing or overlapping media (`ResolvedSettings::media`).
    pub media: bool,
}

impl CompositePass {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let lazy = |name: &str, spv: &'static [u32]| LazyPipeline::compute(device, name, spv);
        let pipeline = lazy("composite", shaders::COMPOSITE_COMP.words());
        let exact = lazy("composite exact", shaders::COMPOSITE_COMP_EXACT.words());
        let single = lazy("composite, one sample", shaders::COMPOSITE_COMP_SINGLE.words());
        let exact_single = lazy("composite exact, one sample", shaders::COMPOSITE_COMP_EXACT_SINGLE.words());
        // The wide layout's glass pass reads the BVH as texels (glsl/common/bvh.glsl, `BVH_TEXELS`).
        let glass = (0..GlassKey::COUNT)
            .map(|k| {
                let key = GlassKey::of_index(k);
                let spv = if key.wide { shaders::GLASS_COMP_WIDE.words() } else { shaders::GLASS_COMP.words() };
                LazyPipeline::compute_specialized(device, &format!("eye glass {key:?}"), spv, &key.spec())
            })
            .collect();
        Ok(CompositePass { device: device.clone(), pipeline, exact, single, exact_single, glass })
    }

    /// Exact transport: the glass's radiance per eye sample under the lights of `i` (at most [`GLASS_LIGHTS`]),
    /// into `i.glass`; `add`: onto what an earlier pass wrote.
    pub fn record_glass(
        &self,
        cmd: vk::CommandBuffer,
        sync: &mut Tracker,
        i: &CompositeInputs,
        add: bool,
    ) -> VkResult<()> {
        assert!(i.more_lights.len() < GLASS_LIGHTS as usize, "a glass pass shades with {GLASS_LIGHTS} lights");
        let key = GlassKey {
            wide: i.wide,
            lights: 1 + i.more_lights.len() as u32,
            dispersive: i.dispersive,
            environment: i.environment,
            textured: i.images.textured,
            media: i.media,
        };
        let pipeline = self.glass[key.index()].get()?;
        // The layout holds the beauty images, which the glass pass does not write: declared as kept.
        let glass = if add { Use::ImageWrite(i.glass) } else { Use::ImageOverwrite(i.glass) };
        pipeline.bind_uses(cmd, sync, &Self::uses(i, glass, Use::ImageWrite))?;
        // Dispersive glass at 2×2 samples a pixel: one invocation a pixel (its samples share their traces).
        let pixels = i.dispersive && i.glass.extent.width == 2 * i.beauty.extent.width;
        pipeline.push(cmd, &CompositePush { pixels: pixels as u32, add: add as u32 });
        let (gx, gy) = if pixels {
            groups_2d(i.beauty.extent.width, i.beauty.extent.height)
        } else {
            groups_2d(i.glass.extent.width, i.glass.extent.height)
        };
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }

    pub fn record(&self, cmd: vk::CommandBuffer, sync: &mut Tracker, i: &CompositeInputs) -> VkResult<()> {
        let single = i.radiance.extent.width == i.beauty.extent.width;
        let pipeline = match (i.exact, single) {
            (true, true) => &self.exact_single,
            (true, false) => &self.exact,
            (false, true) => &self.single,
            (false, false) => &self.pipeline,
        }
        .get()?;
        // The composite reads no push constants (its shader declares none; only the glass pass reads them).
        pipeline.bind_uses(cmd, sync, &Self::uses(i, Use::ImageRead(i.glass), Use::ImageOverwrite))?;
        let (gx, gy) = groups_2d(i.beauty.extent.width, i.beauty.extent.height);
        unsafe { self.device.cmd_dispatch(cmd, gx, gy, 1) };
        Ok(())
    }

    /// The resources of both programs, which share one layout: `glass` as the glass image's use, `beauty` as the
    /// beauty images'. Every map is sampled, the BVH read (the wide layout's glass pass reads its triangles,
    /// instances and wide nodes through texel bindings), and the scene's textures are fixed.
    fn uses<'a>(
        i: &'a CompositeInputs,
        glass: Use<'a>,
        beauty: fn(&'a Image) -> Use<'a>,
    ) -> [Use<'a>; CB_COUNT as usize] {
        // Lights the scene lacks bind the first light's maps (the shader reads only `lights` of them).
        let first = LightMaps { ubo: i.ubo, shadow: i.shadow, irradiance: i.irradiance, recv: i.recv };
        let l = |k: usize| i.more_lights.get(k).copied().unwrap_or(first);
        let (l1, l2) = (l(0), l(1));
        let bvh = Use::Read;
        let (near, lin) = (i.nearest, i.linear);
        let fixed = |img, s| Use::Fixed(Bind::Sampled(img, s));
        ordered([
            (CB_FRAME, Use::Uniform(i.ubo)),
            (CB_RADIANCE, Use::Sampled(i.radiance, near)),
            (CB_FRONT, Use::Sampled(i.front, near)),
            (CB_FRONT_AUX, Use::Sampled(i.front_aux, near)),
            (CB_BACK, Use::Sampled(i.back, near)),
            (CB_RADIANCE_LINEAR, Use::Sampled(i.radiance, lin)),
            (CB_BEAUTY, beauty(i.beauty)),
            (CB_HDR, beauty(i.hdr)),
            (CB_SHADOW, Use::Sampled(i.shadow, near)),
            (CB_IRRADIANCE, Use::Sampled(i.irradiance, lin)),
            (CB_RECEIVERS, Use::Sampled(i.recv, near)),
            (CB_BVH_PAIR, Use::Read(&i.bvh.pair_nodes)),
            (CB_BVH_TRIS, bvh(&i.bvh.triangles)),
            (CB_BVH_NORMALS, bvh(&i.bvh.normals)),
            (CB_BVH_INSTANCES, bvh(&i.bvh.instances)),
            (CB_ALBEDO_TEXTURES, fixed(&i.images.albedo, &i.images.repeat)),
            (CB_ENV, fixed(&i.images.environment, &i.images.equirect)),
            (CB_ENV_IRRADIANCE, fixed(&i.images.environment_irradiance, &i.images.equirect)),
            (CB_GLASS, glass),
            (CB_LIGHT1, Use::Uniform(l1.ubo)),
            (CB_SHADOW1, Use::Sampled(l1.shadow, near)),
            (CB_IRRADIANCE1, Use::Sampled(l1.irradiance, lin)),
            (CB_RECEIVERS1, Use::Sampled(l1.recv, near)),
            (CB_LIGHT2, Use::Uniform(l2.ubo)),
            (CB_SHADOW2, Use::Sampled(l2.shadow, near)),
            (CB_IRRADIANCE2, Use::Sampled(l2.irradiance, lin)),
            (CB_RECEIVERS2, Use::Sampled(l2.recv, near)),
            (CB_BVH_WIDE, bvh(&i.bvh.wide_nodes)),
            (CB_BVH_WIDE_PRIMS, bvh(&i.bvh.wide_prims)),
            (CB_EYE_FLUX, Use::Read(i.eye_flux)),
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::GlassKey;

    /// Every key a frame can ask for has its own pipeline.
    #[test]
    fn glass_keys_index_their_own_pipelines() {
        let mut seen = std::collections::HashSet::new();
        for k in 0..GlassKey::COUNT {
            let key = GlassKey::of_index(k);
            assert!((1..=3).contains(&key.lights));
            assert_eq!(key.index(), k, "{key:?}");
            assert!(seen.insert(k));
        }
        assert_eq!(seen.len(), GlassKey::COUNT);
    }
}
