//! `caustics temporal`: stability over time. The light steps along an orbit about the vertical axis through its
//! target (tilted 25° first when it stands straight above it) for K frames; each frame's caustics AOV E_t is
//! compared with the CPU reference R_t at the same light position (src/reference, cached on disk), for each
//! method. Reported per method, on 64² box-filtered images:
//!
//! - error: mean over t of rel-L1(E_t, R_t) = Σ|E_t − R_t| / Σ R_t;
//! - flicker: mean over t ≥ 1 of Σ|(E_t − E_{t−1}) − (R_t − R_{t−1})| / Σ R_t, the frame-to-frame change that
//!   the reference does not make (a method whose error is the same every frame has no flicker, however large
//!   its error);
//! - the reference's own frame-to-frame change Σ|R_t − R_{t−1}| / Σ R_t, for scale.
//!
//! The references use one seed, so their Monte Carlo noise is the same pattern at every light position and
//! mostly cancels in R_t − R_{t−1}; what remains sets the floor of the flicker column (compare the reference
//! change at half the photons to see it).

use crate::app::commands::{to_rgb, SceneArgs, Session};
use crate::app::LightOrbit;
use caustics::error::{Error, Result};
use caustics::image_io::{self, RgbImage};
use caustics::metrics;
use caustics::reference::{self, Paths, RefParams};
use caustics::scene::{Projection, Scene};
use caustics::settings::{Method, Metric, Quality, Settings, Transport, Tuning};
use caustics::Aov;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args, Debug, Clone)]
pub struct TemporalArgs {
    /// Scene (default: the sphere scene).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Orthographic camera the AOV and the references are binned into.
    #[arg(long, default_value = "top")]
    pub camera: String,
    /// AOV and reference size (compared at 64²).
    #[arg(long, default_value = "128x128")]
    pub size: String,
    /// Frames (light positions) K.
    #[arg(long, default_value_t = 16)]
    pub frames: u32,
    /// Orbit step between frames, degrees.
    #[arg(long, default_value_t = 1.0)]
    pub step_deg: f32,
    /// Play the scene's animation instead (its water, its keyframes): frame k at time k / FPS s, the light still.
    #[arg(long)]
    pub fps: Option<f32>,
    /// Light transport.
    #[arg(long, value_enum, default_value_t = Transport::TwoInterface)]
    pub transport: Transport,
    /// Exact transport: where the splat radius comes from (cell or differential).
    #[arg(long, value_enum, default_value_t = Tuning::default().footprint)]
    pub footprint: caustics::settings::Footprint,
    /// Methods: dense, max-level, max-error, flux-error (comma-separated).
    #[arg(long, default_value = "dense,max-level,max-error", value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Photon level (dense) or maximal traversal level (adaptive).
    #[arg(long, default_value_t = 3)]
    pub level: u32,
    /// Reference paths: two-refractions (what the two-interface model computes) or all.
    #[arg(long, default_value = "two-refractions")]
    pub paths: String,
    /// Reference photons per light position.
    #[arg(long, default_value_t = 4_000_000)]
    pub reference_photons: u64,
    /// Caustic map and refractor g-buffer side.
    #[arg(long, default_value_t = 1024)]
    pub map_res: u32,
    #[arg(long)]
    pub json: Option<PathBuf>,
    #[arg(long)]
    pub markdown: Option<PathBuf>,
}

/// 64² luminance plane of an image.
fn plane64(img: &RgbImage) -> Vec<f64> {
    let (ow, oh) = metrics::comparison_size(64, img.width, img.height);
    metrics::box_filter(&metrics::luminance_plane(img), img.width as usize, img.height as usize, ow, oh)
}

/// The scene with its first light `deg` along its orbit.
fn orbit(scene: &Scene, orbit: &LightOrbit, deg: f32) -> Scene {
    let mut s = scene.clone();
    s.lights[0].position = orbit.at(deg.to_radians());
    s
}

/// The reference at one light position, cached next to the bench's references (the key adds the light's
/// position to the scene file's).
fn reference_at(scene_path: &std::path::Path, scene: &Scene, p: &RefParams) -> Result<RgbImage> {
    let key = reference::cache_key(scene_path, p)?;
    let pos = scene.lights[0].position.to_array().map(f32::to_bits);
    let dir = reference::cache_dir_from_env();
    let file = dir.join(format!("{key}-light-{:08x}{:08x}{:08x}.exr", pos[0], pos[1], pos[2]));
    if let Ok(img) = image_io::read_exr(&file) {
        if img.width == p.width && img.height == p.height {
            return Ok(img);
        }
    }
    let out = reference::trace(scene, p)?;
    std::fs::create_dir_all(&dir).map_err(|e| Error::Io(format!("{}: cannot create: {e}", dir.display())))?;
    image_io::write_exr(&file, &out.image)?;
    Ok(out.image)
}

