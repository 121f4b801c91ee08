//! `caustics reference`: the exact CPU photon tracer, ground truth for the GPU renderer.
//!
//! What it computes, per camera pixel of a receiver surface (docs/design.md, "Ground truth and error"):
//! - Photons leave each light stratified: a jittered grid with exactly one photon per equal-area cell of the
//!   cone's (cos θ, φ) parametrization, which is uniform in solid angle, so each photon carries Φ = I·Ω/N (before
//!   the light color; image channel c carries Φ·color[c]). A directional light (intensity in W/m² across the beam)
//!   samples a rectangle of its beam in the same way, Φ = E·A/N, starting in front of all geometry.
//! - **Sub-cone sampling for `--aov caustics`.** A caustic photon must hit a refractor before anything else, so
//!   only the cone around the light's axis to the refractors that bounds every refractor vertex is sampled (a
//!   cone narrower than 90° is convex, so it holds every triangle too), and for a directional light only the
//!   rectangle of the beam that covers the refractors. Directions of that sub-cone outside the spot cone carry
//!   nothing. `--aov direct` samples the whole spot cone (or the beam rectangle over the whole scene). The stats'
//!   direct flux under `--aov caustics` therefore covers only the sub-cone.
//! - Every triangle of every object, in world space, in one BVH, with the GPU's barycentric-interpolated vertex
//!   normals ([`geometry`]). Ray/triangle tests are watertight, in f64.
//! - At a dielectric (exterior IOR 1.0): exact Snell refraction, exact unpolarized Fresnel, total internal
//!   reflection, any number of interfaces. Reflect or refract is chosen by Russian roulette with probability F,
//!   so a photon's flux never changes and the energy account closes exactly. Which side is inside comes from the
//!   geometric normal (outward winding); F and the new direction come from the interpolated normal, unless it
//!   faces away from the ray or would send the photon to the wrong side of the surface, where the geometric
//!   normal is used instead (counted in the stats). Overlapping refractors are not modelled as nested media:
//!   every interface is between IOR 1.0 and the object's IOR.
//! - A photon stops at its first diffuse hit. `caustics` collects photons with at least one specular interaction
//!   before it, `direct` those with none. `--paths two-refractions` keeps only the caustic photons refracted exactly
//!   twice (in, then out, no reflection); the other caustic photons are counted as filtered. Direct photons are
//!   never filtered.
//! - After [`BOUNCE_CAP`] specular interactions a photon that meets another refractor is cut (counted).
//! - Binning, orthographic cameras only: E = Σ Φ / A per pixel, with A the receiver area the pixel covers, the
//!   pixel's area divided by |n · forward| (n: the receiver's geometric normal). Refractors hide nothing, but a
//!   receiver hidden from the camera by another receiver is not binned (a ray toward the camera through the
//!   receivers only), and nor is a photon on the side of a receiver the camera does not see.
//! - Determinism: each photon's random numbers are a function of (seed, light, photon index), photons are traced
//!   in fixed chunks and reduced in chunk order, so a seed gives a bit-identical image for any thread count.

pub mod cache;
mod geometry;
pub mod optics;
pub mod sampling;
mod tracer;

pub use cache::{cache_dir, cache_key, cached, cached_in};
pub use tracer::Tally;

use crate::error::{AppError, AppResult};
use crate::image_io::{self, RgbImage};
use crate::scene::{CameraView, LightKind, LightView, Projection, Scene};
use crate::settings::parse_size;
use geometry::Geometry;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use sampling::{frame, Emission, Strata};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::Instant;
use tracer::{Binner, LightSetup, Tracer};

/// The most specular interactions a photon may have; one more refractor hit cuts it.
pub const BOUNCE_CAP: u32 = 32;

/// Photons per work chunk: the unit of parallelism and of the fixed-order reduction.
const CHUNK: u64 = 4096;
/// Chunks traced in parallel before their results are reduced (bounds the memory held by deposits).
const BATCH: usize = 64;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    Caustics,
    Direct,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Paths {
    All,
    TwoRefractions,
}

