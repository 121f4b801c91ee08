//! `caustics bench`: speed against error. For each scene it sweeps the light transports (exact, two-interface)
//! and the methods (dense, adaptive max-level, adaptive max-error) over levels, optionally the driven mode and
//! the traversal work-group size, times K
//! frames of each point (median GPU ms from timestamp queries, median wall ms), and scores the last frame's
//! caustics AOV against CPU references (src/reference, cached on disk) with the project's metric.

use crate::app::bench_report::{self, BenchRow};
use crate::app::commands::{to_rgb, SceneArgs, Session};
use crate::app::profiler::Summary;
use caustics::consts::*;
use caustics::error::{Error, Result};
use caustics::image_io::{self, RgbImage};
use caustics::metrics;
use caustics::reference::{self, Paths, RefParams};
use caustics::settings::{Driven, Method, Metric, Quality, Settings, Transport, Tuning, TRAVERSE_WG_SWEEP};
use caustics::{Aov, FrameReport};
use serde_json::json;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args, Debug, Clone, serde::Serialize)]
pub struct BenchArgs {
    /// Scene files, TOML or glTF 2.0 (repeat the flag for several; default: the sphere scene).
    #[arg(long = "scene")]
    pub scenes: Vec<PathBuf>,
    /// Orthographic camera the AOV and the reference are binned into.
    #[arg(long, default_value = "top")]
    pub camera: String,
    /// AOV size (the finest comparison resolution is 256²).
    #[arg(long, default_value = "256x256")]
    pub size: String,
    /// Light transports through the glass: exact, two-interface (comma-separated); each one sweeps every method
    /// and level.
    #[arg(long, value_enum, default_values = ["exact", "two-interface"], value_delimiter = ',')]
    pub transports: Vec<Transport>,
    /// Methods: dense, max-level, max-error, flux-error (comma-separated).
    #[arg(long, default_value = "dense,max-level,max-error", value_delimiter = ',')]
    pub methods: Vec<String>,
    /// Levels (comma-separated or a range like 2-6): 64·2^level cells per side.
    #[arg(long, default_value = "2-5")]
    pub levels: String,
    /// Driven modes for adaptive: gpu, cpu (comma-separated).
    #[arg(long, default_value = "gpu", value_delimiter = ',')]
    pub driven: Vec<String>,
    /// Traversal work-group sides for adaptive (comma-separated, from 1, 2, 4, 8, 16).
    #[arg(long, default_value = "8", value_delimiter = ',')]
    pub traverse_wg: Vec<u32>,
    /// Timed frames per point (after one untimed warm-up frame).
    #[arg(long, default_value_t = 3)]
    pub frames: u32,
    /// Seconds of untimed rendering before the first point of each scene (clock ramp-up, shader compilation).
    #[arg(long, default_value_t = 2.0)]
    pub warmup_s: f64,
    /// Skip the remaining levels of a method once one frame takes longer than this (seconds).
    #[arg(long, default_value_t = 20.0)]
    pub max_frame_s: f64,
    /// Reference photons per light (default: sized to the sweep, 4 per cell of the finest level's grid, between
    /// 1M and 32M: 1M for levels up to 3, 16.8M at level 5).
    #[arg(long)]
    pub reference_photons: Option<u64>,
    /// Which reference the main error columns use: `all` (every light path: ground truth, what exact transport
    /// renders) or `two-refractions` (light refracted exactly twice: what the two-interface model renders, so its
    /// own error). The other one goes into `extra`; the report names the one its tables use.
    #[arg(long, default_value = "all")]
    pub paths: String,
    /// Skip the references (timings and photon counts only).
    #[arg(long)]
    pub no_reference: bool,
    /// Side of the caustic map (and of the shadow map).
    #[arg(long, default_value_t = 1024)]
    pub caustic_res: u32,
    /// The tuning knobs, as `render` takes them (the bench sweeps --driven and --traverse-wg itself).
    #[command(flatten)]
    #[serde(flatten)]
    pub tuning: crate::app::commands::TuningArgs,
    /// Flux-error metric: the target errors to sweep (comma-separated, each in (0, 1]: the relative L1 at 64²
    /// that merging may add to max-level's image), each mapped to its per-cell threshold tau by the calibration
    /// table; with more than one, the rows' metric reads `flux-error@E`. When max-level runs too, each flux-error
    /// row's `extra` holds `added_rel_l1_64`: its rel-L1 at 64² against max-level's image at the same level.
    #[arg(long, default_values_t = [caustics::settings::DEFAULT_TARGET_ERROR], value_delimiter = ',', allow_negative_numbers = true)]
    pub target_errors: Vec<f32>,
    /// Photon budget (MiB); 0: automatic, as for render.
    #[arg(long, default_value_t = 0.0)]
    pub photon_budget: f64,
    /// Do not run anything: re-render the Markdown and the plot from a JSON file a previous run wrote.
    #[arg(long)]
    pub from_json: Option<PathBuf>,
    /// Write every row (and the arguments) as JSON here.
    #[arg(long)]
    pub json: Option<PathBuf>,
    /// Write the Markdown tables here.
    #[arg(long)]
    pub markdown: Option<PathBuf>,
    /// Write the speed-against-error plot (SVG) here.
    #[arg(long)]
    pub plot: Option<PathBuf>,
}

