//! The viewer's overlay (docs/viewer.md "The overlay"): textured 2D triangles drawn over a finished frame, in the
//! frame's own command buffer. Its author (the viewer builds it with egui) hands over meshes in points, with
//! premultiplied sRGB-encoded colors, and the textures they sample; [`OverlayPainter::record`] uploads what changed,
//! draws each mesh inside its clip rectangle with glsl/overlay.vert and overlay.frag, and declares its accesses to
//! the target and the textures as barriers, like every pass.
//!
//! The target is a UNORM image whose bytes are already sRGB-encoded (the tone-mapped beauty image, copied into the
//! window's image), so the triangles blend in that encoding, as egui expects of such a target.

use crate::gpu_types::OverlayPush;
use crate::shaders;
use crate::shaders::consts::OV_TEXTURE;
use crate::vk::image::COLOR_RANGE;
use crate::vk::pipeline::{ordered, Bind, Blend, ColorTarget, GraphicsDesc, Pipeline};
use crate::vk::{Access, Barriers, Buffer, Device, Image, Sampler, VkResult};
use ash::vk;
use gpu_allocator::MemoryLocation;
use std::collections::HashMap;
use std::sync::Arc;

/// A vertex of the overlay: position in points from the target's top left, texture coordinate, and color (RGBA,
/// premultiplied, sRGB-encoded). egui's `epaint::Vertex` has this layout.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct OverlayVertex {
    /// Position in points from the target's top left.
    pub pos: [f32; 2],
    /// Texture coordinate.
    pub uv: [f32; 2],
    /// RGBA, premultiplied, sRGB-encoded.
    pub color: [u8; 4],
}

/// Triangles that sample one texture, drawn inside a clip rectangle (points: min x, min y, max x, max y).
pub struct OverlayMesh<'a> {
    /// Points: min x, min y, max x, max y.
    pub clip: [f32; 4],
    /// The texture's id ([`OverlayPainter::set_texture`]).
    pub texture: u64,
    /// The vertices.
    pub vertices: &'a [OverlayVertex],
    /// Triangles: three indices into `vertices` each.
    pub indices: &'a [u32],
}

/// The image the overlay is drawn into: its current use, and the use it is left in.
pub struct OverlayTarget {
    /// A color-attachment image of a UNORM format (one mip, one layer), and a view of it.
    pub image: vk::Image,
    /// Its view.
    pub view: vk::ImageView,
    /// Its format.
    pub format: vk::Format,
    /// Its size in pixels.
    pub extent: vk::Extent2D,
    /// How the frame used it last.
    pub before: Access,
    /// How the frame uses it next.
    pub after: Access,
}

/// A texture's new texels (RGBA8, premultiplied, sRGB-encoded): all of it, or a rectangle at `pos`.
struct Upload {
    id: u64,
    pos: Option<[u32; 2]>,
    size: [u32; 2],
    linear: bool,
    rgba: Vec<u8>,
}

struct Texture {
    image: Image,
    linear: bool,
}

/// What a frame in flight holds until its slot comes round again: its vertices and indices, the staging buffer
/// of its uploads, and the textures freed while it may still sample them.
#[derive(Default)]
struct Slot {
    vertices: Option<Buffer>,
    indices: Option<Buffer>,
    staging: Option<Buffer>,
    retired: Vec<Image>,
}

/// Draws the overlay's meshes; one per window, for every frame in flight.
pub struct OverlayPainter {
    device: Arc<Device>,
    /// One pipeline per target format (the window's format can change with its swapchain).
    pipelines: HashMap<vk::Format, Pipeline>,
    nearest: Sampler,
    linear: Sampler,
    textures: HashMap<u64, Texture>,
    uploads: Vec<Upload>,
    frees: Vec<u64>,
    slots: Vec<Slot>,
}

impl OverlayPainter {
    /// A painter for `frames_in_flight` frames (the slots [`Self::record`] is called with).
    pub fn new(device: &Arc<Device>, frames_in_flight: usize) -> VkResult<Self> {
        Ok(OverlayPainter {
            device: device.clone(),
            pipelines: HashMap::new(),
            nearest: Sampler::new(device, vk::Filter::NEAREST)?,
            linear: Sampler::new(device, vk::Filter::LINEAR)?,
            textures: HashMap::new(),
            uploads: Vec::new(),
            frees: Vec::new(),
            slots: (0..frames_in_flight.max(1)).map(|_| Slot::default()).collect(),
        })
    }

