//! caustics: real-time refractive caustics with adaptive caustic maps on Vulkan.
pub mod error;
pub mod image_io;
pub mod scene;
pub mod vk;
