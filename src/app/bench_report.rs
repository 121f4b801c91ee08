//! The reporting half of `caustics bench`: one [`BenchRow`] per (scene, transport, method, metric, level, driven)
//! run, a Markdown table, and a log-log SVG plot of error against GPU time.
//!
//! Row shape (the JSON the bench writes, one object per row):
//! - `scene`, `transport` (`exact` or `two-interface`; rows written before the field existed read back as
//!   `two-interface`), `method` (`dense`, `adaptive`, ...), `metric` (`max-level`, `max-error`, or null for
//!   dense), `level` (the `--level`), `equivalent_res` (64·2^level: the light-space grid side the level stands
//!   for), `driven` (`gpu` or `cpu`), `photons` (photons emitted and traced from the light);
//! - `rays_traced`: rays the exact transport traced through the BVH in the last frame (every wave, every Fresnel
//!   branch), null for two-interface;
//! - `gpu_ms_median` (summed GPU stages of one frame) and `frame_ms_median` (wall time of one frame), over frames;
//! - the metric against the reference (caustics::metrics): `rel_l1_64`, `rel_l1_256`, `flux_ratio`, and
//!   `peak_offset_m` (docs/design.md reports all three; defaults to 0 when absent);
//! - `extra`: anything else (per-stage times, overflow counts), free-form JSON, defaults to null.

use caustics::error::{Error, Result};
use caustics::image_io;
use serde::{Deserialize, Serialize};
use std::path::Path;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchRow {
    pub scene: String,
    /// `exact` or `two-interface` (the default, for JSON written before exact transport existed).
    #[serde(default = "two_interface")]
    pub transport: String,
    pub method: String,
    #[serde(default)]
    pub metric: Option<String>,
    pub level: u32,
    pub equivalent_res: u32,
    pub driven: String,
    pub photons: u64,
    /// Rays traced through the BVH in the last frame (exact transport only).
    #[serde(default)]
    pub rays_traced: Option<u64>,
    pub gpu_ms_median: f64,
    pub frame_ms_median: f64,
    // JSON has no NaN: serde_json writes it as null (no reference was used), and these read null back as NaN.
    #[serde(deserialize_with = "f64_or_nan")]
    pub rel_l1_64: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub rel_l1_256: f64,
    #[serde(deserialize_with = "f64_or_nan")]
    pub flux_ratio: f64,
    #[serde(default, deserialize_with = "f64_or_nan")]
    pub peak_offset_m: f64,
    #[serde(default)]
    pub extra: serde_json::Value,
}

fn two_interface() -> String {
    "two-interface".into()
}

fn f64_or_nan<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

impl BenchRow {
    /// The method as `caustics bench --methods` names it: `dense`, `max-level`, `max-error` (adaptive is implied
    /// by its metric); anything else as "method metric".
    pub fn method_label(&self) -> String {
        match (self.method.as_str(), &self.metric) {
            ("adaptive", Some(m)) => m.clone(),
            (method, Some(m)) => format!("{method} {m}"),
            (method, None) => method.to_string(),
        }
    }

    /// The plot series this row belongs to: "scene · transport method", e.g. "sphere · exact dense".
    pub fn series(&self) -> String {
        format!("{} · {} {}", self.scene, self.transport, self.method_label())
    }

    /// The series without its transport ("scene · method"): the plot gives it one colour, and a line style per
    /// transport.
    fn series_group(&self) -> String {
        format!("{} · {}", self.scene, self.method_label())
    }
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

/// A number with `prec` decimals, "–" when missing (NaN: no reference, or a value that does not exist), and
/// never "-0.0".
pub fn num(v: f64, prec: usize) -> String {
    if v.is_nan() {
        "–".to_string()
    } else {
        format!("{:.prec$}", v + 0.0)
    }
}

/// The row's traversal work-group side ("8x8"), "–" for dense (no traversal).
pub fn wg_label(r: &BenchRow) -> String {
    match (r.method.as_str(), r.extra.get("traverse_wg").and_then(|v| v.as_u64())) {
        ("adaptive", Some(w)) => format!("{w}x{w}"),
        _ => "–".to_string(),
    }
}

fn rays(r: &BenchRow) -> String {
    r.rays_traced.map_or_else(|| "–".to_string(), |n| n.to_string())
}

/// A GitHub-flavoured Markdown table of the rows, in their order.
pub fn markdown_table(rows: &[BenchRow]) -> String {
    let mut s = String::from(
        "| scene | transport | method | metric | level | eq. res | driven | wg | photons | rays traced | GPU ms | frame ms | rel-L1 64² | rel-L1 256² | flux ratio | peak offset (m) |\n\
         |---|---|---|---|--:|--:|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            cell(&r.scene),
            cell(&r.transport),
            cell(&r.method),
            cell(r.metric.as_deref().unwrap_or("–")),
            r.level,
            r.equivalent_res,
            cell(&r.driven),
            wg_label(r),
            r.photons,
            rays(r),
            num(r.gpu_ms_median, 3),
            num(r.frame_ms_median, 3),
            num(r.rel_l1_64, 4),
            num(r.rel_l1_256, 4),
            num(r.flux_ratio, 4),
            num(r.peak_offset_m, 4),
        ));
    }
    s
}

