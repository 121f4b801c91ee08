//! Barriers by intent (synchronization2). An [`Access`] names how a resource is used; a [`Barriers`] builder
//! collects transitions between accesses and flushes them in one `vkCmdPipelineBarrier2`.

use super::buffer::Buffer;
use super::context::Device;
use super::image::Image;
use ash::vk;

type Stage = vk::PipelineStageFlags2;
type Acc = vk::AccessFlags2;
type Layout = vk::ImageLayout;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
/// How a pass uses a resource: its stages, accesses and (for an image) layout.
pub enum Access {
    /// First use in a frame: contents are discarded, but whatever earlier frames did with the resource on this
    /// queue must be finished (an execution and memory dependency on all prior commands).
    FrameStart,
    /// Storage buffer/image read in a compute shader.
    ComputeRead,
    /// Storage buffer/image write (or read-modify-write, atomics) in a compute shader.
    ComputeWrite,
    /// Sampled image read in a compute shader.
    ComputeSampled,
    /// Uniform texel buffer read in a compute shader.
    ComputeTexels,
    /// Indirect dispatch/draw arguments.
    IndirectRead,
    /// Vertex buffer read by the input assembler.
    VertexInput,
    /// Index buffer read by the input assembler.
    IndexInput,
    /// Storage buffer read in a vertex shader.
    VertexRead,
    /// Storage buffer written (atomics) in a vertex shader.
    VertexWrite,
    /// Storage buffer read in a fragment shader.
    FragmentRead,
    /// Sampled image read in a vertex shader.
    VertexSampled,
    /// Sampled image read in a fragment shader.
    FragmentSampled,
    /// Color attachment, written and (for blending) read.
    ColorAttachment,
    /// Depth attachment, tested and written.
    DepthAttachment,
    /// Read by a transfer (copy, blit).
    TransferSrc,
    /// Written by a transfer (copy, fill, clear).
    TransferDst,
    /// Read by the host after the submission completed.
    HostRead,
    /// Presented to a swapchain.
    Present,
}

impl Access {
    /// The stages, accesses and image layout of this use.
    pub fn info(self) -> (Stage, Acc, Layout) {
        use Access::*;
        match self {
            FrameStart => (Stage::ALL_COMMANDS, Acc::MEMORY_WRITE | Acc::MEMORY_READ, Layout::UNDEFINED),
            ComputeRead => (Stage::COMPUTE_SHADER, Acc::SHADER_STORAGE_READ, Layout::GENERAL),
            ComputeWrite => {
                (Stage::COMPUTE_SHADER, Acc::SHADER_STORAGE_WRITE | Acc::SHADER_STORAGE_READ, Layout::GENERAL)
            }
            ComputeSampled => (Stage::COMPUTE_SHADER, Acc::SHADER_SAMPLED_READ, Layout::SHADER_READ_ONLY_OPTIMAL),
            ComputeTexels => (Stage::COMPUTE_SHADER, Acc::SHADER_SAMPLED_READ, Layout::GENERAL),
            IndirectRead => (Stage::DRAW_INDIRECT, Acc::INDIRECT_COMMAND_READ, Layout::UNDEFINED),
            VertexInput => (Stage::VERTEX_ATTRIBUTE_INPUT, Acc::VERTEX_ATTRIBUTE_READ, Layout::UNDEFINED),
            IndexInput => (Stage::INDEX_INPUT, Acc::INDEX_READ, Layout::UNDEFINED),
            VertexRead => (Stage::VERTEX_SHADER, Acc::SHADER_STORAGE_READ, Layout::GENERAL),
            VertexWrite => {
                (Stage::VERTEX_SHADER, Acc::SHADER_STORAGE_WRITE | Acc::SHADER_STORAGE_READ, Layout::GENERAL)
            }
            FragmentRead => (Stage::FRAGMENT_SHADER, Acc::SHADER_STORAGE_READ, Layout::GENERAL),
            VertexSampled => (Stage::VERTEX_SHADER, Acc::SHADER_SAMPLED_READ, Layout::SHADER_READ_ONLY_OPTIMAL),
            FragmentSampled => (Stage::FRAGMENT_SHADER, Acc::SHADER_SAMPLED_READ, Layout::SHADER_READ_ONLY_OPTIMAL),
            ColorAttachment => (
                Stage::COLOR_ATTACHMENT_OUTPUT,
                Acc::COLOR_ATTACHMENT_WRITE | Acc::COLOR_ATTACHMENT_READ,
                Layout::COLOR_ATTACHMENT_OPTIMAL,
            ),
            DepthAttachment => (
                Stage::EARLY_FRAGMENT_TESTS | Stage::LATE_FRAGMENT_TESTS,
                Acc::DEPTH_STENCIL_ATTACHMENT_READ | Acc::DEPTH_STENCIL_ATTACHMENT_WRITE,
                Layout::DEPTH_ATTACHMENT_OPTIMAL,
            ),
            // vkCmdFillBuffer and copies are ALL_TRANSFER (a CLEAR stage source is not enough for fills).
            TransferSrc => (Stage::ALL_TRANSFER, Acc::TRANSFER_READ, Layout::TRANSFER_SRC_OPTIMAL),
            TransferDst => (Stage::ALL_TRANSFER, Acc::TRANSFER_WRITE, Layout::TRANSFER_DST_OPTIMAL),
            HostRead => (Stage::HOST, Acc::HOST_READ, Layout::GENERAL),
            Present => (Stage::NONE, Acc::NONE, Layout::PRESENT_SRC_KHR),
        }
    }

