//! Command pool, a reusable command buffer with its fence, and helpers for one-off transfers.

use super::buffer::Buffer;
use super::context::Device;
use super::error::{Check, VkResult};
use ash::vk;
use std::sync::Arc;

/// How long one submission may run before it is reported as hung. Lavapipe at deep traversal levels can take
/// minutes for a frame, so this is generous.
pub const FENCE_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(600);

/// Semaphores for a submission.
#[derive(Default, Clone)]
pub struct SubmitSync {
    /// Semaphores the submission waits on, with the stages that wait.
    pub wait: Vec<(vk::Semaphore, vk::PipelineStageFlags2)>,
    /// Semaphores it signals when done.
    pub signal: Vec<vk::Semaphore>,
}

/// One primary command buffer with a fence: begin, record, submit, wait. Used by the headless renderer (and by
/// the CPU-driven traversal, which submits several times per frame).
pub struct Recorder {
    device: Arc<Device>,
    pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    fence: vk::Fence,
    pending: bool,
    /// Submissions the host waited for ([`Recorder::submit_and_wait`]: uploads, CPU-driven round trips).
    pub blocking_submits: u64,
}

impl Recorder {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        let info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(device.queue_family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        let pool = unsafe { device.create_command_pool(&info, None) }.check("vkCreateCommandPool")?;
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .level(vk::CommandBufferLevel::PRIMARY)
            .command_buffer_count(1);
        let cmd = match unsafe { device.allocate_command_buffers(&alloc) } {
            Ok(v) => v[0],
            Err(e) => {
                unsafe { device.destroy_command_pool(pool, None) };
                return Err(super::VkError::Call { call: "vkAllocateCommandBuffers", result: e });
            }
        };
        let fence = match unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(e) => {
                unsafe { device.destroy_command_pool(pool, None) };
                return Err(super::VkError::Call { call: "vkCreateFence", result: e });
            }
        };
        Ok(Recorder { device: device.clone(), pool, cmd, fence, pending: false, blocking_submits: 0 })
    }

    pub fn begin(&mut self) -> VkResult<vk::CommandBuffer> {
        self.wait()?;
        unsafe {
            self.device
                .reset_command_buffer(self.cmd, vk::CommandBufferResetFlags::empty())
                .check("vkResetCommandBuffer")?;
            let info = vk::CommandBufferBeginInfo::default().flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            self.device.begin_command_buffer(self.cmd, &info).check("vkBeginCommandBuffer")?;
        }
        Ok(self.cmd)
    }

    /// End and submit; the fence signals when the GPU is done.
    pub fn submit(&mut self) -> VkResult<()> {
        self.submit_with(&SubmitSync::default())
    }

    /// End and submit, waiting on and signalling semaphores (presentation).
    pub fn submit_with(&mut self, sync: &SubmitSync) -> VkResult<()> {
        unsafe {
            self.device.end_command_buffer(self.cmd).check("vkEndCommandBuffer")?;
            self.device.reset_fences(&[self.fence]).check("vkResetFences")?;
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
            let waits: Vec<_> = sync
                .wait
                .iter()
                .map(|(s, stage)| vk::SemaphoreSubmitInfo::default().semaphore(*s).stage_mask(*stage))
                .collect();
            let signals: Vec<_> = sync
                .signal
                .iter()
                .map(|s| {
                    vk::SemaphoreSubmitInfo::default().semaphore(*s).stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
                })
                .collect();
            let submit = vk::SubmitInfo2::default()
                .command_buffer_infos(&cmds)
                .wait_semaphore_infos(&waits)
                .signal_semaphore_infos(&signals);
            self.device.queue_submit2(self.device.queue, &[submit], self.fence).check("vkQueueSubmit2")?;
        }
        self.pending = true;
        Ok(())
    }

    /// Wait for the last submit. A device loss is reported; a submit that runs past `FENCE_TIMEOUT` is reported
    /// as an error rather than waited on forever.
    pub fn wait(&mut self) -> VkResult<()> {
        if self.pending {
            match unsafe { self.device.wait_for_fences(&[self.fence], true, FENCE_TIMEOUT.as_nanos() as u64) } {
                Ok(()) => self.pending = false,
                Err(vk::Result::TIMEOUT) => {
                    return Err(super::VkError::Unsupported(format!(
                    "the GPU did not finish a submission within {} s (hung device, or a workload far too large for it)",
                    FENCE_TIMEOUT.as_secs()
                )))
                }
                Err(e) => return Err(e).check("vkWaitForFences"),
            }
        }
        Ok(())
    }

    pub fn submit_and_wait(&mut self) -> VkResult<()> {
        self.blocking_submits += 1;
        self.submit()?;
        self.wait()
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        unsafe {
            if self.pending {
                let _ = self.device.wait_for_fences(&[self.fence], true, FENCE_TIMEOUT.as_nanos() as u64);
            }
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_command_pool(self.pool, None);
        }
    }
}

