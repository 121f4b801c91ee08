//! Per-stage GPU timings over frames: summary statistics, a printed table, JSON, and a Chrome trace (opens in
//! Perfetto or chrome://tracing).

use caustics::FrameReport;
use serde_json::{json, Value};

#[derive(Clone, Copy, Debug, Default, serde::Serialize)]
pub struct Summary {
    pub mean: f64,
    pub median: f64,
    pub min: f64,
    pub max: f64,
}

impl Summary {
    pub fn of(values: &[f64]) -> Summary {
        if values.is_empty() {
            return Summary::default();
        }
        let mut v = values.to_vec();
        v.sort_by(|a, b| a.total_cmp(b));
        let n = v.len();
        let median = if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) };
        Summary { mean: v.iter().sum::<f64>() / n as f64, median, min: v[0], max: v[n - 1] }
    }
}

/// Per-stage summaries over frames, in first-seen stage order, each over the frames that ran the stage (a frame
/// that reused the caustic map has no caustic stages: it does not pull their medians to 0).
pub fn stage_summaries(frames: &[FrameReport]) -> Vec<(String, Summary)> {
    let mut out = summaries_by_label(frames, |f| &f.stages);
    let totals: Vec<f64> = frames.iter().map(|f| f.gpu_ms).collect();
    out.push(("gpu_total".into(), Summary::of(&totals)));
    let wall: Vec<f64> = frames.iter().map(|f| f.frame_ms).collect();
    out.push(("frame_wall".into(), Summary::of(&wall)));
    let rec: Vec<f64> = frames.iter().map(|f| f.record_ms).collect();
    out.push(("cpu_record".into(), Summary::of(&rec)));
    out
}

/// Per-sub-stage summaries (`light_gbuffer.front`, ...) over the frames that ran them, in first-seen order.
pub fn substage_summaries(frames: &[FrameReport]) -> Vec<(String, Summary)> {
    summaries_by_label(frames, |f| &f.substages)
}

