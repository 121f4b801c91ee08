//! `caustics reference`: the exact CPU photon tracer, ground truth for the GPU renderer.
//!
//! What it computes, per camera pixel of a receiver surface (docs/design.md, "Ground truth and error"):
//! - Photons leave each light stratified: a jittered grid with exactly one photon per equal-area cell of the
//!   cone's (cos θ, φ) parametrization, which is uniform in solid angle, so each photon carries Φ = I·Ω/N (before
//!   the light color; image channel c carries Φ·color\[c\]). A directional light (intensity in W/m² across the beam)
//!   samples a rectangle of its beam in the same way, Φ = E·A/N, starting in front of all geometry.
//! - **Sub-cone sampling for `--aov caustics`.** A caustic photon must hit a refractor before anything else, so
//!   only the cone around the light's axis to the refractors that bounds every refractor vertex is sampled (a
//!   cone narrower than 90° is convex, so it holds every triangle too), and for a directional light only the
//!   rectangle of the beam that covers the refractors. Directions of that sub-cone outside the spot cone carry
//!   nothing. `--aov direct` samples the whole spot cone (or the beam rectangle over the whole scene). The stats'
//!   direct flux under `--aov caustics` therefore covers only the sub-cone.
//! - Every triangle of every object, in world space, in one BVH, with the GPU's barycentric-interpolated vertex
//!   normals (the geometry module). Ray/triangle tests are watertight, in f64.
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

mod cache;
mod geometry;
mod optics;
mod sampling;
mod tracer;

pub use cache::{cache_dir_from_env, cache_key, cached_in};
pub use tracer::Tally;

use crate::error::{Error, Result};
use crate::image_io::RgbImage;
use crate::scene::{CameraView, LightKind, LightView, Projection, Scene};
use geometry::Geometry;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use sampling::{frame, Emission, Strata};
use serde::{Deserialize, Serialize};
use std::fmt;
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
/// Which light the reference bins.
pub enum Aov {
    /// Light that met at least one specular interaction before the receiver.
    Caustics,
    /// Light that reached the receiver directly.
    Direct,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
/// Which caustic paths the reference keeps.
pub enum Paths {
    /// Every path.
    All,
    /// Light refracted exactly twice, with no reflection (what the two-interface model computes).
    TwoRefractions,
}

impl FromStr for Aov {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "caustics" => Ok(Aov::Caustics),
            "direct" => Ok(Aov::Direct),
            _ => Err(format!("AOV `{s}`: expected `caustics` or `direct`")),
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
            _ => Err(format!("paths `{s}`: expected `all` or `two-refractions`")),
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
    /// Caustics or direct.
    pub aov: Aov,
    /// Which paths.
    pub paths: Paths,
    /// Photons drawn per light.
    pub photons: u64,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Random seed (the same seed gives a bit-identical image on any number of threads).
    pub seed: u64,
    /// Worker threads; `None` for rayon's global pool. The image does not depend on it.
    pub threads: Option<usize>,
    /// Called as photons are traced, with (photons traced so far, photons in all), for a progress display.
    pub progress: Option<Progress>,
    /// When set, the output keeps a radial profile of the selected AOV's deposited flux around this point.
    pub radial_center: Option<Vec3>,
    /// The scene's time, s: its animated objects are placed where they stand then (as the renderer places them).
    pub time: f32,
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
            progress: None,
            radial_center: None,
            time: 0.0,
        }
    }
}

/// How one light was sampled.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct LightInfo {
    /// `spot`, `directional` or `point`.
    pub kind: String,
    /// "spot cone", "refractor sub-cone", "beam over refractors", "beam over scene", or "none".
    pub sampling: String,
    /// Half-angle of the sampled cone (degrees), for spot lights.
    pub half_angle_deg: Option<f64>,
    /// Solid angle (sr) of the sampled cone, or area (m²) of the sampled beam rectangle.
    pub measure: f64,
    /// Photons drawn for it.
    pub photons: u64,
    /// Flux of each photon, W, before the light color.
    pub flux_per_photon: f64,
    /// Its color.
    pub color: [f64; 3],
}