/// The rows grouped into plot series (in order of first appearance), each as (GPU ms, rel-L1 64²) points sorted
/// by time. Points that a log axis cannot show (non-finite or ≤ 0) are left out.
pub fn plot_series(rows: &[BenchRow]) -> Vec<(String, Vec<(f64, f64)>)> {
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    for r in rows {
        let (x, y) = (r.gpu_ms_median, r.rel_l1_64);
        if !(x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0) {
            continue;
        }
        let name = r.series();
        match series.iter_mut().find(|(n, _)| *n == name) {
            Some((_, pts)) => pts.push((x, y)),
            None => series.push((name, vec![(x, y)])),
        }
    }
    for (_, pts) in &mut series {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    series
}

/// Tableau-10: distinguishable on white, cycled when there are more series.
const COLORS: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// An axis label with three significant digits and no trailing zeros.
fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{v:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Axis key points 1, 2, 5 × 10^k inside `r`, so a log axis is labelled within a decade too.
fn key_points(r: &std::ops::Range<f64>) -> Vec<f64> {
    let mut out = Vec::new();
    let mut k = r.start.log10().floor() as i32;
    while 10f64.powi(k) <= r.end {
        for m in [1.0, 2.0, 5.0] {
            let v = m * 10f64.powi(k);
            if r.contains(&v) {
                out.push(v);
            }
        }
        k += 1;
    }
    out
}

fn log_range(values: impl Iterator<Item = f64>, default: (f64, f64)) -> std::ops::Range<f64> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        (lo, hi) = default;
    }
    // At least a factor 2 wide, padded by a quarter of a decade-ish on each side.
    if hi < lo * 2.0 {
        let m = (lo * hi).sqrt();
        (lo, hi) = (m / 1.5, m * 1.5);
    }
    lo / 1.25..hi * 1.25
}

/// A log-log SVG plot of rel-L1 at 64² (y) against median GPU ms (x), one line per (scene, transport, method,
/// metric): one colour per (scene, method, metric), solid for exact transport, dashed for two-interface.
pub fn svg_plot(rows: &[BenchRow], path: &Path) -> Result<()> {
    let svg = svg_string(rows).map_err(|e| Error::Failed(format!("{}: cannot draw the plot: {e}", path.display())))?;
    Ok(image_io::write_text(path, &svg)?)
}

