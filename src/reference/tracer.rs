//! One photon's path: emission, specular interactions at dielectrics (Russian roulette on the Fresnel
//! reflectance), the first diffuse hit, and its binning into the camera image.

use super::geometry::{Filter, Geometry, Hit};
use super::optics::{fresnel, reflect, refract};
use super::sampling::{Emission, Rng, Strata};
use super::{Aov, Paths, BOUNCE_CAP};
use crate::scene::{CameraView, Material, Scene};
use crate::shaders::consts::MAX_NESTED;
use crate::spectrum::RgbSpectrum;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Per-light emission set-up.
#[derive(Clone, Debug)]
pub(crate) struct LightSetup {
    pub emission: Option<Emission>,
    pub strata: Strata,
    /// Photons drawn for this light.
    pub photons: u64,
    /// Flux of each photon, W, before the light color: I·Ω/N (spot) or E·A/N (directional).
    pub phi: f64,
    pub color: [f64; 3],
    /// Its color as a spectrum (D65 times its upsampled color), for photons that carry a wavelength.
    pub spectrum: crate::spectrum::RgbSpectrum,
}

/// Counts and flux sums (W, before light color) of one chunk of photons, or of the whole run. Every traced
/// photon ends in exactly one of: deposited (caustics or direct), escaped, cut by the bounce cap, filtered out
/// by `--paths`, or lost to a numerical dead end, so the flux account closes.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct Tally {
    /// Photons whose direction fell inside the light (these carry flux).
    pub photons_traced: u64,
    /// Photons drawn from the sampled sub-cone but outside the spot cone: they carry nothing.
    pub photons_outside_cone: u64,
    /// Photons that deposited caustics.
    pub photons_caustics: u64,
    /// Photons that deposited direct light.
    pub photons_direct: u64,
    /// Photons of the selected AOV binned into the image.
    pub photons_in_image: u64,
    /// Photons that left the scene.
    pub photons_escaped: u64,
    /// Photons cut after the bounce cap.
    pub photons_cut: u64,
    /// Photons left out by the paths filter.
    pub photons_filtered: u64,
    /// Photons lost to numerical dead ends.
    pub photons_lost: u64,
    #[serde(default)]
    /// Photons absorbed inside glass.
    pub photons_absorbed: u64,
    /// Flux emitted, W.
    pub flux_emitted: f64,
    /// Flux deposited as caustics, W.
    pub flux_caustics: f64,
    /// Flux deposited as direct light, W.
    pub flux_direct: f64,
    /// Flux of the selected AOV's photons binned into the image (visible to the camera, inside the frame).
    pub flux_in_image: f64,
    /// Σ E · pixel area over the image: `flux_in_image` weighted by |n · forward| of each receiver.
    pub image_flux: f64,
    /// Flux that left the scene, W.
    pub flux_escaped: f64,
    /// Flux cut after the bounce cap, W.
    pub flux_cut: f64,
    /// Flux left out by the paths filter, W.
    pub flux_filtered: f64,
    /// Flux lost to numerical dead ends, W.
    pub flux_lost: f64,
    /// Absorbed inside glass (Beer–Lambert).
    #[serde(default)]
    pub flux_absorbed: f64,
    /// Refractions.
    pub refractions: u64,
    /// Reflections (Fresnel and mirror).
    pub reflections: u64,
    /// Total internal reflections.
    pub total_internal_reflections: u64,
    /// Interactions where the interpolated normal gave a direction on the wrong side of the geometric surface
    /// (or faced away from the ray), so the geometric normal was used instead.
    pub shading_normal_fallbacks: u64,
    /// The most specular interactions of one path.
    pub max_specular_depth: u32,
}

impl Tally {
    /// Add another tally's counts.
    pub fn add(&mut self, o: &Tally) {
        self.photons_traced += o.photons_traced;
        self.photons_outside_cone += o.photons_outside_cone;
        self.photons_caustics += o.photons_caustics;
        self.photons_direct += o.photons_direct;
        self.photons_in_image += o.photons_in_image;
        self.photons_escaped += o.photons_escaped;
        self.photons_cut += o.photons_cut;
        self.photons_filtered += o.photons_filtered;
        self.photons_lost += o.photons_lost;
        self.photons_absorbed += o.photons_absorbed;
        self.flux_emitted += o.flux_emitted;
        self.flux_caustics += o.flux_caustics;
        self.flux_direct += o.flux_direct;
        self.flux_in_image += o.flux_in_image;
        self.image_flux += o.image_flux;
        self.flux_escaped += o.flux_escaped;
        self.flux_cut += o.flux_cut;
        self.flux_filtered += o.flux_filtered;
        self.flux_lost += o.flux_lost;
        self.flux_absorbed += o.flux_absorbed;
        self.refractions += o.refractions;
        self.reflections += o.reflections;
        self.total_internal_reflections += o.total_internal_reflections;
        self.shading_normal_fallbacks += o.shading_normal_fallbacks;
        self.max_specular_depth = self.max_specular_depth.max(o.max_specular_depth);
    }

