//! `caustics soak` (hidden; `tools/soak` runs it): one [`Renderer`](caustics::Renderer) renders N frames
//! headless while the light orbits and the settings change every frame (transport, method, metric, level, index
//! of refraction, output size), and checks that
//!
//! - the program's own heap (the bytes its Rust code holds, counted by its allocator) is the same at every visit of
//!   a setting after the warm-up (the first two full cycles of light positions and settings: the targets of every
//!   setting are created and freed twice), within [`HEAP_SLACK_BYTES`];
//! - resident memory (`/proc/self/statm`, after `malloc_trim`), which also holds lavapipe's heap and its device
//!   memory, does not rise after the warm-up: the least of the last quarter of the later frames stays within
//!   `--rss-bound-mib` of the first quarter's. Its least-squares slope, its minimum and maximum are reported too;
//! - the GPU allocations (gpu-allocator's report) are the same at every visit of a setting after the warm-up
//!   (the same count, and the same bytes within [`GPU_SLACK_BYTES`]: re-uploaded buffers land at other offsets,
//!   with other alignment padding), and the memory blocks behind them never exceed the warm-up's peak;
//! - no validation message is emitted (when validation is on);
//! - every frame's caustic flux (Σ E · pixel area of the caustics AOV through the scene's orthographic camera)
//!   is finite, positive and below the power the light sends into its cone; the first visit of a (light
//!   position, setting) pair is its reference, and every later visit must land within `--flux-tolerance` of it;
//!   under exact transport the energy account must close (residual below 1e-6).
//!
//! Frame i renders setting i mod S at light position ⌊i / S⌋ mod A, so all S settings see each light position
//! in turn and the whole schedule repeats every S·A frames.

use crate::app::commands::{to_rgb, SceneArgs, Session};
use crate::app::LightOrbit;
use caustics::error::{Error, Result};
use caustics::image_io;
use caustics::scene::{Light, LightKind, Material, Scene};
use caustics::settings::{Method, Metric, Quality, Settings, Transport, Tuning};
use caustics::Aov;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug, Clone)]
pub struct SoakArgs {
    /// Scene (default: the sphere scene); it needs an orthographic camera (`--camera`).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Orthographic camera whose caustics AOV gives each frame's flux.
    #[arg(long, default_value = "top")]
    pub camera: String,
    /// Frames to render.
    #[arg(long, default_value_t = 300)]
    pub frames: u32,
    /// Light positions on the orbit (the light turns 360°/A between blocks of settings).
    #[arg(long, default_value_t = 6)]
    pub angles: u32,
    /// Highest photon level in the schedule (levels 0..=this; exact frames stay at 0 and 1).
    #[arg(long, default_value_t = 1)]
    pub max_level: u32,
    /// Side of the caustic map and of the refractor g-buffers.
    #[arg(long, default_value_t = 256)]
    pub map_res: u32,
    /// Allowed rise of resident memory's floor after the warm-up, MiB: the least of the last quarter of the frames
    /// against the least of the first quarter. Measured 1.2 and 1.8 MiB over 224 frames with validation, and a
    /// step of 8 MiB in one run without (lavapipe's heap, flat after it). The program's own heap is held exactly
    /// (within [`HEAP_SLACK_BYTES`]); this bound catches what the driver holds for it.
    #[arg(long, default_value_t = 24.0)]
    pub rss_bound_mib: f64,
    /// Relative tolerance of a frame's caustic flux against the first visit of its light position and setting.
    #[arg(long, default_value_t = 1e-3)]
    pub flux_tolerance: f64,
    /// Write the figures (and memory samples) as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Allowed difference of a setting's GPU allocated bytes between visits (alignment padding).
pub const GPU_SLACK_BYTES: u64 = 64 * 1024;

/// Allowed difference of the program's live heap bytes between visits of a setting after the warm-up.
/// Measured: at most 800 bytes (formatted numbers' lengths); a leak of 100 bytes a frame exceeds it within the
/// short soak's 160 checked frames.
pub const HEAP_SLACK_BYTES: u64 = 16 * 1024;

/// One memory sample (every tenth frame).
struct Sample {
    frame: usize,
    rss: u64,
    heap: u64,
    gpu: caustics::gpu::AllocationTotals,
}

/// What the soak watches of memory: resident memory, the program's heap and the GPU allocations, sampled after each
/// frame; during the warm-up only their peaks, after it their every visit of a setting.
struct Memory {
    warmup: usize,
    rss_base: u64,
    warm_capacity: u64,
    rss_min: u64,
    rss_max: u64,
    /// (frame, bytes) after the warm-up.
    rss_points: Vec<(f64, f64)>,
    samples: Vec<Sample>,
    /// The heap's bytes and the GPU's allocations at each setting's first visit after the warm-up.
    heap_at: Vec<Option<u64>>,
    gpu_alloc: Vec<Option<(usize, u64)>>,
    worst_heap_change: u64,
}

impl Memory {
    /// Sized up front for `frames`: the soak's own records must not grow the heap it measures.
    fn new(frames: usize, settings: usize, warmup: usize) -> Self {
        Memory {
            warmup,
            rss_base: 0,
            warm_capacity: 0,
            rss_min: u64::MAX,
            rss_max: 0,
            rss_points: Vec::with_capacity(frames),
            samples: Vec::with_capacity(frames / 10 + 2),
            heap_at: vec![None; settings],
            gpu_alloc: vec![None; settings],
            worst_heap_change: 0,
        }
    }

