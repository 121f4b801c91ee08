//! Frames in flight: each frame takes a slot (its command buffer, fence and timestamp queries; its uniforms and
//! readback buffer live in the targets), and is read back when a later frame needs the slot or the caller asks.
//! The queue also keeps GPU-driven batching's slot count, adapted from the frames' reports.

use super::keys::Caches;
use crate::error::Result;
use crate::frame::report::{read_aov, read_results};
use crate::frame::{Aov, AovData, FrameReport, SlotVerdict, HOST_ROUNDTRIP};
use crate::settings::{Method, ResolvedSettings};
use crate::shaders::consts::*;
use crate::targets::Targets;
use crate::vk::{Device, Recorder, Timestamps, VkResult};
use std::collections::VecDeque;
use std::sync::Arc;
use std::time::Instant;

/// The most frames that may be in flight at once.
pub const MAX_FRAMES_IN_FLIGHT: usize = 3;

/// The per-frame resources of one frame in flight.
pub(crate) struct FrameSlot {
    pub recorder: Recorder,
    pub timestamps: Timestamps,
}

impl FrameSlot {
    fn new(device: &Arc<Device>) -> VkResult<Self> {
        Ok(FrameSlot { recorder: Recorder::new(device)?, timestamps: Timestamps::new(device, 16384)? })
    }
}

/// A frame submitted and not read back yet.
pub(crate) struct Pending {
    pub slot: usize,
    pub report: FrameReport,
    pub start: Instant,
    /// Index of the frame's first eye-view interval (the per-light sums stop there).
    pub lights_end: usize,
    /// The AOV its readback copies, if any.
    pub aov: Option<Aov>,
    /// Its caustic inputs: the cache entry its states complete.
    pub key: super::keys::CausticKey,
    /// The settings it was recorded with (the readback layout and what to read depend on them).
    pub settings: ResolvedSettings,
    /// Recorded into a host's command buffer: the host submits it and says when it completed (no fence here).
    pub external: bool,
}

pub(crate) struct FrameQueue {
    pub slots: Vec<FrameSlot>,
    /// Frames submitted and not yet read back, oldest first (at most `frames_in_flight`).
    pending: VecDeque<Pending>,
    /// Reports of frames completed on the way (a new frame waiting for its slot, a resize), oldest first.
    completed: Vec<FrameReport>,
    frames_in_flight: usize,
    /// Frames submitted so far (the next frame's slot is this modulo `frames_in_flight`).
    submitted: u64,
    /// GPU-driven batching: slots recorded next frame (adapted from frame to frame; 0: not known yet).
    slots_hint: u32,
    /// Each completed frame's GPU zones, where Tracy's client runs (`--features tracy`).
    #[cfg(feature = "tracy")]
    tracy: Option<crate::tracy::TracyGpu>,
}

impl FrameQueue {
    pub fn new(device: &Arc<Device>) -> VkResult<Self> {
        Ok(FrameQueue {
            slots: vec![FrameSlot::new(device)?],
            pending: VecDeque::new(),
            completed: Vec::new(),
            frames_in_flight: 1,
            submitted: 0,
            slots_hint: 0,
            #[cfg(feature = "tracy")]
            tracy: crate::tracy::TracyGpu::new(device),
        })
    }

    pub fn frames_in_flight(&self) -> usize {
        self.frames_in_flight
    }

    /// Allow `n` frames in flight (the caller has finished every frame first).
    pub fn set_frames_in_flight(&mut self, device: &Arc<Device>, n: usize) -> VkResult<()> {
        debug_assert!(self.pending.is_empty());
        while self.slots.len() < n {
            self.slots.push(FrameSlot::new(device)?);
        }
        self.frames_in_flight = n;
        Ok(())
    }

