//! `caustics render`: a frame (or a sequence) headless, written as PNG or EXR, with its stats.

use super::*;

pub fn run_render(args: &RenderArgs) -> Result<()> {
    let aov = check_output(args.aov.parse()?, &args.out)?;
    if let Some(p) = &args.stats {
        image_io::check_output_dir(p)?;
    }
    if args.frames == 0 {
        return Err(Error::BadInput("--frames must be at least 1".into()));
    }
    if let Some(n) = args.sequence {
        check_sequence(args, n)?;
    }
    if args.accumulate.is_some() && (args.frames != 1 || args.no_reuse) {
        return Err(Error::BadInput(
            "--accumulate averages photon sets into one picture: not with --frames, which repeats a frame, or \
             --no-reuse, which starts every frame afresh"
                .into(),
        ));
    }
    let settings = args.method.settings()?;
    let mut session = Session::open(&args.scene, settings, first_picture_scene)?;
    session.renderer.set_reuse(!args.no_reuse);
    session.renderer.set_accumulation(match args.accumulate {
        Some(Accumulate::Sets(n)) => n,
        Some(Accumulate::Seconds(_)) => u32::MAX,
        None => 1,
    });
    session.announce_defaults();
    session.plan(Some(aov))?;
    let mut reports = Vec::new();
    let mut extra = serde_json::Map::new();
    extra.insert("aov".into(), json!(args.aov));
    if let Some(n) = args.sequence {
        let bar = sequence_bar(n);
        for k in 0..n {
            let t = args.scene.seconds()? + k as f32 / args.fps;
            session.renderer.set_time(t)?;
            // An animated camera moves with its node.
            if let Ok(c) = session.renderer.scene().camera(Some(&session.camera.name)) {
                session.camera = c.clone();
            }
            let (report, img) = converge(&mut session, aov, args.accumulate, &mut reports)?;
            let image = img.ok_or_else(|| Error::Failed("no image was read back".into()))?;
            write_aov(&session, args, aov, &image, &sequence_path(&args.out, k), &mut extra)?;
            reports.push(report);
            bar.inc(1);
        }
        bar.finish_and_clear();
        extra.insert("sequence".into(), json!({"frames": n, "fps": args.fps, "start_s": args.scene.seconds()?}));
    } else if args.accumulate.is_some() {
        let (report, img) = converge(&mut session, aov, args.accumulate, &mut reports)?;
        reports.push(report);
        let image = img.ok_or_else(|| Error::Failed("no image was read back".into()))?;
        write_aov(&session, args, aov, &image, &args.out, &mut extra)?;
    } else {
        let mut image = None;
        for i in 0..args.frames {
            let (report, img) = session.frame(Some(aov))?;
            if args.frames > 1 {
                eprintln!(
                    "frame {}/{}: {:.1} ms GPU, {:.1} ms wall",
                    i + 1,
                    args.frames,
                    report.gpu_ms,
                    report.frame_ms
                );
            }
            reports.push(report);
            image = img;
        }
        let image = image.ok_or_else(|| Error::Failed("no image was read back".into()))?;
        write_aov(&session, args, aov, &image, &args.out, &mut extra)?;
    }
    if let Some(last) = reports.last().filter(|r| r.guard_intact.is_some()) {
        extra.insert("debug_photons".into(), debug_photons_json(&last.debug_photons()));
        extra.insert("photon_guard_intact".into(), json!(last.guard_intact));
    }
    let stats = stats_json(&session, &reports, Value::Object(extra));
    if let Some(p) = &args.stats {
        image_io::write_text(p, &serde_json::to_string_pretty(&stats).unwrap_or_default())?;
    }
    let last = reports.last().expect("a frame");
    let written = match args.sequence {
        Some(n) => format!("{} ({n} frames)", args.out.display()),
        None => args.out.display().to_string(),
    };
    eprintln!(
        "{written}: {} photons, GPU {:.2} ms, frame {:.1} ms on {}",
        last.photons(),
        last.gpu_ms,
        last.frame_ms,
        session.device().info.name
    );
    validation_verdict(&session)
}

/// One picture at the scene's current time: a frame, or with `--accumulate` the average of its photon sets (each
/// a frame; the earlier frames' reports go to `reports`). Returns the last frame's report and image.
fn converge(
    session: &mut Session,
    aov: Aov,
    accumulate: Option<Accumulate>,
    reports: &mut Vec<FrameReport>,
) -> Result<(FrameReport, Option<AovData>)> {
    let start = std::time::Instant::now();
    let (sets, seconds) = match accumulate {
        None => return session.frame(Some(aov)),
        Some(Accumulate::Sets(n)) => (n, f64::INFINITY),
        Some(Accumulate::Seconds(t)) => (u32::MAX, t),
    };
    let bar = accumulate_bar(accumulate);
    loop {
        let (report, image) = session.frame(Some(aov))?;
        bar.set_position(report.photon_sets as u64);
        let done = report.photon_sets >= sets || start.elapsed().as_secs_f64() >= seconds;
        if done || report.reused {
            bar.finish_and_clear();
            eprintln!(
                "averaged {} photon sets ({} photons each) in {:.1} s",
                report.photon_sets,
                report.photons(),
                start.elapsed().as_secs_f64()
            );
            return Ok((report, image));
        }
        reports.push(report);
    }
}

