//! The images and buffers a frame renders into, sized for the settings and the output.

use crate::gpu_types::{FrameData, TransportState, TraversalState};
use crate::passes::{
    coverage::pyramid_layout, photons::INDIRECT_BYTES, AUX_FORMAT, BEAUTY_FORMAT, DEPTH_FORMAT, GEO_FORMAT, HDR_FORMAT,
};
use crate::scene::view::CUBE_FACES;
use crate::scene::MAX_LIGHTS;

/// Passes of a frame at most: a light view's three color passes, for every view of every light (a point light
/// with objects on every side has a view per cube face).
pub const MAX_PASSES: usize = 3 * MAX_LIGHTS * CUBE_FACES;
use crate::settings::ResolvedSettings as Settings;
use crate::vk::{Buffer, Device, Image, VkResult};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Guard entries after the photon buffer's capacity, filled with a canary in debug runs to prove that no shader
/// writes past the capacity it was given.
pub const PHOTON_GUARD: u32 = 1024;
pub const CANARY: u32 = 0xDEAD_BEEF;
/// Bytes of the debug photon dump per photon ([`crate::gpu_types::GpuDebugPhoton`]).
pub const DEBUG_PHOTON_BYTES: u64 = std::mem::size_of::<crate::gpu_types::GpuDebugPhoton>() as u64;

pub struct LightTargets {
    pub front: Image,
    pub front_aux: Image,
    pub back: Image,
    pub depth: Image,
}

pub struct ReceiverTargets {
    pub geo: Image,
    /// Depth of every object from the light: the receiver pass's depth target (receivers, then the refractors
    /// with color writes masked), sampled as the shadow map.
    pub shadow: Image,
    pub flux: Image,
    /// The flux map as one float per texel, for the compute splat (copied into `flux` afterwards).
    pub flux_texels: Buffer,
    pub irradiance: Image,
}

pub struct EyeTargets {
    /// The receivers' eye-view g-buffer: normal and distance, albedo, depth.
    pub recv: Image,
    pub albedo: Image,
    pub depth: Image,
    /// Written by the shading pass: the radiance (a: eye distance) and the AOVs.
    pub radiance: Image,
    pub caustics: Image,
    pub direct: Image,
    pub front: Image,
    pub front_aux: Image,
    pub back: Image,
    pub refr_depth: Image,
    pub beauty: Image,
    /// The beauty image's linear radiance (before exposure and tone mapping).
    pub hdr: Image,
    /// Exact transport: the glass's radiance per eye sample, each light's added in turn (a: 1 where glass is in
    /// front).
    pub glass: Image,
    /// The eye deposit (docs/design.md "The eye deposit"): caustic flux per eye sample, W, in three planes (red,
    /// green, blue), the photon passes' atomic target; 4 bytes where it does not fit one binding.
    pub flux: Buffer,
    /// Whether `flux` holds the eye's samples (12 bytes each within the device's binding limit).
    pub deposit_fits: bool,
}