    /// The slot the next frame takes. When every slot is in flight, this first waits for the oldest frame, the
    /// last to use that slot, and keeps its report for [`FrameQueue::take_completed`].
    pub fn next_slot(&mut self, targets: Option<&Targets>, caches: &mut Caches) -> Result<usize> {
        while self.pending.len() >= self.frames_in_flight {
            let oldest = self.pending.pop_front().expect("a frame in flight");
            let (report, _) = self.complete(oldest, targets, caches)?;
            self.completed.push(report);
        }
        Ok((self.submitted % self.frames_in_flight as u64) as usize)
    }

    /// Wait for every frame in flight and keep their reports.
    pub fn finish(&mut self, targets: Option<&Targets>, caches: &mut Caches) -> Result<()> {
        while let Some(oldest) = self.pending.pop_front() {
            let (report, _) = self.complete(oldest, targets, caches)?;
            self.completed.push(report);
        }
        Ok(())
    }

    /// Wait for the frame just submitted (the only one in flight) and read it back.
    pub fn wait_last(
        &mut self,
        targets: Option<&Targets>,
        caches: &mut Caches,
    ) -> Result<(FrameReport, Option<AovData>)> {
        let last = self.pending.pop_back().expect("the frame just submitted");
        self.complete(last, targets, caches)
    }

    /// Whether a frame recorded into a host's command buffer has not been completed yet.
    pub fn has_external(&self) -> bool {
        self.pending.iter().any(|p| p.external)
    }

    /// Read back the frame recorded into a host's command buffer (the host has waited for its submission).
    pub fn complete_external(
        &mut self,
        targets: Option<&Targets>,
        caches: &mut Caches,
    ) -> Result<(FrameReport, Option<AovData>)> {
        let i = self.pending.iter().position(|p| p.external).expect("a recorded frame");
        let p = self.pending.remove(i).expect("in range");
        self.complete(p, targets, caches)
    }

    /// The reports of the frames completed since the last call, oldest first.
    pub fn take_completed(&mut self) -> Vec<FrameReport> {
        std::mem::take(&mut self.completed)
    }

    pub fn push(&mut self, p: Pending) {
        self.submitted += 1;
        self.pending.push_back(p);
    }

    /// Wait for a submitted frame and read its timings, its traversal and transport state and its AOV.
    fn complete(
        &mut self,
        p: Pending,
        targets: Option<&Targets>,
        caches: &mut Caches,
    ) -> Result<(FrameReport, Option<AovData>)> {
        crate::cpu_zone!("complete");
        let FrameSlot { recorder, timestamps } = &mut self.slots[p.slot];
        if !p.external {
            recorder.wait()?;
        }
        let mut report = p.report;
        report.frame_ms = p.start.elapsed().as_secs_f64() * 1e3;
        report.segments = timestamps.resolve()?;
        report.gpu_start_tick = timestamps.first_tick();
        #[cfg(feature = "tracy")]
        if let Some(t) = self.tracy.as_mut() {
            t.frame(&report);
        }
        if timestamps.overflowed() {
            log::warn!("more stages than timestamp queries: the per-stage GPU times of this frame are truncated");
        }
        report.stages = crate::vk::query::sum_by_label(&report.segments);
        report.substages = crate::vk::query::sum_by_sublabel(&report.segments);
        report.gpu_ms = report.stages.iter().filter(|(l, _)| *l != HOST_ROUNDTRIP).map(|(_, ms)| ms).sum();
        // Each light's light-side stages: the timed intervals from its first mark to the next light's.
        let ends: Vec<usize> =
            report.lights.iter().skip(1).map(|l| l.first_segment).chain(std::iter::once(p.lights_end)).collect();
        for (l, end) in report.lights.iter_mut().zip(ends) {
            l.gpu_ms = report
                .segments
                .get(l.first_segment..end.min(report.segments.len()))
                .unwrap_or(&[])
                .iter()
                .filter(|(label, _, _)| *label != HOST_ROUNDTRIP)
                .map(|(_, _, ms)| ms)
                .sum();
        }
        let t = targets.expect("a frame in flight has targets");
        let readback = &t.readbacks[p.slot];
        let cached = caches.caustic.as_mut().filter(|(k, _)| *k == p.key);
        if report.reused {
            // The frame that computed the maps completed before this one: its states are known.
            if let Some((_, lights)) = cached {
                for (l, c) in report.lights.iter_mut().zip(lights.iter()) {
                    l.state = c.state;
                    l.transport = c.transport;
                }
            }
        } else {
            read_results(t, readback, &p.settings, &mut report)?;
            if let Some((_, lights)) = cached {
                *lights = report.lights.clone();
            }
        }
        report.state = report.lights.first().and_then(|l| l.state);
        report.transport = report.lights.first().and_then(|l| l.transport);
        let img = read_aov(t, readback, &p.settings, p.aov)?;
        Ok((report, img))
    }

