//! The `render` and `profile` commands (the CLI edge: arguments in, files and stats out).

use crate::app::flags::camera_error;
use crate::app::profiler;
use caustics::consts::*;
use caustics::error::{Error, Result};
use caustics::gpu::{Context, ContextDesc};
use caustics::image_io::{self, RgbImage};
use caustics::scene::{Camera, Projection, Scene};
use caustics::settings::BvhLayout;
use caustics::settings::{
    parse_size, CoopChecks, Driven, Footprint, Method, Metric, OnOff, Quality, Refine, ResolvedSettings, Settings,
    Splat, Transport, Tuning, DEFAULT_TARGET_ERROR,
};
use caustics::{Aov, AovData, Frame, FrameDesc, FrameReport, Renderer};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The default scene shipped in assets/scenes/.
mod profile;
mod render;
mod stats;

pub use profile::run_profile;
pub use render::run_render;
use stats::*;

pub fn default_scene() -> PathBuf {
    shipped_scene("sphere.toml")
}

/// The scene `render` and `view` open when given none: the pool in the sun, a picture worth keeping. The
/// measuring commands (`profile`, `reference`, `bench`) open [`default_scene`], the glass ball the results use.
pub fn first_picture_scene() -> PathBuf {
    shipped_scene("swimming_pool.toml")
}

/// assets/scenes/`name`, from the working directory when it holds it, else from the source tree.
fn shipped_scene(name: &str) -> PathBuf {
    let here = PathBuf::from("assets/scenes").join(name);
    if here.is_file() {
        return here;
    }
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/scenes").join(name)
}

#[derive(clap::Args, Debug, Clone)]
pub struct SceneArgs {
    /// Scene file: TOML (.toml) or glTF 2.0 (.gltf, .glb). Default: assets/scenes/swimming_pool.toml for render,
    /// assets/scenes/sphere.toml for profile.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Camera name (default: the scene's first camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Output size WxH [default: 512 high, as wide as the camera's authored aspect ratio (glTF); else 512x512].
    #[arg(long)]
    pub size: Option<String>,
    /// Scene time in seconds: animated objects, cameras and lights stand where their keyframes place them then.
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// The time as the authoring tool's frame N: N / --frame-rate seconds (Blender writes its frame N there; glTF
    /// holds seconds, not frames) [not with --time].
    #[arg(long, conflicts_with = "time", allow_negative_numbers = true)]
    pub frame: Option<f32>,
    /// The frame rate --frame counts in, frames per second (glTF does not record it).
    #[arg(long, default_value_t = 24.0)]
    pub frame_rate: f32,
    /// glTF: the animation that plays, by name or index [default: all of them, together].
    #[arg(long)]
    pub animation: Option<String>,
    /// An equirectangular environment map (.hdr or .exr, 2:1) in place of the scene's: what the glass reflects
    /// and refracts, and light on the receivers (its texel values in W/(m²·sr), scaled by --sky).
    #[arg(long)]
    pub environment: Option<PathBuf>,
}

impl Default for SceneArgs {
    /// The default scene (each command's own), its first camera and size, at time 0.
    fn default() -> Self {
        SceneArgs {
            scene: None,
            camera: None,
            size: None,
            time: 0.0,
            frame: None,
            frame_rate: 24.0,
            animation: None,
            environment: None,
        }
    }
}

impl SceneArgs {
    /// The scene time in seconds: `--time`, or `--frame` at `--frame-rate`.
    pub fn seconds(&self) -> Result<f32> {
        seconds(self.time, self.frame, self.frame_rate)
    }
}

/// `--time T`, or `--frame N` at `--frame-rate F` (N / F seconds), checked.
pub fn seconds(time: f32, frame: Option<f32>, frame_rate: f32) -> Result<f32> {
    if !(frame_rate.is_finite() && frame_rate > 0.0) {
        return Err(Error::BadInput(format!(
            "--frame-rate {frame_rate}: must be a positive number of frames per second"
        )));
    }
    let t = match frame {
        Some(n) if !n.is_finite() => return Err(Error::BadInput(format!("--frame {n}: must be finite"))),
        Some(n) => n / frame_rate,
        None => time,
    };
    if !t.is_finite() {
        return Err(Error::BadInput(format!("--time {t}: must be finite")));
    }
    Ok(t)
}

