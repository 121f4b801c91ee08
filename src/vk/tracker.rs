//! A last-access tracker: each pass declares how it uses a resource (an [`Access`]), and the tracker emits the
//! synchronization2 barriers that order that use after the resource's earlier ones, with the layout transitions
//! images need. It remembers, per resource, the last write (its stages and accesses), the stages that read since,
//! where the write has been made visible, and an image's layout, so no pass names what came before it.
//!
//! The state persists from frame to frame (one queue runs the frames in order), so a frame that reuses the last
//! frame's maps reads them with no barrier at all, and a map rewritten every frame is ordered after the last
//! frame's reads of it. [`Tracker::forget`] drops everything when the resources are re-created.
//!
//! The rules, per declared access (stages S, accesses A, layout L):
//! - an image whose layout is not L, or one declared with [`Tracker::discard`], gets a layout transition ordered
//!   after the last write and every read since (the transition writes the image, so the access then sees it);
//! - a write after a write gets a memory dependency; a write after reads only an execution dependency;
//! - a read after a write gets a memory dependency unless that write is already visible to S and A; a read after
//!   reads needs nothing.
//!
//! Host reads end a resource's history here: the host waits on the frame's fence before it reads, and before the
//! next frame reuses what it read.

use super::buffer::Buffer;
use super::context::Device;
use super::image::Image;
use super::sync::{Access, Barriers};
use ash::vk;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

type Stage = vk::PipelineStageFlags2;
type Acc = vk::AccessFlags2;

#[derive(Clone, Copy, Debug)]
struct State {
    /// The last write's stages and accesses (None: no write since the resource was tracked).
    write: Option<(Stage, Acc)>,
    /// Stages that read since the last write.
    reads: Stage,
    /// Stages and accesses the last write is visible to.
    visible_stages: Stage,
    visible_access: Acc,
    layout: vk::ImageLayout,
}

impl Default for State {
    fn default() -> Self {
        State {
            write: None,
            reads: Stage::NONE,
            visible_stages: Stage::NONE,
            visible_access: Acc::NONE,
            layout: vk::ImageLayout::UNDEFINED,
        }
    }
}

/// What one declaration asks for: the union of its accesses.
struct Use {
    stages: Stage,
    access: Acc,
    layout: vk::ImageLayout,
    write: bool,
}

fn union(accesses: &[Access]) -> Use {
    let mut u = Use { stages: Stage::NONE, access: Acc::NONE, layout: vk::ImageLayout::UNDEFINED, write: false };
    for a in accesses {
        let (s, acc, l) = a.info();
        u.stages |= s;
        u.access |= acc;
        if u.layout == vk::ImageLayout::UNDEFINED {
            u.layout = l;
        }
        u.write |= a.is_write();
    }
    u
}

/// The barrier a declared use needs, if any: (src stages, src accesses, dst stages, dst accesses, old layout).
type Need = (Stage, Acc, Stage, Acc, vk::ImageLayout);

impl State {
    /// Update the state for `u` and return the barrier it needs. `image`: layouts apply; `discard`: the contents
    /// are not needed (an image transitions from UNDEFINED).
    fn apply(&mut self, u: &Use, image: bool, discard: bool) -> Option<Need> {
        // Host reads are ordered by the fence the host waited on.
        let reads = self.reads & !Stage::HOST;
        let (write_stage, write_access) = self.write.unwrap_or((Stage::NONE, Acc::NONE));
        let write_stage = write_stage & !Stage::HOST;
        let transition = image && (discard || self.layout != u.layout);
        let need = if transition {
            let old = if discard { vk::ImageLayout::UNDEFINED } else { self.layout };
            let src_stage = write_stage | reads;
            // A resource with no history transitions after nothing (source stage NONE).
            Some((src_stage, write_access, u.stages, u.access, old))
        } else if u.write {
            let src_stage = write_stage | reads;
            (!src_stage.is_empty()).then(|| {
                let dst_access = if write_access.is_empty() { Acc::NONE } else { u.access };
                (src_stage, write_access, u.stages, dst_access, self.layout)
            })
        } else {
            let covered = self.visible_stages.contains(u.stages) && self.visible_access.contains(u.access);
            (self.write.is_some() && !covered).then_some((write_stage, write_access, u.stages, u.access, self.layout))
        };
        if transition || u.write {
            // The access (or the transition before it) is the resource's latest write.
            self.write = Some((u.stages, if u.write { u.access & writes() } else { Acc::NONE }));
            if !u.write {
                // A transition for a read: the layout change is the write, visible to this read.
                self.write = Some((u.stages, Acc::NONE));
            }
            self.reads = if u.write { Stage::NONE } else { u.stages };
            self.visible_stages = if u.write { Stage::NONE } else { u.stages };
            self.visible_access = if u.write { Acc::NONE } else { u.access };
        } else {
            self.reads |= u.stages;
            if need.is_some() {
                self.visible_stages |= u.stages;
                self.visible_access |= u.access;
            }
        }
        if image {
            self.layout = u.layout;
        }
        need
    }
}