    /// Set texture `id`'s texels (`rgba`: `size` texels, RGBA8, premultiplied, sRGB-encoded): the whole texture
    /// (`pos` None, which makes it), or a rectangle of it at `pos`. `linear`: filtered bilinearly, else nearest. The
    /// upload happens in the next recorded frame.
    pub fn set_texture(&mut self, id: u64, pos: Option<[u32; 2]>, size: [u32; 2], linear: bool, rgba: Vec<u8>) {
        debug_assert_eq!(rgba.len(), 4 * size[0] as usize * size[1] as usize);
        self.uploads.push(Upload { id, pos, size, linear, rgba });
    }

    /// Free texture `id` after the next recorded frame (which may still draw with it).
    pub fn free_texture(&mut self, id: u64) {
        self.frees.push(id);
    }

    /// The textures the painter holds.
    pub fn texture_count(&self) -> usize {
        self.textures.len()
    }

    fn pipeline(&mut self, format: vk::Format) -> VkResult<&Pipeline> {
        if !self.pipelines.contains_key(&format) {
            let stride = std::mem::size_of::<OverlayVertex>() as u32;
            let desc = GraphicsDesc {
                vertex: shaders::OVERLAY_VERT.words(),
                fragment: shaders::OVERLAY_FRAG.words(),
                vertex_attributes: &[
                    (vk::Format::R32G32_SFLOAT, 0),
                    (vk::Format::R32G32_SFLOAT, 8),
                    (vk::Format::R8G8B8A8_UNORM, 16),
                ],
                vertex_stride: stride,
                topology: vk::PrimitiveTopology::TRIANGLE_LIST,
                cull: vk::CullModeFlags::NONE,
                depth: None,
                colors: &[ColorTarget { format, blend: Blend::Over }],
            };
            let pipeline = Pipeline::graphics(&self.device, &format!("overlay {format:?}"), &desc)?;
            self.pipelines.insert(format, pipeline);
        }
        Ok(&self.pipelines[&format])
    }

    /// Host-visible `bytes` for `slot`'s buffer `which`, grown to a power of two so that a few sizes serve.
    fn host_buffer(
        device: &Arc<Device>,
        buffer: &mut Option<Buffer>,
        name: &str,
        bytes: u64,
        usage: vk::BufferUsageFlags,
    ) -> VkResult<()> {
        if buffer.as_ref().is_none_or(|b| b.size < bytes) {
            *buffer = None;
            let size = bytes.next_power_of_two().max(4096);
            *buffer = Some(Buffer::new(device, name, size, usage, MemoryLocation::CpuToGpu)?);
        }
        Ok(())
    }

