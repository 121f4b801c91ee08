//! caustics: real-time refractive caustics with adaptive caustic maps on Vulkan.
pub mod error;
pub mod image_io;
pub mod metrics;
pub mod reference;
pub mod scene;
pub mod vk;
