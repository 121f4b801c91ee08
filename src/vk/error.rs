//! Errors of the Vulkan layer. Every `vk::Result` is turned into a [`VkError`] that names the call.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum VkError {
    #[error("Vulkan loader not found: {0}. Install it with `tools/setup` (Debian package libvulkan1).")]
    Loading(#[from] ash::LoadingError),
    #[error("{call} failed: {result:?}")]
    Call { call: &'static str, result: vk::Result },
    #[error("no usable Vulkan device: {0}. Run `tools/setup` to install Mesa's lavapipe (mesa-vulkan-drivers), or pick another device with CAUSTICS_DEVICE.")]
    NoDevice(String),
    /// CAUSTICS_DEVICE names no usable device; the message says what there is.
    #[error("{0}")]
    NoSuchDevice(String),
    #[error("validation was requested but the Khronos validation layer is not installed. Run `tools/setup` (Debian package vulkan-validationlayers), or set CAUSTICS_VALIDATION=0.")]
    NoValidationLayer,
    #[error("GPU memory allocation failed ({what}): {source}")]
    Alloc {
        what: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
    #[error("device lost during {0}: the GPU driver reset or crashed")]
    DeviceLost(&'static str),
    #[error("{0}")]
    Unsupported(String),
}

pub type VkResult<T> = std::result::Result<T, VkError>;

/// Attach the name of the Vulkan call to a raw `vk::Result`.
pub trait Check<T> {
    fn check(self, call: &'static str) -> VkResult<T>;
}

impl<T> Check<T> for Result<T, vk::Result> {
    fn check(self, call: &'static str) -> VkResult<T> {
        self.map_err(|result| {
            if result == vk::Result::ERROR_DEVICE_LOST {
                VkError::DeviceLost(call)
            } else {
                VkError::Call { call, result }
            }
        })
    }
}