    /// Sample after frame `i` (setting `si`) and check it; returns resident memory and the GPU's allocations.
    fn observe(
        &mut self,
        i: usize,
        si: usize,
        gpu: caustics::gpu::AllocationTotals,
        fail: &mut impl FnMut(String),
    ) -> (u64, caustics::gpu::AllocationTotals) {
        trim_heap();
        let rss = rss_bytes();
        let heap = crate::app::heap::live_bytes();
        if i.is_multiple_of(10) {
            self.samples.push(Sample { frame: i, rss, heap, gpu });
        }
        if i < self.warmup {
            self.rss_base = self.rss_base.max(rss);
            self.warm_capacity = self.warm_capacity.max(gpu.capacity_bytes);
            return (rss, gpu);
        }
        self.rss_max = self.rss_max.max(rss);
        self.rss_min = self.rss_min.min(rss);
        self.rss_points.push((i as f64, rss as f64));
        if gpu.capacity_bytes > self.warm_capacity {
            fail(format!(
                "GPU memory blocks grew to {} bytes (warm-up peak {})",
                gpu.capacity_bytes, self.warm_capacity
            ));
        }
        match self.heap_at[si] {
            None => self.heap_at[si] = Some(heap),
            Some(h) => {
                self.worst_heap_change = self.worst_heap_change.max(heap.abs_diff(h));
                if heap.abs_diff(h) > HEAP_SLACK_BYTES {
                    fail(format!(
                        "the program's heap holds {heap} bytes, {h} at this setting's first visit after warm-up"
                    ));
                }
            }
        }
        match self.gpu_alloc[si] {
            None => self.gpu_alloc[si] = Some((gpu.allocations, gpu.allocated_bytes)),
            Some(a) if a.0 != gpu.allocations || a.1.abs_diff(gpu.allocated_bytes) > GPU_SLACK_BYTES => fail(format!(
                "GPU allocations {} ({} bytes), {} ({} bytes) at this setting's first visit after warm-up",
                gpu.allocations, gpu.allocated_bytes, a.0, a.1
            )),
            _ => {}
        }
        (rss, gpu)
    }

    /// Resident memory's figures in MiB, and the rise of its floor in bytes. A leak raises the floor: the least
    /// resident memory of the last quarter of the frames after the warm-up against the first quarter's. Single
    /// frames' peaks (the allocator's passing high-water marks) and the medians (which jump when a cycle's peaks
    /// outnumber its troughs) move it neither way.
    fn rss_summary(&self, start: u64, bound_mib: f64) -> (serde_json::Value, f64) {
        let mib = |b: u64| b as f64 / 1048576.0;
        let floor = |q: &[(f64, f64)]| q.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
        let (n, qn) = (self.rss_points.len(), self.rss_points.len() / 4);
        let drift = if qn > 0 { floor(&self.rss_points[n - qn..]) - floor(&self.rss_points[..qn]) } else { f64::NAN };
        let after = |b: u64| if n > 0 { mib(b) } else { f64::NAN };
        let summary = json!({
            "start": mib(start), "warmup_peak": mib(self.rss_base),
            "min_after_warmup": after(self.rss_min), "max_after_warmup": after(self.rss_max),
            "final": mib(rss_bytes()), "bound_mib": bound_mib,
            "slope_mib_per_1000_frames": slope(&self.rss_points) * 1000.0 / 1048576.0,
            "floor_drift_mib": drift / 1048576.0,
        });
        (summary, drift)
    }