    /// Emitted flux minus every destination, relative to the emitted flux (0 when nothing was emitted).
    pub fn account_residual(&self) -> f64 {
        let out = self.flux_caustics
            + self.flux_direct
            + self.flux_escaped
            + self.flux_cut
            + self.flux_filtered
            + self.flux_lost
            + self.flux_absorbed;
        if self.flux_emitted > 0.0 {
            (self.flux_emitted - out).abs() / self.flux_emitted
        } else {
            out.abs()
        }
    }
}

/// One photon's contribution to one pixel: irradiance E (W/m², before light color).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Deposit {
    pub pixel: u32,
    pub light: u32,
    /// What it deposits in each channel per unit of `e` (docs/design.md "Color"): 1 in each for a gray photon, 3
    /// in its own channel for a channel's, its wavelength's RGB for a spectral one.
    pub rgb: [f32; 3],
    pub e: f64,
}

#[derive(Default)]
pub(crate) struct ChunkOut {
    pub tally: Tally,
    pub deposits: Vec<Deposit>,
    /// (distance from the radial center, flux) of each deposited photon of the selected AOV.
    pub radial: Vec<(f64, f64)>,
}

/// Bins receiver hits into an orthographic camera's pixels.
pub(crate) struct Binner {
    pub view: CameraView,
    pub position: DVec3,
    pub forward: DVec3,
    pub near: f64,
    /// World area of one pixel on a plane facing the camera: (2·half_w/W)(2·half_h/H).
    pub pixel_area: f64,
}

impl Binner {
    pub fn new(view: CameraView) -> Self {
        let h = view.half_extents().as_dvec2();
        Binner {
            view,
            position: view.position.as_dvec3(),
            forward: view.forward.as_dvec3(),
            near: view.near as f64,
            pixel_area: (2.0 * h.x / view.width as f64) * (2.0 * h.y / view.height as f64),
        }
    }

    /// The pixel and |n · forward| of a receiver hit seen by the camera: the photon must arrive on the side the
    /// camera sees, land inside the frame, and not be hidden by another receiver (refractors hide nothing).
    fn bin(&self, geo: &Geometry, hit: &Hit, d: DVec3) -> Option<(u32, f64)> {
        let cos_cam = hit.ng.dot(self.forward);
        if cos_cam.abs() < 1e-9 || (hit.ng.dot(d) < 0.0) != (cos_cam < 0.0) {
            return None;
        }
        let px = self.view.project(hit.pos.as_vec3())?;
        let (w, h) = (self.view.width, self.view.height);
        if !(px.x >= 0.0 && px.y >= 0.0 && px.x < w as f32 && px.y < h as f32) {
            return None;
        }
        let (ix, iy) = ((px.x as u32).min(w - 1), (px.y as u32).min(h - 1));
        let depth = (hit.pos - self.position).dot(self.forward);
        let tmax = depth - self.near;
        if tmax <= 0.0 {
            return None;
        }
        let toward_cam = if cos_cam < 0.0 { hit.ng } else { -hit.ng };
        let o = hit.pos + toward_cam * offset_scale(hit.pos);
        if geo.intersect(o, -self.forward, tmax, Some(hit.prim), Filter::ReceiversOnly).is_some() {
            return None;
        }
        Some((iy * w + ix, cos_cam.abs()))
    }
}

/// Ray-origin offset along the geometric normal. Hit points are computed in f64 from f32 vertices, so they lie
/// within ~1e-16 relative of their plane; 1e-9 relative clears that by far and is far below any feature size.
fn offset_scale(p: DVec3) -> f64 {
    1e-9 * (1.0 + p.abs().max_element())
}