/// How `--animation` asks a scene to load: all of a glTF file's animations by default.
pub fn load_options(animation: Option<&str>) -> caustics::scene::LoadOptions {
    caustics::scene::LoadOptions { animation: animation.map_or(Default::default(), |a| a.parse().unwrap_or_default()) }
}

/// `--environment PATH` on a loaded scene: the map replaces the scene's own (intensity 1; `--sky` scales it).
pub fn apply_environment(scene: &mut Scene, path: Option<&std::path::Path>) -> Result<()> {
    if let Some(p) = path {
        let map =
            caustics::scene::EnvironmentMap::load(p).map_err(|e| Error::BadInput(format!("--environment: {e}")))?;
        scene.environment = Some(caustics::scene::Environment { map: std::sync::Arc::new(map), intensity: 1.0 });
    }
    Ok(())
}

/// The quality options of `render`, `profile` and `view`: what is rendered and how finely.
#[derive(clap::Args, Debug, Clone, serde::Serialize)]
pub struct QualityArgs {
    /// Light transport through the glass: exact (every path, traced through a BVH in waves) or the papers'
    /// two-interface image-space model (light refracted exactly twice).
    #[arg(long, value_enum, default_value_t = Quality::default().transport)]
    pub transport: Transport,
    /// Photon source: dense grid, or adaptive traversal of the photon quadtree.
    #[arg(long, value_enum, default_value_t = Quality::default().method)]
    pub method: Method,
    /// Adaptive stopping metric [default: flux-error, the fastest to each error in the bench's sweeps]
    /// (adaptive only; dense warns that it ignores it).
    #[arg(long, value_enum)]
    pub metric: Option<Metric>,
    /// What the flux-error metric measures its error in: the light's caustic map (photons where the caustic needs
    /// them) or the camera's image (photons where the camera sees the caustic, as finely as its pixels need; a new
    /// camera then traces afresh) (--metric flux-error only; others warn that they ignore it).
    #[arg(long, value_enum, default_value_t = Quality::default().refine)]
    pub refine: Refine,
    /// Photon grid level: 64·2^N cells per side (dense), or the maximal traversal level (adaptive) [default: 5 on a
    /// GPU, 4 on a CPU device].
    #[arg(long, allow_negative_numbers = true, value_parser = level_arg)]
    pub level: Option<u32>,
    /// Flux-error metric: the target error, the relative L1 at 64² that merging cells may add to max-level's
    /// image at the same level, in (0, 1]; mapped to the metric's per-cell threshold by a measured table
    /// (docs/design.md) [default: 0.001] (--metric flux-error only; other metrics warn that they ignore it).
    #[arg(long, allow_negative_numbers = true)]
    pub target_error: Option<f32>,
    /// Side of the caustic map (and of the shadow map).
    #[arg(long, default_value_t = Quality::default().caustic_res)]
    pub caustic_res: u32,
    /// Beauty anti-aliasing: N×N supersamples per pixel (1..=4; the caustics and direct AOVs are always point
    /// samples at the pixel centers).
    #[arg(long, default_value_t = Quality::default().aa, allow_negative_numbers = true)]
    pub aa: u32,
    /// Beauty exposure in stops (EV), added to the automatic exposure before the ACES tone map.
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,
    /// Sky radiance of the environment in W/(m²·sr) (0: off) [default: 25% of the reference radiance]. It
    /// lights the receivers and is seen through and in the glass; the caustics and direct AOVs never include it.
    #[arg(long, allow_negative_numbers = true)]
    pub sky: Option<f32>,
    /// Exact transport: interfaces an eye ray is followed through (reflection and refraction) before it takes
    /// the environment's radiance.
    #[arg(long, default_value_t = Quality::default().eye_depth, allow_negative_numbers = true)]
    pub eye_depth: u32,
    /// Photon buffer size in MiB (batches are split to fit); 0: automatic (64 MiB on CPU devices; on GPUs 1/64 of
    /// device memory, 64 to 512 MiB, within what one storage-buffer binding allows)
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub photon_budget: f64,
}