pub fn run_temporal(args: &TemporalArgs) -> Result<()> {
    if args.frames < 2 {
        return Err(Error::BadInput("--frames: at least 2".into()));
    }
    if let Some(fps) = args.fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
        return Err(Error::BadInput(format!("--fps {fps}: must be > 0")));
    }
    // Frame k: the light turned by k steps, or the scene at time k / fps.
    let time = |k: u32| args.fps.map_or(0.0, |f| k as f32 / f);
    let step = if args.fps.is_some() { 0.0 } else { args.step_deg };
    for p in [&args.json, &args.markdown].into_iter().flatten() {
        image_io::check_output_dir(p)?;
    }
    let (paths, methods) = paths_and_methods(args)?;
    let base = Settings {
        quality: Quality {
            transport: args.transport,
            level: Some(args.level),
            caustic_res: args.map_res,
            ..Quality::default()
        },
        tuning: Tuning { footprint: args.footprint, gbuffer_res: args.map_res, ..Tuning::default() },
    };
    let scene_args = SceneArgs {
        scene: args.scene.clone(),
        camera: Some(args.camera.clone()),
        size: Some(args.size.clone()),
        ..SceneArgs::default()
    };
    let mut session = Session::open(&scene_args, base.clone(), crate::app::commands::default_scene)?;
    let half_height = match session.camera.projection {
        Projection::Orthographic { half_height } => half_height,
        Projection::Perspective { .. } => {
            return Err(Error::BadInput(format!("--camera {}: must be orthographic", args.camera)))
        }
    };
    let scene0 = session.renderer.scene().clone();
    let light_orbit = LightOrbit::of(&scene0.lights[0]);
    let params = RefParams {
        camera: Some(args.camera.clone()),
        paths,
        photons: args.reference_photons,
        width: session.width,
        height: session.height,
        ..RefParams::default()
    };
    let t = Instant::now();
    let mut refs = Vec::new();
    for k in 0..args.frames {
        let scene = orbit(&scene0, &light_orbit, k as f32 * step);
        let params = RefParams { time: time(k), ..params.clone() };
        refs.push(plane64(&reference_at(&session.scene_path, &scene, &params)?));
    }
    eprintln!("temporal: {} references ready in {:.1} s", refs.len(), t.elapsed().as_secs_f64());
    let ref_change: f64 =
        (1..refs.len()).map(|t| l1(&refs[t], &refs[t - 1]) / sum(&refs[t])).sum::<f64>() / (refs.len() - 1) as f64;
    let mut rows = Vec::new();
    for (name, method, metric) in &methods {
        session.renderer.set_settings(Settings {
            quality: Quality { method: *method, metric: *metric, ..base.quality.clone() },
            tuning: base.tuning.clone(),
        })?;
        let mut planes = Vec::new();
        let mut ms = Vec::new();
        for k in 0..args.frames {
            session.renderer.set_scene(orbit(&scene0, &light_orbit, k as f32 * step))?;
            session.renderer.set_time(time(k))?;
            if k == 0 {
                session.frame(None)?; // warm-up: lavapipe compiles shaders on first use
            }
            let (report, img) = session.frame(Some(Aov::Caustics))?;
            ms.push(report.gpu_ms);
            let rgb = img.as_ref().and_then(to_rgb).ok_or_else(|| Error::Failed("no caustics AOV".into()))?;
            planes.push(plane64(&rgb));
        }
        rows.push(method_row(name, args.level, &planes, &refs, &ms, ref_change));
    }
    crate::app::commands::validation_verdict(&session)?;
    write_outputs(args, &session, (step, half_height), ref_change, &rows)
}

/// `--paths` and `--methods` (each method's name, method and metric).
#[allow(clippy::type_complexity)]
fn paths_and_methods(args: &TemporalArgs) -> Result<(Paths, Vec<(String, Method, Metric)>)> {
    let paths = match args.paths.as_str() {
        "two-refractions" => Paths::TwoRefractions,
        "all" => Paths::All,
        p => return Err(Error::BadInput(format!("--paths `{p}`: expected two-refractions or all"))),
    };
    let methods: Vec<(String, Method, Metric)> = args
        .methods
        .iter()
        .map(|m| match m.as_str() {
            "dense" => Ok((m.clone(), Method::Dense, Metric::MaxLevel)),
            "max-level" => Ok((m.clone(), Method::Adaptive, Metric::MaxLevel)),
            "max-error" => Ok((m.clone(), Method::Adaptive, Metric::MaxError)),
            "flux-error" => Ok((m.clone(), Method::Adaptive, Metric::FluxError)),
            _ => Err(Error::BadInput(format!("--methods `{m}`: expected dense, max-level, max-error or flux-error"))),
        })
        .collect::<Result<_>>()?;
    Ok((paths, methods))
}

