//! `caustics reference`: the exact CPU photon tracer as a command.

use caustics::error::{Error, Result};
use caustics::image_io;
use caustics::reference::{trace, Progress, RefParams};
use caustics::scene::Scene;
use caustics::settings::parse_size;
use glam::Vec3;
use std::path::{Path, PathBuf};

/// `caustics reference` arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct ReferenceArgs {
    /// Scene file: TOML (.toml) or glTF 2.0 (.gltf, .glb) (default: assets/scenes/sphere.toml).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Camera name (must be orthographic; default: the scene's first camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// AOV to write: caustics or direct.
    #[arg(long, default_value = "caustics")]
    pub aov: String,
    /// Which caustic paths to deposit: all, or two-refractions (refracted exactly twice, no reflection).
    #[arg(long, default_value = "all")]
    pub paths: String,
    /// Number of photons per light.
    #[arg(long, default_value_t = 4_000_000)]
    pub photons: u64,
    /// Output size WxH [default: as `render`'s: 512 high, as wide as the camera's authored aspect; else 512x512].
    #[arg(long)]
    pub size: Option<String>,
    /// glTF: the animation that plays, by name or index [default: all of them, together].
    #[arg(long)]
    pub animation: Option<String>,
    /// Random seed: the same seed gives a bit-identical image on any number of threads.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Output image: 32-bit float OpenEXR, RGB = irradiance in W/m².
    #[arg(long)]
    pub out: PathBuf,
    /// Write stats JSON here: the energy account, photon counts, photons/s, wall time, threads, seed.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Scene time in seconds: animated objects stand where their keyframes place them then (as `render --time`
    /// places them).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// The time as the authoring tool's frame N: N / --frame-rate seconds (as `render --frame`) [not with --time].
    #[arg(long, conflicts_with = "time", allow_negative_numbers = true)]
    pub frame: Option<f32>,
    /// The frame rate --frame counts in, frames per second (glTF does not record it).
    #[arg(long, default_value_t = 24.0)]
    pub frame_rate: f32,
    /// Also report the radii holding 50% and 90% of the AOV's flux around this point, "x,y,z".
    #[arg(long)]
    pub radial_center: Option<String>,
}

fn parse_vec3(s: &str, flag: &str) -> Result<Vec3> {
    let v: Vec<f32> = s
        .split(',')
        .map(|x| x.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| Error::BadInput(format!("{flag}: expected three comma-separated numbers x,y,z, got `{s}`")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(Error::BadInput(format!("{flag}: expected three finite numbers x,y,z, got `{s}`"))),
    }
}

impl ReferenceArgs {
    /// Validate the arguments into [`RefParams`] (bad values are [`Error::BadInput`] naming the flag).
    pub fn params(&self) -> Result<RefParams> {
        let (width, height) = match &self.size {
            Some(s) => parse_size(s, "--size")?,
            None => (512, 512),
        };
        if self.photons == 0 {
            return Err(Error::BadInput("--photons: must be at least 1".into()));
        }
        if self.threads == Some(0) {
            return Err(Error::BadInput("--threads: must be at least 1".into()));
        }
        Ok(RefParams {
            camera: self.camera.clone(),
            aov: self.aov.parse().map_err(|e| Error::BadInput(format!("--aov: {e}")))?,
            paths: self.paths.parse().map_err(|e| Error::BadInput(format!("--paths: {e}")))?,
            photons: self.photons,
            width,
            height,
            seed: self.seed,
            threads: self.threads,
            progress: Some(progress_bar()),
            radial_center: self.radial_center.as_deref().map(|s| parse_vec3(s, "--radial-center")).transpose()?,
            time: super::commands::seconds(self.time, self.frame, self.frame_rate)?,
        })
    }
}

fn check_output(path: &Path, flag: &str, ext: &str) -> Result<()> {
    if path.extension().and_then(|e| e.to_str()).map(|e| e.eq_ignore_ascii_case(ext)) != Some(true) {
        return Err(Error::BadInput(format!("{flag}: {} must end in .{ext}", path.display())));
    }
    image_io::check_output_dir(path).map_err(|e| Error::BadInput(format!("{flag}: {e}")))
}

/// `caustics reference`.
pub fn run(args: &ReferenceArgs) -> Result<()> {
    let mut params = args.params()?;
    check_output(&args.out, "--out", "exr")?;
    if let Some(s) = &args.stats {
        check_output(s, "--stats", "json")?;
    }
    let scene_path = args.scene.clone().unwrap_or_else(super::commands::default_scene);
    let mut scene = Scene::load_with(&scene_path, &super::commands::load_options(args.animation.as_deref()))?;
    // The camera as it stands at --time, for the default size (the tracer places the scene there itself).
    scene.set_time(params.time);
    if let Ok(c) = scene.camera(args.camera.as_deref()) {
        (params.width, params.height) = caustics::settings::output_size(args.size.as_deref(), "--size", c)?;
    }
    let out = trace(&scene, &params)?;
    let mut meta = image_io::ExrMeta::new();
    meta.insert("scene".into(), scene_path.display().to_string());
    meta.insert("scene_hash".into(), image_io::file_hash(&scene_path));
    meta.insert("camera".into(), out.stats.camera.clone());
    meta.insert("camera_kind".into(), "orthographic".into());
    meta.insert("aov".into(), args.aov.clone());
    meta.insert("units".into(), "W/m^2".into());
    meta.insert("transport".into(), "reference".into());
    meta.insert("paths".into(), args.paths.clone());
    meta.insert("photons".into(), args.photons.to_string());
    meta.insert("seed".into(), args.seed.to_string());
    meta.insert("level".into(), "none".into());
    meta.insert("time".into(), params.time.to_string());
    image_io::write_exr_meta(&args.out, &out.image, &meta)?;
    if let Some(s) = &args.stats {
        let json = serde_json::to_string_pretty(&out.stats).map_err(|e| Error::Failed(e.to_string()))?;
        image_io::write_text(s, &json)?;
    }
    let st = &out.stats;
    let a = &st.energy_account;
    println!(
        "{} {} ({}): {} photons/light, {:.3} s, {:.0} photons/s, {} threads",
        st.scene, st.aov, st.paths, st.photons_per_light, st.wall_s, st.photons_per_s, st.threads
    );
    println!(
        "flux W: emitted {:.6}, caustics {:.6}, direct {:.6}, escaped {:.6}, cut {:.6}, filtered {:.6}, lost {:.6}, absorbed {:.6} (residual {:.1e})",
        a.emitted, a.deposited_caustics, a.deposited_direct, a.escaped, a.cut_by_bounce_cap, a.filtered_by_paths, a.lost, a.absorbed, a.residual_rel
    );
    println!("{} in image: {:.6} W (Σ E·pixel area = {:.6} W)", st.aov, a.aov_in_image, a.image_integral);
    if let Some(r) = &st.radial {
        println!("radial around {:?}: r50 = {:?} m, r90 = {:?} m", r.center, r.r50, r.r90);
    }
    Ok(())
}

/// A progress bar on stderr for the tracer (drawn only when stderr is a terminal).
pub fn progress_bar() -> Progress {
    let template = "{bar:40} {human_pos}/{human_len} photons  {per_sec}  eta {eta}";
    let bar = crate::app::stderr_bar(|| indicatif::ProgressBar::new(0), template);
    Progress(std::sync::Arc::new(move |done, total| {
        bar.set_length(total);
        bar.set_position(done);
        if done >= total {
            bar.finish_and_clear();
        }
    }))
}
