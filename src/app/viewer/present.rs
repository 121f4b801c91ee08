//! The viewer's final target: the frame's `beauty` image (R8G8B8A8_UNORM, already tone-mapped and sRGB-encoded)
//! copied into the acquired swapchain image, an optional copy of that image for a screenshot, and the transition
//! to PRESENT_SRC. These commands are appended to the frame's last command buffer (`frame::Finish`).
//!
//! The beauty bytes are sRGB-encoded already, so they must reach the swapchain image unchanged:
//! - UNORM swapchain: one blit (it swizzles RGBA to BGRA where needed and does no sRGB conversion);
//! - sRGB swapchain: a blit would encode the bytes a second time, so the blit goes to an intermediate image of the
//!   swapchain format's UNORM twin and a copy (bits unchanged: the formats are size-compatible) moves it into the
//!   swapchain image.
//! - The overlay (overlay.rs) is drawn into the swapchain image after the blit where its images allow it (a UNORM
//!   format with COLOR_ATTACHMENT usage), else into the intermediate image before the copy.

use crate::app::viewer::swapchain::{is_bgra, is_srgb, unorm_twin, Swapchain};
use ash::vk;
use caustics::gpu::{Access, Barriers, Buffer, Device, Image, VkError, VkResult, COLOR_RANGE};
use caustics::overlay::{OverlayMesh, OverlayPainter, OverlayTarget};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Where a screenshot's pixels came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CaptureSource {
    /// The swapchain image itself, after the copy into it (needs TRANSFER_SRC usage on swapchain images).
    Swapchain,
    /// The beauty image that was copied into the swapchain image (when swapchain images lack TRANSFER_SRC).
    Beauty,
}

/// A screenshot: RGBA8, opaque, row 0 at the top.
#[derive(Clone, Debug)]
pub struct Capture {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    pub source: CaptureSource,
}

/// The overlay a frame draws: its painter, the frame's slot, its meshes and the window's pixels per point.
pub struct Overlay<'a> {
    pub painter: &'a mut OverlayPainter,
    pub slot: usize,
    pub meshes: &'a [OverlayMesh<'a>],
    pub pixels_per_point: f32,
}

pub struct Presenter {
    device: Arc<Device>,
    /// For sRGB swapchains: the blit target, in the swapchain format's UNORM twin.
    intermediate: Option<Image>,
    capture: Option<Buffer>,
    capture_layout: Option<(u32, u32, bool, CaptureSource)>,
}

fn full_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers {
        aspect_mask: vk::ImageAspectFlags::COLOR,
        mip_level: 0,
        base_array_layer: 0,
        layer_count: 1,
    }
}

fn corner(e: vk::Extent2D) -> vk::Offset3D {
    vk::Offset3D { x: e.width as i32, y: e.height as i32, z: 1 }
}

impl Presenter {
    pub fn new(device: &Arc<Device>) -> Self {
        Presenter { device: device.clone(), intermediate: None, capture: None, capture_layout: None }
    }

    fn blit_dst_supported(&self, format: vk::Format) -> bool {
        let props =
            unsafe { self.device.instance.raw.get_physical_device_format_properties(self.device.physical, format) };
        props.optimal_tiling_features.contains(vk::FormatFeatureFlags::BLIT_DST)
    }

    /// Make the per-swapchain resources (the intermediate image for sRGB formats, or to draw the overlay into;
    /// the screenshot buffer).
    pub fn prepare(&mut self, swapchain: &Swapchain, capture: bool, overlay: bool) -> VkResult<()> {
        let format = swapchain.format.format;
        let extent = swapchain.extent;
        let direct = !is_srgb(format) && self.blit_dst_supported(format) && (!overlay || !swapchain.views.is_empty());
        if direct {
            self.intermediate = None;
        } else {
            let twin = unorm_twin(format);
            if !self.blit_dst_supported(twin) {
                return Err(VkError::Unsupported(format!(
                    "cannot fill the swapchain: neither {format:?} nor {twin:?} supports BLIT_DST"
                )));
            }
            if self.intermediate.as_ref().map(|i| (i.format, i.extent)) != Some((twin, extent)) {
                self.intermediate = None;
                // SAMPLED only because vk::Image always makes a view, and a view needs a view-compatible usage.
                let usage = vk::ImageUsageFlags::TRANSFER_DST
                    | vk::ImageUsageFlags::TRANSFER_SRC
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::COLOR_ATTACHMENT;
                self.intermediate = Some(Image::new(&self.device, "present intermediate", twin, extent, usage)?);
            }
        }
        if capture {
            let bytes = 4 * extent.width as u64 * extent.height as u64;
            if self.capture.as_ref().map(|b| b.size) != Some(bytes.max(4)) {
                self.capture = None;
                self.capture = Some(Buffer::new(
                    &self.device,
                    "screenshot readback",
                    bytes,
                    vk::BufferUsageFlags::TRANSFER_DST,
                    MemoryLocation::GpuToCpu,
                )?);
            }
        }
        Ok(())
    }