/// The SVG text of [`svg_plot`].
pub fn svg_string(rows: &[BenchRow]) -> Result<String, Box<dyn std::error::Error>> {
    use plotters::prelude::*;
    let series = plot_series(rows);
    let xr = log_range(series.iter().flat_map(|s| s.1.iter().map(|p| p.0)), (0.1, 100.0));
    let yr = log_range(series.iter().flat_map(|s| s.1.iter().map(|p| p.1)), (1e-3, 1.0));
    let y_label = match rows.iter().find_map(|r| r.extra.get("reference_paths").and_then(|v| v.as_str())) {
        Some("all") => "rel-L1 at 64² vs the all-paths reference",
        Some("two-refractions") => "rel-L1 at 64² vs the two-refraction reference",
        _ => "rel-L1 at 64² vs reference",
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (960, 640)).into_drawing_area();
        root.fill(&WHITE)?;
        let caption = if series.is_empty() { "rel-L1 vs GPU time (no plottable rows)" } else { "rel-L1 vs GPU time" };
        let mut chart = ChartBuilder::on(&root)
            .caption(caption, ("sans-serif", 22))
            .margin(16)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(
                xr.clone().log_scale().with_key_points(key_points(&xr)),
                yr.clone().log_scale().with_key_points(key_points(&yr)),
            )?;
        chart
            .configure_mesh()
            .x_desc("GPU ms per frame (median)")
            .y_desc(y_label)
            .x_label_formatter(&|v| short(*v))
            .y_label_formatter(&|v| short(*v))
            .draw()?;
        let mut groups: Vec<String> = Vec::new();
        for (name, pts) in &series {
            let row = rows.iter().find(|r| r.series() == *name).expect("a series comes from a row");
            let group = row.series_group();
            let i = groups.iter().position(|g| *g == group).unwrap_or_else(|| {
                groups.push(group);
                groups.len() - 1
            });
            let (r, g, b) = COLORS[i % COLORS.len()];
            let color = RGBColor(r, g, b).to_rgba();
            let style = color.stroke_width(2);
            if row.transport == "two-interface" {
                chart
                    .draw_series(DashedLineSeries::new(pts.iter().copied(), 8, 5, style))?
                    .label(name.as_str())
                    .legend(move |(x, y)| {
                        plotters::element::DashedPathElement::new(vec![(x, y), (x + 20, y)], 6, 3, style)
                    });
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.stroke_width(2))))?;
            } else {
                chart
                    .draw_series(LineSeries::new(pts.iter().copied(), style))?
                    .label(name.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], style));
                chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
            }
        }
        if !series.is_empty() {
            chart
                .configure_series_labels()
                .position(SeriesLabelPosition::UpperRight)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
    }
    Ok(svg)
}

fn extra_f64(r: &BenchRow, key: &str) -> f64 {
    r.extra.get(key).and_then(|v| v.as_f64()).unwrap_or(f64::NAN)
}

/// The method and metric, "adaptive max-error" or "dense".
fn method_key(r: &BenchRow) -> String {
    match &r.metric {
        Some(m) => format!("{} {}", r.method, m),
        None => r.method.clone(),
    }
}

/// What the pivots match rows on besides scene and level: the transport, and the method and metric.
fn series_key(r: &BenchRow) -> (String, String) {
    (r.transport.clone(), method_key(r))
}

/// Whether the rows hold more than one transport (then the pivots name it beside the method).
fn several_transports(rows: &[BenchRow]) -> bool {
    rows.iter().any(|r| r.transport != rows[0].transport)
}

/// A pivot's method label: "adaptive max-error", or "exact adaptive max-error" when the rows mix transports.
fn shown_key(r: &BenchRow, with_transport: bool) -> String {
    if with_transport {
        format!("{} {}", r.transport, method_key(r))
    } else {
        method_key(r)
    }
}

/// Wyman & Nichols' Table 1 layout: photons splatted by each method at each equivalent grid, per scene, beside
/// the full grid (what a caustic map that emits every texel of its photon buffer would splat). Only the rows of
/// GPU-driven, default work-group runs are used (photon counts do not depend on either). Under exact transport a
/// photon is a light-space cell whose paths are traced (its rays are in the full table); when the rows mix
/// transports, each transport has its own columns.
pub fn photon_table(rows: &[BenchRow]) -> String {
    let with_t = several_transports(rows);
    let mut out = String::new();
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    for scene in scenes {
        let rs: Vec<&BenchRow> = rows.iter().filter(|r| r.scene == scene && r.driven == "gpu").collect();
        let mut methods: Vec<((String, String), String)> = Vec::new();
        let mut levels: Vec<u32> = Vec::new();
        for r in &rs {
            let k = series_key(r);
            if !methods.iter().any(|m| m.0 == k) {
                methods.push((k, shown_key(r, with_t)));
            }
            if !levels.contains(&r.level) {
                levels.push(r.level);
            }
        }
        levels.sort_unstable();
        out.push_str(&format!("\n**{scene}**: photons splatted\n\n| grid | full grid |"));
        for (_, label) in &methods {
            out.push_str(&format!(" {} |", cell(label)));
        }
        out.push_str("\n|--:|--:|");
        out.push_str(&"--:|".repeat(methods.len()));
        out.push('\n');
        for l in levels {
            let res = 64u64 << l;
            out.push_str(&format!("| {res}² | {} |", res * res));
            for (k, _) in &methods {
                match rs.iter().find(|r| r.level == l && series_key(r) == *k) {
                    Some(r) => out.push_str(&format!(" {} |", r.photons)),
                    None => out.push_str(" – |"),
                }
            }
            out.push('\n');
        }
    }
    out
}