/// The transport as `--transport` and the bench JSON name it.
fn transport_name(t: Transport) -> &'static str {
    match t {
        Transport::Exact => "exact",
        Transport::TwoInterface => "two-interface",
    }
}

/// Exact transport's wave counts and energy account (in W: the account's units are the light's intensity) for a
/// row's `extra`; null for two-interface.
fn exact_extra(report: &FrameReport, intensity: f64) -> serde_json::Value {
    let Some(ts) = report.transport else {
        return serde_json::Value::Null;
    };
    let energy = ts.energy_json(intensity);
    json!({
        "waves": ts.waves,
        "max_depth": ts.max_depth,
        "splat_records": ts.records_total,
        "queue_overflows": ts.overflows,
        "energy": energy,
    })
}

fn parse_levels(s: &str) -> Result<Vec<u32>> {
    let bad = || Error::BadInput(format!("--levels `{s}`: expected a list like 2,3,4 or a range like 2-6"));
    let mut out = Vec::new();
    for part in s.split(',') {
        if let Some((a, b)) = part.split_once('-') {
            let (a, b): (u32, u32) = (a.trim().parse().map_err(|_| bad())?, b.trim().parse().map_err(|_| bad())?);
            if a > b {
                return Err(bad());
            }
            out.extend(a..=b);
        } else {
            out.push(part.trim().parse().map_err(|_| bad())?);
        }
    }
    if out.is_empty() || out.iter().any(|&l| l >= MAX_LEVELS) {
        return Err(bad());
    }
    Ok(out)
}

/// One configuration to time.
#[derive(Clone, Debug)]
struct Point {
    method: Method,
    metric: Metric,
    driven: Driven,
    wg: u32,
    /// Flux-error's target error (the default for the other metrics).
    target_error: f32,
    /// The row's metric label: `flux-error@E` when several target errors are swept, else the metric's name.
    label: String,
}

impl Point {
    fn key(&self) -> String {
        match self.method {
            Method::Dense => "dense".into(),
            Method::Adaptive => format!(
                "{} {}-driven wg{}",
                self.label,
                if self.driven == Driven::Gpu { "gpu" } else { "cpu" },
                self.wg
            ),
        }
    }
}

