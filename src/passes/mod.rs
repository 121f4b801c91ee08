//! One file per pass. Each owns its pipelines and records itself; src/frame/ puts them in order and joins
//! them with barriers.

pub mod composite;
pub mod coverage;
pub mod eye;
pub mod geometry;
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

/// Begin dynamic rendering on `colors` (cleared to zero or loaded) and an optional depth target (cleared to 1),
/// with a full-target viewport and scissor.
pub fn begin_rendering(
    device: &Device,
    cmd: ash::vk::CommandBuffer,
    extent: ash::vk::Extent2D,
    colors: &[&crate::vk::Image],
    clear_colors: bool,
    depth: Option<&crate::vk::Image>,
) {
    begin_rendering_with(device, cmd, extent, colors, clear_colors, depth, true)
}

/// [`begin_rendering`], choosing whether the depth attachment is cleared or loaded.
pub fn begin_rendering_with(
    device: &Device,
    cmd: ash::vk::CommandBuffer,
    extent: ash::vk::Extent2D,
    colors: &[&crate::vk::Image],
    clear_colors: bool,
    depth: Option<&crate::vk::Image>,
    clear_depth: bool,
) {
    use ash::vk;
    let color_infos: Vec<_> = colors
        .iter()
        .map(|img| {
            vk::RenderingAttachmentInfo::default()
                .image_view(img.view)
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(if clear_colors { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD })
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } })
        })
        .collect();
    let depth_info = depth.map(|d| {
        vk::RenderingAttachmentInfo::default()
            .image_view(d.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(if clear_depth { vk::AttachmentLoadOp::CLEAR } else { vk::AttachmentLoadOp::LOAD })
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } })
    });
    let area = vk::Rect2D { offset: vk::Offset2D::default(), extent };
    let mut info = vk::RenderingInfo::default().render_area(area).layer_count(1).color_attachments(&color_infos);
    if let Some(d) = depth_info.as_ref() {
        info = info.depth_attachment(d);
    }
    unsafe {
        device.cmd_begin_rendering(cmd, &info);
        device.cmd_set_viewport(
            cmd,
            0,
            &[vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            }],
        );
        device.cmd_set_scissor(cmd, 0, &[area]);
    }
}

/// Work groups for a 2D image pass.
pub fn groups_2d(w: u32, h: u32) -> (u32, u32) {
    let t = crate::shaders::consts::TILE_WG;
    (w.div_ceil(t), h.div_ceil(t))
}