    /// Whether this use writes.
    pub fn is_write(self) -> bool {
        matches!(
            self,
            Access::FrameStart
                | Access::ComputeWrite
                | Access::VertexWrite
                | Access::ColorAttachment
                | Access::DepthAttachment
                | Access::TransferDst
        )
    }
}

fn merge(accesses: &[Access]) -> (Stage, Acc, Layout) {
    let mut out = (Stage::NONE, Acc::NONE, Layout::UNDEFINED);
    for a in accesses {
        let (s, acc, l) = a.info();
        out.0 |= s;
        out.1 |= acc;
        if out.2 == Layout::UNDEFINED {
            out.2 = l;
        }
    }
    out
}

/// A batch of barriers, flushed together.
#[derive(Default)]
pub struct Barriers {
    buffers: Vec<vk::BufferMemoryBarrier2<'static>>,
    images: Vec<vk::ImageMemoryBarrier2<'static>>,
}

impl Barriers {
    /// No barriers yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Make `prev` accesses of `buffer` visible to (and ordered before) `next` accesses.
    pub fn buffer(&mut self, buffer: &Buffer, prev: &[Access], next: &[Access]) -> &mut Self {
        self.buffer_raw(buffer.raw, prev, next)
    }

    /// [`Barriers::buffer`] on a raw buffer handle.
    pub fn buffer_raw(&mut self, buffer: vk::Buffer, prev: &[Access], next: &[Access]) -> &mut Self {
        let (ss, sa, _) = merge(prev);
        let (ds, da, _) = merge(next);
        // Read-after-read needs no barrier; write-after-read needs only an execution dependency.
        let src_access = if prev.iter().any(|a| a.is_write()) { sa } else { Acc::NONE };
        self.push_buffer(buffer, (ss, src_access), (ds, da))
    }

    /// A barrier on the whole of `buffer` from `src` (stages, accesses) to `dst`; with no source access it is an
    /// execution dependency only.
    pub(crate) fn push_buffer(&mut self, buffer: vk::Buffer, src: (Stage, Acc), dst: (Stage, Acc)) -> &mut Self {
        self.buffers.push(
            vk::BufferMemoryBarrier2::default()
                .src_stage_mask(src.0)
                .src_access_mask(src.1)
                .dst_stage_mask(dst.0)
                .dst_access_mask(if src.1.is_empty() { Acc::NONE } else { dst.1 })
                .buffer(buffer)
                .offset(0)
                .size(vk::WHOLE_SIZE),
        );
        self
    }

    /// Transition `image` from `prev` accesses (and their layout) to `next`.
    pub fn image(&mut self, image: &Image, prev: &[Access], next: &[Access]) -> &mut Self {
        self.image_raw(image.raw, image.range(), prev, next)
    }

    /// [`Barriers::image`] on a raw image handle and range.
    pub fn image_raw(
        &mut self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        prev: &[Access],
        next: &[Access],
    ) -> &mut Self {
        let (ss, sa, old) = merge(prev);
        let (ds, da, new) = merge(next);
        let src_access = if prev.iter().any(|a| a.is_write()) { sa } else { Acc::NONE };
        self.push_image(image, range, (ss, src_access, old), (ds, da, new))
    }

    /// A barrier on `range` of `image` from `src` (stages, accesses, layout) to `dst`.
    pub(crate) fn push_image(
        &mut self,
        image: vk::Image,
        range: vk::ImageSubresourceRange,
        src: (Stage, Acc, Layout),
        dst: (Stage, Acc, Layout),
    ) -> &mut Self {
        self.images.push(
            vk::ImageMemoryBarrier2::default()
                .src_stage_mask(src.0)
                .src_access_mask(src.1)
                .dst_stage_mask(dst.0)
                .dst_access_mask(dst.1)
                .old_layout(src.2)
                .new_layout(dst.2)
                .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
                .image(image)
                .subresource_range(range),
        );
        self
    }

    /// Whether no barrier was added.
    pub fn is_empty(&self) -> bool {
        self.buffers.is_empty() && self.images.is_empty()
    }

    /// Record the barriers in one `vkCmdPipelineBarrier2` and clear them.
    pub fn flush(&mut self, device: &Device, cmd: vk::CommandBuffer) {
        if self.is_empty() {
            return;
        }
        let dep =
            vk::DependencyInfo::default().buffer_memory_barriers(&self.buffers).image_memory_barriers(&self.images);
        unsafe { device.cmd_pipeline_barrier2(cmd, &dep) };
        self.clear();
    }

    /// Drop the barriers added.
    pub(crate) fn clear(&mut self) {
        self.buffers.clear();
        self.images.clear();
    }
}