/// The tuning knobs (`--help` lists them under "Tuning"): each default is the measured best for the device, so a
/// user needs none of them; they exist to measure the alternatives.
#[derive(clap::Args, Debug, Clone, serde::Serialize)]
pub struct TuningArgs {
    /// How splat records reach the caustic flux map: points drawn indirectly (raster), a compute pass with
    /// float atomics (compute), that pass gathering a work group's taps in shared memory first (tiled), or the
    /// faster for the device (auto).
    #[arg(long, value_enum, default_value_t = Tuning::default().splat, help_heading = "Tuning")]
    pub splat: Splat,
    /// Exact transport: splat radius from the photon's cell (cell) or, per map axis, from where the cell lands,
    /// by ray differentials (differential).
    #[arg(long, value_enum, default_value_t = Tuning::default().footprint, help_heading = "Tuning")]
    pub footprint: Footprint,
    /// Exact transport: cut a Fresnel branch below this fraction of its photon's flux (the cut flux is accounted).
    #[arg(long, default_value_t = Tuning::default().flux_threshold, allow_negative_numbers = true, help_heading = "Tuning")]
    pub flux_threshold: f32,
    /// Exact transport: a Fresnel branch below this fraction of its photon's flux is traced once per block of
    /// the finest level's cells (`--weak-block`; by one of the block's photons, carrying the block's share, with a
    /// splat as wide as the block) instead of by each photon; the flux moved is accounted (0: off).
    #[arg(long, default_value_t = Tuning::default().weak_branches, allow_negative_numbers = true, help_heading = "Tuning")]
    pub weak_branches: f32,
    /// Exact transport: the side of a weak-branch block in cells of the finest level, 2 or 4; 0: automatic (4).
    /// Photons as large as the block or larger trace their own weak branches.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, help_heading = "Tuning")]
    pub weak_block: u32,
    /// Exact transport: BVH node layout (pair: both children's boxes in the parent; single: one box per node;
    /// threaded: stackless; wide: compressed 8-wide nodes; auto: single on GPUs, wide on CPU devices, the faster on
    /// each).
    #[arg(long, value_enum, default_value_t = BvhLayout::Auto, help_heading = "Tuning")]
    pub bvh_layout: BvhLayout,
    /// Side of the light-view refractor g-buffers (power of two).
    #[arg(long, default_value_t = Tuning::default().gbuffer_res, help_heading = "Tuning")]
    pub gbuffer_res: u32,
    /// Max-error metric: convergence bound in caustic-map texels.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true, help_heading = "Tuning")]
    pub error_bound: f32,
    /// Testing and calibration: the flux-error metric's per-cell threshold tau itself, instead of the one
    /// --target-error maps to.
    #[arg(long, hide = true, allow_negative_numbers = true)]
    pub tau: Option<f32>,
    /// Max-error and flux-error metrics: first level checked for convergence [default: 3; flux-error: 3, at most
    /// --level - 1]. Flux-error's look-ahead starts one level above it: a cell there may emit its four children at
    /// once, never itself.
    #[arg(long, allow_negative_numbers = true, value_parser = level_arg, help_heading = "Tuning")]
    pub check_level: Option<u32>,
    /// Exact transport, max-error and flux-error at --traverse-wg 8: trace each cell's four checks in four
    /// invocations at once (on) or in one, one after another (off); auto: on for GPUs, off for CPU devices.
    #[arg(long, value_enum, default_value_t = CoopChecks::Auto, help_heading = "Tuning")]
    pub coop_checks: CoopChecks,
    /// Exact transport with a compute splat: deposit the light that lands where the light's caustic map cannot
    /// hold it (a ceiling, a wall behind the light, a floor under an overhang) in the eye's image, where the
    /// camera sees it (on), or count it as unseen (off).
    #[arg(long, value_enum, default_value_t = OnOff::On, help_heading = "Tuning")]
    pub eye_deposit: OnOff,
    /// Batch slots recorded per frame for GPU-driven batching (0: automatic, adapted between frames).
    #[arg(long, default_value_t = 0, help_heading = "Tuning")]
    pub batch_slots: u32,
    /// Testing: do not split batches on overflow (overflowing work is dropped and counted).
    #[arg(long, hide = true)]
    pub no_batching: bool,
    /// Testing: dump up to N splatted photons into the stats JSON.
    #[arg(long, hide = true, default_value_t = 0)]
    pub debug_photons: u32,
    /// Testing: dump only photons of this level or deeper.
    #[arg(long, hide = true, default_value_t = 0)]
    pub debug_min_level: u32,
}

