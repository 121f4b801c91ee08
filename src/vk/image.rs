//! RAII 2D images on gpu-allocator, with a view over all mips.

use super::context::Device;
use super::error::{Check, VkError, VkResult};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// The color aspect of an image's first mip level and layer: a swapchain image's, or any single-level color
/// target's.
pub const COLOR_RANGE: vk::ImageSubresourceRange = vk::ImageSubresourceRange {
    aspect_mask: vk::ImageAspectFlags::COLOR,
    base_mip_level: 0,
    level_count: 1,
    base_array_layer: 0,
    layer_count: 1,
};

/// A 2D image with its memory and a view, freed when dropped.
pub struct Image {
    device: Arc<Device>,
    /// Unique for the process's lifetime (a raw handle may be reused once destroyed): what
    /// the frame's barrier tracker keys its history by.
    pub id: u64,
    /// The image.
    pub raw: vk::Image,
    /// A view of it.
    pub view: vk::ImageView,
    /// Its format.
    pub format: vk::Format,
    /// Its size.
    pub extent: vk::Extent2D,
    /// The aspect its view covers.
    pub aspect: vk::ImageAspectFlags,
    /// Its mip levels.
    pub levels: u32,
    /// Its array layers (a layered image's view is a 2D array).
    pub layers: u32,
    allocation: Option<Allocation>,
    /// Its name (in validation messages).
    pub name: String,
}

pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D32_SFLOAT | vk::Format::D16_UNORM | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT => {
            vk::ImageAspectFlags::DEPTH | vk::ImageAspectFlags::STENCIL
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

impl Image {
    /// A device-local image of `format` and `extent` with `usage`.
    pub fn new(
        device: &Arc<Device>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        usage: vk::ImageUsageFlags,
    ) -> VkResult<Self> {
        Image::with_levels(device, name, format, extent, usage, 1, None)
    }

    /// A device-local image with `levels` mip levels and, with `layers`, that many array layers and a 2D-array
    /// view (a sampler2DArray's), else one layer and a 2D view.
    pub fn with_levels(
        device: &Arc<Device>,
        name: &str,
        format: vk::Format,
        extent: vk::Extent2D,
        usage: vk::ImageUsageFlags,
        levels: u32,
        layers: Option<u32>,
    ) -> VkResult<Self> {
        let (layer_count, view_type) = match layers {
            Some(n) => (n.max(1), vk::ImageViewType::TYPE_2D_ARRAY),
            None => (1, vk::ImageViewType::TYPE_2D),
        };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width.max(1), height: extent.height.max(1), depth: 1 })
            .mip_levels(levels)
            .array_layers(layer_count)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let raw = unsafe { device.create_image(&info, None) }.check("vkCreateImage")?;
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = match device.allocator().allocate(&AllocationCreateDesc {
            name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(source) => {
                unsafe { device.destroy_image(raw, None) };
                return Err(VkError::Alloc {
                    what: format!("image `{name}` {}x{}", extent.width, extent.height),
                    source,
                });
            }
        };
        let aspect = aspect_of(format);
        let bound = unsafe { device.bind_image_memory(raw, allocation.memory(), allocation.offset()) }
            .check("vkBindImageMemory");
        let view = bound.and_then(|_| {
            let view_info =
                vk::ImageViewCreateInfo::default().image(raw).view_type(view_type).format(format).subresource_range(
                    vk::ImageSubresourceRange {
                        aspect_mask: aspect,
                        base_mip_level: 0,
                        level_count: levels,
                        base_array_layer: 0,
                        layer_count,
                    },
                );
            unsafe { device.create_image_view(&view_info, None) }.check("vkCreateImageView")
        });
        let view = match view {
            Ok(v) => v,
            Err(e) => {
                let _ = device.allocator().free(allocation);
                unsafe { device.destroy_image(raw, None) };
                return Err(e);
            }
        };
        device.set_name(raw, name);
        Ok(Image {
            id: super::next_resource_id(),
            device: device.clone(),
            raw,
            view,
            format,
            extent,
            aspect,
            levels,
            layers: layer_count,
            allocation: Some(allocation),
            name: name.to_string(),
        })
    }

    /// The subresource range of all its mip levels and layers.
    pub fn range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange {
            aspect_mask: self.aspect,
            base_mip_level: 0,
            level_count: self.levels,
            base_array_layer: 0,
            layer_count: self.layers,
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_image_view(self.view, None);
            self.device.destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take() {
            let _ = self.device.allocator().free(a);
        }
        self.device.retire(self.id);
    }
}

/// A sampler that frees itself.
pub struct Sampler {
    device: Arc<Device>,
    /// The sampler.
    pub raw: vk::Sampler,
}

impl Sampler {
    /// A clamp-to-edge sampler with `filter`.
    pub fn new(device: &Arc<Device>, filter: vk::Filter) -> VkResult<Self> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .mipmap_mode(vk::SamplerMipmapMode::NEAREST)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(0.0);
        let raw = unsafe { device.create_sampler(&info, None) }.check("vkCreateSampler")?;
        Ok(Sampler { device: device.clone(), raw })
    }
}

impl Sampler {
    /// A trilinear sampler over all mips that repeats in u and, with `repeat_v`, in v (else clamps v): albedo
    /// textures repeat in both; an equirectangular environment map wraps in longitude only.
    pub fn repeating(device: &Arc<Device>, repeat_v: bool) -> VkResult<Self> {
        let v = if repeat_v { vk::SamplerAddressMode::REPEAT } else { vk::SamplerAddressMode::CLAMP_TO_EDGE };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::REPEAT)
            .address_mode_v(v)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        let raw = unsafe { device.create_sampler(&info, None) }.check("vkCreateSampler")?;
        Ok(Sampler { device: device.clone(), raw })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        unsafe { self.device.destroy_sampler(self.raw, None) };
    }
}