impl EyeTargets {
    /// The beauty images at `width`×`height`; the eye buffers they are composited from `aa` times larger per side
    /// (the supersamples).
    pub fn new(device: &Arc<Device>, width: u32, height: u32, aa: u32, binding_limit: u64) -> VkResult<Self> {
        use vk::ImageUsageFlags as U;
        let flux_bytes = Self::deposit_bytes(width, height, aa);
        let deposit_fits = flux_bytes <= binding_limit;
        let flux = Buffer::new(
            device,
            "eye deposit",
            if deposit_fits { flux_bytes } else { 4 },
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let img = |name: &str, format, usage| Image::new(device, name, format, ext(aa * width, aa * height), usage);
        let out = |name: &str, format, usage| Image::new(device, name, format, ext(width, height), usage);
        let color = U::COLOR_ATTACHMENT | U::SAMPLED;
        let shaded = U::STORAGE | U::SAMPLED | U::TRANSFER_SRC;
        Ok(EyeTargets {
            recv: img("eye receivers", GEO_FORMAT, color)?,
            albedo: img("eye receiver albedo", crate::passes::eye::ALBEDO_FORMAT, color)?,
            depth: img("eye depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?,
            radiance: img("eye radiance", HDR_FORMAT, shaded)?,
            caustics: img("eye caustics", HDR_FORMAT, shaded)?,
            direct: img("eye direct", HDR_FORMAT, shaded)?,
            front: img("eye refractor front", GEO_FORMAT, color)?,
            front_aux: img("eye refractor ior", AUX_FORMAT, color)?,
            back: img("eye refractor back", GEO_FORMAT, color)?,
            refr_depth: img("eye refractor depth", DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?,
            beauty: out("beauty", BEAUTY_FORMAT, U::STORAGE | U::TRANSFER_SRC)?,
            hdr: out("beauty linear", HDR_FORMAT, U::STORAGE | U::TRANSFER_SRC)?,
            glass: img("eye glass radiance", HDR_FORMAT, U::STORAGE)?,
            flux,
            deposit_fits,
        })
    }

    /// The eye deposit's bytes: three floats per eye sample.
    pub fn deposit_bytes(width: u32, height: u32, aa: u32) -> u64 {
        12 * (aa * width) as u64 * (aa * height) as u64
    }
}

pub struct PhotonBuffers {
    pub state: Buffer,
    pub photons: Buffer,
    pub indirect: Buffer,
    pub coverage: Buffer,
    pub debug: Buffer,
    /// One splat record (16 bytes) per photon-buffer entry.
    pub splats: Buffer,
    /// Photons that carry their color (`ResolvedSettings::carried_color`): each record's color or wavelength (4 bytes).
    pub splat_tints: Buffer,
    /// Exact transport: the wave state and energy account, and two ray queues (32 bytes a ray).
    pub transport: Buffer,
    pub queues: [Buffer; 2],
    pub capacity: u32,
    pub pyramid_offsets: Vec<u32>,
}

impl LightTargets {
    /// The refractors' and receivers' g-buffers from the light, `s.gbuffer_side()` a side.
    fn new(device: &Arc<Device>, s: &Settings) -> VkResult<Self> {
        use vk::ImageUsageFlags as U;
        let img = |name: &str, format, e, usage| Image::new(device, name, format, e, usage);
        let color = U::COLOR_ATTACHMENT | U::SAMPLED;
        let r = ext(s.gbuffer_side(), s.gbuffer_side());
        Ok(LightTargets {
            front: img("light front", GEO_FORMAT, r, color)?,
            front_aux: img("light front ior", AUX_FORMAT, r, color)?,
            back: img("light back", GEO_FORMAT, r, color)?,
            depth: img("light depth", DEPTH_FORMAT, r, U::DEPTH_STENCIL_ATTACHMENT)?,
        })
    }
}

impl ReceiverTargets {
    /// One light view's receiver maps, `s.caustic_res` a side.
    fn new(device: &Arc<Device>, s: &Settings) -> VkResult<Self> {
        use vk::ImageUsageFlags as U;
        let img = |name: &str, format, e, usage| Image::new(device, name, format, e, usage);
        let color = U::COLOR_ATTACHMENT | U::SAMPLED;
        let m = ext(s.caustic_res, s.caustic_res);
        Ok(ReceiverTargets {
            geo: img("receivers from light", GEO_FORMAT, m, color)?,
            shadow: img("shadow map", DEPTH_FORMAT, m, U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED)?,
            flux: img(
                "caustic flux map",
                crate::passes::flux_format(device),
                m,
                color | U::TRANSFER_SRC | U::TRANSFER_DST,
            )?,
            flux_texels: flux_texels(device, s)?,
            irradiance: img("caustic irradiance map", HDR_FORMAT, m, U::STORAGE | U::SAMPLED | U::TRANSFER_DST)?,
        })
    }
}

impl PhotonBuffers {
    /// The photon stage's buffers, for `s.photon_capacity()` photons.
    fn new(device: &Arc<Device>, s: &Settings) -> VkResult<Self> {
        use vk::BufferUsageFlags as B;
        let gpu = MemoryLocation::GpuOnly;
        let capacity = s.photon_capacity();
        let tints = if s.carried_color.carried() { capacity } else { 4 };
        let mips = s.gbuffer_level() + 1;
        let (pyramid_offsets, pyramid_len) = pyramid_layout(s.gbuffer_side(), mips);
        let debug_bytes = 16 + DEBUG_PHOTON_BYTES * s.debug_photons.max(1) as u64;
        // Exact transport's two ray queues; the wide layout's waves read their rays as texels too.
        let ray_queue = |name: &str| {
            let bytes = s.ray_bytes() as u64 * s.ray_queue_capacity().max(1) as u64;
            Buffer::new(device, name, bytes, B::STORAGE_BUFFER | B::UNIFORM_TEXEL_BUFFER, gpu)?
                .with_texel_view(vk::Format::R32G32B32A32_UINT, 16)
        };
        Ok(PhotonBuffers {
            state: Buffer::new(
                device,
                "traversal state",
                std::mem::size_of::<TraversalState>() as u64,
                B::STORAGE_BUFFER | B::TRANSFER_DST | B::TRANSFER_SRC,
                gpu,
            )?,
            // The wide layout's waves read the photons and the coverage pyramid as texels (glsl/wave.comp).
            photons: Buffer::new(
                device,
                "photon buffer",
                8 * (capacity as u64 + PHOTON_GUARD as u64),
                B::STORAGE_BUFFER | B::UNIFORM_TEXEL_BUFFER | B::TRANSFER_DST | B::TRANSFER_SRC,
                gpu,
            )?
            .with_texel_view(vk::Format::R32G32_UINT, 8)?,
            indirect: Buffer::new(
                device,
                "indirect commands",
                INDIRECT_BYTES,
                B::STORAGE_BUFFER | B::INDIRECT_BUFFER | B::TRANSFER_DST,
                gpu,
            )?,
            coverage: Buffer::new(
                device,
                "coverage pyramid",
                4 * pyramid_len as u64,
                B::STORAGE_BUFFER | B::UNIFORM_TEXEL_BUFFER,
                gpu,
            )?
            .with_texel_view(vk::Format::R32_UINT, 4)?,
            debug: Buffer::new(
                device,
                "debug photons",
                debug_bytes,
                B::STORAGE_BUFFER | B::TRANSFER_DST | B::TRANSFER_SRC,
                gpu,
            )?,
            splats: Buffer::new(device, "splat records", 16 * capacity as u64, B::STORAGE_BUFFER, gpu)?,
            // Color photons: a record's color, one word each; else never read.
            splat_tints: Buffer::new(device, "splat record colors", 4 * tints as u64, B::STORAGE_BUFFER, gpu)?,
            transport: Buffer::new(
                device,
                "transport state",
                std::mem::size_of::<TransportState>() as u64,
                B::STORAGE_BUFFER | B::TRANSFER_DST | B::TRANSFER_SRC,
                gpu,
            )?,
            queues: [ray_queue("ray queue 0")?, ray_queue("ray queue 1")?],
            capacity,
            pyramid_offsets,
        })
    }
}

pub struct Targets {
    /// The uniforms of each frame in flight (`ubos[slot]`), and within it of each pass: light-major, one per light
    /// and color channel (its views, power and channel). The host writes a slot's uniforms only after the frame
    /// that last used that slot has finished.
    pub ubos: Vec<Vec<Buffer>>,
    pub light: LightTargets,
    /// Each light's receiver g-buffer, shadow map, flux and irradiance maps.
    pub receivers: Vec<ReceiverTargets>,
    pub eye: EyeTargets,
    pub photon: PhotonBuffers,
    /// Host-visible, one per frame in flight: the traversal state, the debug dump, the guard, and one AOV image.
    pub readbacks: Vec<Buffer>,
    pub width: u32,
    pub height: u32,
    /// Eye-view supersampling factor per side (the eye buffers are `aa` times the output size).
    pub aa: u32,
}

fn ext(w: u32, h: u32) -> vk::Extent2D {
    vk::Extent2D { width: w, height: h }
}

impl Targets {
    /// Whether a frame under `s` runs the eye deposit: asked for (exact transport, a compute splat), a flux map
    /// the compute splat adds into, and an eye deposit within one binding.
    pub fn eye_deposit(&self, s: &Settings) -> bool {
        s.eye_deposit
            && self.eye.deposit_fits
            && self.receivers.first().is_some_and(|r| r.flux.format == vk::Format::R32_SFLOAT)
    }

    /// `aa`: eye-view supersampling per side; `lights`: how many light views get their own receiver maps
    /// (1..=MAX_LIGHTS·CUBE_FACES); `passes`: uniforms, one per light view and color channel; `slots`: frames in
    /// flight.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        device: &Arc<Device>,
        s: &Settings,
        width: u32,
        height: u32,
        aa: u32,
        lights: usize,
        passes: usize,
        slots: usize,
    ) -> VkResult<Self> {
        let light = LightTargets::new(device, s)?;
        let receivers = (0..lights.max(1)).map(|_| ReceiverTargets::new(device, s)).collect::<VkResult<Vec<_>>>()?;
        let eye = EyeTargets::new(device, width, height, aa, s.binding_limit)?;
        let photon = PhotonBuffers::new(device, s)?;
        Ok(Targets {
            ubos: Self::frame_uniforms(device, slots, passes)?,
            light,
            receivers,
            eye,
            photon,
            readbacks: Self::readback_buffers(device, s, width, height, slots)?,
            width,
            height,
            aa,
        })
    }

    /// The uniforms' buffers: `passes` for each of `slots` frames in flight.
    fn frame_uniforms(device: &Arc<Device>, slots: usize, passes: usize) -> VkResult<Vec<Vec<Buffer>>> {
        (0..slots.max(1))
            .map(|_| {
                (0..passes.max(1))
                    .map(|_| {
                        Buffer::new(
                            device,
                            "frame uniforms",
                            std::mem::size_of::<FrameData>() as u64,
                            vk::BufferUsageFlags::UNIFORM_BUFFER,
                            MemoryLocation::CpuToGpu,
                        )
                    })
                    .collect::<VkResult<Vec<_>>>()
            })
            .collect()
    }

    fn readback_buffers(
        device: &Arc<Device>,
        s: &Settings,
        width: u32,
        height: u32,
        slots: usize,
    ) -> VkResult<Vec<Buffer>> {
        let bytes = Self::readback_layout(s, 16 * width as u64 * height as u64).total;
        (0..slots.max(1))
            .map(|_| {
                Buffer::new(
                    device,
                    "readback",
                    bytes,
                    // A continuation restores its passes' states from the frame before.
                    vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::TRANSFER_SRC,
                    MemoryLocation::GpuToCpu,
                )
            })
            .collect()
    }

    /// A new output size: only the eye-sized targets and the readback buffer change.
    pub fn resize(&mut self, device: &Arc<Device>, s: &Settings, width: u32, height: u32, aa: u32) -> VkResult<()> {
        self.eye = EyeTargets::new(device, width, height, aa, s.binding_limit)?;
        self.aa = aa;
        self.readbacks = Self::readback_buffers(device, s, width, height, self.readbacks.len())?;
        self.width = width;
        self.height = height;
        Ok(())
    }

    /// Where each thing lies in the readback buffer.
    pub fn readback_layout(s: &Settings, aov_bytes: u64) -> ReadbackLayout {
        let state = 0u64;
        let transport = MAX_PASSES as u64 * std::mem::size_of::<TraversalState>() as u64;
        let debug = transport + MAX_PASSES as u64 * std::mem::size_of::<TransportState>() as u64;
        let guard = debug + 16 + DEBUG_PHOTON_BYTES * s.debug_photons.max(1) as u64;
        let aov = guard + 8 * PHOTON_GUARD as u64;
        ReadbackLayout { state, transport, debug, guard, aov, total: aov + aov_bytes }
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ReadbackLayout {
    /// MAX_PASSES traversal states, one per light and color channel.
    pub state: u64,
    /// MAX_PASSES transport states, one per light and color channel.
    pub transport: u64,
    pub debug: u64,
    pub guard: u64,
    pub aov: u64,
    pub total: u64,
}

/// The coarse levels of a `res`² map's flux texels (glsl/common/splat_levels.glsl): as many halvings as `res`
/// allows, at most SPLAT_LEVELS.
pub fn splat_levels(res: u32) -> u32 {
    crate::shaders::consts::SPLAT_LEVELS.min(res.trailing_zeros())
}

/// The compute splat's flux texels, every plane. The resolve reads them through a texel view (a device whose texel
/// buffers are too short for them gets none, and the resolve samples the flux image instead).
fn flux_texels(device: &Arc<Device>, s: &Settings) -> VkResult<Buffer> {
    use vk::BufferUsageFlags as B;
    let usage = B::STORAGE_BUFFER | B::UNIFORM_TEXEL_BUFFER | B::TRANSFER_SRC | B::TRANSFER_DST;
    let bytes = 4 * splat_texels(s.caustic_res) * flux_planes(s);
    Buffer::new(device, "caustic flux texels", bytes, usage, MemoryLocation::GpuOnly)?
        .with_texel_view(vk::Format::R32_SFLOAT, 4)
}

/// Planes of the flux texels: red, green and blue where the photons carry their color, else one.
pub fn flux_planes(s: &Settings) -> u64 {
    if s.carried_color.carried() {
        3
    } else {
        1
    }
}

/// Texels of a `res`² map's flux texels with their coarse levels (one plane).
pub fn splat_texels(res: u32) -> u64 {
    (0..=splat_levels(res)).map(|m| ((res >> m) as u64).pow(2)).sum()
}