impl FromStr for Aov {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "caustics" => Ok(Aov::Caustics),
            "direct" => Ok(Aov::Direct),
            _ => Err(format!("--aov: expected `caustics` or `direct`, got `{s}`")),
        }
    }
}

impl fmt::Display for Aov {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Aov::Caustics => "caustics",
            Aov::Direct => "direct",
        })
    }
}

impl FromStr for Paths {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "all" => Ok(Paths::All),
            "two-refractions" => Ok(Paths::TwoRefractions),
            _ => Err(format!("--paths: expected `all` or `two-refractions`, got `{s}`")),
        }
    }
}

impl fmt::Display for Paths {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(match self {
            Paths::All => "all",
            Paths::TwoRefractions => "two-refractions",
        })
    }
}

/// Parameters of one reference run (the library form of `caustics reference`).
#[derive(Clone, Debug)]
pub struct RefParams {
    /// Camera name; `None` for the scene's first camera. Must be orthographic.
    pub camera: Option<String>,
    pub aov: Aov,
    pub paths: Paths,
    /// Photons drawn per light.
    pub photons: u64,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    /// Worker threads; `None` for rayon's global pool. The image does not depend on it.
    pub threads: Option<usize>,
    /// Show a progress bar on stderr (only drawn when stderr is a terminal).
    pub progress: bool,
    /// When set, the output keeps a radial profile of the selected AOV's deposited flux around this point.
    pub radial_center: Option<Vec3>,
}

impl Default for RefParams {
    fn default() -> Self {
        RefParams {
            camera: None,
            aov: Aov::Caustics,
            paths: Paths::All,
            photons: 1_000_000,
            width: 512,
            height: 512,
            seed: 1,
            threads: None,
            progress: false,
            radial_center: None,
        }
    }
}

/// How one light was sampled.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LightInfo {
    pub kind: String,
    /// "spot cone", "refractor sub-cone", "beam over refractors", "beam over scene", or "none".
    pub sampling: String,
    /// Half-angle of the sampled cone (degrees), for spot lights.
    pub half_angle_deg: Option<f64>,
    /// Solid angle (sr) of the sampled cone, or area (m²) of the sampled beam rectangle.
    pub measure: f64,
    pub photons: u64,
    /// Flux of each photon, W, before the light color.
    pub flux_per_photon: f64,
    pub color: [f64; 3],
}

/// Where the emitted flux went (W, before light color). `emitted = deposited_caustics + deposited_direct +
/// escaped + cut_by_bounce_cap + filtered_by_paths + lost + absorbed`; `residual_rel` is the relative mismatch.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EnergyAccount {
    pub emitted: f64,
    pub deposited_caustics: f64,
    pub deposited_direct: f64,
    pub escaped: f64,
    pub cut_by_bounce_cap: f64,
    pub filtered_by_paths: f64,
    pub lost: f64,
    /// Absorbed inside glass.
    #[serde(default)]
    pub absorbed: f64,
    pub residual_rel: f64,
    /// Flux of the selected AOV binned into the image, and Σ E · pixel area over the image.
    pub aov_in_image: f64,
    pub image_integral: f64,
}

/// The flux-weighted radial distribution of the selected AOV's deposits around a center.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RadialStats {
    pub center: [f32; 3],
    pub flux: f64,
    /// Radii (m) within which 50% and 90% of that flux lands.
    pub r50: Option<f64>,
    pub r90: Option<f64>,
}

/// The stats written by `--stats`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RefStats {
    pub scene: String,
    pub camera: String,
    pub aov: Aov,
    pub paths: Paths,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
    pub photons_per_light: u64,
    pub threads: usize,
    pub triangles: usize,
    pub bvh_build_s: f64,
    pub trace_s: f64,
    pub wall_s: f64,
    /// Photons drawn (all lights) per second of tracing.
    pub photons_per_s: f64,
    pub bounce_cap: u32,
    pub lights: Vec<LightInfo>,
    pub energy_account: EnergyAccount,
    pub counts: Tally,
    pub radial: Option<RadialStats>,
}

