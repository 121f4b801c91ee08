//! caustics: real-time refractive caustics with adaptive caustic maps on Vulkan.
pub mod bench_report;
pub mod commands;
pub mod error;
pub mod frame;
pub mod gpu_types;
pub mod image_io;
pub mod metrics;
pub mod passes;
pub mod profiler;
pub mod reference;
pub mod renderer;
pub mod scene;
pub mod scene_gpu;
pub mod settings;
pub mod shaders;
pub mod targets;
pub mod vk;
