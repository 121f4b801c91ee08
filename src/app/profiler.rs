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
        for (label, start, dur) in &f.segments {
            events.push(json!({"name": label, "ph": "X", "pid": 1, "tid": 1, "ts": (t0 + start) * 1e3, "dur": dur * 1e3, "cat": "gpu"}));
        }
        t0 += f.frame_ms.max(f.segments.last().map(|s| s.1 + s.2).unwrap_or(0.0));
    }
    json!({
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "metadata": {"tid 0": "frames (wall clock)", "tid 1": "GPU stages (timestamp queries)"}
    })
}