/// A log-binned, flux-weighted histogram of distances: 0.05% relative resolution from 1 µm to 100 m.
#[derive(Clone, Debug)]
pub struct RadialProfile {
    pub center: Vec3,
    bins: Vec<f64>,
    total: f64,
}

const RADIAL_MIN: f64 = 1e-6;
const RADIAL_STEP: f64 = 1.0005;

impl RadialProfile {
    fn new(center: Vec3) -> Self {
        let n = ((100.0 / RADIAL_MIN).ln() / RADIAL_STEP.ln()).ceil() as usize + 2;
        RadialProfile { center, bins: vec![0.0; n], total: 0.0 }
    }

    fn add(&mut self, r: f64, flux: f64) {
        let i = if r < RADIAL_MIN { 0 } else { 1 + ((r / RADIAL_MIN).ln() / RADIAL_STEP.ln()) as usize };
        let last = self.bins.len() - 1;
        self.bins[i.min(last)] += flux;
        self.total += flux;
    }

    pub fn total_flux(&self) -> f64 {
        self.total
    }

    /// The radius within which `fraction` of the flux lands (interpolated within a bin), if any flux landed.
    pub fn radius_containing(&self, fraction: f64) -> Option<f64> {
        if self.total <= 0.0 {
            return None;
        }
        let target = fraction.clamp(0.0, 1.0) * self.total;
        let mut acc = 0.0;
        for (i, &b) in self.bins.iter().enumerate() {
            if b > 0.0 && acc + b >= target {
                let (lo, hi) = if i == 0 {
                    (0.0, RADIAL_MIN)
                } else {
                    (RADIAL_MIN * RADIAL_STEP.powi(i as i32 - 1), RADIAL_MIN * RADIAL_STEP.powi(i as i32))
                };
                return Some(lo + (hi - lo) * ((target - acc) / b).clamp(0.0, 1.0));
            }
            acc += b;
        }
        None
    }
}

/// The result of [`trace`].
#[derive(Clone, Debug)]
pub struct RefOutput {
    /// RGB irradiance, W/m² (E · light color per channel).
    pub image: RgbImage,
    pub stats: RefStats,
    /// Present when [`RefParams::radial_center`] was set.
    pub radial: Option<RadialProfile>,
}

fn orthographic_camera<'a>(scene: &'a Scene, name: Option<&str>) -> AppResult<&'a crate::scene::Camera> {
    let camera = scene.camera(name).map_err(AppError::BadInput)?;
    if let Projection::Perspective { .. } = camera.projection {
        let ortho: Vec<&str> = scene
            .cameras
            .iter()
            .filter(|c| matches!(c.projection, Projection::Orthographic { .. }))
            .map(|c| c.name.as_str())
            .collect();
        let usable = if ortho.is_empty() {
            "the scene has no orthographic camera: add one (docs/scenes.md)".to_string()
        } else {
            format!("use --camera {}", ortho.join(" or --camera "))
        };
        return Err(AppError::BadInput(format!(
            "{}: camera `{}` is perspective; the reference bins into orthographic cameras only ({usable})",
            scene.path.display(),
            camera.name
        )));
    }
    Ok(camera)
}

/// The cone from `apex` around the refractor vertices: (axis, cosine of the half-angle), or `None` when it
/// would reach 90° or more (a vertex beside or behind the apex).
fn bounding_cone(apex: DVec3, points: &[DVec3]) -> Option<(DVec3, f64)> {
    let mut sum = DVec3::ZERO;
    let mut dirs = Vec::with_capacity(points.len());
    for &p in points {
        let d = (p - apex).normalize_or_zero();
        if d == DVec3::ZERO {
            return None;
        }
        sum += d;
        dirs.push(d);
    }
    let axis = sum.normalize_or_zero();
    if axis == DVec3::ZERO {
        return None;
    }
    let cos_min = dirs.iter().map(|d| d.dot(axis)).fold(1.0f64, f64::min);
    if cos_min <= 1e-3 {
        return None;
    }
    // A little margin against rounding: the cone must contain every vertex.
    Some((axis, (cos_min.clamp(-1.0, 1.0).acos() + 1e-7).cos()))
}