/// GPU-driven against CPU-driven, per scene, transport, method and level: frame wall time, and the traversal
/// phase alone (traverse + stats + the CPU-driven host round trips, from `extra`).
pub fn driven_table(rows: &[BenchRow]) -> String {
    let with_t = several_transports(rows);
    let mut out = String::from(
        "| scene | method | level | photons | frame ms, GPU-driven | frame ms, CPU-driven | speedup | traversal ms, GPU-driven | traversal ms, CPU-driven | speedup | host readbacks (CPU-driven) |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    let phase = |r: &BenchRow| {
        extra_f64(r, "traverse_ms") + extra_f64(r, "stats_ms") + extra_f64(r, "host_roundtrip_ms").max(0.0)
    };
    for g in rows.iter().filter(|r| r.driven == "gpu") {
        let Some(c) = rows
            .iter()
            .find(|c| c.driven == "cpu" && c.scene == g.scene && c.level == g.level && series_key(c) == series_key(g))
        else {
            continue;
        };
        out.push_str(&format!(
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2}x | {:.2} | {:.2} | {:.2}x | {} |\n",
            cell(&g.scene),
            cell(&shown_key(g, with_t)),
            g.level,
            g.photons,
            g.frame_ms_median,
            c.frame_ms_median,
            c.frame_ms_median / g.frame_ms_median,
            phase(g),
            phase(c),
            phase(c) / phase(g),
            c.extra.get("host_readbacks_per_frame").and_then(|v| v.as_u64()).unwrap_or(0),
        ));
    }
    out
}

/// The traversal work-group sweep: per scene, transport, method and level, GPU frame ms and traversal ms for
/// each work-group side.
pub fn wg_table(rows: &[BenchRow]) -> String {
    let with_t = several_transports(rows);
    let mut wgs: Vec<u64> = rows.iter().filter_map(|r| r.extra.get("traverse_wg").and_then(|v| v.as_u64())).collect();
    wgs.sort_unstable();
    wgs.dedup();
    let mut out = String::from("| scene | method | level | photons |");
    for w in &wgs {
        out.push_str(&format!(" {w}x{w}: GPU ms (traverse ms) |"));
    }
    out.push_str("\n|---|---|--:|--:|");
    out.push_str(&"--:|".repeat(wgs.len()));
    out.push('\n');
    let mut seen: Vec<(String, (String, String), u32)> = Vec::new();
    for r in rows {
        let key = (r.scene.clone(), series_key(r), r.level);
        if seen.contains(&key) {
            continue;
        }
        seen.push(key.clone());
        out.push_str(&format!("| {} | {} | {} | {} |", cell(&key.0), cell(&shown_key(r, with_t)), key.2, r.photons));
        for w in &wgs {
            match rows.iter().find(|x| {
                x.scene == key.0
                    && series_key(x) == key.1
                    && x.level == key.2
                    && x.extra.get("traverse_wg").and_then(|v| v.as_u64()) == Some(*w)
            }) {
                Some(x) => out.push_str(&format!(" {:.2} ({:.2}) |", x.gpu_ms_median, extra_f64(x, "traverse_ms"))),
                None => out.push_str(" – |"),
            }
        }
        out.push('\n');
    }
    out
}