/// Where the emitted flux went (W, before light color). `emitted = deposited_caustics + deposited_direct +
/// escaped + cut_by_bounce_cap + filtered_by_paths + lost + absorbed`; `residual_rel` is the relative mismatch.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct EnergyAccount {
    /// Flux emitted toward the scene, W.
    pub emitted: f64,
    /// Deposited as caustics, W.
    pub deposited_caustics: f64,
    /// Deposited as direct light, W.
    pub deposited_direct: f64,
    /// Left the scene, W.
    pub escaped: f64,
    /// Cut after the bounce cap, W.
    pub cut_by_bounce_cap: f64,
    /// Left out by `--paths two-refractions`, W.
    pub filtered_by_paths: f64,
    /// Numerical dead ends, W.
    pub lost: f64,
    /// Absorbed inside glass.
    #[serde(default)]
    pub absorbed: f64,
    /// |emitted − every destination| / emitted.
    pub residual_rel: f64,
    /// Flux of the selected AOV binned into the image, and Σ E · pixel area over the image.
    pub aov_in_image: f64,
    /// Σ E · pixel area over the image, W.
    pub image_integral: f64,
}

/// The flux-weighted radial distribution of the selected AOV's deposits around a center.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RadialStats {
    /// The center.
    pub center: [f32; 3],
    /// The AOV's flux deposited in all, W.
    pub flux: f64,
    /// Radii (m) within which 50% and 90% of that flux lands.
    pub r50: Option<f64>,
    /// See `r50`.
    pub r90: Option<f64>,
}

/// The stats written by `--stats`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RefStats {
    /// The scene file.
    pub scene: String,
    /// The camera binned into.
    pub camera: String,
    /// Caustics or direct.
    pub aov: Aov,
    /// Which paths.
    pub paths: Paths,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Random seed.
    pub seed: u64,
    /// Photons per light.
    pub photons_per_light: u64,
    /// Worker threads.
    pub threads: usize,
    /// Triangles traced.
    pub triangles: usize,
    /// BVH build time, s.
    pub bvh_build_s: f64,
    /// Tracing time, s.
    pub trace_s: f64,
    /// Wall time, s.
    pub wall_s: f64,
    /// Photons drawn (all lights) per second of tracing.
    pub photons_per_s: f64,
    /// Specular interactions a path may have.
    pub bounce_cap: u32,
    /// Each light's sampling.
    pub lights: Vec<LightInfo>,
    /// Where the flux went.
    pub energy_account: EnergyAccount,
    /// Photon and event counts.
    pub counts: Tally,
    /// The radial profile, when asked for.
    pub radial: Option<RadialStats>,
}

/// A log-binned, flux-weighted histogram of distances: 0.05% relative resolution from 1 µm to 100 m.
#[derive(Clone, Debug)]
pub struct RadialProfile {
    /// The center of the profile.
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

    /// The profile's flux, W.
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
    /// Its statistics.
    pub stats: RefStats,
    /// Present when [`RefParams::radial_center`] was set.
    pub radial: Option<RadialProfile>,
}

