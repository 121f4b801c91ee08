//! The Vulkan layer a host sees: a context the renderer creates ([`Context::headless`], or with the instance
//! extensions a window surface needs) or imports from the host ([`Context::import`]), the device with its queue
//! and allocator, RAII buffers and images, barriers by intent, and the errors of Vulkan calls.

pub use crate::vk::context::{kind_name, AllocationTotals, Imported};
pub use crate::vk::debug::messenger_info as validation_messenger_info;
pub use crate::vk::image::COLOR_RANGE;
pub use crate::vk::{
    validation_message_count, Access, Barriers, Buffer, Check, Context, ContextDesc, Device, DeviceInfo, Image,
    Instance, Sampler, SubmitSync, VkError, VkResult,
};