    fn samples_json(&self) -> Vec<serde_json::Value> {
        self.samples
            .iter()
            .map(|s| {
                json!({
                    "frame": s.frame, "rss_bytes": s.rss, "heap_bytes": s.heap, "gpu_allocations": s.gpu.allocations,
                    "gpu_allocated_bytes": s.gpu.allocated_bytes, "gpu_block_bytes": s.gpu.capacity_bytes,
                })
            })
            .collect()
    }
}

/// One entry of the settings schedule.
#[derive(Clone, Debug)]
struct Step {
    transport: Transport,
    method: Method,
    metric: Metric,
    level: u32,
    ior: f32,
    size: (u32, u32),
}

impl Step {
    fn name(&self) -> String {
        let t = if self.transport == Transport::Exact { "exact" } else { "two-interface" };
        let m = match (self.method, self.metric) {
            (Method::Dense, _) => "dense",
            (_, Metric::MaxLevel) => "max-level",
            (_, Metric::MaxError) => "max-error",
            (_, Metric::FluxError) => "flux-error",
        };
        format!("{t} {m} L{} ior {} {}x{}", self.level, self.ior, self.size.0, self.size.1)
    }
}

/// The schedule: two-interface at every level and method, exact at levels 0 and 1, three indices of refraction
/// and five output sizes (all at least as wide as tall, so the square floor stays in the frame).
fn schedule(max_level: u32) -> Vec<Step> {
    use Method::*;
    use Metric::*;
    use Transport::*;
    let sizes = [(64, 64), (96, 64), (128, 128), (80, 80), (112, 64)];
    let iors = [1.5, 1.33, 1.7];
    let mut out = Vec::new();
    let mut k = 0;
    let mut push = |transport, method, metric, level| {
        out.push(Step { transport, method, metric, level, ior: iors[k % 3], size: sizes[k % 5] });
        k += 1;
    };
    for level in 0..=max_level {
        push(TwoInterface, Dense, MaxLevel, level);
        push(TwoInterface, Adaptive, MaxLevel, level);
        push(TwoInterface, Adaptive, MaxError, level);
    }
    push(Exact, Dense, MaxLevel, 0);
    push(Exact, Adaptive, MaxError, max_level.min(1));
    out
}

/// Give free heap pages back to the OS (glibc's `malloc_trim`), so that resident memory measures what is
/// allocated rather than how the allocator's arenas happen to be fragmented (lavapipe's device memory comes
/// from the heap, and its worker threads free into several arenas).
fn trim_heap() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        extern "C" {
            fn malloc_trim(pad: usize) -> i32;
        }
        // SAFETY: malloc_trim only returns unused memory to the OS; it is thread-safe.
        unsafe {
            malloc_trim(0);
        }
    }
}

/// Resident set size in bytes (Linux; 0 elsewhere).
pub fn rss_bytes() -> u64 {
    let page = 4096u64;
    std::fs::read_to_string("/proc/self/statm")
        .ok()
        .and_then(|s| s.split_whitespace().nth(1).and_then(|v| v.parse::<u64>().ok()))
        .map_or(0, |pages| pages * page)
}

/// Least-squares slope of y over x.
fn slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    if n < 2.0 {
        return 0.0;
    }
    let (mx, my) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let (sxy, sxx) = points.iter().fold((0.0, 0.0), |(a, b), (x, y)| (a + (x - mx) * (y - my), b + (x - mx).powi(2)));
    if sxx > 0.0 {
        sxy / sxx
    } else {
        0.0
    }
}

fn with_ior(scene: &Scene, ior: f32) -> Scene {
    let mut s = scene.clone();
    for o in &mut s.objects {
        if let Material::Dielectric { ior: i, .. } = &mut o.material {
            *i = ior;
        }
    }
    s
}