/// Adaptive traversal's single-valued tuning (the bench sweeps both as lists instead).
#[derive(clap::Args, Debug, Clone, serde::Serialize)]
pub struct TraversalArgs {
    /// Who writes the traversal's dispatch arguments: the GPU (indirect) or the host (readback per level)
    /// [default: gpu] (adaptive only; dense warns that it ignores it).
    #[arg(long, value_enum, help_heading = "Tuning")]
    pub driven: Option<Driven>,
    /// Traversal work-group side (1, 2, 4, 8 or 16).
    #[arg(long, default_value_t = TRAVERSE_WG, help_heading = "Tuning")]
    pub traverse_wg: u32,
}

/// Every option that shapes a frame: the quality, then the tuning.
#[derive(clap::Args, Debug, Clone)]
pub struct MethodArgs {
    #[command(flatten)]
    pub quality: QualityArgs,
    #[command(flatten)]
    pub traversal: TraversalArgs,
    #[command(flatten)]
    pub tuning: TuningArgs,
}

impl TuningArgs {
    /// The tuning these flags give (driven and the work group from `traversal`, or the bench's row).
    pub fn tuning(&self, driven: Driven, traverse_wg: u32) -> Tuning {
        Tuning {
            splat: self.splat,
            footprint: self.footprint,
            flux_threshold: self.flux_threshold,
            weak_branches: self.weak_branches,
            weak_block: self.weak_block,
            bvh_layout: self.bvh_layout,
            driven,
            gbuffer_res: self.gbuffer_res,
            error_bound: self.error_bound,
            tau: self.tau,
            check_level: self.check_level,
            traverse_wg,
            coop_checks: self.coop_checks,
            eye_deposit: self.eye_deposit == OnOff::On,
            batching: !self.no_batching,
            batch_slots: self.batch_slots,
            debug_photons: self.debug_photons,
            debug_min_level: self.debug_min_level,
            ..Tuning::default()
        }
    }
}

impl QualityArgs {
    pub fn quality(&self) -> Quality {
        Quality {
            transport: self.transport,
            method: self.method,
            metric: self.metric.unwrap_or(Quality::default().metric),
            refine: self.refine,
            level: self.level,
            target_error: self.target_error.unwrap_or(DEFAULT_TARGET_ERROR),
            caustic_res: self.caustic_res,
            aa: self.aa,
            exposure_ev: self.exposure,
            sky: self.sky,
            eye_depth: self.eye_depth,
            photon_budget_mib: self.photon_budget,
        }
    }
}

/// A level flag (`--level`, `--check-level`): an integer in 0..MAX_LEVELS, with a range message for anything else
/// (negative numbers included).
pub fn level_arg(s: &str) -> Result<u32, String> {
    let range = format!("must be an integer in 0..={}", MAX_LEVELS - 1);
    match s.trim().parse::<i64>() {
        Ok(v) if (0..MAX_LEVELS as i64).contains(&v) => Ok(v as u32),
        Ok(v) => Err(format!("{v}: {range}")),
        Err(_) => Err(format!("`{s}`: {range}")),
    }
}

