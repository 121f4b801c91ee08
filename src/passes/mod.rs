//! One file per pass. Each owns its pipelines and records itself; src/frame/ puts them in order and joins
//! them with barriers.

pub mod composite;
pub mod coverage;
pub mod eye;
pub mod geometry;
pub mod overlay;
pub mod photons;
pub mod resolve;
pub mod scene_update;

use crate::vk::{Device, VkResult};
use std::sync::Arc;

// Every pass binds its resources as push descriptors, and Vulkan guarantees 32 of them (maxPushDescriptors) on
// every device with VK_KHR_push_descriptor: the largest layouts stay within it, so no device is refused for it
// (pipeline creation checks each layout against the device's own limit all the same, src/vk/pipeline.rs).
const _: () = {
    use crate::shaders::consts::{CB_COUNT, EB_COUNT, PB_COUNT};
    assert!(CB_COUNT <= 32 && PB_COUNT <= 32 && EB_COUNT <= 32);
};

/// The view-space g-buffers: distance (float bits) and an octahedral normal (glsl/common/gbuffer.glsl).
pub const GEO_FORMAT: ash::vk::Format = ash::vk::Format::R32G32_UINT;
pub const AUX_FORMAT: ash::vk::Format = ash::vk::Format::R32_SFLOAT;
pub const DEPTH_FORMAT: ash::vk::Format = ash::vk::Format::D32_SFLOAT;
pub const HDR_FORMAT: ash::vk::Format = ash::vk::Format::R32G32B32A32_SFLOAT;
pub const BEAUTY_FORMAT: ash::vk::Format = ash::vk::Format::R8G8B8A8_UNORM;

/// Every pipeline of a frame.
pub struct Passes {
    pub geometry: geometry::GeometryPass,
    pub coverage: coverage::CoveragePass,
    pub photons: photons::PhotonPasses,
    pub resolve: resolve::ResolvePass,
    pub eye: eye::EyePass,
    pub composite: composite::CompositePass,
    pub scene_update: scene_update::SceneUpdatePass,
}

/// The caustic flux map holds one channel (the light's color is applied in the resolve): R32F where the device
/// can blend it, else RGBA32F.
pub fn flux_format(device: &Device) -> ash::vk::Format {
    let f = ash::vk::Format::R32_SFLOAT;
    let props = unsafe { device.instance.raw.get_physical_device_format_properties(device.physical, f) };
    if props.optimal_tiling_features.contains(ash::vk::FormatFeatureFlags::COLOR_ATTACHMENT_BLEND) {
        f
    } else {
        HDR_FORMAT
    }
}

impl Passes {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        Ok(Passes {
            geometry: geometry::GeometryPass::new(device)?,
            coverage: coverage::CoveragePass::new(device)?,
            photons: photons::PhotonPasses::new(device, flux_format(device))?,
            resolve: resolve::ResolvePass::new(device)?,
            eye: eye::EyePass::new(device)?,
            composite: composite::CompositePass::new(device)?,
            scene_update: scene_update::SceneUpdatePass::new(device),
        })
    }
}

/// Work groups for a 2D image pass.
pub fn groups_2d(w: u32, h: u32) -> (u32, u32) {
    let t = crate::shaders::consts::TILE_WG;
    (w.div_ceil(t), h.div_ceil(t))
}