pub fn run_soak(args: &SoakArgs) -> Result<()> {
    if args.frames == 0 || args.angles == 0 {
        return Err(Error::BadInput("--frames and --angles must be at least 1".into()));
    }
    if args.max_level > 6 {
        return Err(Error::BadInput(format!("--max-level {}: at most 6", args.max_level)));
    }
    if let Some(p) = &args.json {
        image_io::check_output_dir(p)?;
    }
    let steps = schedule(args.max_level);
    let base = Settings {
        quality: Quality { caustic_res: args.map_res, ..Quality::default() },
        tuning: Tuning { gbuffer_res: args.map_res, ..Tuning::default() },
    };
    let scene_args = SceneArgs {
        scene: args.scene.clone(),
        camera: Some(args.camera.clone()),
        size: Some("64x64".into()),
        ..SceneArgs::default()
    };
    let mut session = Session::open(&scene_args, base.clone(), crate::app::commands::default_scene)?;
    if session.pixel_area().is_none() {
        return Err(Error::BadInput(format!("--camera {}: the soak needs an orthographic camera", args.camera)));
    }
    let scene0 = session.renderer.scene().clone();
    let orbit = LightOrbit::of(&scene0.lights[0]);
    let cone_power = cone_power(&scene0.lights[0]);
    let s_count = steps.len();
    let period = s_count * args.angles as usize;
    let warmup = (2 * period).min(args.frames as usize);
    let mut checks = Checks::new(args, period, Memory::new(args.frames as usize, s_count, warmup));
    let mut ior_now = f32::NAN;
    for i in 0..args.frames as usize {
        let (si, ai) = (i % s_count, (i / s_count) % args.angles as usize);
        let step = &steps[si];
        let angle = std::f32::consts::TAU * ai as f32 / args.angles as f32;
        let mut scene =
            if step.ior != ior_now { with_ior(&scene0, step.ior) } else { session.renderer.scene().clone() };
        ior_now = step.ior;
        scene.lights[0].position = orbit.at(angle);
        session.renderer.set_scene(scene)?;
        session.renderer.set_settings(Settings {
            quality: Quality {
                transport: step.transport,
                method: step.method,
                metric: step.metric,
                level: Some(step.level),
                ..base.quality.clone()
            },
            tuning: base.tuning.clone(),
        })?;
        (session.width, session.height) = step.size;
        if !checks.frame(&mut session, cone_power, i, step, (si, ai), s_count)? {
            break;
        }
    }
    checks.finish(args, &session, &steps, warmup, cone_power)
}

/// The power a light sends into its cone, W: a bound on any frame's caustic flux.
fn cone_power(light: &Light) -> f64 {
    match light.kind {
        LightKind::Spot => light.intensity as f64 * std::f64::consts::TAU * (1.0 - (light.cone as f64).cos()),
        LightKind::Directional => f64::INFINITY,
        LightKind::Point => light.intensity as f64 * 4.0 * std::f64::consts::PI,
    }
}

/// What the soak has checked so far: the first visits' flux, the failures and the worst figures. Sized up front:
/// the soak's own records must not grow the heap it measures.
struct Checks {
    flux_tolerance: f64,
    frames: u32,
    reference: Vec<Option<f64>>,
    failures: Vec<String>,
    worst_flux_dev: f64,
    worst_residual: f64,
    ms_by_transport: [(f64, u32); 2],
    memory: Memory,
    start: Instant,
    rss_start: u64,
}

impl Checks {
    fn new(args: &SoakArgs, period: usize, memory: Memory) -> Self {
        Checks {
            flux_tolerance: args.flux_tolerance,
            frames: args.frames,
            reference: vec![None; period],
            failures: Vec::with_capacity(21),
            worst_flux_dev: 0.0,
            worst_residual: 0.0,
            ms_by_transport: [(0.0, 0); 2],
            memory,
            start: Instant::now(),
            rss_start: rss_bytes(),
        }
    }

    /// Render frame `i` (setting `si` at light position `ai`) and check it. Returns whether the soak goes on (a
    /// validation message ends it).
    fn frame(
        &mut self,
        session: &mut Session,
        cone_power: f64,
        i: usize,
        step: &Step,
        (si, ai): (usize, usize),
        s_count: usize,
    ) -> Result<bool> {
        let t = Instant::now();
        let (report, img) = session.frame(Some(Aov::Caustics))?;
        let wall = t.elapsed().as_secs_f64() * 1e3;
        let slot = &mut self.ms_by_transport[(step.transport == Transport::Exact) as usize];
        *slot = (slot.0 + wall, slot.1 + 1);
        let rgb = img.as_ref().and_then(to_rgb).ok_or_else(|| Error::Failed("no caustics AOV read back".into()))?;
        let area = session.pixel_area().expect("orthographic");
        let flux = rgb.data.iter().map(|p| p[0] as f64).sum::<f64>() * area;
        let failures = &mut self.failures;
        let mut fail = |m: String| {
            if failures.len() < 20 {
                eprintln!("soak: frame {i} ({}, light {ai}): {m}", step.name());
            }
            failures.push(m);
        };
        if !(flux.is_finite() && flux > 0.0 && flux <= cone_power) {
            fail(format!("caustic flux {flux} W outside (0, {cone_power}] W"));
        }
        let key = ai * s_count + si;
        match self.reference[key] {
            None => self.reference[key] = Some(flux),
            Some(r) => {
                let dev = (flux - r).abs() / r.abs().max(1e-12);
                self.worst_flux_dev = self.worst_flux_dev.max(dev);
                if dev > self.flux_tolerance {
                    fail(format!("caustic flux {flux} W against {r} W at its first visit (rel. {dev:.2e})"));
                }
            }
        }
        if let Some(ts) = report.transport {
            let residual = ts.residual();
            self.worst_residual = self.worst_residual.max(residual);
            if residual > 1e-6 {
                fail(format!("exact transport's energy account residual {residual:.2e}"));
            }
        }
        let messages = caustics::gpu::validation_message_count();
        if session.validation && messages > 0 {
            fail(format!("{messages} validation messages"));
            return Ok(false);
        }
        let (rss, gpu) = self.memory.observe(i, si, session.device().allocation_report(), &mut fail);
        if (i + 1).is_multiple_of(100) {
            eprintln!(
                "soak: {}/{} frames, {:.0} s, RSS {:.1} MiB, GPU {} allocations {:.1} MiB, worst flux deviation {:.2e}",
                i + 1,
                self.frames,
                self.start.elapsed().as_secs_f64(),
                rss as f64 / 1048576.0,
                gpu.allocations,
                gpu.allocated_bytes as f64 / 1048576.0,
                self.worst_flux_dev
            );
        }
        Ok(true)
    }