fn orthographic_camera<'a>(scene: &'a Scene, name: Option<&str>) -> Result<&'a crate::scene::Camera> {
    let camera = scene.camera(name).map_err(|e| match name {
        Some(n) => Error::setting("RefParams::camera", n, e),
        None => Error::BadInput(e), // the scene has no camera at all
    })?;
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
            format!("its orthographic cameras: {}", ortho.join(", "))
        };
        return Err(Error::setting(
            "RefParams::camera",
            &camera.name,
            format!(
                "{}: camera `{}` is perspective; the reference bins into orthographic cameras only ({usable})",
                scene.path.display(),
                camera.name
            ),
        ));
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
            let spectrum = crate::spectrum::RgbSpectrum::fit(color);
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
                (LightSetup { emission: None, strata: Strata::new(1), photons: 0, phi: 0.0, color, spectrum }, info)
            };
            let (emission, sampling, half) = match light.kind {
                LightKind::Spot | LightKind::Point => {
                    if caustics_only && refractor_pts.is_empty() {
                        return none(if light.kind == LightKind::Spot { "spot" } else { "point" });
                    }
                    // A point light is a spot light whose cone is the whole sphere.
                    let cos_spot = if light.kind == LightKind::Point { -1.0 } else { (light.cone as f64).cos() };
                    // A sphere light's rays start up to its radius to the side: the sub-cone widens by the angle
                    // the sphere shows the nearest glass.
                    let radius = light.radius as f64;
                    let widen = |(axis, cos_half): (DVec3, f64)| {
                        let near = refractor_pts.iter().map(|&q| (q - pos).length()).fold(f64::INFINITY, f64::min);
                        let grow = if radius > 0.0 { (radius / near.max(radius)).asin() } else { 0.0 };
                        (axis, (cos_half.clamp(-1.0, 1.0).acos() + grow).min(std::f64::consts::PI).cos())
                    };
                    let sub = if caustics_only { bounding_cone(pos, &refractor_pts).map(widen) } else { None };
                    let (axis, u, v, cos_half, sampling) = match sub {
                        Some((axis, cos_half)) if cos_half > cos_spot => {
                            let (u, v) = frame(axis);
                            (axis, u, v, cos_half, "refractor sub-cone")
                        }
                        _ if light.kind == LightKind::Point => (fwd, right, down, cos_spot, "sphere"),
                        _ => (fwd, right, down, cos_spot, "spot cone"),
                    };
                    let e = Emission::Cone { origin: pos, u, v, axis, cos_half, spot_axis: fwd, cos_spot, radius };
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
                    // A sun's tilted rays reach what they light from as far to the side as its depth times the
                    // tangent of its angular radius.
                    let radius = light.angular_radius as f64;
                    let depth1 = pts.iter().map(|&q| (q - pos).dot(fwd)).fold(f64::NEG_INFINITY, f64::max);
                    let m = (depth1 - depth0 + 1e-3).max(0.0) * radius.tan();
                    let (x0, x1, y0, y1) = (x0 - m, x1 + m, y0 - m, y1 + m);
                    let pad = 1e-6 * (1.0 + (x1 - x0).max(y1 - y0));
                    let (x0, x1, y0, y1) = (x0 - pad, x1 + pad, y0 - pad, y1 + pad);
                    let corner = pos + right * x0 + down * y0 + fwd * (depth0 - 1e-3 - pad);
                    let e = Emission::Beam { corner, eu: right * (x1 - x0), ev: down * (y1 - y0), dir: fwd, radius };
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
                LightSetup {
                    emission: Some(emission),
                    strata: Strata::new(p.photons),
                    photons: p.photons,
                    phi,
                    color,
                    spectrum,
                },
                info,
            )
        })
        .collect()
}

/// A progress callback: (photons traced so far, photons in all). Called from the thread that reduces the chunks.
#[derive(Clone)]
pub struct Progress(pub std::sync::Arc<dyn Fn(u64, u64) + Send + Sync>);

impl std::fmt::Debug for Progress {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Progress")
    }
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
    progress: Option<&Progress>,
    total: u64,
) -> Reduced {
    let mut tally = Tally::default();
    let mut image = vec![[0.0f64; 3]; pixels];
    let mut profile = radial.map(RadialProfile::new);
    let mut done = 0u64;
    for batch in chunks.chunks(BATCH) {
        let outs: Vec<_> = batch.par_iter().map(|&(li, s, e)| tracer.chunk(li, s, e)).collect();
        done += batch.iter().map(|&(_, s, e)| e - s).sum::<u64>();
        if let Some(p) = progress {
            (p.0)(done, total);
        }
        // Fixed-order reduction: chunk by chunk, deposit by deposit.
        for out in outs {
            tally.add(&out.tally);
            for d in &out.deposits {
                // Spectral photons carry their light's color in their deposits.
                let c = match tracer.color {
                    tracer::PhotonColor::Spectral => [1.0; 3],
                    _ => tracer.lights[d.light as usize].color,
                };
                let px = &mut image[d.pixel as usize];
                for k in 0..3 {
                    px[k] += d.e * d.rgb[k] as f64 * c[k];
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
pub fn trace(scene: &Scene, p: &RefParams) -> Result<RefOutput> {
    let start = Instant::now();
    if p.photons == 0 {
        return Err(Error::setting("RefParams::photons", p.photons, "must be at least 1"));
    }
    if p.width == 0 || p.height == 0 {
        return Err(Error::setting(
            "RefParams::width",
            format!("{}x{}", p.width, p.height),
            "width and height must be at least 1",
        ));
    }
    if !p.time.is_finite() {
        return Err(Error::setting("RefParams::time", p.time, "must be finite"));
    }
    let timed;
    let scene = if scene.is_animated() && scene.time != p.time {
        timed = scene.at_time(p.time);
        &timed
    } else {
        scene
    };
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
    let trace_start = Instant::now();
    let pixels = (p.width * p.height) as usize;
    let reduced = match p.threads {
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map_err(|e| Error::Failed(format!("cannot start {n} worker threads: {e}")))?
            .install(|| run_chunks(&tracer, &chunks, pixels, p.radial_center, p.progress.as_ref(), total)),
        None => run_chunks(&tracer, &chunks, pixels, p.radial_center, p.progress.as_ref(), total),
    };
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