fn points(args: &BenchArgs) -> Result<Vec<Point>> {
    let mut out = Vec::new();
    let driven: Vec<Driven> = args
        .driven
        .iter()
        .map(|d| match d.as_str() {
            "gpu" => Ok(Driven::Gpu),
            "cpu" => Ok(Driven::Cpu),
            _ => Err(Error::BadInput(format!("--driven `{d}`: expected gpu or cpu"))),
        })
        .collect::<Result<_>>()?;
    for e in &args.target_errors {
        if !(e.is_finite() && *e > 0.0 && *e <= 1.0) {
            return Err(Error::BadInput(format!(
                "--target-errors {e}: each must lie in (0, 1] (the relative L1 at 64² that merging may add)"
            )));
        }
    }
    for wg in &args.traverse_wg {
        if !TRAVERSE_WG_SWEEP.contains(wg) {
            return Err(Error::BadInput(format!("--traverse-wg {wg}: must be one of 1, 2, 4, 8, 16")));
        }
    }
    for m in &args.methods {
        let metric = match m.as_str() {
            "dense" => {
                out.push(Point {
                    method: Method::Dense,
                    metric: Metric::MaxLevel,
                    driven: Driven::Gpu,
                    wg: TRAVERSE_WG,
                    target_error: caustics::settings::DEFAULT_TARGET_ERROR,
                    label: "dense".into(),
                });
                continue;
            }
            "max-level" => Metric::MaxLevel,
            "max-error" => Metric::MaxError,
            "flux-error" => Metric::FluxError,
            _ => {
                return Err(Error::BadInput(format!(
                    "--methods `{m}`: expected dense, max-level, max-error or flux-error"
                )))
            }
        };
        let targets: Vec<(f32, String)> = if metric == Metric::FluxError {
            let many = args.target_errors.len() > 1;
            args.target_errors
                .iter()
                .map(|&e| (e, if many { format!("flux-error@{e}") } else { metric.name().to_string() }))
                .collect()
        } else {
            vec![(caustics::settings::DEFAULT_TARGET_ERROR, metric.name().to_string())]
        };
        for (target_error, label) in &targets {
            for d in &driven {
                for wg in &args.traverse_wg {
                    out.push(Point {
                        method: Method::Adaptive,
                        metric,
                        driven: *d,
                        wg: *wg,
                        target_error: *target_error,
                        label: label.clone(),
                    });
                }
            }
        }
    }
    Ok(out)
}

struct References {
    main: Option<RgbImage>,
    other: Option<RgbImage>,
    /// The main reference's own noise, rel-L1 at 64² and 256²: half the rel-L1 between its two halves.
    noise: Option<(f64, f64)>,
}

/// Reference photons for a sweep up to `max_level`: `--reference-photons`, else 4 per cell of the finest grid,
/// clamped to 1M..=32M (so that a sweep of small levels does not wait for a 32M-photon reference). That keeps the
/// reference's noise below dense's error up to level 4, not at level 5: on the sphere an 8M-photon reference is
/// 0.51% (rel-L1 64²) from a 256M one, where dense at level 5 is 0.12% (docs/design.md, "Ground truth and error"). The bench
/// measures the noise of the reference it uses and reports it with every row (`reference_noise`).
pub fn reference_photons(explicit: Option<u64>, max_level: u32) -> u64 {
    explicit.unwrap_or_else(|| {
        let cells = ((LEVEL0_RES as u64) << max_level).pow(2);
        (4 * cells).clamp(1_000_000, 32_000_000)
    })
}

/// The bench warns when its reference's noise exceeds this share of a scene's smallest error (rel-L1 64²).
const NOISE_WARN: f64 = 0.3;