    /// The resident memory's verdict, the summary (printed, and written to `--json`), and the soak's result.
    fn finish(
        mut self,
        args: &SoakArgs,
        session: &Session,
        steps: &[Step],
        warmup: usize,
        cone_power: f64,
    ) -> Result<()> {
        let mib = |b: u64| b as f64 / 1048576.0;
        let (rss_json, drift) = self.memory.rss_summary(self.rss_start, args.rss_bound_mib);
        if drift > args.rss_bound_mib * 1048576.0 {
            self.failures.push(format!(
                "resident memory's floor rose {:.1} MiB after the warm-up (least of the last quarter of the frames \
                 against the first's), over the bound of {} MiB",
                drift / 1048576.0,
                args.rss_bound_mib
            ));
        }
        let ms = |k: usize| self.ms_by_transport[k].0 / self.ms_by_transport[k].1.max(1) as f64;
        let memory = &self.memory;
        let summary = json!({
            "device": session.device().info.name,
            "validation": {"enabled": session.validation, "messages": caustics::gpu::validation_message_count()},
            "scene": session.scene_path.display().to_string(),
            "frames": args.frames,
            "period_frames": self.reference.len(),
            "warmup_frames": warmup,
            "schedule": steps.iter().map(Step::name).collect::<Vec<_>>(),
            "light_positions": args.angles,
            "wall_s": self.start.elapsed().as_secs_f64(),
            "mean_frame_ms": {"two_interface": ms(0), "exact": ms(1)},
            "rss_mib": rss_json,
            "heap": {"slack_bytes": HEAP_SLACK_BYTES, "worst_change_bytes": memory.worst_heap_change},
            "gpu": {
                "warmup_block_peak_mib": mib(memory.warm_capacity),
                "allocations_per_setting": memory.gpu_alloc.iter().map(|a| a.map(|(n, b)| json!({"count": n, "mib": mib(b)}))).collect::<Vec<_>>(),
            },
            "flux": {"tolerance": args.flux_tolerance, "worst_relative_deviation": self.worst_flux_dev, "cone_power_w": cone_power},
            "exact_worst_residual": self.worst_residual,
            "failures": self.failures.len(),
            "first_failures": self.failures.iter().take(20).collect::<Vec<_>>(),
            "samples": memory.samples_json(),
        });
        if let Some(p) = &args.json {
            image_io::write_text(p, &serde_json::to_string_pretty(&summary).unwrap_or_default())?;
        }
        let f = |k: &str| rss_json[k].as_f64().unwrap_or(f64::NAN);
        eprintln!(
            "soak: {} frames in {:.0} s; RSS peak {:.1} MiB in the warm-up, {:.1}..{:.1} MiB after ({:+.2} MiB per 1000 frames); \
             floor drift {:+.1} MiB; heap change at most {} bytes; worst flux deviation {:.2e}; exact residual {:.1e}; {} failures",
            args.frames,
            self.start.elapsed().as_secs_f64(),
            f("warmup_peak"),
            f("min_after_warmup"),
            f("max_after_warmup"),
            f("slope_mib_per_1000_frames"),
            drift / 1048576.0,
            memory.worst_heap_change,
            self.worst_flux_dev,
            self.worst_residual,
            self.failures.len()
        );
        if !self.failures.is_empty() {
            return Err(Error::Failed(format!(
                "soak: {} failed checks (first: {})",
                self.failures.len(),
                self.failures[0]
            )));
        }
        crate::app::commands::validation_verdict(session)
    }
}