#[cfg(test)]
/// `count` elements from the start of `src` (a transfer source), through a host-visible buffer, once every
/// earlier submission's writes are done.
pub fn download_buffer<T: bytemuck::Pod>(
    device: &Arc<Device>,
    recorder: &mut Recorder,
    src: &Buffer,
    count: usize,
) -> VkResult<Vec<T>> {
    let bytes = (count * std::mem::size_of::<T>()) as u64;
    let dst = Buffer::new(
        device,
        &format!("{} (download)", src.name),
        bytes,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
    )?;
    let cmd = recorder.begin()?;
    let all = vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)
        .src_access_mask(vk::AccessFlags2::MEMORY_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_READ);
    let to_host = vk::MemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::HOST)
        .dst_access_mask(vk::AccessFlags2::HOST_READ);
    unsafe {
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[all]));
        device.cmd_copy_buffer(cmd, src.raw, dst.raw, &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }]);
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&[to_host]));
    }
    recorder.submit_and_wait()?;
    dst.read(0, count)
}

/// Copy `data` into a device-local buffer through a staging buffer (works whether or not device memory is
/// host-visible). Empty data gives a buffer of the minimum size.
pub fn upload_buffer<T: bytemuck::Pod>(
    device: &Arc<Device>,
    recorder: &mut Recorder,
    name: &str,
    data: &[T],
    usage: vk::BufferUsageFlags,
) -> VkResult<Buffer> {
    let bytes = std::mem::size_of_val(data) as u64;
    if bytes == 0 {
        // Nothing to copy (a scene with no objects yet): a buffer of the minimum size, to bind.
        return Buffer::new(device, name, 4, usage, gpu_allocator::MemoryLocation::GpuOnly);
    }
    let staging = Buffer::with_data(device, &format!("{name} (staging)"), data, vk::BufferUsageFlags::TRANSFER_SRC)?;
    let dst = Buffer::new(
        device,
        name,
        bytes,
        usage | vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuOnly,
    )?;
    let cmd = recorder.begin()?;
    unsafe {
        device.cmd_copy_buffer(
            cmd,
            staging.raw,
            dst.raw,
            &[vk::BufferCopy { src_offset: 0, dst_offset: 0, size: bytes }],
        );
    }
    recorder.submit_and_wait()?;
    Ok(dst)
}

/// A sampled image made from host texels: `levels[l]` holds mip level `l` of every layer, layer after layer, each
/// `max(width >> l, 1)` × `max(height >> l, 1)` texels of `T` (one texel of `format`). It is left in
/// SHADER_READ_ONLY_OPTIMAL, its upload ordered before every later command on the queue (no frame declares it
/// to the tracker: nothing writes it again).
#[allow(clippy::too_many_arguments)]
pub fn upload_image<T: bytemuck::Pod>(
    device: &Arc<Device>,
    recorder: &mut Recorder,
    name: &str,
    format: vk::Format,
    extent: vk::Extent2D,
    layers: Option<u32>,
    levels: &[Vec<T>],
) -> VkResult<super::Image> {
    let image = super::Image::with_levels(
        device,
        name,
        format,
        extent,
        vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_DST,
        levels.len() as u32,
        layers,
    )?;
    let flat: Vec<T> = levels.iter().flatten().copied().collect();
    let staging = Buffer::with_data(device, &format!("{name} (staging)"), &flat, vk::BufferUsageFlags::TRANSFER_SRC)?;
    let mut regions = Vec::new();
    let mut offset = 0u64;
    for (l, level) in levels.iter().enumerate() {
        let (w, h) = ((extent.width >> l).max(1), (extent.height >> l).max(1));
        assert_eq!(level.len() as u64, (w * h * image.layers) as u64, "mip {l} of `{name}` has the wrong size");
        regions.push(
            vk::BufferImageCopy::default()
                .buffer_offset(offset)
                .image_subresource(vk::ImageSubresourceLayers {
                    aspect_mask: vk::ImageAspectFlags::COLOR,
                    mip_level: l as u32,
                    base_array_layer: 0,
                    layer_count: image.layers,
                })
                .image_extent(vk::Extent3D { width: w, height: h, depth: 1 }),
        );
        offset += std::mem::size_of_val(level.as_slice()) as u64;
    }
    let cmd = recorder.begin()?;
    let to_dst = vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::NONE)
        .src_access_mask(vk::AccessFlags2::NONE)
        .dst_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .dst_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .old_layout(vk::ImageLayout::UNDEFINED)
        .new_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
        .image(image.raw)
        .subresource_range(image.range());
    let to_read = vk::ImageMemoryBarrier2::default()
        .src_stage_mask(vk::PipelineStageFlags2::ALL_TRANSFER)
        .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
        .dst_stage_mask(vk::PipelineStageFlags2::FRAGMENT_SHADER | vk::PipelineStageFlags2::COMPUTE_SHADER)
        .dst_access_mask(vk::AccessFlags2::SHADER_SAMPLED_READ)
        .old_layout(vk::ImageLayout::TRANSFER_DST_OPTIMAL)
        .new_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
        .image(image.raw)
        .subresource_range(image.range());
    unsafe {
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&[to_dst]));
        device.cmd_copy_buffer_to_image(cmd, staging.raw, image.raw, vk::ImageLayout::TRANSFER_DST_OPTIMAL, &regions);
        device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&[to_read]));
    }
    recorder.submit_and_wait()?;
    Ok(image)
}