fn references(args: &BenchArgs, scene: &Path, width: u32, height: u32, photons: u64) -> Result<References> {
    if args.no_reference {
        return Ok(References { main: None, other: None, noise: None });
    }
    let (main, other) = match args.paths.as_str() {
        "two-refractions" => (Paths::TwoRefractions, Paths::All),
        "all" => (Paths::All, Paths::TwoRefractions),
        p => return Err(Error::BadInput(format!("--paths `{p}`: expected two-refractions or all"))),
    };
    let make = |paths, photons, seed| {
        let p = RefParams {
            camera: Some(args.camera.clone()),
            paths,
            photons,
            width,
            height,
            seed,
            progress: Some(crate::app::reference_cmd::progress_bar()),
            ..RefParams::default()
        };
        let t = Instant::now();
        eprintln!("reference {:?} for {}: {photons} photons, seed {seed} (cached once built)", paths, scene.display());
        let img = reference::cached_in(&reference::cache_dir_from_env(), scene, &p)?;
        eprintln!("reference {:?} for {}: ready in {:.1} s", paths, scene.display(), t.elapsed().as_secs_f64());
        Ok::<_, Error>(img)
    };
    // The main reference is two independent halves, averaged: the rel-L1 between them is about twice the noise of
    // their mean (each half's deviation has sqrt(2) times the mean's, their difference sqrt(2) times a half's).
    let half = photons.div_ceil(2);
    let (a, b) = (make(main, half, 1)?, make(main, half, 2)?);
    let noise_at =
        |res| (metrics::max_comparison_res(&a, &b) >= res).then(|| metrics::compare(&a, &b, res, 2.0).rel_l1 / 2.0);
    let noise = (noise_at(64).unwrap_or(f64::NAN), noise_at(256).unwrap_or(f64::NAN));
    let mut mean = a;
    for (m, q) in mean.data.iter_mut().zip(&b.data) {
        for c in 0..3 {
            m[c] = 0.5 * (m[c] + q[c]);
        }
    }
    eprintln!(
        "reference {:?} for {}: noise rel-L1 64² {}%, 256² {}% (half the difference of its halves)",
        main,
        scene.display(),
        bench_report::num(100.0 * noise.0, 4),
        bench_report::num(100.0 * noise.1, 3)
    );
    Ok(References { main: Some(mean), other: Some(make(other, photons, 1)?), noise: Some(noise) })
}

fn median_of(frames: &[FrameReport], f: impl Fn(&FrameReport) -> f64) -> f64 {
    Summary::of(&frames.iter().map(f).collect::<Vec<_>>()).median
}

fn stage_median(frames: &[FrameReport], prefix: &str) -> f64 {
    // `+ 0.0`: an empty sum is -0.0, and a stage a frame did not run reads better as 0.
    median_of(frames, |f| f.stages.iter().filter(|(l, _)| l.starts_with(prefix)).map(|(_, ms)| ms).sum::<f64>() + 0.0)
}

fn write_reports(args: &BenchArgs, device: &str, rows: &[BenchRow]) -> Result<()> {
    if let Some(p) = &args.markdown {
        image_io::write_text(p, &format!("Device: {device}\n\n{}", bench_report::markdown_report(rows)))?;
    }
    if let Some(p) = &args.plot {
        bench_report::svg_plot(rows, p)?;
    }
    Ok(())
}

pub fn run_bench(args: &BenchArgs) -> Result<()> {
    for p in [&args.json, &args.markdown, &args.plot].into_iter().flatten() {
        image_io::check_output_dir(p)?;
    }
    if let Some(src) = &args.from_json {
        return report_from_json(args, src);
    }
    let levels = parse_levels(&args.levels)?;
    let pts = points(args)?;
    let scenes = if args.scenes.is_empty() { vec![crate::app::commands::default_scene()] } else { args.scenes.clone() };
    let mut rows: Vec<BenchRow> = Vec::new();
    let mut device = String::new();
    for scene_path in &scenes {
        device = bench_scene(args, scene_path, &levels, &pts, &mut rows)?;
    }
    let photons = reference_photons(args.reference_photons, levels.iter().copied().max().unwrap_or(0));
    let doc = json!({"device": device, "args": args, "reference_photons": photons, "rows": rows});
    if let Some(p) = &args.json {
        image_io::write_text(p, &serde_json::to_string_pretty(&doc).unwrap_or_default())?;
    }
    write_reports(args, &device, &rows)?;
    println!("{}", bench_report::markdown_table(&rows));
    Ok(())
}