fn light_setups(scene: &Scene, p: &RefParams) -> Vec<(LightSetup, LightInfo)> {
    let refractor_pts: Vec<DVec3> =
        scene.refractors().flat_map(|o| o.mesh.positions.iter().map(|v| v.as_dvec3())).collect();
    let all_pts: Vec<DVec3> =
        scene.objects.iter().flat_map(|o| o.mesh.positions.iter().map(|v| v.as_dvec3())).collect();
    let caustics_only = p.aov == Aov::Caustics;
    scene
        .lights
        .iter()
        .map(|light| {
            let (right, down, fwd) = LightView::basis(light);
            let (right, down, fwd) = (right.as_dvec3(), down.as_dvec3(), fwd.as_dvec3());
            let pos = light.position.as_dvec3();
            let color = light.color.as_dvec3().to_array();
            let none = |kind: &str| {
                let info = LightInfo {
                    kind: kind.into(),
                    sampling: "none".into(),
                    half_angle_deg: None,
                    measure: 0.0,
                    photons: 0,
                    flux_per_photon: 0.0,
                    color,
                };
                (LightSetup { emission: None, strata: Strata::new(1), photons: 0, phi: 0.0, color }, info)
            };
            let (emission, sampling, half) = match light.kind {
                LightKind::Spot | LightKind::Point => {
                    if caustics_only && refractor_pts.is_empty() {
                        return none(if light.kind == LightKind::Spot { "spot" } else { "point" });
                    }
                    // A point light is a spot light whose cone is the whole sphere.
                    let cos_spot = if light.kind == LightKind::Point { -1.0 } else { (light.cone as f64).cos() };
                    let sub = if caustics_only { bounding_cone(pos, &refractor_pts) } else { None };
                    let (axis, u, v, cos_half, sampling) = match sub {
                        Some((axis, cos_half)) if cos_half > cos_spot => {
                            let (u, v) = frame(axis);
                            (axis, u, v, cos_half, "refractor sub-cone")
                        }
                        _ if light.kind == LightKind::Point => (fwd, right, down, cos_spot, "sphere"),
                        _ => (fwd, right, down, cos_spot, "spot cone"),
                    };
                    let e = Emission::Cone { origin: pos, u, v, axis, cos_half, spot_axis: fwd, cos_spot };
                    (e, sampling, Some(cos_half.acos().to_degrees()))
                }
                LightKind::Directional => {
                    let pts = if caustics_only { &refractor_pts } else { &all_pts };
                    if pts.is_empty() {
                        return none("directional");
                    }
                    let proj = |a: DVec3| pts.iter().map(move |&q| (q - pos).dot(a));
                    let (x0, x1) =
                        (proj(right).fold(f64::INFINITY, f64::min), proj(right).fold(f64::NEG_INFINITY, f64::max));
                    let (y0, y1) =
                        (proj(down).fold(f64::INFINITY, f64::min), proj(down).fold(f64::NEG_INFINITY, f64::max));
                    let depth0 = all_pts.iter().map(|&q| (q - pos).dot(fwd)).fold(f64::INFINITY, f64::min);
                    let pad = 1e-6 * (1.0 + (x1 - x0).max(y1 - y0));
                    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
                    let corner = pos + right * x0 + down * y0 + fwd * (depth0 - 1e-3 - pad);
                    let e = Emission::Beam { corner, eu: right * (x1 - x0), ev: down * (y1 - y0), dir: fwd };
                    (e, if caustics_only { "beam over refractors" } else { "beam over scene" }, None)
                }
            };
            let measure = emission.measure();
            let phi = light.intensity as f64 * measure / p.photons as f64;
            let kind = match light.kind {
                LightKind::Spot => "spot",
                LightKind::Directional => "directional",
                LightKind::Point => "point",
            };
            let info = LightInfo {
                kind: kind.into(),
                sampling: sampling.into(),
                half_angle_deg: half,
                measure,
                photons: p.photons,
                flux_per_photon: phi,
                color,
            };
            (
                LightSetup { emission: Some(emission), strata: Strata::new(p.photons), photons: p.photons, phi, color },
                info,
            )
        })
        .collect()
}

