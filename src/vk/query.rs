//! Timestamp queries. A frame writes a timestamp at each stage boundary ([`Timestamps::mark`]); the interval
//! from one mark to the next is charged to the first mark's label, and intervals with the same label are summed
//! (traversal levels across batches, say).

use super::context::Device;
use super::error::{Check, VkResult};
use ash::vk;
use std::sync::Arc;

pub struct Timestamps {
    device: Arc<Device>,
    pool: vk::QueryPool,
    capacity: u32,
    labels: Vec<&'static str>,
    overflowed: bool,
    /// The first timestamp that [`Timestamps::resolve`] read, in device ticks (masked to the valid bits).
    first_tick: Option<u64>,
}

impl Timestamps {
    pub fn new(device: &Arc<Device>, capacity: u32) -> VkResult<Self> {
        let info = vk::QueryPoolCreateInfo::default().query_type(vk::QueryType::TIMESTAMP).query_count(capacity);
        let pool = unsafe { device.create_query_pool(&info, None) }.check("vkCreateQueryPool")?;
        Ok(Timestamps {
            device: device.clone(),
            pool,
            capacity,
            labels: Vec::new(),
            overflowed: false,
            first_tick: None,
        })
    }

    /// Reset the pool at the start of a command buffer.
    pub fn reset(&mut self, cmd: vk::CommandBuffer) {
        unsafe { self.device.cmd_reset_query_pool(cmd, self.pool, 0, self.capacity) };
        self.labels.clear();
        self.overflowed = false;
    }

    /// Write a timestamp once all previously recorded work is complete, and start a stage called `label`.
    pub fn mark(&mut self, cmd: vk::CommandBuffer, label: &'static str) {
        let index = self.labels.len() as u32;
        if index >= self.capacity {
            self.overflowed = true;
            return;
        }
        unsafe { self.device.cmd_write_timestamp2(cmd, vk::PipelineStageFlags2::ALL_COMMANDS, self.pool, index) };
        self.labels.push(label);
    }

    /// Every interval: (label, start ms from the first timestamp, duration ms). Call after the work completed.
    pub fn resolve(&mut self) -> VkResult<Vec<(&'static str, f64, f64)>> {
        let n = self.labels.len();
        self.first_tick = None;
        if n < 2 {
            return Ok(Vec::new());
        }
        let mut ticks = vec![0u64; n];
        unsafe {
            self.device
                .get_query_pool_results(
                    self.pool,
                    0,
                    &mut ticks,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
                .check("vkGetQueryPoolResults")?;
        }
        let mask = self.device.info.timestamp_mask();
        let ms = |dt: u64| (dt & mask) as f64 * self.device.info.timestamp_period as f64 * 1e-6;
        self.first_tick = Some(ticks[0] & mask);
        let out = (0..n - 1)
            .filter(|&i| !self.labels[i].is_empty())
            .map(|i| (self.labels[i], ms(ticks[i].wrapping_sub(ticks[0])), ms(ticks[i + 1].wrapping_sub(ticks[i]))))
            .collect();
        Ok(out)
    }

    /// Marks so far this frame: the index of the next mark's interval in [`Timestamps::resolve`]'s list.
    pub fn len(&self) -> usize {
        self.labels.len()
    }

    /// The frame's first timestamp, in device ticks, once [`Timestamps::resolve`] read it.
    pub fn first_tick(&self) -> Option<u64> {
        self.first_tick
    }

    pub fn overflowed(&self) -> bool {
        self.overflowed
    }
}

impl Drop for Timestamps {
    fn drop(&mut self) {
        unsafe { self.device.destroy_query_pool(self.pool, None) };
    }
}

/// Sum intervals by stage, in first-seen order: a `stage.part` label counts to `stage`.
pub fn sum_by_label(segments: &[(&'static str, f64, f64)]) -> Vec<(&'static str, f64)> {
    sum_by(segments, |l| l.split('.').next().unwrap_or(l))
}

/// The sub-stages: intervals labelled `stage.part` summed by their whole label (their stage's entry in
/// [`sum_by_label`] holds their sum).
pub fn sum_by_sublabel(segments: &[(&'static str, f64, f64)]) -> Vec<(&'static str, f64)> {
    let subs: Vec<_> = segments.iter().filter(|(l, _, _)| l.contains('.')).copied().collect();
    sum_by(&subs, |l| l)
}

fn sum_by(
    segments: &[(&'static str, f64, f64)],
    key: impl Fn(&'static str) -> &'static str,
) -> Vec<(&'static str, f64)> {
    let mut out: Vec<(&'static str, f64)> = Vec::new();
    for (label, _, ms) in segments {
        let k = key(label);
        match out.iter_mut().find(|(l, _)| *l == k) {
            Some(e) => e.1 += ms,
            None => out.push((k, *ms)),
        }
    }
    out
}