/// `--from-json`: the reports of an earlier run's JSON, without rendering.
fn report_from_json(args: &BenchArgs, src: &Path) -> Result<()> {
    let text =
        std::fs::read_to_string(src).map_err(|e| Error::BadInput(format!("{}: cannot read: {e}", src.display())))?;
    let doc: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Error::BadInput(format!("{}: not a bench JSON: {e}", src.display())))?;
    let rows: Vec<BenchRow> = serde_json::from_value(doc["rows"].clone())
        .map_err(|e| Error::BadInput(format!("{}: rows: {e}", src.display())))?;
    let device = doc["device"].as_str().unwrap_or("").to_string();
    write_reports(args, &device, &rows)?;
    println!("{}", bench_report::markdown_report(&rows));
    Ok(())
}

/// What one scene's sweep shares: its name, its light's intensity, the settings the points start from, and the
/// references the rows are scored against.
struct SceneBench {
    name: String,
    intensity: f64,
    base: Settings,
    refs: References,
}

/// One scene's sweep over the transports, points and levels: its rows appended to `rows`, each flux-error row also
/// scored against max-level's image at its level. Returns the device's description.
fn bench_scene(
    args: &BenchArgs,
    scene_path: &Path,
    levels: &[u32],
    pts: &[Point],
    rows: &mut Vec<BenchRow>,
) -> Result<String> {
    let scene_args = SceneArgs {
        scene: Some(scene_path.to_path_buf()),
        camera: Some(args.camera.clone()),
        size: Some(args.size.clone()),
        ..SceneArgs::default()
    };
    let base = Settings {
        quality: Quality { caustic_res: args.caustic_res, photon_budget_mib: args.photon_budget, ..Quality::default() },
        tuning: args.tuning.tuning(Driven::Gpu, TRAVERSE_WG),
    };
    let mut session = Session::open(&scene_args, base.clone(), crate::app::commands::default_scene)?;
    // Max-level's image per (transport, level), and the flux-error rows to score against it once the scene's
    // sweep is done (the methods may come in any order).
    let mut max_level_images: HashMap<(&'static str, u32), RgbImage> = HashMap::new();
    let mut flux_error_rows: Vec<(usize, &'static str, u32, RgbImage)> = Vec::new();
    // Every timed frame runs every stage.
    session.renderer.set_reuse(false);
    let device = format!("{} ({})", session.device().info.name, session.device().info.driver);
    let photons = reference_photons(args.reference_photons, levels.iter().copied().max().unwrap_or(0));
    let refs = references(args, scene_path, session.width, session.height, photons)?;
    // GPUs ramp their clocks up under load, and lavapipe compiles shaders on first use: render for a while
    // before the first timed point, or it comes out several times slower than the later ones.
    let warm = Instant::now();
    while warm.elapsed().as_secs_f64() < args.warmup_s {
        session.frame(None)?;
    }
    let sb = SceneBench {
        name: scene_path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
        intensity: session.renderer.scene().lights.first().map_or(0.0, |l| l.intensity as f64),
        base,
        refs,
    };
    for (&transport, p) in args.transports.iter().flat_map(|t| pts.iter().map(move |p| (t, p))) {
        let key = format!("{} {}", transport_name(transport), p.key());
        for &level in levels {
            if p.method == Method::Dense && level > 12 {
                continue;
            }
            let (row, image) = bench_point(args, &mut session, &sb, transport, p, level)?;
            eprintln!(
                "{} {key:<42} L{level:<2} {:>10} photons {:>11} rays  GPU {:>9.2} ms  frame {:>9.2} ms  rel-L1 64² {}  256² {}  flux {}",
                sb.name,
                row.photons,
                row.rays_traced.map_or_else(|| "–".to_string(), |n| n.to_string()),
                row.gpu_ms_median,
                row.frame_ms_median,
                bench_report::num(row.rel_l1_64, 4),
                bench_report::num(row.rel_l1_256, 4),
                bench_report::num(row.flux_ratio, 4)
            );
            let slow = row.frame_ms_median > args.max_frame_s * 1e3;
            if p.method == Method::Adaptive && p.metric == Metric::FluxError {
                flux_error_rows.push((rows.len(), transport_name(transport), level, image));
            } else if p.method == Method::Adaptive && p.metric == Metric::MaxLevel {
                max_level_images.entry((transport_name(transport), level)).or_insert(image);
            }
            rows.push(row);
            if slow {
                eprintln!("{} {key}: frames take over {} s; skipping its deeper levels", sb.name, args.max_frame_s);
                break;
            }
        }
    }
    for (i, transport, level, image) in flux_error_rows {
        if let Some(ml) = max_level_images.get(&(transport, level)) {
            let added = metrics::compare(&image, ml, 64, 2.0).rel_l1;
            let r = &mut rows[i];
            eprintln!(
                "{} {} {} L{level}: rel-L1 64² against max-level (added by merging) {added:.6}",
                r.scene,
                r.transport,
                r.metric.as_deref().unwrap_or("")
            );
            if let serde_json::Value::Object(m) = &mut r.extra {
                m.insert("added_rel_l1_64".into(), json!(added));
            }
        }
    }
    warn_of_reference_noise(&sb, rows);
    crate::app::commands::validation_verdict(&session)?;
    Ok(device)
}

/// One point of the sweep at one level: a warm-up frame, then `--frames` timed frames, the last read back and
/// scored. Returns its row and the last frame's caustics.
fn bench_point(
    args: &BenchArgs,
    session: &mut Session,
    sb: &SceneBench,
    transport: Transport,
    p: &Point,
    level: u32,
) -> Result<(BenchRow, RgbImage)> {
    let s = Settings {
        quality: Quality {
            transport,
            method: p.method,
            metric: p.metric,
            level: Some(level),
            target_error: p.target_error,
            ..sb.base.quality.clone()
        },
        tuning: Tuning { driven: p.driven, traverse_wg: p.wg, ..sb.base.tuning.clone() },
    };
    session.renderer.set_settings(s)?;
    let t = Instant::now();
    session.frame(None)?; // warm-up: lavapipe compiles shaders on first use
    let warm = t.elapsed().as_secs_f64();
    let mut frames = Vec::new();
    let mut image = None;
    for i in 0..args.frames {
        let last = i + 1 == args.frames;
        let (r, img) = session.frame(if last { Some(Aov::Caustics) } else { None })?;
        frames.push(r);
        if last {
            image = img.as_ref().and_then(to_rgb);
        }
    }
    let image = image.ok_or_else(|| Error::Failed("no caustics image was read back".into()))?;
    let row = bench_row(args, sb, transport, p, level, &frames, &image, warm);
    Ok((row, image))
}

/// The row of a point's timed `frames`, whose last frame's caustics are `image`.
#[allow(clippy::too_many_arguments)]
fn bench_row(
    args: &BenchArgs,
    sb: &SceneBench,
    transport: Transport,
    p: &Point,
    level: u32,
    frames: &[FrameReport],
    image: &RgbImage,
    warm: f64,
) -> BenchRow {
    let last = frames.last().expect("frames").clone();
    let st = last.state.unwrap_or(bytemuck::Zeroable::zeroed());
    // Only the resolutions the image carries (a 64² image scored at 256² would measure the filter).
    let score = |r: &Option<RgbImage>, res| {
        r.as_ref()
            .filter(|r| metrics::max_comparison_res(image, r) >= res)
            .map(|r| metrics::compare(image, r, res, 2.0))
    };
    let (m64, m256) = (score(&sb.refs.main, 64), score(&sb.refs.main, 256));
    let (o64, o256) = (score(&sb.refs.other, 64), score(&sb.refs.other, 256));
    let nan = f64::NAN;
    let flux_error = p.method == Method::Adaptive && p.metric == Metric::FluxError;
    BenchRow {
        scene: sb.name.clone(),
        transport: transport_name(transport).into(),
        method: format!("{:?}", p.method).to_lowercase(),
        metric: (p.method == Method::Adaptive).then(|| p.label.clone()),
        level,
        equivalent_res: LEVEL0_RES << level,
        driven: if p.driven == Driven::Gpu { "gpu".into() } else { "cpu".into() },
        photons: st.photons_total as u64,
        rays_traced: last.transport.map(|t| t.rays_traced as u64),
        gpu_ms_median: median_of(frames, |f| f.gpu_ms) + 0.0,
        frame_ms_median: median_of(frames, |f| f.frame_ms) + 0.0,
        rel_l1_64: m64.map(|m| m.rel_l1).unwrap_or(nan),
        rel_l1_256: m256.map(|m| m.rel_l1).unwrap_or(nan),
        flux_ratio: m64.map(|m| m.flux_ratio).unwrap_or(nan),
        peak_offset_m: m256.map(|m| m.peak_offset_m).unwrap_or(nan),
        extra: json!({
            "reference_paths": args.paths,
            "reference_noise": sb.refs.noise.map(|(n64, n256)| json!({"rel_l1_64": n64, "rel_l1_256": n256})),
            "other_reference": {
                "rel_l1_64": o64.map(|m| m.rel_l1), "rel_l1_256": o256.map(|m| m.rel_l1),
                "flux_ratio": o64.map(|m| m.flux_ratio),
            },
            "traverse_wg": p.wg,
            "target_error": flux_error.then_some(p.target_error),
            "tau": flux_error.then(|| caustics::calibration::tau_for_target_error(p.target_error)),
            "traverse_ms": stage_median(frames, "traverse"),
            "photon_trace_ms": stage_median(frames, "photon_trace"),
            "transport_ms": stage_median(frames, "transport"),
            "splat_ms": stage_median(frames, "splat"),
            "light_gbuffer_ms": stage_median(frames, "light_gbuffer"),
            "eye_ms": stage_median(frames, "eye"),
            "stats_ms": stage_median(frames, "stats"),
            "host_roundtrip_ms": stage_median(frames, caustics::HOST_ROUNDTRIP),
            "host_readbacks_per_frame": last.host_readbacks,
            "batches": st.batches_committed,
            "overflow_events": st.batches_aborted,
            "photon_buffer_bytes": 8 * st.peak_used as u64,
            "warmup_s": warm,
            "exact_transport": exact_extra(&last, sb.intensity),
        }),
    }
}

/// A warning when the scene's reference is so noisy that the errors near its noise mostly measure it.
fn warn_of_reference_noise(sb: &SceneBench, rows: &[BenchRow]) {
    let Some((noise, _)) = sb.refs.noise else {
        return;
    };
    let best = rows.iter().filter(|r| r.scene == sb.name).map(|r| r.rel_l1_64).fold(f64::INFINITY, f64::min);
    if noise > NOISE_WARN * best {
        eprintln!(
            "warning: {}: the reference's noise (rel-L1 64² {:.4}%) is over {:.0}% of the smallest error \
             ({:.4}%): the errors near it mostly measure the reference, and their differences shrink; raise \
             --reference-photons (4× the photons halve the noise)",
            sb.name,
            100.0 * noise,
            100.0 * NOISE_WARN,
            100.0 * best
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reference_photons_follow_the_sweep() {
        assert_eq!(reference_photons(None, 2), 1_000_000);
        assert_eq!(reference_photons(None, 3), 1_048_576);
        assert_eq!(reference_photons(None, 5), 16_777_216);
        assert_eq!(reference_photons(None, 8), 32_000_000);
        assert_eq!(reference_photons(Some(5), 8), 5);
    }
}
