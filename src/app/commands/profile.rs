//! `caustics profile`: frames timed stage by stage, with a Chrome trace and an SVG report.

use super::*;

pub fn run_profile(args: &ProfileArgs) -> Result<()> {
    if args.frames == Some(0) {
        return Err(Error::BadInput("--frames must be at least 1".into()));
    }
    for p in args.trace.iter().chain(&args.plot) {
        image_io::check_output_dir(p)?;
    }
    let settings = args.method.settings()?;
    let mut session = Session::open(&args.scene, settings, default_scene)?;
    // The profiler times every stage: nothing is reused.
    session.renderer.set_reuse(false);
    session.announce_defaults();
    // A CPU device profiles fewer frames unless told (lavapipe at level 5 took 35 minutes for the 21 frames a GPU
    // profiles in a second).
    let cpu = session.device().info.is_cpu();
    let frames = args.frames.unwrap_or(if cpu { PROFILE_FRAMES_CPU } else { PROFILE_FRAMES_GPU });
    let warmup = args.warmup.unwrap_or(1);
    let per_frame = session.plan(None)?;
    eprintln!(
        "profile: {warmup} warm-up and {frames} timed frames at level {} on {}{} (--frames, --warmup and --level \
         change it)",
        session.renderer.config().level,
        session.device().info.name,
        per_frame.map(|t| format!(", about {:.0} s", t * (frames + warmup) as f64)).unwrap_or_default()
    );
    for _ in 0..warmup {
        session.frame(None)?;
    }
    let mut reports = Vec::new();
    for i in 0..frames {
        let (r, _) = session.frame(None)?;
        if !args.json && (i + 1) % 10 == 0 {
            eprintln!("profiled {}/{} frames", i + 1, frames);
        }
        reports.push(r);
    }
    let summaries = profiler::stage_summaries(&reports);
    if args.json {
        let stats = stats_json(&session, &reports, json!({}));
        println!("{}", serde_json::to_string_pretty(&stats).unwrap_or_default());
    } else {
        let s = &session.renderer.config();
        let last = reports.last().expect("frames");
        println!(
            "{} | {} | {:?} {} level {} ({}²) {} | {} photons, {} batches, {} host readbacks/frame",
            session.device().info.name,
            session.scene_path.display(),
            s.method,
            if s.method == Method::Adaptive { format!("{:?}", s.metric) } else { String::new() },
            s.level,
            LEVEL0_RES << s.level,
            if s.method == Method::Adaptive { format!("{:?}-driven", s.driven) } else { String::new() },
            last.state.map(|x| x.photons_total).unwrap_or(0),
            last.state.map(|x| x.batches_committed).unwrap_or(0),
            last.host_readbacks
        );
        let photons = last.state.map(|x| x.photons_total as u64);
        let bvh = &session.renderer.bvh_stats();
        println!(
            "load: scene {:.0} ms, renderer {:.0} ms{}",
            session.load_ms[0],
            session.load_ms[1],
            if bvh.built {
                format!(", BVH {:.0} ms ({} triangles, in the first frame)", bvh.build_ms, bvh.triangles)
            } else {
                String::new()
            }
        );
        print!("{}", profiler::table(&summaries, reports.len(), photons));
        let subs = profiler::substage_summaries(&reports);
        let (waves, parts): (Vec<_>, Vec<_>) = subs.iter().partition(|(l, _)| l.starts_with("transport_bounces.wave_"));
        for (l, v) in parts {
            println!("  {l:<28} median {:8.3} ms", v.median);
        }
        if !waves.is_empty() {
            print!("{}", wave_lines(&waves, last.transport.map(|t| t.wave_rays())));
        }
    }
    if let Some(p) = &args.trace {
        image_io::write_text(p, &serde_json::to_string(&profiler::chrome_trace(&reports)).unwrap_or_default())?;
        eprintln!("wrote {}", p.display());
    }
    if let Some(p) = &args.plot {
        let title = format!("{} on {}", session.scene_path.display(), session.device().info.name);
        let svg = profiler::stage_plot(&reports, &title)
            .map_err(|e| Error::Failed(format!("{}: cannot draw the plot: {e}", p.display())))?;
        image_io::write_text(p, &svg)?;
        eprintln!("wrote {}", p.display());
    }
    validation_verdict(&session)
}

/// The bounce waves in two lines, from wave 1 (wave 0 is `transport_primary`): each wave's median ms and, when the
/// frame counted them (`TransportState::wave_rays`, up to the last wave with rays), its rays; the empty waves at the
/// end in one sum.
pub(super) fn wave_lines(waves: &[&(String, profiler::Summary)], rays: Option<Vec<u32>>) -> String {
    let ms: Vec<f64> = waves.iter().map(|(_, v)| v.median).collect();
    let live = rays.as_ref().map_or(ms.len(), |r| r.len().saturating_sub(1));
    let cell = |x: f64| if x >= 10.0 { format!("{x:.1}") } else { format!("{x:.3}") };
    let mut out = format!("  transport_bounces waves 1-{live}, median ms:\n   ");
    for x in &ms[..live.min(ms.len())] {
        out += &format!(" {}", cell(*x));
    }
    out.push('\n');
    if let Some(r) = &rays {
        out += "  rays:\n   ";
        for n in r.iter().skip(1).take(live) {
            out += &format!(" {n}");
        }
        out.push('\n');
    }
    if live < ms.len() {
        out += &format!("  waves {}-{} empty: {:.3} ms together\n", live + 1, ms.len(), ms[live..].iter().sum::<f64>());
    }
    out
}