/// A progress bar for --accumulate's photon sets on stderr (drawn only when stderr is a terminal).
fn accumulate_bar(accumulate: Option<Accumulate>) -> indicatif::ProgressBar {
    match accumulate {
        Some(Accumulate::Sets(n)) => crate::app::stderr_bar(
            || indicatif::ProgressBar::new(n as u64),
            "{bar:40} photon set {pos}/{len}  eta {eta}",
        ),
        _ => crate::app::stderr_bar(indicatif::ProgressBar::new_spinner, "{spinner} photon set {pos}  {elapsed}"),
    }
}

/// Write a frame's AOV to `path` (PNG or EXR with its metadata); a caustics or direct AOV's flux goes in `extra`.
pub(super) fn write_aov(
    session: &Session,
    args: &RenderArgs,
    aov: Aov,
    image: &AovData,
    path: &Path,
    extra: &mut serde_json::Map<String, Value>,
) -> Result<()> {
    match image {
        AovData::Rgba8 { width, height, rgba } => Ok(image_io::write_png(path, *width, *height, rgba)?),
        AovData::Float { .. } => {
            let rgb = to_rgb(image).expect("float image");
            if let (Some(area), false) = (session.pixel_area(), aov == Aov::BeautyHdr) {
                let flux: f64 = rgb.data.iter().map(|p| p[0] as f64).sum::<f64>() * area;
                extra.insert("aov_flux_w".into(), json!(flux));
            }
            Ok(image_io::write_exr_meta(path, &rgb, &exr_meta(session, &args.aov))?)
        }
    }
}

/// `--sequence N`: at least one frame, a positive frame rate, no `--frames`, and an output name with a run of `#`
/// long enough for the frame numbers.
pub(super) fn check_sequence(args: &RenderArgs, n: u32) -> Result<()> {
    if n == 0 {
        return Err(Error::BadInput("--sequence must be at least 1 frame".into()));
    }
    if !(args.fps.is_finite() && args.fps > 0.0) {
        return Err(Error::BadInput(format!("--fps {}: must be a positive number of frames per second", args.fps)));
    }
    if args.frames != 1 {
        return Err(Error::BadInput(
            "--frames repeats one time's frame; --sequence renders frames at successive times: give one of them".into(),
        ));
    }
    let name = args.out.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    let run = hash_run(name).map_or(0, |(a, b)| b - a);
    let digits = (n - 1).max(1).ilog10() as usize + 1;
    if run < digits {
        return Err(Error::BadInput(format!(
            "--out {}: a sequence's file name needs a run of at least {digits} `#` for the frame number (for example \
             frame_{}.png)",
            args.out.display(),
            "#".repeat(digits.max(4))
        )));
    }
    Ok(())
}

/// The last run of `#` in a file name: (start, end) byte offsets.
pub(super) fn hash_run(name: &str) -> Option<(usize, usize)> {
    let end = name.rfind('#')? + 1;
    let start = name[..end].trim_end_matches('#').len();
    Some((start, end))
}

/// Frame `k` of a sequence written to `out`: its file name's last run of `#` replaced by `k`, zero-padded to the
/// run's length.
pub(super) fn sequence_path(out: &Path, k: u32) -> PathBuf {
    let name = out.file_name().and_then(|n| n.to_str()).unwrap_or_default();
    match hash_run(name) {
        Some((a, b)) => out.with_file_name(format!("{}{:0width$}{}", &name[..a], k, &name[b..], width = b - a)),
        None => out.to_path_buf(),
    }
}

/// A progress bar for a sequence's frames on stderr (drawn only when stderr is a terminal).
pub(super) fn sequence_bar(n: u32) -> indicatif::ProgressBar {
    crate::app::stderr_bar(|| indicatif::ProgressBar::new(n as u64), "{bar:40} frame {pos}/{len}  {per_sec}  eta {eta}")
}

/// The EXR header metadata of a rendered AOV (docs/design.md, "CLI contract").
pub(super) fn exr_meta(session: &Session, aov: &str) -> image_io::ExrMeta {
    let s = &session.renderer.config();
    let mut m = image_io::ExrMeta::new();
    m.insert("scene".into(), session.scene_path.display().to_string());
    m.insert("scene_hash".into(), image_io::file_hash(&session.scene_path));
    m.insert("camera".into(), session.camera.name.clone());
    m.insert("camera_kind".into(), camera_kind(&session.camera).into());
    m.insert("aov".into(), aov.into());
    m.insert("units".into(), if aov == "beauty" { "W/(m^2 sr)" } else { "W/m^2" }.into());
    m.insert("transport".into(), json!(s.transport).as_str().unwrap_or_default().into());
    m.insert("method".into(), json!(s.method).as_str().unwrap_or_default().into());
    m.insert("level".into(), s.level.to_string());
    m.insert("time".into(), session.renderer.time().to_string());
    m
}