pub(crate) struct Tracer<'a> {
    pub geo: &'a Geometry,
    pub lights: Vec<LightSetup>,
    pub binner: Binner,
    pub aov: Aov,
    pub paths: Paths,
    pub seed: u64,
    pub radial_center: Option<DVec3>,
    /// IOR of each scene object per color channel (0 for receivers); the three are equal without dispersion.
    pub ior: Vec<[f64; 3]>,
    /// Absorption coefficient inside each dielectric per color channel, 1/m (0 elsewhere).
    pub absorption: Vec<([f64; 3], RgbSpectrum)>,
    /// The medium beyond each dielectric's surface (`Object::outside`; None: air).
    pub outside: Vec<Option<usize>>,
    /// Each object's medium priority (`Object::priority`; 0: an explicit interface).
    pub priority: Vec<u32>,
    /// How photons carry color (docs/design.md "Color").
    pub color: PhotonColor,
}

/// How the reference's photons carry color.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhotonColor {
    /// No glass depends on it: every photon lands in every channel.
    Gray,
    /// Some medium absorbs colors unequally: each photon traces one channel, drawn at random, and its caustic lands
    /// in that channel only, with 3 times its flux.
    Channels,
    /// Some glass disperses: each photon traces one wavelength, drawn uniformly over the range, and its caustic
    /// lands as that wavelength's RGB (`spectrum_rgb`), as the GPU's spectral photons do.
    Spectral,
}

/// The light one photon traces: a color channel's IORs and absorption (1: the d line, for gray), or a wavelength's.
#[derive(Clone, Copy, Debug)]
enum Band {
    Channel(usize),
    Wavelength(f64),
}

impl Band {
    /// An IOR given at the C, d and F lines, in this band.
    fn ior(self, n: &[f64; 3]) -> f64 {
        match self {
            Band::Channel(c) => n[c],
            Band::Wavelength(nm) => crate::spectrum::cauchy_ior(*n, nm),
        }
    }

    /// An absorption coefficient given per channel (and as its spectrum), in this band.
    fn sigma(self, s: &([f64; 3], RgbSpectrum)) -> f64 {
        match self {
            Band::Channel(c) => s.0[c],
            Band::Wavelength(nm) => s.1.at(nm),
        }
    }
}

/// A dielectric hit as the medium rules see it: whether it is an interface at all (`through`: no), the IORs behind
/// and in front of the surface, and the medium and volumes beyond it.
struct Crossing {
    through: bool,
    n_in: f64,
    n_out: f64,
    medium: Option<usize>,
    nested: Vec<usize>,
}

enum Interaction {
    Reflected { dir: DVec3, tir: bool },
    Refracted { dir: DVec3 },
}

/// Reflect or refract at a dielectric interface between IOR `ior` (behind the geometric normal) and `outside` (in
/// front of it), chosen by Russian roulette with probability F (`xi` uniform in [0, 1)), by the rules of
/// docs/design.md "Shading normals" as the GPU's `split_interface` applies them. Inside/outside comes from the
/// geometric normal. F and the directions come from the interpolated normal where it lies on the geometric
/// normal's side and faces the ray, else from the geometric normal. The branch is chosen by that F; a direction it
/// would send to the wrong side of the surface is recomputed about the geometric normal, with the same F (a
/// refraction that cannot be made so reflects). The `bool` tells whether the geometric normal gave the direction.
fn interact(d: DVec3, hit: &Hit, ior: f64, outside: f64, xi: f64) -> Option<(Interaction, bool)> {
    if ior == MIRROR {
        return mirror(d, hit);
    }
    let entering = d.dot(hit.ng) < 0.0;
    let eta = if entering { outside / ior } else { ior / outside };
    let ng_f = if entering { hit.ng } else { -hit.ng };
    let ns_f = if entering { hit.ns } else { -hit.ns };
    let use_ns = hit.ns.dot(hit.ng) > 0.0 && -d.dot(ns_f) > 0.0;
    let n = if use_ns { ns_f } else { ng_f };
    let cos_i = -d.dot(n);
    if cos_i <= 0.0 {
        return None;
    }
    let f = fresnel(cos_i, eta);
    if let Some(cos_t) = f.cos_t.filter(|_| xi >= f.reflectance) {
        let t = refract(d, n, eta, cos_i, cos_t).normalize();
        if t.dot(ng_f) < 0.0 {
            return Some((Interaction::Refracted { dir: t }, !use_ns));
        }
        // The interpolated normal bends the ray back out: refract about the geometric normal instead.
        let c = -d.dot(ng_f);
        if let Some(cos_tg) = fresnel(c, eta).cos_t.filter(|_| c > 0.0) {
            let t = refract(d, ng_f, eta, c, cos_tg).normalize();
            if t.dot(ng_f) < 0.0 {
                return Some((Interaction::Refracted { dir: t }, true));
            }
        }
    }
    let tir = f.cos_t.is_none();
    let r = reflect(d, n).normalize();
    if r.dot(ng_f) > 0.0 {
        return Some((Interaction::Reflected { dir: r, tir }, !use_ns));
    }
    let r = reflect(d, ng_f).normalize();
    (r.dot(ng_f) > 0.0).then_some((Interaction::Reflected { dir: r, tir }, true))
}

