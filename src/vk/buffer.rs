//! RAII buffers on gpu-allocator.

use super::context::Device;
use super::error::{Check, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// A buffer with its memory, freed when dropped.
pub struct Buffer {
    device: Arc<Device>,
    /// Unique for the process's lifetime (a raw handle may be reused once destroyed): what
    /// the frame's barrier tracker keys its history by.
    pub id: u64,
    /// The buffer.
    pub raw: vk::Buffer,
    /// Its size in bytes.
    pub size: u64,
    allocation: Option<Allocation>,
    /// Its name (in validation messages).
    pub name: String,
    /// A view of its texels ([`Buffer::with_texel_view`]; null without one), which a texel-buffer binding reads.
    pub texels: vk::BufferView,
}

impl Buffer {
    /// A buffer of `size` bytes with `usage`, in memory at `location`.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> VkResult<Self> {
        let size = size.max(4);
        let info = vk::BufferCreateInfo::default().size(size).usage(usage).sharing_mode(vk::SharingMode::EXCLUSIVE);
        let raw = unsafe { device.create_buffer(&info, None) }.check("vkCreateBuffer")?;
        let requirements = unsafe { device.get_buffer_memory_requirements(raw) };
        let allocation = device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(source) => {
                unsafe { device.destroy_buffer(raw, None) };
                return Err(VkError::Alloc { what: format!("buffer `{name}` ({size} bytes)"), source });
            }
        };
        if let Err(e) = unsafe { device.bind_buffer_memory(raw, allocation.memory(), allocation.offset()) } {
            let _ = device.allocator().free(allocation);
            unsafe { device.destroy_buffer(raw, None) };
            return Err(VkError::Call { call: "vkBindBufferMemory", result: e });
        }
        device.set_name(raw, name);
        Ok(Buffer {
            device: device.clone(),
            id: super::next_resource_id(),
            raw,
            size,
            allocation: Some(allocation),
            name: name.to_string(),
            texels: vk::BufferView::null(),
        })
    }

    /// The buffer with a view of its whole range as texels of `format` (`texel_bytes` each), for shaders that read it
    /// through a uniform texel buffer (it needs the UNIFORM_TEXEL_BUFFER usage). A device reads at most
    /// maxTexelBufferElements texels through one view: a longer buffer gets none ([`Buffer::texel_view`] says so).
    pub fn with_texel_view(mut self, format: vk::Format, texel_bytes: u64) -> VkResult<Self> {
        let texels = self.size / texel_bytes;
        if texels > self.device.info.limits.max_texel_buffer_elements as u64 {
            log::debug!("buffer `{}`: {texels} texels, more than one texel buffer reads; no texel view", self.name);
            return Ok(self);
        }
        let info =
            vk::BufferViewCreateInfo::default().buffer(self.raw).format(format).offset(0).range(texels * texel_bytes);
        self.texels = unsafe { self.device.create_buffer_view(&info, None) }.check("vkCreateBufferView")?;
        self.device.set_name(self.texels, &format!("{} (texels)", self.name));
        Ok(self)
    }

    /// Its texel view, or an error naming the buffer when it has none (longer than a texel buffer reads).
    pub fn texel_view(&self) -> VkResult<vk::BufferView> {
        if self.texels == vk::BufferView::null() {
            return Err(VkError::Unsupported(format!(
                "buffer `{}` ({} bytes) is longer than this device reads through a texel buffer \
                 (maxTexelBufferElements {}), which the wide BVH layout needs: use the pair layout (Tuning::bvh_layout)",
                self.name, self.size, self.device.info.limits.max_texel_buffer_elements
            )));
        }
        Ok(self.texels)
    }

    /// A host-visible buffer filled with `data` (uniforms, readbacks, staging).
    pub fn with_data<T: bytemuck::Pod>(
        device: &Arc<Device>,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> VkResult<Self> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut b = Buffer::new(device, name, bytes.len() as u64, usage, MemoryLocation::CpuToGpu)?;
        b.write(0, data)?;
        Ok(b)
    }

    /// Write into a host-visible buffer at a byte offset.
    pub fn write<T: bytemuck::Pod>(&mut self, offset: u64, data: &[T]) -> VkResult<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let name = self.name.clone();
        let slice = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| VkError::Unsupported(format!("buffer `{name}` is not host-visible")))?;
        let start = offset as usize;
        let end = start + bytes.len();
        if end > slice.len() {
            return Err(VkError::Unsupported(format!("write of {} bytes past the end of `{name}`", bytes.len())));
        }
        slice[start..end].copy_from_slice(bytes);
        Ok(())
    }

    /// Read a host-visible buffer (call only after the GPU work that wrote it has completed).
    pub fn read<T: bytemuck::Pod>(&self, offset: u64, count: usize) -> VkResult<Vec<T>> {
        let slice = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| VkError::Unsupported(format!("buffer `{}` is not host-visible", self.name)))?;
        let start = offset as usize;
        let end = start + count * std::mem::size_of::<T>();
        if end > slice.len() {
            return Err(VkError::Unsupported(format!("read past the end of `{}`", self.name)));
        }
        Ok(bytemuck::pod_collect_to_vec(&slice[start..end]))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe {
            if self.texels != vk::BufferView::null() {
                self.device.destroy_buffer_view(self.texels, None);
            }
            self.device.destroy_buffer(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
        self.device.retire(self.id);
    }
}
