//! How long a frame will take on this device, measured rather than guessed: two probe frames of the same scene
//! and settings, at lower levels and smaller outputs, time the light side (the photons and the maps of every
//! light and color pass) and the eye view. Each part is a fixed cost plus a cost per unit of work (photons for the
//! light side, pixels for the eye view), so the two probes fit both and the frame's own work is extrapolated: its
//! photons from the probes' growth per level, its pixels from its size.

use super::{FrameDesc, Renderer};
use crate::error::Result;
use crate::settings::Method;
use crate::settings::Metric;
use std::time::Instant;

/// What [`Renderer::estimate`] expects a frame to take.
#[derive(Clone, Copy, Debug)]
pub struct FrameEstimate {
    /// The frame's GPU time, seconds: the light side and the eye view.
    pub seconds: f64,
    /// The light side's part (light views, photons, transport, splat, resolve; every light and color pass).
    pub light_seconds: f64,
    /// The eye view's part (receivers, glass, composite, readback).
    pub eye_seconds: f64,
    /// The photons expected.
    pub photons: f64,
    /// Recording the frame's commands on the host, seconds (the larger probe's: the commands hardly depend on the
    /// level or the size, and they are recorded before the GPU starts).
    pub record_seconds: f64,
    /// What the probes took, seconds of wall time.
    pub probe_seconds: f64,
}

impl FrameEstimate {
    /// The frame's expected wall time: recording, then the GPU's work.
    pub fn wall_seconds(&self) -> f64 {
        self.record_seconds + self.seconds
    }
}

/// Stages of the eye view (the rest of a frame is its light side).
fn is_eye_stage(label: &str) -> bool {
    label.starts_with("eye") || label == "composite" || label == "readback"
}

/// One probe: its light-side and eye ms, its photons, pixels and recording ms.
struct Probe {
    light_ms: f64,
    eye_ms: f64,
    photons: f64,
    pixels: f64,
    record_ms: f64,
}

/// `y = a + b x` through two points (b ≥ 0: more work never costs less), at `x`.
fn line_at(x0: f64, y0: f64, x1: f64, y1: f64, x: f64) -> f64 {
    if (x1 - x0).abs() < 1e-9 * x1.abs().max(1.0) {
        return y1.max(y0);
    }
    let b = ((y1 - y0) / (x1 - x0)).max(0.0);
    (y1 + b * (x - x1)).max(y1.min(y0))
}

impl Renderer {
    /// Estimate the frame `desc` describes from probe frames: one three levels below the frame's (but at level 1
    /// at least) at a quarter of its side, run twice, and one a level above that at half its side (both at the
    /// frame's own level when it is 2 or lower). The first run builds and compiles what the frame runs, so that no
    /// compile falls inside a timed probe: a CPU driver compiles a pipeline when it first runs it (lavapipe:
    /// seconds for the traversal's), for each size class of the images it samples (lavapipe: whether a side is a
    /// power of two), and a level-0 probe runs other pipelines than a frame of level 1 or more. A compile inside a
    /// timed probe once made a 1 s frame's estimate 59 s. For a frame of several seconds the
    /// probes cost about a fifth of it; they leave the renderer as it was (they reuse nothing, and nothing reuses
    /// them).
    pub fn estimate(&mut self, desc: &FrameDesc) -> Result<FrameEstimate> {
        let start = Instant::now();
        let level = desc.level.map_or(self.config.level, |l| l.min(self.config.level));
        let view = |div: u32| {
            let mut v = *desc.camera;
            v.width = (desc.camera.width / div).max(16);
            v.height = (desc.camera.height / div).max(16);
            v
        };
        let reuse = std::mem::replace(&mut self.reuse, false);
        let hint = self.queue.slots_hint();
        let probe = |r: &mut Renderer, l: u32, camera: &crate::scene::CameraView| -> Result<Probe> {
            let d = FrameDesc { camera, aov: None, level: Some(l), preview: desc.preview };
            let f = r.render(&d)?;
            let eye: f64 = f.report.stages.iter().filter(|(l, _)| is_eye_stage(l)).map(|(_, ms)| ms).sum();
            Ok(Probe {
                light_ms: f.report.gpu_ms - eye,
                eye_ms: eye,
                photons: f.report.photons() as f64,
                pixels: (camera.width * camera.height) as f64,
                record_ms: f.report.record_ms,
            })
        };
        let (quarter, half) = (view(4), view(2));
        let la = if level <= 2 { level } else { (level - 3).max(1) };
        let lb = if level <= 2 { level } else { la + 1 };
        let result = (|| -> Result<(Probe, Probe)> {
            probe(self, la, &quarter)?;
            Ok((probe(self, la, &quarter)?, probe(self, lb, &half)?))
        })();
        self.reuse = reuse;
        self.queue.restore_slots_hint(hint);
        self.caches.clear();
        let (a, b) = result?;
        // The frame's photons: dense and max-level cover the same cells at every level, four children a cell; the
        // metrics merge some, as the probes' own growth shows.
        let steps = (level - lb) as i32;
        let growth = match (self.config.method, self.config.metric) {
            (Method::Dense, _) | (Method::Adaptive, Metric::MaxLevel) => 4.0,
            _ if la < lb && a.photons > 0.0 => (b.photons / a.photons).clamp(2.0, 4.0),
            _ => 4.0,
        };
        let photons = b.photons * growth.powi(steps);
        let frame_pixels = (desc.camera.width * desc.camera.height) as f64;
        let light_ms = line_at(a.photons, a.light_ms, b.photons, b.light_ms, photons);
        let eye_ms = line_at(a.pixels, a.eye_ms, b.pixels, b.eye_ms, frame_pixels);
        Ok(FrameEstimate {
            seconds: (light_ms + eye_ms) * 1e-3,
            light_seconds: light_ms * 1e-3,
            eye_seconds: eye_ms * 1e-3,
            photons,
            record_seconds: a.record_ms.max(b.record_ms) * 1e-3,
            probe_seconds: start.elapsed().as_secs_f64(),
        })
    }
}