/// The `ior` entry of a mirror object.
const MIRROR: f64 = -1.0;

/// A perfect mirror reflects everything, about the interpolated normal unless that sends the photon to the wrong
/// side of the geometric surface (then about the geometric normal).
fn mirror(d: DVec3, hit: &Hit) -> Option<(Interaction, bool)> {
    let ng_f = if d.dot(hit.ng) < 0.0 { hit.ng } else { -hit.ng };
    let ns = if hit.ns.dot(hit.ng) > 0.0 { hit.ns } else { hit.ng };
    let ns_f = if ns.dot(ng_f) > 0.0 { ns } else { -ns };
    for (k, n) in [ns_f, ng_f].into_iter().enumerate() {
        if -d.dot(n) <= 0.0 {
            continue;
        }
        let r = reflect(d, n).normalize();
        if r.dot(ng_f) > 0.0 {
            return Some((Interaction::Reflected { dir: r, tir: false }, k == 1));
        }
    }
    None
}

impl Tracer<'_> {
    pub fn new<'a>(
        scene: &Scene,
        geo: &'a Geometry,
        lights: Vec<LightSetup>,
        binner: Binner,
        p: &super::RefParams,
    ) -> Tracer<'a> {
        let ior = scene
            .objects
            .iter()
            .map(|o| match o.material {
                Material::Dielectric { .. } => o.material.ior_rgb().map(|n| n as f64),
                Material::Mirror => [MIRROR; 3],
                Material::Diffuse { .. } => [0.0; 3],
            })
            .collect();
        let absorption = scene
            .objects
            .iter()
            .map(|o| {
                let s = o.absorption().to_array().map(|x| x as f64);
                (s, RgbSpectrum::fit(s))
            })
            .collect();
        Tracer {
            geo,
            lights,
            binner,
            aov: p.aov,
            paths: p.paths,
            seed: p.seed,
            radial_center: p.radial_center.map(|c| c.as_dvec3()),
            ior,
            absorption,
            // (A scene built in code may name no dielectric: the renderer refuses it, the reference takes air.)
            outside: (0..scene.objects.len()).map(|i| scene.outside_of(i)).collect(),
            priority: scene.objects.iter().map(|o| if o.is_mirror() { 0 } else { o.priority }).collect(),
            color: match (scene.disperses(), scene.color_channels()) {
                (true, _) => PhotonColor::Spectral,
                (false, 3) => PhotonColor::Channels,
                _ => PhotonColor::Gray,
            },
        }
    }

    /// Trace photons [start, end) of light `li`.
    pub fn chunk(&self, li: usize, start: u64, end: u64) -> ChunkOut {
        let mut out = ChunkOut::default();
        for i in start..end {
            self.photon(li, i, &mut out);
        }
        out
    }

    fn photon(&self, li: usize, i: u64, out: &mut ChunkOut) {
        let light = &self.lights[li];
        let Some(emission) = light.emission else {
            return;
        };
        let mut rng = Rng::new(self.seed, li as u64, i);
        let (a, b) = light.strata.point(i, rng.next_f64(), rng.next_f64());
        let t = &mut out.tally;
        // A sun's direction takes two numbers more (other lights' photons draw the same numbers as before).
        let (c, e) = if emission.has_size() { (rng.next_f64(), rng.next_f64()) } else { (0.0, 0.0) };
        let Some((mut o, mut d)) = emission.ray(a, b, c, e) else {
            t.photons_outside_cone += 1;
            return;
        };
        let phi = light.phi;
        // The band this photon traces, and what its caustic deposits per channel.
        let (band, rgb) = match self.color {
            PhotonColor::Gray => (Band::Channel(1), [1.0; 3]),
            PhotonColor::Channels => {
                let k = ((rng.next_f64() * 3.0) as usize).min(2);
                (Band::Channel(k), std::array::from_fn(|c| if c == k { 3.0 } else { 0.0 }))
            }
            PhotonColor::Spectral => {
                use crate::spectrum::{spectrum_rgb, SPECTRUM_MAX_NM, SPECTRUM_MIN_NM};
                let nm = SPECTRUM_MIN_NM + (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) * rng.next_f64();
                let s = light.spectrum.at(nm);
                (Band::Wavelength(nm), spectrum_rgb(nm).map(|x| (x * s) as f32))
            }
        };
        t.photons_traced += 1;
        t.flux_emitted += phi;
        // Surfaces met: refractions, reflections, and volumes' surfaces passed through (no interface there), which
        // count towards the cap as the waves count them (a wave per surface met).
        let (mut refr, mut refl, mut through) = (0u32, 0u32, 0u32);
        let mut skip = None;
        // The medium the photon travels in (None: air, where lights are): the object it is inside; and the volumes
        // with a priority it is inside.
        let mut medium: Option<usize> = None;
        let mut nested: Vec<usize> = Vec::new();
        loop {
            let Some(hit) = self.geo.intersect(o, d, f64::INFINITY, skip, Filter::All) else {
                t.photons_escaped += 1;
                t.flux_escaped += phi;
                return;
            };
            let sigma = medium.map_or(0.0, |m| band.sigma(&self.absorption[m]));
            if sigma > 0.0 {
                // The segment that ends here ran through an absorbing medium: Beer–Lambert, by Russian roulette.
                if rng.next_f64() >= (-sigma * (hit.pos - o).length()).exp() {
                    t.photons_absorbed += 1;
                    t.flux_absorbed += phi;
                    return;
                }
            }
            if hit.receiver {
                // Light that met no glass is the same in every channel (spectral photons carry the light's color:
                // there it is that color, their mean).
                let rgb = match (refr + refl, self.color) {
                    (0, PhotonColor::Spectral) => light.color.map(|c| c as f32),
                    (0, _) => [1.0; 3],
                    _ => rgb,
                };
                self.deposit(li, &hit, d, refr, refl, phi, rgb, out);
                return;
            }
            if refr + refl + through >= BOUNCE_CAP {
                t.photons_cut += 1;
                t.flux_cut += phi;
                return;
            }
            let entering = d.dot(hit.ng) < 0.0;
            let x = self.crossing(hit.object as usize, entering, medium, &nested, band);
            let toward_incident = if entering { hit.ng } else { -hit.ng };
            if x.through {
                // A volume's surface inside one of higher priority: no interface, the photon goes on beyond it.
                o = hit.pos - toward_incident * offset_scale(hit.pos);
                (medium, nested) = (x.medium, x.nested);
                skip = Some(hit.prim);
                through += 1;
                continue;
            }
            let Some((event, fallback)) = interact(d, &hit, x.n_in, x.n_out, rng.next_f64()) else {
                t.photons_lost += 1;
                t.flux_lost += phi;
                return;
            };
            t.shading_normal_fallbacks += fallback as u64;
            let eps = offset_scale(hit.pos);
            match event {
                Interaction::Reflected { dir, tir } => {
                    refl += 1;
                    t.reflections += 1;
                    t.total_internal_reflections += tir as u64;
                    o = hit.pos + toward_incident * eps;
                    d = dir;
                }
                Interaction::Refracted { dir } => {
                    // Across the surface: into the object, or out to the medium beyond it.
                    (medium, nested) = (x.medium, x.nested);
                    refr += 1;
                    t.refractions += 1;
                    o = hit.pos - toward_incident * eps;
                    d = dir;
                }
            }
            t.max_specular_depth = t.max_specular_depth.max(refr + refl);
            skip = Some(hit.prim);
        }
    }

    /// What a photon in `medium`, inside the volumes `nested`, meets at a hit on object `k` (glsl/common/interface.glsl
    /// `crossing_at`, docs/design.md "Media").
    fn crossing(&self, k: usize, entering: bool, medium: Option<usize>, nested: &[usize], band: Band) -> Crossing {
        let ior = |m: Option<usize>| m.map_or(1.0, |j| band.ior(&self.ior[j]));
        if self.priority[k] == 0 {
            let outside = self.outside[k];
            let medium = if entering { Some(k) } else { outside };
            return Crossing {
                through: false,
                n_in: band.ior(&self.ior[k]),
                n_out: ior(outside),
                medium,
                nested: nested.to_vec(),
            };
        }
        let mut after = nested.to_vec();
        if entering && after.len() < MAX_NESTED as usize {
            after.push(k);
        } else if let Some(i) = after.iter().position(|&j| j == k).filter(|_| !entering) {
            after.remove(i);
        }
        // The highest priority's medium (ties: the later object), air when none.
        let top = after.iter().copied().max_by_key(|&j| (self.priority[j], j));
        let (n_before, n_after) = (ior(medium), ior(top));
        let (n_in, n_out) = if entering { (n_after, n_before) } else { (n_before, n_after) };
        Crossing { through: top == medium, n_in, n_out, medium: top, nested: after }
    }

    #[allow(clippy::too_many_arguments)]
    fn deposit(
        &self,
        li: usize,
        hit: &Hit,
        d: DVec3,
        refr: u32,
        refl: u32,
        phi: f64,
        rgb: [f32; 3],
        out: &mut ChunkOut,
    ) {
        let t = &mut out.tally;
        let caustic = refr + refl > 0;
        if caustic && self.paths == Paths::TwoRefractions && !(refr == 2 && refl == 0) {
            t.photons_filtered += 1;
            t.flux_filtered += phi;
            return;
        }
        if caustic {
            t.photons_caustics += 1;
            t.flux_caustics += phi;
        } else {
            t.photons_direct += 1;
            t.flux_direct += phi;
        }
        if caustic != (self.aov == Aov::Caustics) {
            return;
        }
        if let Some(c) = self.radial_center {
            out.radial.push(((hit.pos - c).length(), phi));
        }
        if let Some((pixel, cos)) = self.binner.bin(self.geo, hit, d) {
            t.photons_in_image += 1;
            t.flux_in_image += phi;
            t.image_flux += phi * cos;
            out.deposits.push(Deposit { pixel, light: li as u32, rgb, e: phi * cos / self.binner.pixel_area });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{interact, Interaction};
    use crate::reference::geometry::Hit;
    use glam::DVec3;

    /// Total internal reflection at a glass | water interface (IOR 1.5 inside, water's 1.33 beyond it): from the
    /// glass side beyond the critical angle asin(1.33 / 1.5) = 62.46°, and only there; from the water side never,
    /// and against air (the default outside) already beyond asin(1 / 1.5) = 41.81°.
    #[test]
    fn glass_against_water_reflects_totally_only_beyond_its_critical_angle() {
        let hit = Hit { prim: 0, pos: DVec3::ZERO, ng: DVec3::Y, ns: DVec3::Y, object: 0, receiver: false };
        let critical = (1.33f64 / 1.5).asin().to_degrees();
        // A ray at `deg` from the normal, from inside the glass (going up through the surface) or from outside.
        let ray = |deg: f64, from_inside: bool| {
            let (s, c) = deg.to_radians().sin_cos();
            DVec3::new(s, if from_inside { c } else { -c }, 0.0)
        };
        // xi = 1 - 1e-12: refraction wherever it exists (it is taken when xi >= F).
        let tir = |d: DVec3, outside: f64| match interact(d, &hit, 1.5, outside, 1.0 - 1e-12) {
            Some((Interaction::Reflected { tir, .. }, _)) => tir,
            Some((Interaction::Refracted { .. }, _)) => false,
            None => panic!("no direction"),
        };
        for deg in [10.0, 40.0, 45.0, 60.0, critical - 0.05, critical + 0.05, 70.0, 85.0] {
            assert_eq!(tir(ray(deg, true), 1.33), deg > critical, "glass to water at {deg}°");
            assert!(!tir(ray(deg, false), 1.33), "water to glass at {deg}°");
            assert_eq!(tir(ray(deg, true), 1.0), deg > 41.81, "glass to air at {deg}°");
        }
        // Refraction out into water bends by Snell's law with the two media's IORs.
        if let Some((Interaction::Refracted { dir }, _)) = interact(ray(40.0, true), &hit, 1.5, 1.33, 1.0 - 1e-12) {
            let sin_t = dir.x.hypot(dir.z);
            assert!((sin_t - 1.5 / 1.33 * 40f64.to_radians().sin()).abs() < 1e-12, "sin θt {sin_t}");
        } else {
            panic!("40° from glass into water refracts");
        }
    }
}