impl MethodArgs {
    /// The settings these flags give, validated, with a warning for each flag the method ignores.
    pub fn settings(&self) -> Result<Settings> {
        let (q, t) = (&self.quality, &self.traversal);
        let s = Settings {
            quality: q.quality(),
            tuning: self.tuning.tuning(t.driven.unwrap_or(Driven::Gpu), t.traverse_wg),
        };
        s.validate()?;
        let (method, metric) = (s.quality.method, s.quality.metric);
        if method == Method::Dense {
            for (flag, given) in [("--metric", q.metric.is_some()), ("--driven", t.driven.is_some())] {
                if given {
                    log::warn!("{flag} applies to --method adaptive only; --method dense ignores it");
                }
            }
        }
        let refine_given = q.refine != Quality::default().refine;
        for (flag, given) in [
            ("--target-error", q.target_error.is_some()),
            ("--tau", self.tuning.tau.is_some()),
            ("--refine", refine_given),
        ] {
            if given && (method == Method::Dense || metric != Metric::FluxError) {
                log::warn!("{flag} applies to --method adaptive --metric flux-error only; ignored");
            }
        }
        if q.target_error.is_some() && self.tuning.tau.is_some() {
            log::warn!("--tau overrides the threshold --target-error maps to");
        }
        if let (Method::Dense, Some(level)) = (method, q.level) {
            if level > 12 {
                return Err(Error::BadInput(format!(
                    "--level {level}: dense goes up to level 12 (262,144² photons); use --method adaptive for deeper \
                     levels"
                )));
            }
        }
        Ok(s)
    }
}

#[derive(clap::Args, Debug, Clone)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Output: beauty (the tone-mapped image as .png, or its linear radiance in W/(m²·sr) as .exr), caustics or
    /// direct (irradiance in W/m², .exr).
    #[arg(long, default_value = "beauty")]
    pub aov: String,
    /// Output file: .png or .exr for beauty, .exr for caustics and direct.
    #[arg(long)]
    pub out: PathBuf,
    /// Write stats JSON here.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Frames to render (stats cover all of them; the image is the last).
    #[arg(long, default_value_t = 1)]
    pub frames: u32,
    /// Recompute every stage of every frame (by default a frame whose light, geometry and settings did not change
    /// reuses the last frame's caustic map and runs only the eye and composite passes).
    #[arg(long)]
    pub no_reuse: bool,
    /// Render an animation of N frames, from --time on at --fps frames per second, each written to --out with its
    /// run of `#` replaced by the frame's number (frame_####.png: frame_0000.png, ...).
    #[arg(long, value_name = "N")]
    pub sequence: Option<u32>,
    /// Frames per second of --sequence.
    #[arg(long, default_value_t = 30.0)]
    pub fps: f32,
    /// A converged picture: average N photon sets (each a fresh sampling of every cell: N frames), or as many as S
    /// seconds allow (`30s`). Its error against the exact caustic falls as 1 / sqrt(N). With --sequence, each frame
    /// of the animation is converged so.
    #[arg(long, value_name = "N|Ss", value_parser = parse_accumulate, allow_hyphen_values = true)]
    pub accumulate: Option<Accumulate>,
}

/// `--accumulate`: how many photon sets a still picture averages, or for how long it adds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Accumulate {
    Sets(u32),
    Seconds(f64),
}

/// `N` (at least 1) or `Ss` (seconds, positive).
pub fn parse_accumulate(text: &str) -> std::result::Result<Accumulate, String> {
    let bad = || format!("{text}: give a number of photon sets (64) or seconds (30s)");
    match text.strip_suffix('s') {
        Some(secs) => match secs.parse::<f64>() {
            Ok(t) if t.is_finite() && t > 0.0 => Ok(Accumulate::Seconds(t)),
            _ => Err(bad()),
        },
        None => match text.parse::<u32>() {
            Ok(n) if n >= 1 => Ok(Accumulate::Sets(n)),
            _ => Err(bad()),
        },
    }
}