    /// Record the pending uploads into `cmd` (frame slot `slot`): each into a staging buffer, then copied into its
    /// texture, which is left for the fragment shader.
    fn record_uploads(&mut self, cmd: vk::CommandBuffer, slot: usize) -> VkResult<()> {
        let uploads = std::mem::take(&mut self.uploads);
        if uploads.is_empty() {
            return Ok(());
        }
        let bytes: u64 = uploads.iter().map(|u| u.rgba.len() as u64).sum();
        let s = &mut self.slots[slot];
        Self::host_buffer(&self.device, &mut s.staging, "overlay uploads", bytes, vk::BufferUsageFlags::TRANSFER_SRC)?;
        let staging = s.staging.as_mut().expect("staging");
        let mut offset = 0u64;
        let mut copies = Vec::new();
        for u in &uploads {
            staging.write(offset, &u.rgba)?;
            copies.push(offset);
            offset += u.rgba.len() as u64;
        }
        // The submission makes the host's writes visible to the device: no barrier for the staging buffer.
        for (u, &at) in uploads.iter().zip(&copies) {
            // A whole texture of the size it has is written in place (the overlay's graph, every frame).
            let same = self.textures.get(&u.id).is_some_and(|t| {
                (t.image.extent.width, t.image.extent.height, t.linear) == (u.size[0], u.size[1], u.linear)
            });
            let fresh = u.pos.is_none() && !same;
            if fresh {
                let extent = vk::Extent2D { width: u.size[0].max(1), height: u.size[1].max(1) };
                let usage = vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST;
                let image = Image::new(&self.device, "overlay texture", vk::Format::R8G8B8A8_UNORM, extent, usage)?;
                if let Some(old) = self.textures.insert(u.id, Texture { image, linear: u.linear }) {
                    self.slots[slot].retired.push(old.image);
                }
            }
            let Some(tex) = self.textures.get(&u.id) else {
                continue; // a partial update of a texture that was never set: nothing to update
            };
            let prev = if fresh { Access::FrameStart } else { Access::FragmentSampled };
            let staging = self.slots[slot].staging.as_ref().expect("staging");
            let mut b = Barriers::new();
            b.image(&tex.image, &[prev], &[Access::TransferDst]).flush(&self.device, cmd);
            let [x, y] = u.pos.unwrap_or([0, 0]);
            let region = vk::BufferImageCopy::default()
                .buffer_offset(at)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: 0,
                    base_array_layer: 0,
                    layer_count: 1,
                })
                .image_offset(vk::Offset3D { x: x as i32, y: y as i32, z: 0 })
                .image_extent(vk::Extent3D { width: u.size[0], height: u.size[1], depth: 1 });
            unsafe {
                self.device.cmd_copy_buffer_to_image(
                    cmd,
                    staging.raw,
                    tex.image.raw,
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &[region],
                );
            }
            b.image(&tex.image, &[Access::TransferDst], &[Access::FragmentSampled]).flush(&self.device, cmd);
        }
        Ok(())
    }

    /// Record the overlay into `cmd`, the frame of slot `slot` (whose last frame has completed): the pending uploads,
    /// then `meshes` over `target`, whose size is `points` × `pixels_per_point`. Then the textures freed since the
    /// last frame are kept until this slot comes round again.
    pub fn record(
        &mut self,
        cmd: vk::CommandBuffer,
        slot: usize,
        target: OverlayTarget,
        meshes: &[OverlayMesh],
        pixels_per_point: f32,
    ) -> VkResult<()> {
        let slot = slot % self.slots.len();
        // The slot's last frame is done: what it retired can go.
        self.slots[slot].retired.clear();
        self.record_uploads(cmd, slot)?;
        let vertex_bytes: u64 = meshes.iter().map(|m| std::mem::size_of_val(m.vertices) as u64).sum();
        let index_bytes: u64 = meshes.iter().map(|m| std::mem::size_of_val(m.indices) as u64).sum();
        {
            let s = &mut self.slots[slot];
            let usage = vk::BufferUsageFlags::VERTEX_BUFFER;
            Self::host_buffer(&self.device, &mut s.vertices, "overlay vertices", vertex_bytes, usage)?;
            let usage = vk::BufferUsageFlags::INDEX_BUFFER;
            Self::host_buffer(&self.device, &mut s.indices, "overlay indices", index_bytes, usage)?;
            let (mut v, mut i) = (0u64, 0u64);
            for m in meshes {
                s.vertices.as_mut().expect("vertices").write(v, m.vertices)?;
                s.indices.as_mut().expect("indices").write(i, m.indices)?;
                v += std::mem::size_of_val(m.vertices) as u64;
                i += std::mem::size_of_val(m.indices) as u64;
            }
        }
        let extent = target.extent;
        let range = COLOR_RANGE;
        // The vertices and indices are the host's writes, which the submission makes visible.
        Barriers::new()
            .image_raw(target.image, range, &[target.before], &[Access::ColorAttachment])
            .flush(&self.device, cmd);
        let s = &self.slots[slot];
        let buffers = (s.vertices.as_ref().expect("vertices").raw, s.indices.as_ref().expect("indices").raw);
        let device = self.device.clone();
        self.pipeline(target.format)?;
        // The render area holds what the meshes draw (each one's bounds within its clip rectangle), not the whole
        // target: a CPU device loads and stores only its tiles.
        let area = meshes.iter().filter_map(|m| clip_pixels(drawn_bounds(m), pixels_per_point, extent)).reduce(union);
        if let Some(area) = area {
            self.draw(cmd, &target, area, buffers, meshes, pixels_per_point);
        }
        Barriers::new().image_raw(target.image, range, &[Access::ColorAttachment], &[target.after]).flush(&device, cmd);
        for id in std::mem::take(&mut self.frees) {
            if let Some(t) = self.textures.remove(&id) {
                self.slots[slot].retired.push(t.image);
            }
        }
        Ok(())
    }

    /// Draw `meshes` (their vertices and indices in `buffers`) inside `area` of `target`, with the pipeline of its
    /// format (made).
    fn draw(
        &self,
        cmd: vk::CommandBuffer,
        target: &OverlayTarget,
        area: vk::Rect2D,
        (vertices, indices): (vk::Buffer, vk::Buffer),
        meshes: &[OverlayMesh],
        pixels_per_point: f32,
    ) {
        let (device, extent) = (&self.device, target.extent);
        let pipeline = &self.pipelines[&target.format];
        let attachment = vk::RenderingAttachmentInfo::default()
            .image_view(target.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE);
        let rendering = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(std::slice::from_ref(&attachment));
        let points = [extent.width as f32 / pixels_per_point, extent.height as f32 / pixels_per_point];
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, pipeline.raw);
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: extent.width as f32,
                height: extent.height as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_bind_vertex_buffers(cmd, 0, &[vertices], &[0]);
            device.cmd_bind_index_buffer(cmd, indices, 0, vk::IndexType::UINT32);
        }
        pipeline.push(cmd, &OverlayPush { size: points });
        let (mut first_vertex, mut first_index) = (0i32, 0u32);
        for m in meshes {
            let n = m.indices.len() as u32;
            let drawn = self.textures.get(&m.texture).zip(clip_pixels(m.clip, pixels_per_point, extent));
            if let (Some((tex, scissor)), true) = (drawn, n > 0) {
                let sampler = if tex.linear { &self.linear } else { &self.nearest };
                pipeline.bind(cmd, &ordered([(OV_TEXTURE, Bind::Sampled(&tex.image, sampler))]));
                unsafe {
                    device.cmd_set_scissor(cmd, 0, &[scissor]);
                    device.cmd_draw_indexed(cmd, n, 1, first_index, first_vertex, 0);
                }
            }
            first_vertex += m.vertices.len() as i32;
            first_index += n;
        }
        unsafe { device.cmd_end_rendering(cmd) };
    }
}

