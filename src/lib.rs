//! **caustics**: real-time refractive caustics on Vulkan, with adaptive caustic maps (Wyman & Nichols 2009) built
//! the way Piao (2015) built them on compute shaders: one photon buffer with an atomic append counter, traversal
//! levels launched with `vkCmdDispatchIndirect`, photons splatted indirectly, every indirect command written by the
//! GPU, and no host readback inside a frame. Exact transport traces every glass path through a BVH of the scene.
//!
//! The library renders headless (it creates its own device, a CPU one such as lavapipe included), into a window
//! surface a host owns, or inside a host's own Vulkan device and command buffer:
//!
//! - [`gpu::Context::headless`] creates a device; [`gpu::Context::import`] wraps the host's instance, physical
//!   device, device and queue (see [`gpu::Imported`] for what they must enable).
//! - [`Renderer::new`] takes the device, a [`scene::Scene`] and [`settings::Settings`]; the scene can also be built
//!   in code ([`scene::Scene::new`], [`Renderer::add_mesh`], [`Renderer::add_instance`],
//!   [`Renderer::set_transform`], [`Renderer::set_light`], [`Renderer::set_material`]).
//! - [`Renderer::render`] renders a frame and returns its AOVs as host images with the frame's stats;
//!   [`Renderer::record`] records a frame into the host's command buffer and copies the beauty image into the
//!   host's image.
//!
//! ```no_run
//! use caustics::{gpu, scene::Scene, settings::Settings, Aov, FrameDesc, Renderer};
//!
//! # fn main() -> Result<(), caustics::Error> {
//! let context = gpu::Context::headless(&gpu::ContextDesc::default())?;
//! let scene = Scene::load(std::path::Path::new("assets/scenes/sphere.toml"))?;
//! let camera = scene.camera(Some("top")).map_err(caustics::Error::BadInput)?.clone();
//! let mut renderer = Renderer::new(context.device, scene, Settings::default())?;
//! let view = renderer.camera_view(&camera, 256, 256);
//! let frame = renderer.render(&FrameDesc::new(&view, Some(Aov::Caustics)))?;
//! println!("{} photons, {:.1} ms on the GPU", frame.report.photons(), frame.report.gpu_ms);
//! # Ok(())
//! # }
//! ```
//!
//! Errors are typed ([`Error`]); the library prints nothing (it reports through the `log` crate) and reads the
//! environment only where a function says so ([`gpu::ContextDesc::from_env`],
//! [`reference::cache_dir_from_env`]).
#![recursion_limit = "256"]
#![warn(missing_docs)]

pub mod calibration;
pub mod error;
pub mod gpu;
pub mod image_io;
pub mod metrics;
pub mod reference;
pub mod scene;
pub mod settings;

mod bvh;
mod frame;
mod gpu_types;
#[cfg(test)]
mod layout_check;
mod passes;
mod renderer;
mod scene_gpu;
mod shaders;
mod targets;
mod vk;

pub use error::{Error, Result};
pub use frame::{Aov, AovData, FrameReport, LightReport, SceneUpdateReport, SlotVerdict, HOST_ROUNDTRIP};
pub use gpu_types::{LevelCounters, TransportState, TraversalState, ACCOUNT_TERMS};
pub use renderer::{
    BvhStats, Finish, Frame, FrameDesc, FrameEstimate, FrameOutput, InstanceId, MeshId, RecordTarget, RecordedFrame,
    Renderer, Views, MAX_FRAMES_IN_FLIGHT,
};

/// Constants the renderer and its shaders share (src/shader_consts.rs): grid sizes, limits and the layouts of the
/// GPU's buffers.
pub mod consts {
    pub use crate::shaders::consts::*;
}