/// One summary per label of `of(frame)`, in first-seen order, each over the frames that have the label.
fn summaries_by_label(
    frames: &[FrameReport],
    of: impl Fn(&FrameReport) -> &[(&'static str, f64)],
) -> Vec<(String, Summary)> {
    let mut labels: Vec<&str> = Vec::new();
    for f in frames {
        for (l, _) in of(f) {
            if !labels.contains(l) {
                labels.push(l);
            }
        }
    }
    labels
        .iter()
        .map(|l| {
            let v: Vec<f64> =
                frames.iter().filter_map(|f| of(f).iter().find(|(x, _)| x == l).map(|(_, ms)| *ms)).collect();
            (l.to_string(), Summary::of(&v))
        })
        .collect()
}

/// The host-side entries of [`stage_summaries`]: wall-clock time of a frame and host command recording. They are
/// not GPU time, so the stats keep them out of `gpu_ms` (as `wall_ms` and `cpu_ms`).
pub const HOST_STAGES: [&str; 2] = ["frame_wall", "cpu_record"];

/// `gpu_ms`: the GPU stages (timestamp queries) and their sum `gpu_total`, without the host entries.
pub fn gpu_json(s: &[(String, Summary)]) -> Value {
    let gpu: Vec<(String, Summary)> = s.iter().filter(|(l, _)| !HOST_STAGES.contains(&l.as_str())).cloned().collect();
    summaries_json(&gpu)
}

/// One entry's summary as JSON (zeros when absent).
pub fn summary_json(s: &[(String, Summary)], name: &str) -> Value {
    let v = s.iter().find(|(l, _)| l == name).map(|(_, v)| *v).unwrap_or_default();
    json!({"mean": v.mean, "median": v.median, "min": v.min, "max": v.max})
}

pub fn summaries_json(s: &[(String, Summary)]) -> Value {
    let mut m = serde_json::Map::new();
    for (l, v) in s {
        m.insert(l.clone(), json!({"mean": v.mean, "median": v.median, "min": v.min, "max": v.max}));
    }
    Value::Object(m)
}

/// Photons per millisecond of each GPU stage's median, and of the whole frame's (`gpu_total`): the throughput
/// that scales with the photon count (stages with a fixed cost show large numbers).
pub fn throughput_json(s: &[(String, Summary)], photons: u64) -> Value {
    let mut m = serde_json::Map::new();
    for (l, v) in s.iter().filter(|(l, _)| !HOST_STAGES.contains(&l.as_str())) {
        if v.median > 0.0 {
            m.insert(l.clone(), json!(photons as f64 / v.median));
        }
    }
    Value::Object(m)
}

/// The per-stage table; with `photons`, a photons/ms column (photons over the stage's median).
pub fn table(s: &[(String, Summary)], frames: usize, photons: Option<u64>) -> String {
    let mut out = format!(
        "{:<18} {:>10} {:>10} {:>10} {:>10} {:>12}   ({} frames, ms)\n",
        "stage",
        "mean",
        "median",
        "min",
        "max",
        if photons.is_some() { "photons/ms" } else { "" },
        frames
    );
    for (l, v) in s {
        if l == "gpu_total" {
            out.push_str(&format!("{}\n", "-".repeat(75)));
        }
        let rate = match photons {
            Some(p) if v.median > 0.0 && !HOST_STAGES.contains(&l.as_str()) => format!("{:.0}", p as f64 / v.median),
            _ => String::new(),
        };
        out.push_str(&format!(
            "{:<18} {:>10.3} {:>10.3} {:>10.3} {:>10.3} {:>12}\n",
            l, v.mean, v.median, v.min, v.max, rate
        ));
    }
    out
}

/// Chrome trace: one complete event per timed GPU interval; frames laid end to end on the wall clock.
pub fn chrome_trace(frames: &[FrameReport]) -> Value {
    let mut events = Vec::new();
    let mut t0 = 0.0;
    for (i, f) in frames.iter().enumerate() {
        events.push(json!({"name": format!("frame {i}"), "ph": "X", "pid": 1, "tid": 0, "ts": t0 * 1e3, "dur": f.frame_ms * 1e3, "cat": "frame"}));
        events.push(json!({"name": "record", "ph": "X", "pid": 1, "tid": 2, "ts": t0 * 1e3, "dur": f.record_ms * 1e3, "cat": "cpu"}));
        for (label, start, dur) in &f.segments {
            events.push(json!({"name": label, "ph": "X", "pid": 1, "tid": 1, "ts": (t0 + start) * 1e3, "dur": dur * 1e3, "cat": "gpu"}));
        }
        t0 += f.frame_ms.max(f.segments.last().map(|s| s.1 + s.2).unwrap_or(0.0));
    }
    json!({
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "metadata": {
            "tid 0": "frames (wall clock)",
            "tid 1": "GPU stages (timestamp queries)",
            "tid 2": "CPU: recording the frame's commands"
        }
    })
}

/// Tableau-20: the stage colors of the report and of the viewer's overlay (one per stage for up to 20 stages).
pub const STAGE_COLORS: [(u8, u8, u8); 20] = [
    (31, 119, 180),
    (174, 199, 232),
    (255, 127, 14),
    (255, 187, 120),
    (44, 160, 44),
    (152, 223, 138),
    (214, 39, 40),
    (255, 152, 150),
    (148, 103, 189),
    (197, 176, 213),
    (140, 86, 75),
    (196, 156, 148),
    (227, 119, 194),
    (247, 182, 210),
    (127, 127, 127),
    (199, 199, 199),
    (188, 189, 34),
    (219, 219, 141),
    (23, 190, 207),
    (158, 218, 229),
];

/// The SVG report of `profile --plot`: each frame a bar of its stages' GPU ms stacked bottom up (in first-seen
/// order), and beside the bars a legend of each stage with its median over the frames that ran it.
pub fn stage_plot(frames: &[FrameReport], title: &str) -> Result<String, Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let summaries = summaries_by_label(frames, |f| &f.stages);
    let peak = frames.iter().map(|f| f.stages.iter().map(|(_, ms)| ms).sum::<f64>()).fold(0.0, f64::max);
    let color = |i: usize| {
        let (r, g, b) = STAGE_COLORS[i % STAGE_COLORS.len()];
        RGBColor(r, g, b)
    };
    let n = frames.len().max(1);
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (1040, 560)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(&format!("GPU ms per stage: {title}"), ("sans-serif", 18))?;
        let (left, right) = root.split_horizontally(720);
        let mut chart = ChartBuilder::on(&left)
            .margin(16)
            .x_label_area_size(40)
            .y_label_area_size(64)
            .build_cartesian_2d(-0.5..n as f64 - 0.5, 0.0..(peak * 1.05).max(1e-3))?;
        chart
            .configure_mesh()
            .x_desc("frame")
            .y_desc("GPU ms")
            .x_labels(n.min(20))
            .x_label_formatter(&|v| format!("{}", v.round() as i64 + 1))
            .disable_x_mesh()
            .draw()?;
        for (i, (label, _)) in summaries.iter().enumerate() {
            let bars = frames.iter().enumerate().filter_map(|(k, f)| {
                let at = f.stages.iter().position(|(l, _)| *l == label)?;
                let below: f64 = f.stages[..at].iter().map(|(_, ms)| ms).sum();
                let top = below + f.stages[at].1;
                Some(Rectangle::new([(k as f64 - 0.4, below), (k as f64 + 0.4, top)], color(i).filled()))
            });
            chart.draw_series(bars)?;
        }
        let font = ("sans-serif", 13).into_font();
        for (i, (label, summary)) in summaries.iter().enumerate().rev() {
            // The legend reads top down as the bars stack bottom up.
            let y = 24 + 20 * (summaries.len() - 1 - i) as i32;
            right.draw(&Rectangle::new([(8, y), (20, y + 12)], color(i).filled()))?;
            let text = format!("{label}  {:.2} ms", summary.median);
            right.draw(&Text::new(text, (28, y), font.clone()))?;
        }
        right.draw(&Text::new("stage, median over the frames", (8, 4), font.clone()))?;
        root.present()?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The trace puts each frame on three tracks: its wall-clock span, its GPU stages where the timestamps put them,
    /// and the CPU's recording of its commands.
    #[test]
    fn the_chrome_trace_has_the_frames_gpu_stages_and_cpu_recording() {
        let frame = |record_ms| {
            let mut f = FrameReport::default();
            (f.frame_ms, f.record_ms) = (10.0, record_ms);
            f.segments = vec![("eye", 1.0, 2.0), ("composite", 3.0, 0.5)];
            f
        };
        let trace = chrome_trace(&[frame(0.25), frame(0.5)]);
        let events = trace["traceEvents"].as_array().unwrap();
        let on = |tid: u64| events.iter().filter(|e| e["tid"] == tid).collect::<Vec<_>>();
        assert_eq!(on(0).len(), 2);
        assert_eq!(on(1).len(), 4);
        let cpu = on(2);
        assert_eq!(cpu.len(), 2);
        // The second frame starts where the first one's wall-clock span ends; durations are in µs.
        assert_eq!((cpu[1]["ts"].as_f64(), cpu[1]["dur"].as_f64()), (Some(10_000.0), Some(500.0)));
        assert_eq!(on(1)[2]["ts"].as_f64(), Some(11_000.0));
    }
}