#[derive(clap::Args, Debug, Clone)]
pub struct ProfileArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Frames to time [default: 20 on a GPU, 3 on a CPU device].
    #[arg(long)]
    pub frames: Option<u32>,
    /// Untimed frames first (the first submit JIT-compiles shaders on lavapipe) [default: 1].
    #[arg(long)]
    pub warmup: Option<u32>,
    /// Print JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Write a Chrome trace (Perfetto, chrome://tracing).
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Write an SVG report: each timed frame's GPU ms as a bar of its stages, and each stage's median.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// A loaded scene with its camera, and a device.
pub struct Session {
    pub scene_path: PathBuf,
    pub camera: Camera,
    pub width: u32,
    pub height: u32,
    pub renderer: Renderer,
    pub validation: bool,
    /// When set (see [`Session::plan`]), [`Session::frame`] prints the elapsed time every few seconds against it.
    pub slow_frame_s: Option<f64>,
    /// The load phase, ms: reading the scene (its meshes parsed and repaired), and the renderer's start (device,
    /// scene buffers, pipelines). The first frame that needs the BVH builds it (`BvhStats::build_ms`).
    pub load_ms: [f64; 2],
}

/// Frames estimated to take longer than this (seconds) get a warning and a progress line.
pub const SLOW_FRAME_S: f64 = 5.0;

/// Frames `profile` times by default: 20 on a GPU, 3 on a CPU device (about a minute at its default level).
pub const PROFILE_FRAMES_GPU: u32 = 20;
/// See [`PROFILE_FRAMES_GPU`].
pub const PROFILE_FRAMES_CPU: u32 = 3;

impl Session {
    /// Opens `args.scene`, or the scene `default` names.
    pub fn open(args: &SceneArgs, settings: Settings, default: fn() -> PathBuf) -> Result<Session> {
        if let Some(s) = &args.size {
            parse_size(s, "--size")?;
        }
        let path = args.scene.clone().unwrap_or_else(default);
        let start = std::time::Instant::now();
        // A spinner on a terminal while a big scene loads.
        let spinner = indicatif::ProgressBar::new_spinner().with_message(format!("loading {}", path.display()));
        spinner.enable_steady_tick(std::time::Duration::from_millis(120));
        let scene = Scene::load_with(&path, &load_options(args.animation.as_deref()));
        spinner.finish_and_clear();
        let mut scene = scene?;
        let scene_ms = start.elapsed().as_secs_f64() * 1e3;
        apply_environment(&mut scene, args.environment.as_deref())?;
        scene.set_time(args.seconds()?);
        let camera = scene.camera(args.camera.as_deref()).map_err(|e| camera_error(args.camera.as_deref(), e))?.clone();
        let (width, height) = caustics::settings::output_size(args.size.as_deref(), "--size", &camera)?;
        let desc = ContextDesc::from_env();
        let ctx = Context::headless(&desc)?;
        let renderer = Renderer::new(ctx.device, scene, settings)?;
        let renderer_ms = start.elapsed().as_secs_f64() * 1e3 - scene_ms;
        Ok(Session {
            scene_path: path,
            camera,
            width,
            height,
            renderer,
            validation: desc.validation,
            slow_frame_s: None,
            load_ms: [scene_ms, renderer_ms],
        })
    }

    pub fn device(&self) -> &Arc<caustics::gpu::Device> {
        self.renderer.device()
    }

    /// One line on what the device chose where the user left the choice to it: the level (and with it the method,
    /// metric and transport the frame runs), and why.
    pub fn announce_defaults(&self) {
        if self.renderer.settings().quality.level.is_some() {
            return;
        }
        let c = self.renderer.config();
        let info = &self.device().info;
        let method = match c.method {
            Method::Dense => "dense".to_string(),
            Method::Adaptive => format!("adaptive {}", c.metric.name()),
        };
        let transport = match c.transport {
            Transport::Exact => "exact",
            Transport::TwoInterface => "two-interface",
        };
        let (class, other) =
            if info.is_cpu() { ("a CPU device", "5 on a GPU") } else { ("a GPU", "4 on a CPU device") };
        eprintln!(
            "{}: level {} ({}² photon grid), {method}, {transport} transport: the default level for {class} ({other}); \
             --level changes it",
            info.name,
            c.level,
            LEVEL0_RES << c.level
        );
    }