/// Exact transport against the two-interface model, per scene, method and level (same driven mode and
/// work-group size): what exact costs (GPU ms, rays traced) and what it buys (error and flux against the
/// reference the rows were scored with; with `--paths all`, ground truth).
pub fn transport_table(rows: &[BenchRow]) -> String {
    let mut out = String::from(
        "| scene | method | level | photons | rays traced (exact) | GPU ms, two-interface | GPU ms, exact | exact / two-interface | rel-L1 64², two-interface | rel-L1 64², exact | flux ratio, two-interface | flux ratio, exact |\n\
         |---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|\n",
    );
    let wg = |r: &BenchRow| r.extra.get("traverse_wg").and_then(|v| v.as_u64());
    for e in rows.iter().filter(|r| r.transport == "exact") {
        let Some(t) = rows.iter().find(|t| {
            t.transport == "two-interface"
                && t.scene == e.scene
                && t.level == e.level
                && t.driven == e.driven
                && method_key(t) == method_key(e)
                && wg(t) == wg(e)
        }) else {
            continue;
        };
        out.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {}x | {} | {} | {} | {} |\n",
            cell(&e.scene),
            cell(&e.method_label()),
            e.level,
            e.photons,
            rays(e),
            num(t.gpu_ms_median, 2),
            num(e.gpu_ms_median, 2),
            num(e.gpu_ms_median / t.gpu_ms_median, 2),
            num(t.rel_l1_64, 4),
            num(e.rel_l1_64, 4),
            num(t.flux_ratio, 4),
            num(e.flux_ratio, 4),
        ));
    }
    out
}

/// The reference's noise for a scene (half the rel-L1 64² between the reference's two halves), when the rows
/// carry it.
fn reference_noise(rows: &[BenchRow], scene: &str) -> Option<f64> {
    rows.iter()
        .filter(|r| r.scene == scene)
        .find_map(|r| r.extra.get("reference_noise").and_then(|v| v.get("rel_l1_64")).and_then(|v| v.as_f64()))
}

