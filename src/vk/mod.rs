//! A thin, safe-ish layer over ash: instance and device, RAII buffers and images, push-descriptor pipelines,
//! synchronization2 barriers, command recording and timestamp queries.

pub mod buffer;
pub mod cmd;
pub mod context;
pub mod debug;
pub mod error;
pub mod image;
pub mod pipeline;
pub mod query;
/// SPIR-V reading (shared with build.rs): each pipeline's layout is checked against what its shaders declare.
#[path = "../../build/spirv.rs"]
pub(crate) mod spirv;
pub mod sync;
pub mod tracker;
pub mod uses;

pub use buffer::Buffer;
pub use cmd::{Recorder, SubmitSync};
pub use context::{Context, ContextDesc, Device, DeviceInfo, Instance};
pub use debug::validation_message_count;
pub use error::{Check, VkError, VkResult};
pub use image::{Image, Sampler};
pub use pipeline::{Bind, Blend, ColorTarget, GraphicsDesc, Pipeline};
pub use query::Timestamps;
pub use sync::{Access, Barriers};
pub use tracker::Tracker;
pub use uses::{Raster, Target, Use};

/// A fresh id for a buffer or an image.
fn next_resource_id() -> u64 {
    static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
    NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
}