/// The sum of a plane.
fn sum(p: &[f64]) -> f64 {
    p.iter().sum::<f64>()
}

/// L1 distance of two planes.
fn l1(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum::<f64>()
}

/// One method's row: its frames' `planes` against the references `refs` (mean and max rel-L1, the flicker: the
/// rel-L1 of the frame-to-frame change against the reference's, and the frame-to-frame change), and the mean of
/// its GPU ms.
fn method_row(
    name: &str,
    level: u32,
    planes: &[Vec<f64>],
    refs: &[Vec<f64>],
    ms: &[f64],
    ref_change: f64,
) -> serde_json::Value {
    let n = planes.len();
    let error = (0..n).map(|t| l1(&planes[t], &refs[t]) / sum(&refs[t])).sum::<f64>() / n as f64;
    let max_error = (0..n).map(|t| l1(&planes[t], &refs[t]) / sum(&refs[t])).fold(0.0, f64::max);
    let flicker_t: Vec<f64> = (1..n)
        .map(|t| {
            let num: f64 = (0..refs[t].len())
                .map(|i| ((planes[t][i] - planes[t - 1][i]) - (refs[t][i] - refs[t - 1][i])).abs())
                .sum();
            num / sum(&refs[t])
        })
        .collect();
    let flicker = flicker_t.iter().sum::<f64>() / flicker_t.len() as f64;
    let change = (1..n).map(|t| l1(&planes[t], &planes[t - 1]) / sum(&refs[t])).sum::<f64>() / (n - 1) as f64;
    let gpu_ms = ms.iter().sum::<f64>() / ms.len() as f64;
    eprintln!(
        "temporal: {name} L{}: error {error:.4} (max {max_error:.4}), flicker {flicker:.4} (max {:.4}), change {change:.4}, reference change {ref_change:.4}, {gpu_ms:.1} GPU ms",
        level,
        flicker_t.iter().cloned().fold(0.0, f64::max)
    );
    json!({
        "method": name, "level": level, "mean_rel_l1": error, "max_rel_l1": max_error,
        "flicker": flicker, "max_flicker": flicker_t.iter().cloned().fold(0.0, f64::max),
        "frame_change": change, "gpu_ms_mean": gpu_ms,
    })
}

/// The table on stdout, and the `--markdown` and `--json` files.
fn write_outputs(
    args: &TemporalArgs,
    session: &Session,
    (step, half_height): (f32, f32),
    ref_change: f64,
    rows: &[serde_json::Value],
) -> Result<()> {
    let md = markdown(args, session, ref_change, rows);
    print!("{md}");
    if let Some(p) = &args.markdown {
        image_io::write_text(p, &md)?;
    }
    if let Some(p) = &args.json {
        let doc = json!({
            "device": session.device().info.name, "scene": session.scene_path.display().to_string(),
            "frames": args.frames, "step_deg": step, "fps": args.fps, "half_height": half_height,
            "reference_photons": args.reference_photons, "paths": args.paths, "reference_change": ref_change,
            "rows": rows,
        });
        image_io::write_text(p, &serde_json::to_string_pretty(&doc).unwrap_or_default())?;
    }
    Ok(())
}

/// The results as a markdown table, with a line naming what was run.
fn markdown(args: &TemporalArgs, session: &Session, ref_change: f64, rows: &[serde_json::Value]) -> String {
    let mut md = format!(
        "{} on {}, {} transport, {} frames, {}, 64² against the {} reference ({} photons); \
         the reference's own frame-to-frame change is {:.4}\n\n\
         | method | level | GPU ms | mean rel-L1 | max rel-L1 | flicker | max flicker | frame change |\n|---|--:|--:|--:|--:|--:|--:|--:|\n",
        session.scene_path.display(),
        session.device().info.name,
        if args.transport == Transport::Exact { "exact" } else { "two-interface" },
        args.frames,
        args.fps.map_or(format!("light orbit step {}°", args.step_deg), |f| format!("the scene's time at {f} fps")),
        args.paths,
        args.reference_photons,
        ref_change
    );
    for r in rows {
        md += &format!(
            "| {} | {} | {:.1} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |\n",
            r["method"].as_str().unwrap_or(""),
            r["level"],
            r["gpu_ms_mean"].as_f64().unwrap_or(f64::NAN),
            r["mean_rel_l1"].as_f64().unwrap_or(f64::NAN),
            r["max_rel_l1"].as_f64().unwrap_or(f64::NAN),
            r["flicker"].as_f64().unwrap_or(f64::NAN),
            r["max_flicker"].as_f64().unwrap_or(f64::NAN),
            r["frame_change"].as_f64().unwrap_or(f64::NAN),
        );
    }
    md
}
