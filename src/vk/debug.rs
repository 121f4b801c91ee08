//! Debug messenger: routes validation messages to `log` and counts warnings and errors.
//!
//! The loader reports ~100 INFO messages through the messenger on startup, so only WARNING and ERROR severities
//! are counted. Tests read [`validation_message_count`] (also written to the stats JSON) and fail on any message.

use ash::vk;
use std::ffi::CStr;
use std::sync::atomic::{AtomicU64, Ordering};

static MESSAGES: AtomicU64 = AtomicU64::new(0);

/// Number of WARNING or ERROR messages reported by the validation layers so far in this process.
pub fn validation_message_count() -> u64 {
    MESSAGES.load(Ordering::Relaxed)
}

pub(crate) unsafe extern "system" fn messenger_callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut std::ffi::c_void,
) -> vk::Bool32 {
    let message = if data.is_null() || (*data).p_message.is_null() {
        "<no message>".to_string()
    } else {
        CStr::from_ptr((*data).p_message).to_string_lossy().into_owned()
    };
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) {
        MESSAGES.fetch_add(1, Ordering::Relaxed);
        log::error!("[vulkan {kind:?}] {message}");
    } else if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING) {
        MESSAGES.fetch_add(1, Ordering::Relaxed);
        log::warn!("[vulkan {kind:?}] {message}");
    } else {
        log::trace!("[vulkan {kind:?}] {message}");
    }
    vk::FALSE
}

/// A debug messenger that routes every validation message to `log` and counts the warnings and errors in
/// [`validation_message_count`]: a host that creates its own instance chains it into its `VkInstanceCreateInfo`
/// (and creates one with it) to have the renderer's tests and stats see its messages.
pub fn messenger_info() -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING
                | vk::DebugUtilsMessageSeverityFlagsEXT::INFO
                | vk::DebugUtilsMessageSeverityFlagsEXT::VERBOSE,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(messenger_callback))
}