    /// A rough upper bound of one frame's time in seconds, from its photon count: every cell of the level's grid
    /// (dense and adaptive max-level emit at most that many) times a per-photon cost measured on lavapipe
    /// (about 0.25 µs per photon for two-interface, 6 µs for exact transport, whose photons
    /// become several rays each), 100× less on a GPU. `None` for max-error and flux-error, whose counts are not
    /// known ahead.
    pub fn estimate_frame_s(&self) -> Option<f64> {
        frame_estimate_s(self.renderer.config(), self.device().info.is_cpu())
    }

    /// Estimate a frame of `aov` on this device (probe frames, `Renderer::estimate`) where it may be slow: on CPU
    /// devices, and wherever the photon count alone says it may take over [`SLOW_FRAME_S`]. A frame estimated
    /// over it gets a line saying so and progress lines while it renders. Returns the estimate, in seconds of
    /// wall time, when one was made.
    pub fn plan(&mut self, aov: Option<Aov>) -> Result<Option<f64>> {
        let cpu = self.device().info.is_cpu();
        if !cpu && !self.estimate_frame_s().is_some_and(|t| t > SLOW_FRAME_S) {
            return Ok(None);
        }
        let view = self.renderer.camera_view(&self.camera, self.width, self.height);
        let e = self.renderer.estimate(&FrameDesc::new(&view, aov))?;
        let est = e.wall_seconds();
        if est > SLOW_FRAME_S {
            let c = self.renderer.config();
            eprintln!(
                "a frame should take about {est:.0} s here (level {}: {:.1} s for the photons and maps, {:.1} s \
                 for the eye view, timed on {:.1} s of smaller frames); a lower --level is faster",
                c.level, e.light_seconds, e.eye_seconds, e.probe_seconds
            );
            self.slow_frame_s = Some(est);
        }
        Ok(Some(est))
    }
    /// Render one frame (a frame whose batch slots run out is finished in further submissions, not rendered
    /// again: see `Renderer::render`).
    pub fn frame(&mut self, aov: Option<Aov>) -> Result<(FrameReport, Option<AovData>)> {
        let view = self.renderer.camera_view(&self.camera, self.width, self.height);
        let Frame { report, image } = match self.slow_frame_s {
            None => self.renderer.render(&FrameDesc::new(&view, aov))?,
            Some(est) => {
                let renderer = &mut self.renderer;
                let frame = with_progress(est, || renderer.render(&FrameDesc::new(&view, aov)))?;
                // The next frame's progress goes by this one's measured time.
                self.slow_frame_s = Some(frame.report.frame_ms * 1e-3);
                frame
            }
        };
        if report.continuations > 0 {
            eprintln!(
                "the photon buffer filled before the frame was done: {} more submission{} traced the tiles left, \
                 keeping the photons already traced (a larger --photon-budget does it in one)",
                report.continuations,
                if report.continuations == 1 { "" } else { "s" }
            );
        }
        if report.unfinished_tiles > 0 {
            log::warn!(
                "{} tiles of the photon quadtree were not traced: the photon budget needs more than {MAX_BATCHES} \
                 batches (raise --photon-budget)",
                report.unfinished_tiles
            );
        }
        Ok((report, image))
    }

    pub fn pixel_area(&self) -> Option<f64> {
        self.camera.pixel_area(self.width, self.height)
    }
}

/// Check `--out`'s extension against the AOV, and return the AOV to read back: beauty written as `.exr` is the
/// linear radiance (`Aov::BeautyHdr`).
fn check_output(aov: Aov, out: &Path) -> Result<Aov> {
    let ext = out.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    let want = if aov == Aov::Beauty { "png" } else { "exr" };
    if aov == Aov::Beauty && ext == "exr" {
        return Ok(Aov::BeautyHdr);
    }
    if ext != want {
        return Err(Error::BadInput(format!(
            "--out {}: the {} AOV is written as .{want}",
            out.display(),
            match aov {
                Aov::Beauty | Aov::BeautyHdr => "beauty",
                Aov::Caustics => "caustics",
                Aov::Direct => "direct",
            }
        )));
    }
    Ok(aov)
}

