//! Tracy zones (`--features tracy`): each completed frame's GPU stages, from the same timestamp queries as
//! [`FrameReport::stages`](crate::FrameReport::stages), as GPU zones on the device's clock, and the host's recording,
//! submission and readback as CPU zones, with a frame mark per frame.
//!
//! The GPU context is calibrated to Tracy's host clock through VK_EXT_calibrated_timestamps
//! ([`DeviceInfo::calibrated_timestamps`](crate::gpu::DeviceInfo)): the device's clock is read from the host, and
//! Tracy takes its own clock at that call. It is read again every second, so that a clock that drifts or resets
//! (a GPU's power states) stays aligned. Without the extension each frame's last timestamp stands for the moment its
//! results were read back, which places the zones late by the readback's latency.
//!
//! A program that uses the library with this feature starts Tracy's client first (`tracy_client::Client::start()`;
//! the command-line applications do), and connects Tracy's profiler to it: the client sends only while one is
//! connected (Tracy's on-demand mode).

use crate::frame::FrameReport;
use crate::vk::Device;
use ash::vk;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How often the GPU clock is read again.
const RESYNC: Duration = Duration::from_secs(1);

/// The GPU zones of one device's queue.
pub(crate) struct TracyGpu {
    device: Arc<Device>,
    context: tracy_client::GpuContext,
    /// Nanoseconds per device tick.
    period_ns: f64,
    /// When the clock was last read (None: never, without calibrated timestamps).
    synced: Option<Instant>,
}

impl TracyGpu {
    /// A GPU context for `device`'s queue, or None when Tracy's client is not running.
    pub fn new(device: &Arc<Device>) -> Option<TracyGpu> {
        let client = tracy_client::Client::running()?;
        let period = device.info.timestamp_period;
        let now = device_ticks(device).unwrap_or(0);
        let name = format!("{} queue", device.info.name);
        let context = client.new_gpu_context(Some(&name), tracy_client::GpuContextType::Vulkan, now, period).ok()?;
        if device.calibrated.is_none() {
            log::info!("tracy: no VK_EXT_calibrated_timestamps; GPU zones are placed by each frame's readback");
        }
        let synced = device.calibrated.as_ref().map(|_| Instant::now());
        Some(TracyGpu { device: device.clone(), context, period_ns: period as f64, synced })
    }

    /// Emit a completed frame's GPU zones (one per timed interval, named by its stage label) and a frame mark.
    pub fn frame(&mut self, report: &FrameReport) {
        let Some(start) = report.gpu_start_tick else { return };
        match self.synced {
            Some(at) if at.elapsed() >= RESYNC => {
                if let Some(now) = device_ticks(&self.device) {
                    self.context.sync_gpu_time(now);
                    self.synced = Some(Instant::now());
                }
            }
            Some(_) => {}
            // The frame's last timestamp is about now: its results were just read back.
            None => {
                let end = report.segments.last().map_or(0.0, |&(_, at, ms)| at + ms);
                self.context.sync_gpu_time(self.tick(start, end));
            }
        }
        for &(label, at, ms) in &report.segments {
            let Ok(mut span) = self.context.span_alloc(label, "frame", file!(), line!()) else { break };
            span.end_zone();
            span.upload_timestamp_start(self.tick(start, at));
            span.upload_timestamp_end(self.tick(start, at + ms));
        }
        tracy_client::frame_mark();
    }

    /// The device tick `ms` milliseconds after `start`.
    fn tick(&self, start: u64, ms: f64) -> i64 {
        start as i64 + (ms * 1e6 / self.period_ns).round() as i64
    }
}

/// The device's clock now, through VK_EXT_calibrated_timestamps.
fn device_ticks(device: &Device) -> Option<i64> {
    let ext = device.calibrated.as_ref()?;
    let info = [vk::CalibratedTimestampInfoEXT::default().time_domain(vk::TimeDomainEXT::DEVICE)];
    let (ticks, _deviation) = unsafe { ext.get_calibrated_timestamps(&info) }.ok()?;
    Some((ticks[0] & device.info.timestamp_mask()) as i64)
}