/// The fastest setting to each error: per scene and transport, the GPU-driven rows that no other row beats on
/// both GPU time and rel-L1 64² (the lower-left front of the error-against-time plot), fastest first. Beside each,
/// the fastest dense row that reaches its error, and how many times faster the row is ("–" where no dense row
/// reaches it). Errors within 0.1% of each other (the same image, summed in another order) are one error: only
/// the fastest of them is on the front. A front row whose error is below the previous one's by less than the
/// reference's noise is marked: every row is scored against the same reference, so the order may still hold,
/// but the reference alone cannot vouch for it.
pub fn front_table(rows: &[BenchRow]) -> String {
    const SAME_ERROR: f64 = 1e-3;
    let usable = |r: &&BenchRow| {
        r.driven == "gpu" && r.rel_l1_64.is_finite() && r.gpu_ms_median.is_finite() && r.gpu_ms_median > 0.0
    };
    let mut groups: Vec<(String, String)> = Vec::new();
    for r in rows.iter().filter(usable) {
        let g = (r.scene.clone(), r.transport.clone());
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    let mut out = String::new();
    for (scene, transport) in groups {
        let mut rs: Vec<&BenchRow> =
            rows.iter().filter(usable).filter(|r| r.scene == scene && r.transport == transport).collect();
        rs.sort_by(|a, b| a.gpu_ms_median.total_cmp(&b.gpu_ms_median).then(a.rel_l1_64.total_cmp(&b.rel_l1_64)));
        let noise = reference_noise(rows, &scene);
        out.push_str(&format!(
            "\n**{scene}** ({transport}): the fastest setting to each error\n\n\
             | setting | level | photons | rel-L1 64² | GPU ms | fastest dense to this error | faster than it | note |\n\
             |---|--:|--:|--:|--:|---|--:|---|\n"
        ));
        let mut best = f64::INFINITY;
        for r in rs.iter().copied() {
            if r.rel_l1_64 >= best * (1.0 - SAME_ERROR) {
                continue;
            }
            let dense = rs
                .iter()
                .filter(|d| d.method == "dense" && d.rel_l1_64 <= r.rel_l1_64 * (1.0 + SAME_ERROR))
                .min_by(|a, b| a.gpu_ms_median.total_cmp(&b.gpu_ms_median));
            let (dense_cell, speedup) = match dense {
                Some(d) => (
                    format!("dense L{} ({} ms)", d.level, num(d.gpu_ms_median, 2)),
                    format!("{}x", num(d.gpu_ms_median / r.gpu_ms_median, 2)),
                ),
                None => ("none reaches it".to_string(), "–".to_string()),
            };
            let note = match noise {
                Some(n) if best.is_finite() && best - r.rel_l1_64 < n => "within the noise of the row above",
                _ => "",
            };
            out.push_str(&format!(
                "| {} | {} | {} | {}% | {} | {} | {} | {} |\n",
                cell(&r.method_label()),
                r.level,
                r.photons,
                num(100.0 * r.rel_l1_64, 4),
                num(r.gpu_ms_median, 2),
                dense_cell,
                speedup,
                note
            ));
            best = r.rel_l1_64;
        }
    }
    out
}

/// Which CPU reference the rows' errors are measured against, in words, from their `extra.reference_paths`:
/// None when no row was scored.
pub fn reference_label(rows: &[BenchRow]) -> Option<String> {
    let paths: std::collections::BTreeSet<&str> = rows
        .iter()
        .filter(|r| r.rel_l1_64.is_finite())
        .filter_map(|r| r.extra.get("reference_paths").and_then(|v| v.as_str()))
        .collect();
    let name = |p: &str| match p {
        "all" => "every light path (`--paths all`: ground truth)".to_string(),
        "two-refractions" => {
            "light refracted exactly twice (`--paths two-refractions`: the two-interface model's own paths)".into()
        }
        p => format!("`--paths {p}`"),
    };
    match paths.len() {
        0 => None,
        1 => paths.first().map(|p| name(p)),
        _ => Some(format!("mixed: {}", paths.iter().map(|p| name(p)).collect::<Vec<_>>().join("; "))),
    }
}

/// Everything that applies to these rows: the full table, then the pivots. Every table's errors are against the
/// reference [`reference_label`] names, stated first.
pub fn markdown_report(rows: &[BenchRow]) -> String {
    let mut out = match reference_label(rows) {
        Some(l) => format!("Errors (rel-L1, flux ratio, peak offset) are against the CPU reference of {l}.\n\n"),
        None => "No reference: timings and photon counts only.\n\n".to_string(),
    };
    out.push_str(&markdown_table(rows));
    // The reference's own noise: every row's rel-L1 includes it, so errors well below it read as about the noise,
    // and their differences shrink.
    let mut noise: Vec<(String, f64)> = Vec::new();
    for r in rows {
        if let (Some(n), false) = (reference_noise(rows, &r.scene), noise.iter().any(|(s, _)| *s == r.scene)) {
            noise.push((r.scene.clone(), n));
        }
    }
    if !noise.is_empty() {
        let list: Vec<String> = noise.iter().map(|(s, n)| format!("{s} {:.4}%", 100.0 * n)).collect();
        out.push_str(&format!(
            "\nReference noise, rel-L1 64² (half the difference of the reference's two halves): {}. Every rel-L1 \
             above includes it: errors well below it read as about the noise, and their differences shrink.\n",
            list.join(", ")
        ));
    }
    if rows.iter().filter(|r| r.rel_l1_64.is_finite()).count() > 1 {
        out.push_str("\n### The fastest setting to each error (the plot's lower-left front)\n");
        out.push_str(&front_table(rows));
    }
    if rows.iter().any(|r| r.transport == "exact") && rows.iter().any(|r| r.transport == "two-interface") {
        out.push_str("\n### Exact transport against two-interface\n\n");
        out.push_str(&transport_table(rows));
    }
    let methods: std::collections::BTreeSet<(String, String)> = rows.iter().map(series_key).collect();
    if methods.len() > 1 {
        out.push_str("\n### Photons splatted (the layout of Wyman & Nichols' Table 1)\n");
        out.push_str(&photon_table(rows));
    }
    if rows.iter().any(|r| r.driven == "cpu") && rows.iter().any(|r| r.driven == "gpu") {
        out.push_str("\n### GPU-driven against CPU-driven\n\n");
        out.push_str(&driven_table(rows));
    }
    let wgs: std::collections::BTreeSet<u64> =
        rows.iter().filter_map(|r| r.extra.get("traverse_wg").and_then(|v| v.as_u64())).collect();
    if wgs.len() > 1 {
        out.push_str("\n### Traversal work-group size\n\n");
        out.push_str(&wg_table(rows));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(scene: &str, method: &str, metric: Option<&str>, level: u32, gpu: f64, err: f64) -> BenchRow {
        BenchRow {
            scene: scene.into(),
            transport: "two-interface".into(),
            method: method.into(),
            metric: metric.map(Into::into),
            level,
            equivalent_res: 64 << level,
            driven: "gpu".into(),
            photons: 4096 << (2 * level),
            rays_traced: None,
            gpu_ms_median: gpu,
            frame_ms_median: gpu * 1.5,
            rel_l1_64: err,
            rel_l1_256: err * 2.0,
            flux_ratio: 0.99,
            peak_offset_m: 0.01,
            extra: serde_json::json!({ "note": "made up" }),
        }
    }

    fn exact(mut r: BenchRow) -> BenchRow {
        r.transport = "exact".into();
        r.rays_traced = Some(3 * r.photons);
        r.gpu_ms_median *= 4.0;
        r.rel_l1_64 /= 2.0;
        r.flux_ratio = 1.0;
        r
    }

    fn rows() -> Vec<BenchRow> {
        vec![
            row("sphere", "dense", None, 3, 40.0, 0.05),
            row("sphere", "dense", None, 1, 5.0, 0.2),
            row("sphere", "adaptive", Some("max-error"), 3, 12.0, 0.06),
            row("sphere", "adaptive", Some("max-error"), 5, 30.0, 0.02),
            row("bunny", "adaptive", Some("max-level"), 4, 25.0, 0.08),
            row("bunny", "adaptive", Some("max-level"), 2, f64::NAN, 0.1),
        ]
    }

    #[test]
    fn table_has_a_line_per_row() {
        let t = markdown_table(&rows());
        let lines: Vec<&str> = t.lines().collect();
        assert_eq!(lines.len(), 2 + 6);
        assert!(lines[0].starts_with("| scene | transport | method | metric | level |"));
        assert_eq!(
            lines[2],
            "| sphere | two-interface | dense | – | 3 | 512 | gpu | – | 262144 | – | 40.000 | 60.000 | 0.0500 | 0.1000 | 0.9900 | 0.0100 |"
        );
        assert!(lines[4].contains("| two-interface | adaptive | max-error | 3 |"));
        let cols = lines[0].matches('|').count();
        assert!(lines.iter().all(|l| l.matches('|').count() == cols), "{t}");
    }

    #[test]
    fn rows_round_trip_through_json() {
        let mut r = rows();
        r[1] = exact(r[1].clone());
        let json = serde_json::to_string(&r[..5]).unwrap();
        assert!(json.contains(r#""transport":"exact""#) && json.contains(r#""rays_traced":49152"#), "{json}");
        assert!(json.contains(r#""rays_traced":null"#), "{json}");
        let back: Vec<BenchRow> = serde_json::from_str(&json).unwrap();
        assert_eq!(back, r[..5].to_vec());
        // Optional fields may be absent (rows written before exact transport existed are two-interface).
        let minimal = r#"{"scene":"s","method":"dense","level":0,"equivalent_res":64,"driven":"gpu","photons":1,
            "gpu_ms_median":1.0,"frame_ms_median":2.0,"rel_l1_64":0.1,"rel_l1_256":0.2,"flux_ratio":1.0}"#;
        let m: BenchRow = serde_json::from_str(minimal).unwrap();
        assert_eq!(
            (m.transport.as_str(), m.rays_traced, m.metric, m.peak_offset_m, m.extra),
            ("two-interface", None, None, 0.0, serde_json::Value::Null)
        );
    }

    #[test]
    fn series_group_and_sort_and_skip_unplottable_points() {
        let s = plot_series(&rows());
        let names: Vec<&str> = s.iter().map(|x| x.0.as_str()).collect();
        assert_eq!(
            names,
            ["sphere · two-interface dense", "sphere · two-interface max-error", "bunny · two-interface max-level"]
        );
        assert_eq!(s[0].1, vec![(5.0, 0.2), (40.0, 0.05)]);
        assert_eq!(s[2].1.len(), 1, "the NaN row is left out");
    }

    #[test]
    fn missing_values_are_dashes_and_zero_has_no_sign() {
        assert_eq!(num(f64::NAN, 4), "–");
        assert_eq!(num(-0.0, 1), "0.0");
        assert_eq!(num(0.12345, 3), "0.123");
    }

    #[test]
    fn transports_pair_up_in_their_pivot() {
        let mut rs = rows();
        rs.extend(rows().into_iter().map(exact));
        let t = transport_table(&rs);
        let lines: Vec<&str> = t.lines().collect();
        // One line per exact row with a two-interface twin (all six).
        assert_eq!(lines.len(), 2 + 6, "{t}");
        assert_eq!(
            lines[2],
            "| sphere | dense | 3 | 262144 | 786432 | 40.00 | 160.00 | 4.00x | 0.0500 | 0.0250 | 0.9900 | 1.0000 |"
        );
        assert!(lines[4].starts_with("| sphere | max-error | 3 |"), "{t}");
        let report = markdown_report(&rs);
        assert!(report.contains("### Exact transport against two-interface"));
        // The photon table names the transport beside the method when the rows mix them.
        assert!(report.contains(" exact dense | ") && report.contains(" two-interface dense | "), "{report}");
        // A single transport keeps the plain labels and has no transport pivot.
        let single = markdown_report(&rows());
        assert!(!single.contains("Exact transport against") && !single.contains("two-interface dense"), "{single}");
    }

    #[test]
    fn the_front_keeps_the_rows_nothing_beats_and_names_dense_at_their_error() {
        let mut rs = rows();
        rs.push(row("sphere", "adaptive", Some("max-error"), 4, 20.0, 0.055));
        // The same error as dense level 1 (summed in another order) and slower: not on the front.
        rs.push(row("sphere", "adaptive", Some("max-level"), 1, 5.1, 0.2 * (1.0 - 1e-9)));
        rs.push(row("sphere", "dense", None, 4, 35.0, 0.03));
        for r in rs.iter_mut().filter(|r| r.scene == "sphere") {
            r.extra = serde_json::json!({ "reference_noise": { "rel_l1_64": 0.015 } });
        }
        let t = front_table(&rs);
        let lines: Vec<&str> = t.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| setting")).collect();
        assert_eq!(
            lines,
            [
                // The fastest row is on the front, and is its own dense.
                "| dense | 1 | 16384 | 20.0000% | 5.00 | dense L1 (5.00 ms) | 1.00x |  |",
                // Dense level 4 (0.03, 35 ms) is the fastest dense row at or below 0.06 (level 3: 0.05, 40 ms).
                "| max-error | 3 | 262144 | 6.0000% | 12.00 | dense L4 (35.00 ms) | 2.92x |  |",
                // 0.005 below the previous front row, under the noise (0.015).
                "| max-error | 4 | 1048576 | 5.5000% | 20.00 | dense L4 (35.00 ms) | 1.75x | within the noise of the row above |",
                "| max-error | 5 | 4194304 | 2.0000% | 30.00 | none reaches it | – |  |",
                // Bunny: the row without a GPU time is left out.
                "| max-level | 4 | 1048576 | 8.0000% | 25.00 | none reaches it | – |  |",
            ],
            "{t}"
        );
        // Dense levels 3 and 4 (slower than max-error level 5 and worse) are not on the front.
        assert!(!t.contains("| dense | 3 |") && !t.contains("| dense | 4 |") && !t.contains("max-level | 1"), "{t}");
        assert!(t.contains("**sphere** (two-interface)") && t.contains("**bunny** (two-interface)"), "{t}");
        assert!(markdown_report(&rs).contains("### The fastest setting to each error"));
    }

    #[test]
    fn key_points_are_one_two_five() {
        assert_eq!(key_points(&(0.015..0.25)), vec![0.02, 0.05, 0.1, 0.2]);
        assert_eq!(key_points(&(3.0..60.0)), vec![5.0, 10.0, 20.0, 50.0]);
    }

    #[test]
    fn axis_labels_are_short() {
        assert_eq!(short(10.0), "10");
        assert_eq!(short(0.05), "0.05");
        assert_eq!(short(0.12345), "0.123");
        assert_eq!(short(1234.6), "1235");
        assert_eq!(short(2.5), "2.5");
    }

    #[test]
    fn svg_plot_writes_a_log_log_chart() {
        let dir = std::env::temp_dir().join(format!("caustics-bench-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("plot.svg");
        let mut rs = rows();
        rs.extend(rows().into_iter().map(exact));
        svg_plot(&rs, &path).unwrap();
        let svg = std::fs::read_to_string(&path).unwrap();
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        for label in [
            "sphere · two-interface dense",
            "sphere · exact dense",
            "sphere · two-interface max-error",
            "bunny · exact max-level",
            "GPU ms",
        ] {
            assert!(svg.contains(label), "missing {label}");
        }
        // No rows at all still gives a valid (empty) chart.
        svg_plot(&[], &path).unwrap();
        assert!(std::fs::read_to_string(&path).unwrap().contains("no plottable rows"));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