fn progress_bar(total: u64, show: bool) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !show || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(total);
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{bar:40} {human_pos}/{human_len} photons  {per_sec}  eta {eta}")
    {
        bar.set_style(style);
    }
    bar
}

struct Reduced {
    tally: Tally,
    image: Vec<[f64; 3]>,
    radial: Option<RadialProfile>,
    threads: usize,
}

fn run_chunks(
    tracer: &Tracer,
    chunks: &[(usize, u64, u64)],
    pixels: usize,
    radial: Option<Vec3>,
    bar: &indicatif::ProgressBar,
) -> Reduced {
    let mut tally = Tally::default();
    let mut image = vec![[0.0f64; 3]; pixels];
    let mut profile = radial.map(RadialProfile::new);
    for batch in chunks.chunks(BATCH) {
        let outs: Vec<_> = batch
            .par_iter()
            .map(|&(li, s, e)| {
                let out = tracer.chunk(li, s, e);
                bar.inc(e - s);
                out
            })
            .collect();
        // Fixed-order reduction: chunk by chunk, deposit by deposit.
        for out in outs {
            tally.add(&out.tally);
            for d in &out.deposits {
                let c = tracer.lights[d.light as usize].color;
                let px = &mut image[d.pixel as usize];
                if d.channel < 3 {
                    let k = d.channel as usize;
                    px[k] += 3.0 * d.e * c[k];
                } else {
                    for k in 0..3 {
                        px[k] += d.e * c[k];
                    }
                }
            }
            if let Some(p) = profile.as_mut() {
                for &(r, f) in &out.radial {
                    p.add(r, f);
                }
            }
        }
    }
    Reduced { tally, image, radial: profile, threads: rayon::current_num_threads() }
}

/// Trace photons through `scene` and bin them into the orthographic camera's image.
pub fn trace(scene: &Scene, p: &RefParams) -> AppResult<RefOutput> {
    let start = Instant::now();
    if p.photons == 0 {
        return Err(AppError::BadInput("--photons: must be at least 1".into()));
    }
    if p.width == 0 || p.height == 0 {
        return Err(AppError::BadInput("--size: width and height must be at least 1".into()));
    }
    let camera = orthographic_camera(scene, p.camera.as_deref())?;
    let view = CameraView::new(camera, p.width, p.height, scene.bounds());
    let geo = Geometry::new(scene);
    let bvh_build_s = start.elapsed().as_secs_f64();
    let (lights, infos): (Vec<_>, Vec<_>) = light_setups(scene, p).into_iter().unzip();
    let chunks: Vec<(usize, u64, u64)> = lights
        .iter()
        .enumerate()
        .flat_map(|(li, l)| {
            (0..l.photons.div_ceil(CHUNK)).map(move |c| (li, c * CHUNK, ((c + 1) * CHUNK).min(l.photons)))
        })
        .collect();
    let total: u64 = lights.iter().map(|l| l.photons).sum();
    let tracer = Tracer::new(scene, &geo, lights, Binner::new(view), p);
    let bar = progress_bar(total, p.progress);
    let trace_start = Instant::now();
    let pixels = (p.width * p.height) as usize;
    let reduced = match p.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| AppError::Failed(format!("cannot start {n} worker threads: {e}")))?
            .install(|| run_chunks(&tracer, &chunks, pixels, p.radial_center, &bar)),
        None => run_chunks(&tracer, &chunks, pixels, p.radial_center, &bar),
    };
    bar.finish_and_clear();
    let trace_s = trace_start.elapsed().as_secs_f64();
    let image = RgbImage {
        width: p.width,
        height: p.height,
        data: reduced.image.iter().map(|px| px.map(|v| v as f32)).collect(),
    };
    let t = &reduced.tally;
    let energy_account = EnergyAccount {
        emitted: t.flux_emitted,
        deposited_caustics: t.flux_caustics,
        deposited_direct: t.flux_direct,
        escaped: t.flux_escaped,
        cut_by_bounce_cap: t.flux_cut,
        filtered_by_paths: t.flux_filtered,
        lost: t.flux_lost,
        absorbed: t.flux_absorbed,
        residual_rel: t.account_residual(),
        aov_in_image: t.flux_in_image,
        image_integral: t.image_flux,
    };
    let radial = reduced.radial.as_ref().map(|r| RadialStats {
        center: r.center.to_array(),
        flux: r.total_flux(),
        r50: r.radius_containing(0.5),
        r90: r.radius_containing(0.9),
    });
    let stats = RefStats {
        scene: scene.path.display().to_string(),
        camera: camera.name.clone(),
        aov: p.aov,
        paths: p.paths,
        width: p.width,
        height: p.height,
        seed: p.seed,
        photons_per_light: p.photons,
        threads: reduced.threads,
        triangles: geo.triangle_count(),
        bvh_build_s,
        trace_s,
        wall_s: start.elapsed().as_secs_f64(),
        photons_per_s: if trace_s > 0.0 { total as f64 / trace_s } else { 0.0 },
        bounce_cap: BOUNCE_CAP,
        lights: infos,
        energy_account,
        counts: reduced.tally.clone(),
        radial,
    };
    Ok(RefOutput { image, stats, radial: reduced.radial })
}