    /// Record: beauty → swapchain image `index` (acquired; the submit waits for its semaphore at ALL_TRANSFER),
    /// with `overlay` drawn over it (prepared with `overlay` true), optionally a copy of it into the screenshot
    /// buffer, then the transition to PRESENT_SRC.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        beauty: &Image,
        (swapchain, index): (&Swapchain, u32),
        capture: bool,
        overlay: Option<Overlay>,
    ) -> VkResult<()> {
        let d = &*self.device;
        let target = swapchain.images[index as usize];
        let range = COLOR_RANGE;
        let extent = swapchain.extent;
        // The acquire's semaphore wait covers ALL_TRANSFER; starting the layout transition from that stage chains
        // it after the wait (the presentation engine's reads of the previous contents are over by then).
        let acquire = vk::ImageMemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .src_access_mask(vk::AccessFlags2::NONE)
            .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
            .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .old_layout(vk::ImageLayout::UNDEFINED)
            .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(target)
            .subresource_range(range);
        unsafe {
            d.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&[acquire]));
        }
        let src_extent = beauty.extent;
        let blit_to = |dst: vk::Image| {
            let region = vk::ImageBlit2::default()
                .src_subresource(full_layers())
                .src_offsets([vk::Offset3D::default(), corner(src_extent)])
                .dst_subresource(full_layers())
                .dst_offsets([vk::Offset3D::default(), corner(extent)]);
            let info = vk::BlitImageInfo2::default()
                .src_image(beauty.raw)
                .src_image_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                .dst_image(dst)
                .dst_image_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                .regions(std::slice::from_ref(&region))
                // A preview drawn at a lower resolution is scaled up with bilinear filtering.
                .filter(if (src_extent.width, src_extent.height) == (extent.width, extent.height) {
                    vk::Filter::NEAREST
                } else {
                    vk::Filter::LINEAR
                });
            unsafe { d.cmd_blit_image2(cmd, &info) };
        };
        match &self.intermediate {
            None => {
                blit_to(target);
                if let Some(o) = overlay {
                    let into = OverlayTarget {
                        image: target,
                        view: swapchain.views[index as usize],
                        format: swapchain.format.format,
                        extent,
                        before: Access::TransferDst,
                        after: Access::TransferDst,
                    };
                    o.painter.record(cmd, o.slot, into, o.meshes, o.pixels_per_point)?
                }
            }
            Some(im) => {
                let mut b = Barriers::new();
                b.image(im, &[Access::FrameStart], &[Access::TransferDst]).flush(d, cmd);
                blit_to(im.raw);
                match overlay {
                    Some(o) => {
                        let into = OverlayTarget {
                            image: im.raw,
                            view: im.view,
                            format: im.format,
                            extent: im.extent,
                            before: Access::TransferDst,
                            after: Access::TransferSrc,
                        };
                        o.painter.record(cmd, o.slot, into, o.meshes, o.pixels_per_point)?
                    }
                    None => {
                        b.image(im, &[Access::TransferDst], &[Access::TransferSrc]).flush(d, cmd);
                    }
                }
                let region = vk::ImageCopy2::default()
                    .src_subresource(full_layers())
                    .dst_subresource(full_layers())
                    .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 });
                let info = vk::CopyImageInfo2::default()
                    .src_image(im.raw)
                    .src_image_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL)
                    .dst_image(target)
                    .dst_image_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
                    .regions(std::slice::from_ref(&region));
                unsafe { d.cmd_copy_image2(cmd, &info) };
            }
        }
        let mut post = Barriers::new();
        let last = self.record_capture(cmd, beauty, (swapchain, index), capture, &mut post);
        // The render-done semaphore is signalled at ALL_COMMANDS, which covers this transition.
        post.image_raw(target, range, &[last], &[Access::Present]).flush(&self.device, cmd);
        Ok(())
    }

    /// Record the copy of the presented image (or, where the swapchain's cannot be read, of `beauty`) into the
    /// screenshot buffer when `capture`; `post` gets the buffer's barrier for the host. Returns the swapchain
    /// image's last use.
    fn record_capture(
        &mut self,
        cmd: vk::CommandBuffer,
        beauty: &Image,
        (swapchain, index): (&Swapchain, u32),
        capture: bool,
        post: &mut Barriers,
    ) -> Access {
        let d = &*self.device;
        let target = swapchain.images[index as usize];
        let mut last = Access::TransferDst;
        self.capture_layout = None;
        if let (true, Some(buf)) = (capture, &self.capture) {
            let mut b = Barriers::new();
            b.buffer(buf, &[Access::FrameStart], &[Access::TransferDst]);
            let (image, size, bgra, source) = if swapchain.usage.contains(vk::ImageUsageFlags::TRANSFER_SRC) {
                b.image_raw(target, COLOR_RANGE, &[Access::TransferDst], &[Access::TransferSrc]);
                last = Access::TransferSrc;
                (target, swapchain.extent, is_bgra(swapchain.format.format), CaptureSource::Swapchain)
            } else {
                (beauty.raw, beauty.extent, false, CaptureSource::Beauty)
            };
            b.flush(d, cmd);
            let region = vk::BufferImageCopy::default().image_subresource(full_layers()).image_extent(vk::Extent3D {
                width: size.width,
                height: size.height,
                depth: 1,
            });
            unsafe {
                d.cmd_copy_image_to_buffer(cmd, image, vk::ImageLayout::TRANSFER_SRC_OPTIMAL, buf.raw, &[region]);
            }
            post.buffer(buf, &[Access::TransferDst], &[Access::HostRead]);
            self.capture_layout = Some((size.width, size.height, bgra, source));
        }
        last
    }

    /// The screenshot recorded by the last [`Self::record`] (call after its submit completed).
    pub fn read_capture(&self) -> VkResult<Option<Capture>> {
        let (Some((width, height, bgra, source)), Some(buf)) = (self.capture_layout, &self.capture) else {
            return Ok(None);
        };
        let mut rgba = buf.read::<u8>(0, 4 * width as usize * height as usize)?;
        for p in rgba.chunks_exact_mut(4) {
            if bgra {
                p.swap(0, 2);
            }
            p[3] = 255;
        }
        Ok(Some(Capture { width, height, rgba, source }))
    }
}
