//! **caustics**: real-time refractive caustics on Vulkan, with adaptive caustic maps (Wyman & Nichols 2009) built
//! the way Piao (2015) built them on compute shaders: one photon buffer with an atomic append counter, traversal
//! levels launched with `vkCmdDispatchIndirect`, photons splatted indirectly, every indirect command written by the
//! GPU, and no host readback inside a frame. Exact transport traces every glass path through a BVH of the scene.
//!
//! Three ways to use it:
//!
//! - **Headless**: [`gpu::Context::headless`] creates an instance and a device (a CPU one such as lavapipe
//!   included), and [`Renderer::render`] renders a frame and returns its AOVs as host images with the frame's stats
//!   (below, and `examples/headless.rs`).
//! - **In a window**: [`gpu::Instance::new`] with the window system's extensions
//!   ([`gpu::ContextDesc::instance_extensions`], [`gpu::ContextDesc::swapchain`]), [`gpu::Device::new`] with a
//!   filter for a queue that presents, and [`Renderer::submit`]: its `finish` callback appends the host's copy of
//!   the [`FrameOutput`] to its swapchain image, and its [`gpu::SubmitSync`] semaphores wait for that image and
//!   signal its presentation. The `caustics view` viewer (the `apps` feature) is built this way.
//! - **In a host's device**: [`gpu::Context::import`] wraps the host's instance, physical device, device and queue
//!   (see [`gpu::Imported`] for what they must enable); [`Renderer::record`] records a frame into the host's command
//!   buffer and copies the beauty image into the host's image, and [`Renderer::complete`] collects its report once
//!   the host's submission has finished (`examples/embed.rs` on an ash host, `examples/wgpu.rs` in a wgpu
//!   application).
//!
//! [`Renderer::new`] takes the device, a [`scene::Scene`] and [`settings::Settings`]; the scene can also be built in
//! code ([`scene::Scene::new`], [`Renderer::add_mesh`], [`Renderer::add_instance`], [`Renderer::set_transform`],
//! [`Renderer::set_light`], [`Renderer::set_material`]).
//!
//! On Debian and Ubuntu, the shaderc library the build compiles the shaders with needs a link fix in the user's
//! cargo configuration, which the repository's `tools/setup` adds (README.md, "As a library").
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
pub mod spectrum;

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
#[cfg(feature = "tracy")]
mod tracy;

/// A Tracy CPU zone named `$name` from here to the end of the enclosing block, where Tracy's client runs
/// (`--features tracy`; nothing otherwise).
#[cfg(feature = "tracy")]
macro_rules! cpu_zone {
    ($name:literal) => {
        let _zone = tracy_client::Client::running().map(|c| c.span(tracy_client::span_location!($name), 0));
    };
}
#[cfg(not(feature = "tracy"))]
macro_rules! cpu_zone {
    ($name:literal) => {};
}
pub(crate) use cpu_zone;
mod vk;

pub use error::{Error, Result};
pub use frame::{Aov, AovData, DebugPhoton, FrameReport, LightReport, SceneUpdateReport, SlotVerdict, HOST_ROUNDTRIP};
pub use gpu_types::{LevelCounters, TransportState, TraversalState, ACCOUNT_TERMS};
pub use renderer::{
    emitters, lights_without_receivers, BvhStats, Emitter, Finish, Frame, FrameDesc, FrameEstimate, FrameOutput,
    InstanceId, MeshId, Pipelines, RecordTarget, RecordedFrame, Renderer, Views, MAX_FRAMES_IN_FLIGHT,
};

/// The viewer's overlay: textured 2D triangles over a finished frame (src/passes/overlay.rs).
pub mod overlay {
    pub use crate::passes::overlay::{OverlayMesh, OverlayPainter, OverlayTarget, OverlayVertex};
}

/// Constants the renderer and its shaders share (src/shader_consts.rs): grid sizes, limits and the layouts of the
/// GPU's buffers.
pub mod consts {
    pub use crate::shaders::consts::*;
}