/// `caustics reference` arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct ReferenceArgs {
    /// Scene file (default: assets/scenes/sphere.toml).
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
    /// Output size WxH.
    #[arg(long, default_value = "512x512")]
    pub size: String,
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
    /// Also report the radii holding 50% and 90% of the AOV's flux around this point, "x,y,z".
    #[arg(long)]
    pub radial_center: Option<String>,
}

fn parse_vec3(s: &str, flag: &str) -> AppResult<Vec3> {
    let v: Vec<f32> =
        s.split(',').map(|x| x.trim().parse::<f32>()).collect::<Result<_, _>>().map_err(|_| {
            AppError::BadInput(format!("{flag}: expected three comma-separated numbers x,y,z, got `{s}`"))
        })?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vec3::new(*x, *y, *z)),
        _ => Err(AppError::BadInput(format!("{flag}: expected three finite numbers x,y,z, got `{s}`"))),
    }
}

impl ReferenceArgs {
    /// Validate the arguments into [`RefParams`] (bad values are [`AppError::BadInput`] naming the flag).
    pub fn params(&self) -> AppResult<RefParams> {
        let (width, height) = parse_size(&self.size, "--size")?;
        if self.photons == 0 {
            return Err(AppError::BadInput("--photons: must be at least 1".into()));
        }
        if self.threads == Some(0) {
            return Err(AppError::BadInput("--threads: must be at least 1".into()));
        }
        Ok(RefParams {
            camera: self.camera.clone(),
            aov: self.aov.parse().map_err(AppError::BadInput)?,
            paths: self.paths.parse().map_err(AppError::BadInput)?,
            photons: self.photons,
            width,
            height,
            seed: self.seed,
            threads: self.threads,
            progress: true,
            radial_center: self.radial_center.as_deref().map(|s| parse_vec3(s, "--radial-center")).transpose()?,
        })
    }
}

fn check_output(path: &Path, flag: &str, ext: &str) -> AppResult<()> {
    if path.extension().and_then(|e| e.to_str()).map(|e| e.eq_ignore_ascii_case(ext)) != Some(true) {
        return Err(AppError::BadInput(format!("{flag}: {} must end in .{ext}", path.display())));
    }
    image_io::check_output_dir(path).map_err(|e| AppError::BadInput(format!("{flag}: {e}")))
}

/// `caustics reference`.
pub fn run(args: &ReferenceArgs) -> AppResult<()> {
    let params = args.params()?;
    check_output(&args.out, "--out", "exr")?;
    if let Some(s) = &args.stats {
        check_output(s, "--stats", "json")?;
    }
    let scene_path = args.scene.clone().unwrap_or_else(crate::commands::default_scene);
    let scene = Scene::load(&scene_path)?;
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
    image_io::write_exr_meta(&args.out, &out.image, &meta)?;
    if let Some(s) = &args.stats {
        let json = serde_json::to_string_pretty(&out.stats).map_err(|e| AppError::Failed(e.to_string()))?;
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