/// Every write access a [`Access`] may carry.
fn writes() -> Acc {
    Acc::SHADER_STORAGE_WRITE
        | Acc::COLOR_ATTACHMENT_WRITE
        | Acc::DEPTH_STENCIL_ATTACHMENT_WRITE
        | Acc::TRANSFER_WRITE
        | Acc::MEMORY_WRITE
}

/// Per-resource last accesses and the barriers declared since the last flush.
pub struct Tracker {
    states: HashMap<u64, State>,
    /// Buffers and images destroyed since the last [`Tracker::prune`] (the device fills it).
    retired: Arc<Mutex<Vec<u64>>>,
    pending: Barriers,
    /// Barriers flushed so far (each `vkCmdPipelineBarrier2` call counts once).
    flushes: u64,
}

impl Tracker {
    pub fn new(device: &Device) -> Self {
        Tracker { states: HashMap::new(), retired: device.retired_ids(), pending: Barriers::default(), flushes: 0 }
    }

    /// Drop the histories of the buffers and images destroyed since the last call (a renderer that re-creates
    /// resources as its settings change would otherwise keep one history per resource it ever made).
    pub fn prune(&mut self) {
        let mut retired = self.retired.lock().unwrap_or_else(|e| e.into_inner());
        for id in retired.drain(..) {
            self.states.remove(&id);
        }
    }

    /// Resources with a history.
    #[cfg(test)]
    fn tracked(&self) -> usize {
        self.states.len()
    }

    /// Declare that the next commands use `buffer` with `accesses`.
    pub fn buffer(&mut self, buffer: &Buffer, accesses: &[Access]) -> &mut Self {
        let u = union(accesses);
        let state = self.states.entry(buffer.id).or_default();
        if let Some((ss, sa, ds, da, _)) = state.apply(&u, false, false) {
            self.pending.push_buffer(buffer.raw, (ss, sa), (ds, da));
        }
        self
    }

    /// Declare that the next commands use `image` with `accesses`, keeping its contents.
    pub fn image(&mut self, image: &Image, accesses: &[Access]) -> &mut Self {
        self.image_use(image, accesses, false)
    }

    /// Declare that the next commands overwrite `image` with `accesses`: its contents are not needed, so it
    /// transitions from UNDEFINED (after every earlier use of it).
    pub fn discard(&mut self, image: &Image, accesses: &[Access]) -> &mut Self {
        self.image_use(image, accesses, true)
    }

    fn image_use(&mut self, image: &Image, accesses: &[Access], discard: bool) -> &mut Self {
        let u = union(accesses);
        let state = self.states.entry(image.id).or_default();
        if let Some((ss, sa, ds, da, old)) = state.apply(&u, true, discard) {
            self.pending.push_image(image.raw, image.range(), (ss, sa, old), (ds, da, u.layout));
        }
        self
    }

    /// Record the declared barriers in one `vkCmdPipelineBarrier2` (nothing when none is needed).
    pub fn flush(&mut self, device: &Device, cmd: vk::CommandBuffer) {
        if self.pending.is_empty() {
            return;
        }
        self.pending.flush(device, cmd);
        self.flushes += 1;
    }

    /// The barrier commands recorded so far.
    pub fn flushes(&self) -> u64 {
        self.flushes
    }