    /// After a frame, set the batch slots GPU-driven batching records next time: as many as this frame used plus
    /// a margin when it finished every tile; twice what it needed when tiles were left over (the frame's caustic
    /// is then incomplete, and its cache entry is dropped so that the next frame recomputes it).
    pub fn adapt_batch_slots(&mut self, report: &FrameReport, caches: &mut Caches) -> SlotVerdict {
        let Some(st) = report.state.as_ref() else { return SlotVerdict::Complete };
        if report.unfinished_tiles == 0 || report.batch_slots >= MAX_BATCHES {
            if report.batch_slots > 1 {
                self.slots_hint = (st.slots_used + st.slots_used / 4 + 1).min(MAX_BATCHES);
            }
            return if report.unfinished_tiles == 0 { SlotVerdict::Complete } else { SlotVerdict::OutOfSlots };
        }
        caches.caustic = None;
        let needed = st.slots_used + st.stack_size;
        self.slots_hint = (needed.max(report.batch_slots) * 2).min(MAX_BATCHES);
        SlotVerdict::Incomplete
    }

    /// Forget the adapted slot count (the method, level or metric changed).
    pub fn reset_batch_slots(&mut self) {
        self.slots_hint = 0;
    }

    /// Put back an adapted slot count (probe frames at other levels leave the frame's own).
    pub fn restore_slots_hint(&mut self, hint: u32) {
        self.slots_hint = hint;
    }

    /// The adapted slot count (0 before any frame needed more than one).
    pub fn slots_hint(&self) -> u32 {
        self.slots_hint
    }

    /// Batch slots to record for GPU-driven adaptive traversal: one when the worst case (every cell of the photon
    /// window covered) fits the photon buffer; else the adapted count of the frames before, or, before any, the
    /// most a frame can need: each slot commits a tile's batch or splits it into four, and a tile `d` splits deep
    /// covers 4^-d of the grid, so once its worst case fits no tile splits further, and the slots are at most
    /// the tiles of the splits above that depth plus the tiles at it. A frame that still runs out is finished by
    /// continuations ([`crate::Renderer::render`]).
    pub fn batch_slots(&self, s: &ResolvedSettings, capacity: u32) -> u32 {
        if s.batch_slots > 0 {
            return s.batch_slots;
        }
        if s.method != Method::Adaptive {
            return 1;
        }
        // The worst case: every cell of every level a candidate (the buffer's entries), and every cell of the
        // last level a photon (the batch's photons).
        let cells0 = (LEVEL0_RES * LEVEL0_RES) as f64;
        let l = s.level as i32;
        let photons = cells0 * 4f64.powi(l);
        let worst = cells0 * (4f64.powi(l + 1) - 1.0) / 3.0 + photons;
        let need =
            |tiles: f64| (worst / tiles / capacity as f64).max(photons / tiles / s.batch_photons(capacity) as f64);
        if need(1.0) <= 1.0 {
            return 1;
        }
        if self.slots_hint > 0 {
            return self.slots_hint;
        }
        let mut depth = 0;
        while need(4f64.powi(depth)) > 1.0 && depth < 6 + l {
            depth += 1;
        }
        let splits = (4f64.powi(depth) - 1.0) / 3.0;
        ((splits + 4f64.powi(depth)) as u32).clamp(2, MAX_BATCHES)
    }
}