/// What a mesh can draw, in points: its vertices' bounds within its clip rectangle (min x, min y, max x, max y),
/// one pixel wider each way for the rasterizer's rounding.
fn drawn_bounds(m: &OverlayMesh) -> [f32; 4] {
    let mut b = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
    for v in m.vertices {
        b = [b[0].min(v.pos[0]), b[1].min(v.pos[1]), b[2].max(v.pos[0]), b[3].max(v.pos[1])];
    }
    [(b[0] - 1.0).max(m.clip[0]), (b[1] - 1.0).max(m.clip[1]), (b[2] + 1.0).min(m.clip[2]), (b[3] + 1.0).min(m.clip[3])]
}

/// The smallest rectangle holding `a` and `b`.
fn union(a: vk::Rect2D, b: vk::Rect2D) -> vk::Rect2D {
    let (x0, y0) = (a.offset.x.min(b.offset.x), a.offset.y.min(b.offset.y));
    let x1 = (a.offset.x + a.extent.width as i32).max(b.offset.x + b.extent.width as i32);
    let y1 = (a.offset.y + a.extent.height as i32).max(b.offset.y + b.extent.height as i32);
    vk::Rect2D {
        offset: vk::Offset2D { x: x0, y: y0 },
        extent: vk::Extent2D { width: (x1 - x0) as u32, height: (y1 - y0) as u32 },
    }
}

/// A clip rectangle in points as a scissor in pixels, within the target; None where nothing of it is inside.
fn clip_pixels(clip: [f32; 4], pixels_per_point: f32, extent: vk::Extent2D) -> Option<vk::Rect2D> {
    let (w, h) = (extent.width as f32, extent.height as f32);
    let x0 = (clip[0] * pixels_per_point).round().clamp(0.0, w);
    let y0 = (clip[1] * pixels_per_point).round().clamp(0.0, h);
    let x1 = (clip[2] * pixels_per_point).round().clamp(x0, w);
    let y1 = (clip[3] * pixels_per_point).round().clamp(y0, h);
    (x1 > x0 && y1 > y0).then_some(vk::Rect2D {
        offset: vk::Offset2D { x: x0 as i32, y: y0 as i32 },
        extent: vk::Extent2D { width: (x1 - x0) as u32, height: (y1 - y0) as u32 },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertex is egui's: 20 bytes, the color at 16 (the pipeline's attribute offsets).
    #[test]
    fn the_vertex_has_the_attribute_offsets_the_pipeline_reads() {
        assert_eq!(std::mem::size_of::<OverlayVertex>(), 20);
        assert_eq!(std::mem::offset_of!(OverlayVertex, uv), 8);
        assert_eq!(std::mem::offset_of!(OverlayVertex, color), 16);
    }

    #[test]
    fn clip_rectangles_become_scissors_inside_the_target() {
        let e = vk::Extent2D { width: 100, height: 50 };
        let r = clip_pixels([-5.0, 10.0, 40.0, 80.0], 2.0, e).unwrap();
        assert_eq!((r.offset.x, r.offset.y, r.extent.width, r.extent.height), (0, 20, 80, 30));
        assert!(clip_pixels([60.0, 0.0, 70.0, 10.0], 2.0, e).is_none(), "wholly right of the target");
        assert!(clip_pixels([10.0, 10.0, 10.0, 20.0], 1.0, e).is_none(), "empty");
        let u = union(r, clip_pixels([50.0, 5.0, 60.0, 8.0], 1.0, e).unwrap());
        assert_eq!((u.offset.x, u.offset.y, u.extent.width, u.extent.height), (0, 5, 80, 45));
    }
}