    /// Forget what is known of every resource's history (a frame's recording failed, so what the queue will run is
    /// not known): each one's next use waits for all earlier commands, and an image's contents are lost (its layout
    /// is unknown). Pending declarations are dropped.
    pub fn forget(&mut self) {
        for s in self.states.values_mut() {
            *s = State {
                write: Some((Stage::ALL_COMMANDS, Acc::MEMORY_WRITE)),
                reads: Stage::ALL_COMMANDS,
                ..State::default()
            };
        }
        self.pending.clear();
    }

    /// Drop every resource's history: the tracked resources were destroyed after the device went idle, and those
    /// that replace them have none.
    pub fn clear(&mut self) {
        self.states.clear();
        self.pending.clear();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn apply(s: &mut State, a: &[Access], image: bool) -> Option<Need> {
        s.apply(&union(a), image, false)
    }

    #[test]
    fn read_after_read_needs_nothing_and_a_write_is_made_visible_once() {
        let mut s = State::default();
        // A first write of a buffer with no history: nothing to wait for.
        assert!(apply(&mut s, &[Access::ComputeWrite], false).is_none());
        let n = apply(&mut s, &[Access::ComputeRead], false).expect("read after write");
        assert_eq!(n.0, Stage::COMPUTE_SHADER);
        assert!(n.1.contains(Acc::SHADER_STORAGE_WRITE));
        assert!(apply(&mut s, &[Access::ComputeRead], false).is_none(), "already visible");
        let n = apply(&mut s, &[Access::VertexRead], false).expect("a new stage");
        assert_eq!(n.2, Stage::VERTEX_SHADER);
        // A write after those reads waits for both readers (and for the write they read).
        let n = apply(&mut s, &[Access::TransferDst], false).expect("write after read");
        assert_eq!(n.0, Stage::COMPUTE_SHADER | Stage::VERTEX_SHADER);
        // A write after reads of data no tracked write made (uploaded before): an execution dependency only.
        let mut s = State::default();
        assert!(apply(&mut s, &[Access::ComputeRead], false).is_none(), "nothing to wait for");
        let n = apply(&mut s, &[Access::TransferDst], false).expect("write after read");
        assert_eq!(n.0, Stage::COMPUTE_SHADER);
        assert!(n.1.is_empty() && n.3.is_empty(), "{n:?}");
    }

    #[test]
    fn images_transition_when_the_layout_changes() {
        let mut s = State::default();
        let n = apply(&mut s, &[Access::ColorAttachment], true).expect("first layout");
        assert_eq!(n.4, vk::ImageLayout::UNDEFINED);
        let n = apply(&mut s, &[Access::ComputeSampled, Access::FragmentSampled], true).expect("to sampled");
        assert_eq!(n.4, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        assert!(n.1.contains(Acc::COLOR_ATTACHMENT_WRITE));
        assert!(apply(&mut s, &[Access::ComputeSampled], true).is_none(), "same layout, already visible");
        let n = s.apply(&union(&[Access::ColorAttachment]), true, true).expect("discard");
        assert_eq!(n.4, vk::ImageLayout::UNDEFINED);
        assert!(n.0.contains(Stage::COMPUTE_SHADER | Stage::FRAGMENT_SHADER), "after the reads: {:?}", n.0);
    }

    #[test]
    fn a_destroyed_buffer_leaves_the_tracker_at_the_next_prune() {
        let desc = crate::vk::ContextDesc { validation: true, ..crate::vk::ContextDesc::from_env() };
        let device = crate::vk::Context::headless(&desc).expect("a Vulkan device").device;
        let mut tracker = Tracker::new(&device);
        let other = Tracker::new(&device);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let kept = Buffer::new(&device, "kept", 64, usage, gpu_allocator::MemoryLocation::GpuOnly).expect("buffer");
        for _ in 0..3 {
            let b = Buffer::new(&device, "passing", 64, usage, gpu_allocator::MemoryLocation::GpuOnly).expect("buffer");
            tracker.buffer(&b, &[Access::ComputeWrite]).buffer(&kept, &[Access::ComputeRead]);
            tracker.pending.clear();
        }
        assert_eq!(tracker.tracked(), 4);
        tracker.prune();
        assert_eq!(tracker.tracked(), 1, "the kept buffer's history stays");
        // Every tracker of the device hears of each destroyed resource.
        assert_eq!(other.retired.lock().expect("list").len(), 3);
        drop(other);
        drop(kept);
        tracker.prune();
        assert_eq!(tracker.tracked(), 0);
    }
}
