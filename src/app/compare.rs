//! `caustics compare A.exr B.exr`: the project's error metric on two images, with thresholds that fail the
//! command.

use caustics::error::{Error, Result};
use caustics::image_io;
use caustics::metrics::{check_pair, compare, max_comparison_res, Metrics};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// `caustics compare A.exr B.exr`: A is the image under test, B the reference.
#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    /// Image under test (EXR).
    pub a: PathBuf,
    /// Reference image (EXR).
    pub b: PathBuf,
    /// Comparison resolution for the peak offset and the thresholds (rel-L1 is also printed at 64² and 256², where
    /// the images are that wide or wider).
    /// [default: 64, or the images' width where they are narrower]
    #[arg(long)]
    pub res: Option<u32>,
    /// Physical width of the images in meters (2.0 for the canonical `top` camera).
    #[arg(long, default_value_t = 2.0)]
    pub extent: f32,
    /// Fail (exit 1) when rel-L1 at --res is above this.
    #[arg(long)]
    pub max_rel_l1: Option<f64>,
    /// Fail (exit 1) when the flux ratio is below this.
    #[arg(long)]
    pub min_flux_ratio: Option<f64>,
    /// Fail (exit 1) when the flux ratio is above this.
    #[arg(long)]
    pub max_flux_ratio: Option<f64>,
    /// Print the result as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

/// What `caustics compare --json` prints.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct CompareReport {
    pub a: String,
    pub b: String,
    /// Null where the images are narrower than 64 (or 256) pixels: a comparison finer than the images is not made.
    pub rel_l1_64: Option<f64>,
    pub rel_l1_256: Option<f64>,
    /// How periodic the residual is at 256² (`metrics::periodic_share`; null for images narrower than 256).
    pub periodic_share_256: Option<f64>,
    /// The metrics at `--res`, on which the thresholds act.
    pub at_res: Metrics,
    pub extent_m: f32,
    pub failures: Vec<String>,
}

pub fn run_compare(args: &CompareArgs) -> Result<()> {
    if args.res == Some(0) {
        return Err(Error::BadInput("--res: must be at least 1".into()));
    }
    if !(args.extent.is_finite() && args.extent > 0.0) {
        return Err(Error::BadInput(format!("--extent: must be a positive width in meters, got {}", args.extent)));
    }
    let (a, meta_a) = image_io::read_exr_meta(&args.a)?;
    let (b, meta_b) = image_io::read_exr_meta(&args.b)?;
    check_pair(&args.a, &a, &meta_a, &args.b, &b, &meta_b)?;
    let sizes =
        format!("{} is {}x{}, {} is {}x{}", args.a.display(), a.width, a.height, args.b.display(), b.width, b.height);
    let (ra, rb) = (a.width as f64 / a.height as f64, b.width as f64 / b.height as f64);
    if ((ra - rb) / rb).abs() > 1e-3 {
        return Err(Error::BadInput(format!("{sizes}: the aspect ratios differ")));
    }
    if (a.width, a.height) != (b.width, b.height) {
        log::warn!("{sizes}: both are box-filtered to the comparison sizes, which only go up to the smaller image");
    }
    // Only the resolutions both images can carry: filtering an image up to a finer grid than its own pixels would
    // measure the filter, not the images (a 64² pair "compared at 256²" reads many times its real error).
    let carried = max_comparison_res(&a, &b);
    let res = args.res.unwrap_or(64.min(carried));
    if res > carried {
        return Err(Error::BadInput(format!("--res {res}: above what the images carry ({carried} columns; {sizes})")));
    }
    let m64 = (carried >= 64).then(|| compare(&a, &b, 64, args.extent));
    let m256 = (carried >= 256).then(|| compare(&a, &b, 256, args.extent));
    let periodic = (carried >= 256).then(|| caustics::metrics::periodic_share(&a, &b, 256));
    let m = compare(&a, &b, res, args.extent);
    let mut failures = Vec::new();
    // A NaN fails every threshold.
    let above = |v: f64, max: f64| v.is_nan() || v > max;
    let below = |v: f64, min: f64| v.is_nan() || v < min;
    if let Some(x) = args.max_rel_l1 {
        if above(m.rel_l1, x) {
            failures.push(format!("rel-L1 at {}² is {:.6}, above --max-rel-l1 {x}", m.res, m.rel_l1));
        }
    }
    if let Some(x) = args.min_flux_ratio {
        if below(m.flux_ratio, x) {
            failures.push(format!("flux ratio {:.6} is below --min-flux-ratio {x}", m.flux_ratio));
        }
    }
    if let Some(x) = args.max_flux_ratio {
        if above(m.flux_ratio, x) {
            failures.push(format!("flux ratio {:.6} is above --max-flux-ratio {x}", m.flux_ratio));
        }
    }
    if args.json {
        let report = CompareReport {
            a: args.a.display().to_string(),
            b: args.b.display().to_string(),
            rel_l1_64: m64.map(|m| m.rel_l1),
            rel_l1_256: m256.map(|m| m.rel_l1),
            periodic_share_256: periodic,
            at_res: m,
            extent_m: args.extent,
            failures: failures.clone(),
        };
        println!("{}", serde_json::to_string_pretty(&report).map_err(|e| Error::Failed(e.to_string()))?);
    } else {
        for (label, m) in [("rel-L1 (64²): ", m64), ("rel-L1 (256²):", m256)] {
            match m {
                Some(m) => println!("{label} {:.6}", m.rel_l1),
                None => println!("{label} – (finer than the images: {carried} columns)"),
            }
        }
        if let Some(p) = periodic {
            println!("periodic share of the residual (256²): {p:.4}");
        }
        if ![64, 256].contains(&m.res) {
            println!("rel-L1 ({}²): {:.6}", m.res, m.rel_l1);
        }
        println!("flux ratio:    {:.6}", m.flux_ratio);
        println!("peak offset:   {:.4} m (at {}²)", m.peak_offset_m, m.res);
    }
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::Failed(format!("{} vs {}: {}", args.a.display(), args.b.display(), failures.join("; "))))
    }
}
