//! Errors of the Vulkan layer. Every `vk::Result` is turned into a [`VkError`] that names the call.

use ash::vk;

/// An error of the Vulkan layer: the failed call, or what is missing, with a hint where there is one.
#[derive(Debug, thiserror::Error)]
pub enum VkError {
    /// The Vulkan loader could not be loaded.
    #[error("Vulkan loader not found: {0}. Install it with `tools/setup` (Debian package libvulkan1).")]
    Loading(#[from] ash::LoadingError),
    /// A Vulkan call failed.
    #[error("{call} failed: {result:?}")]
    Call {
        /// The call.
        call: &'static str,
        /// Its result.
        result: vk::Result,
    },
    /// No device fits.
    #[error("no usable Vulkan device: {0}. Run `tools/setup` to install Mesa's lavapipe (mesa-vulkan-drivers), or pick another device with CAUSTICS_DEVICE.")]
    NoDevice(String),
    /// CAUSTICS_DEVICE names no usable device; the message says what there is.
    #[error("{0}")]
    NoSuchDevice(String),
    /// Validation was asked for without the layer.
    #[error("validation was requested but the Khronos validation layer is not installed. Run `tools/setup` (Debian package vulkan-validationlayers), or set CAUSTICS_VALIDATION=0.")]
    NoValidationLayer,
    /// An allocation failed.
    #[error("GPU memory allocation failed ({what}): {source}")]
    Alloc {
        /// What was being allocated.
        what: String,
        /// The allocator's error.
        #[source]
        source: gpu_allocator::AllocationError,
    },
    /// The device was lost.
    #[error("device lost during {0}: the GPU driver reset or crashed")]
    DeviceLost(&'static str),
    /// The device or the request cannot do what is asked.
    #[error("{0}")]
    Unsupported(String),
    /// A pipeline's layout does not match what its shader declares (a defect of this crate, named precisely).
    #[error("{0}")]
    Interface(String),
}

/// The result of a Vulkan-layer operation.
pub type VkResult<T> = std::result::Result<T, VkError>;

/// Attach the name of the Vulkan call to a raw `vk::Result`.
pub trait Check<T> {
    /// The result, with the call's name on its error.
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