/// See [`Session::estimate_frame_s`]; `cpu`: the device is a CPU driver (lavapipe).
pub fn frame_estimate_s(s: &ResolvedSettings, cpu: bool) -> Option<f64> {
    if s.method == Method::Adaptive && s.metric != Metric::MaxLevel {
        return None;
    }
    let cells = ((LEVEL0_RES as f64) * (1u64 << s.level) as f64).powi(2);
    let per_photon_us = match s.transport {
        Transport::Exact => 6.0,
        Transport::TwoInterface => 0.25,
    };
    Some(cells * per_photon_us * 1e-6 / if cpu { 1.0 } else { 100.0 })
}

/// Run `work`, printing the elapsed time every 5 s against the estimate `est` seconds (a frame is one submission
/// with no host readback inside it, so the host sees its work only when it is done).
fn with_progress<T>(est: f64, work: impl FnOnce() -> T) -> T {
    let (done, wait) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|scope| {
        scope.spawn(move || {
            let start = std::time::Instant::now();
            while let Err(std::sync::mpsc::RecvTimeoutError::Timeout) =
                wait.recv_timeout(std::time::Duration::from_secs(5))
            {
                eprintln!("rendering: {:.0} s of about {est:.0} s", start.elapsed().as_secs_f64());
            }
        });
        let out = work();
        let _ = done.send(());
        out
    })
}

pub fn to_rgb(data: &AovData) -> Option<RgbImage> {
    match data {
        AovData::Float { width, height, rgba } => {
            Some(RgbImage { width: *width, height: *height, data: rgba.iter().map(|p| [p[0], p[1], p[2]]).collect() })
        }
        AovData::Rgba8 { .. } => None,
    }
}

/// Whether the settings run the flux-error metric (the stats then report its target error and tau).
pub fn flux_error(s: &ResolvedSettings) -> bool {
    s.method == Method::Adaptive && s.metric == Metric::FluxError
}

/// "orthographic" or "perspective".
pub fn camera_kind(c: &Camera) -> &'static str {
    match c.projection {
        Projection::Orthographic { .. } => "orthographic",
        Projection::Perspective { .. } => "perspective",
    }
}

/// Any validation message fails the command (after its outputs are written).
pub fn validation_verdict(session: &Session) -> Result<()> {
    let n = caustics::gpu::validation_message_count();
    if session.validation && n > 0 {
        return Err(Error::Failed(format!("{n} Vulkan validation messages (see above)")));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slow_frames_are_foreseen() {
        let at =
            |method, level, transport| ResolvedSettings { method, level, transport, ..ResolvedSettings::default() };
        let dense8 = frame_estimate_s(&at(Method::Dense, 8, Transport::TwoInterface), true).unwrap();
        assert!(dense8 > SLOW_FRAME_S, "dense level 8 on lavapipe: {dense8} s");
        let dense2 = frame_estimate_s(&at(Method::Dense, 2, Transport::TwoInterface), true).unwrap();
        assert!(dense2 < SLOW_FRAME_S, "{dense2}");
        // The README's default render (exact, level 5) takes about 22 s on lavapipe.
        let exact5 = frame_estimate_s(&at(Method::Dense, 5, Transport::Exact), true).unwrap();
        assert!((10.0..60.0).contains(&exact5), "{exact5}");
        assert!(frame_estimate_s(&at(Method::Dense, 5, Transport::Exact), false).unwrap() < SLOW_FRAME_S);
    }

    #[test]
    fn level_arg_gives_the_range() {
        assert_eq!(level_arg("3"), Ok(3));
        for bad in ["-1", "99", "x"] {
            assert!(level_arg(bad).unwrap_err().contains("must be an integer in 0..="), "{bad}");
        }
    }
}
