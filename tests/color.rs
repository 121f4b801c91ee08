//! Color (docs/design.md "Color"): a scene whose glass disperses (`abbe`) traces its photons once per color
//! channel, each with that channel's IOR and absorption, into its own channel of the caustic map; one whose glass
//! only absorbs colors unequally (`absorption = [r, g, b]`) traces color photons, which carry their RGB weight,
//! in one pass; every other scene keeps one gray pass per light.
//! Checked against exactness (each channel equals a gray render with that channel's material), against Snell's
//! law (the prism's channels land where the per-channel IOR sends them), and against the CPU reference.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::reference::{Aov, Paths};
use caustics::settings::{Metric, Settings, Splat};
use common::*;
use std::path::Path;
use std::sync::Arc;

const COLORED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/colored_glass.toml");
const PRISM: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/prism.toml");

/// One channel of `img`, copied into all three (so that luminance-based metrics see that channel alone).
fn channel(img: &RgbImage, c: usize) -> RgbImage {
    let mut out = img.clone();
    for p in &mut out.data {
        *p = [p[c]; 3];
    }
    out
}

fn flux(img: &RgbImage, c: usize) -> f64 {
    img.data.iter().map(|p| p[c] as f64).sum()
}

/// The caustics AOV of `scene`'s `top` camera at `side`² under exact transport at `level` (adaptive flux-error,
/// the default method), with the settings changed by `f`, rendered in process on the shared device; validation
/// stayed silent.
fn exact(
    device: &Arc<caustics::gpu::Device>,
    scene: &str,
    side: u32,
    level: u32,
    f: impl FnOnce(&mut Settings),
) -> Shot {
    shot_at(device, scene, with(adaptive(level, Metric::FluxError), f), 0.0, caustics::Aov::Caustics, side)
}

/// The energy account's residual of each pass of a frame.
fn residuals(s: &Shot) -> Vec<f64> {
    s.report.lights.iter().map(|l| l.transport.expect("an exact-transport pass").residual()).collect()
}

/// The linear beauty of the scene `text` (written as NAME.toml in `dir`) through `camera` at 64², one sample a
/// pixel, level 2, with the settings changed by `f`, rendered in process on the shared device; validation stayed
/// silent.
fn beauty(
    device: &Arc<caustics::gpu::Device>,
    dir: &Path,
    name: &str,
    text: &str,
    camera: &str,
    f: impl FnOnce(&mut Settings),
) -> RgbImage {
    beauty_aa(device, dir, name, text, camera, 1, f)
}

/// [`beauty`] at `aa`×`aa` samples a pixel.
fn beauty_aa(
    device: &Arc<caustics::gpu::Device>,
    dir: &Path,
    name: &str,
    text: &str,
    camera: &str,
    aa: u32,
    f: impl FnOnce(&mut Settings),
) -> RgbImage {
    let scene = dir.join(format!("{name}.toml"));
    std::fs::write(&scene, text).unwrap();
    let settings = with(Settings::default(), |s| {
        s.quality.aa = aa;
        s.quality.level = Some(2);
        f(s);
    });
    let mut r = renderer(device, scene.to_str().unwrap(), settings);
    let (img, _) = camera_aov(&mut r, camera, (64, 64), caustics::Aov::BeautyHdr);
    img
}

/// Beer–Lambert per channel in one pass: the amber sphere's photons carry their color (one "rgb" pass), and each
/// channel of its caustic equals the caustic of the same sphere with gray absorption at that channel's coefficient
/// (the same rays, the same splats), but for the flux threshold. A color photon keeps a branch while its brightest
/// channel is above the threshold, so red is traced exactly as its own pass traces it, and green and blue keep
/// branches their own passes cut: their excess is at most the flux those passes cut (weak branches off, so that
/// nothing else depends on a channel's weight). Where the photons cannot carry their color (the point draw's
/// one-channel map), the scene takes three channel passes, which must agree with the gray ones to float rounding.
/// Measured on lavapipe at level 2: red equal to 2.4e-7 rel-L1; green and blue 9.1e-5 and 3.7e-5 above their gray
/// passes, which cut 1.16e-3 and 1.17e-3; the channel passes equal to 8e-8. A gray scene runs one gray pass.
#[test]
fn colored_absorption_is_exact_per_channel() {
    let (_gpu, device) = gpu();
    let dir = out_dir("color_absorption");
    let no_weak = |s: &mut Settings| s.tuning.weak_branches = 0.0;
    let raster = |s: &mut Settings| {
        s.tuning.weak_branches = 0.0;
        s.tuning.splat = Splat::Raster;
    };
    let amber = exact(&device, COLORED, 128, 2, no_weak);
    assert_eq!(amber.passes(), ["rgb"], "one pass of color photons");
    assert_eq!(amber.report.host_readbacks, 0);
    let closes = |s: &Shot| {
        for (channel, res) in s.passes().iter().zip(residuals(s)) {
            assert!(res.abs() < 1e-6, "{channel}: energy residual {res}");
        }
    };
    closes(&amber);
    let img = &amber.img;
    let amber_raster = exact(&device, COLORED, 128, 2, raster);
    assert_eq!(amber_raster.passes(), ["red", "green", "blue"], "the point draw: three channel passes");
    closes(&amber_raster);
    let rimg = &amber_raster.img;
    let text = std::fs::read_to_string(COLORED).unwrap();
    let mut fluxes = Vec::new();
    for (c, sigma) in ["0.3", "1.2", "3.0"].iter().enumerate() {
        let gray = text.replace("absorption = [0.3, 1.2, 3.0]", &format!("absorption = {sigma}"));
        assert_ne!(gray, text);
        let path = dir.join(format!("gray{c}.toml"));
        std::fs::write(&path, gray.replace("../meshes/", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/meshes/")))
            .unwrap();
        let gs = exact(&device, path.to_str().unwrap(), 128, 2, no_weak);
        assert_eq!(gs.passes(), ["gray"], "a gray scene: one gray pass");
        // The share of the gray pass's caustic flux that its threshold cut.
        let cut = gs.energy("cut_threshold") / gs.energy("caustics");
        let gimg = &gs.img;
        let (a, b) = (flux(img, c), flux(gimg, c));
        let m = compare(&channel(img, c), &channel(gimg, c), 64, 2.0);
        eprintln!(
            "channel {c}: one pass {a:.6e}, gray sigma {sigma} {b:.6e} (ratio - 1: {:.2e}, its cut {cut:.2e}), rel-L1 {:.2e}",
            a / b - 1.0,
            m.rel_l1
        );
        let slack = if c == 0 { 1e-5 } else { cut + 1e-5 };
        assert!(a / b > 1.0 - 1e-5 && a / b < 1.0 + slack, "channel {c}: {a} vs {b} (cut {cut})");
        assert!(m.rel_l1 < slack, "channel {c}: rel-L1 {} (cut {cut})", m.rel_l1);
        // The channel pass against the gray one, both drawn as points.
        let gr = exact(&device, path.to_str().unwrap(), 128, 2, raster).img;
        let mr = compare(&channel(rimg, c), &channel(&gr, c), 64, 2.0);
        let (ar, br) = (flux(rimg, c), flux(&gr, c));
        eprintln!("channel {c}: its own pass {ar:.6e}, gray {br:.6e}, rel-L1 {:.2e}", mr.rel_l1);
        assert!((ar / br - 1.0).abs() < 1e-4 && mr.rel_l1 < 1e-4, "channel {c}: {ar} vs {br}, rel-L1 {}", mr.rel_l1);
        fluxes.push(a);
    }
    // Amber: red passes most, blue least.
    assert!(fluxes[0] > fluxes[1] && fluxes[1] > fluxes[2], "{fluxes:?}");
}

/// The centroid along x (m) of channel `c` of a top view of the prism's floor (columns along +x over [-1, 1] m),
/// over the band of light refracted once in and once out, which lands on x in [0.0, 0.33] m (light reflected inside
/// the wedge first leaves through its vertical face and lands farther out).
fn prism_centroid(img: &RgbImage, c: usize) -> f64 {
    let (w, h) = (img.width as usize, img.height as usize);
    let (mut sx, mut s) = (0.0, 0.0);
    for y in 0..h {
        for x in 0..w {
            let v = img.data[y * w + x][c] as f64;
            let xm = -1.0 + 2.0 * (x as f64 + 0.5) / w as f64;
            if (-0.1..0.45).contains(&xm) {
                sx += v * xm;
                s += v;
            }
        }
    }
    sx / s
}

/// Where light of wavelength `nm` leaving the prism's 30° face lands: x(λ) = h̄·tan(asin(n(λ)·sin 30°) − 30°).
fn prism_land(nm: f64) -> f64 {
    let ior = caustics::scene::Material::Dielectric { ior: 1.5, absorption: glam::Vec3::ZERO, abbe: 15.0 }.ior_rgb();
    let t30 = 30f64.to_radians();
    let h_mean = 0.6 - 0.2 * t30.tan();
    h_mean * ((caustics::spectrum::cauchy_ior(ior.map(f64::from), nm) * t30.sin()).asin() - t30).tan()
}

/// Each channel's centroid by Snell's law per wavelength under a light of spectrum `light` (relative to white):
/// ∫ k_c(λ) s(λ) x(λ) dλ / ∫ k_c(λ) s(λ) dλ, midpoint rule at 0.1 nm.
fn prism_snell_centroids(light: impl Fn(f64) -> f64) -> [f64; 3] {
    use caustics::spectrum::{spectrum_rgb, SPECTRUM_MAX_NM, SPECTRUM_MIN_NM};
    let n = 4000;
    let (mut sx, mut sw) = ([0.0; 3], [0.0; 3]);
    for i in 0..n {
        let nm = SPECTRUM_MIN_NM + (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) * (i as f64 + 0.5) / n as f64;
        let (k, x, l) = (spectrum_rgb(nm), prism_land(nm), light(nm));
        for c in 0..3 {
            sx[c] += k[c] * l * x;
            sw[c] += k[c] * l;
        }
    }
    std::array::from_fn(|c| sx[c] / sw[c])
}

/// The prism (Abbe number 15) in spectral photons: each photon traces one wavelength, with Cauchy's IOR there, and
/// deposits that wavelength's RGB. Light leaving the 30° face lands at x(λ) = h̄·tan(asin(n(λ)·sin 30°) − 30°), with
/// h̄ = 0.4845 m the mean height of the exit face, so each channel's centroid (over the band of light refracted once
/// in and once out) is ∫ k_c(λ) x(λ) dλ / ∫ k_c(λ) dλ, k_c the channel's response (`spectrum_rgb`): Snell's law
/// per wavelength, weighed by the CIE observer. Blue's centroid lies 19.6 mm beyond red's. Measured on lavapipe at
/// level 3: within 20, 7 and 74 µm of it (red, green, blue); the test allows 0.5 mm per channel (an eighth of a
/// pixel of the 512² image) and 0.3 mm on the red-blue separation. Where photons cannot carry their color (the
/// point draw), three channel passes land at Snell's law of their lines.
#[test]
fn prism_disperses_by_snell() {
    let (_gpu, device) = gpu();
    let s = exact(&device, PRISM, 512, 3, |_| ());
    assert_eq!(s.passes(), ["spectral"], "one pass of spectral photons");
    assert!(residuals(&s)[0].abs() < 1e-6);
    let expect = prism_snell_centroids(|_| 1.0);
    let got: Vec<f64> = (0..3).map(|c| prism_centroid(&s.img, c)).collect();
    eprintln!("prism centroids (m): got {got:?}, Snell per wavelength {expect:?}");
    for c in 0..3 {
        assert!((got[c] - expect[c]).abs() < 5e-4, "channel {c}: {} vs {}", got[c], expect[c]);
    }
    let (sep, sep_expect) = (got[2] - got[0], expect[2] - expect[0]);
    assert!(sep_expect > 0.005 && (sep - sep_expect).abs() < 3e-4, "separation {sep} vs {sep_expect}");
    // The point draw's one-channel map: three passes, each refracting at its channel's line, landing where Snell's
    // law with that line's IOR says. Measured: within 5 µm in each.
    let rs = exact(&device, PRISM, 512, 3, |s| s.tuning.splat = Splat::Raster);
    assert_eq!(rs.passes(), ["red", "green", "blue"]);
    for c in 0..3 {
        let (got, expect) = (prism_centroid(&rs.img, c), prism_land(caustics::scene::CHANNEL_NM[c] as f64));
        eprintln!("prism channel pass {c}: centroid {got}, Snell at its line {expect}");
        assert!((got - expect).abs() < 5e-4, "channel pass {c}: {got} vs {expect}");
    }
}

/// The prism under an orange light (1.0, 0.45, 0.1), written in `dir`: its path.
fn orange_prism(dir: &Path) -> String {
    let text = std::fs::read_to_string(PRISM).unwrap();
    let colored = text.replace("color = [1.0, 1.0, 1.0]", "color = [1.0, 0.45, 0.1]");
    assert_ne!(colored, text);
    let path = dir.join("orange.toml");
    std::fs::write(&path, colored.replace("../meshes/", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/meshes/")))
        .unwrap();
    path.to_str().unwrap().to_string()
}

/// A colored light is a spectrum (docs/design.md "Color"): under an orange light (1.0, 0.45, 0.1) the prism's
/// spectral photons weigh their wavelengths by the light's upsampled spectrum, so each channel's centroid moves to
/// Snell's law weighed by k_c(λ)·s(λ) (blue's 5.7 mm towards the red end, red's 1.1 mm), and each
/// channel's flux is the white light's times the light's color. Tinting the white caustic by the color would leave
/// the centroids where white light puts them. Measured on lavapipe at level 3: centroids within 16, 23 and 37 µm,
/// fluxes within 0.08%, 0.004% and 0.3% of the color (red, green, blue); the test allows 0.5 mm per centroid and
/// 1% per flux. `color_matches_reference` holds the same scene against the CPU reference.
#[test]
fn a_colored_light_is_a_spectrum() {
    let (_gpu, device) = gpu();
    let dir = out_dir("color_light_spectrum");
    let orange = [1.0, 0.45, 0.1];
    let path = orange_prism(&dir);
    let s = exact(&device, &path, 512, 3, |_| ());
    assert_eq!(s.passes()[0], "spectral");
    let (img, white) = (&s.img, exact(&device, PRISM, 512, 3, |_| ()).img);
    let spectrum = caustics::spectrum::RgbSpectrum::fit(orange);
    let expect = prism_snell_centroids(|nm| spectrum.at(nm));
    let white_expect = prism_snell_centroids(|_| 1.0);
    let got: Vec<f64> = (0..3).map(|c| prism_centroid(img, c)).collect();
    eprintln!("orange light: centroids {got:?}, Snell weighed by its spectrum {expect:?}, by white {white_expect:?}");
    for c in 0..3 {
        assert!((got[c] - expect[c]).abs() < 5e-4, "channel {c}: {} vs {}", got[c], expect[c]);
    }
    // The spectrum moves blue's centroid (whose response has a lobe at the red end, where this light is
    // brightest) by ten times the tolerance.
    assert!((expect[2] - white_expect[2]).abs() > 5e-3, "{expect:?} vs {white_expect:?}");
    for (c, &k) in orange.iter().enumerate() {
        let ratio = flux(img, c) / flux(&white, c);
        eprintln!("channel {c}: flux {ratio:.5} of white's, color {k}");
        assert!((ratio / k - 1.0).abs() < 0.01, "channel {c}: {ratio} of white's flux, color {k}");
    }
}

/// Spectral photons absorb per wavelength, by the absorption's upsampled spectrum (Jakob and Hanika 2019,
/// `RgbSpectrum`): light straight down through a dispersive slab (Abbe number 10) 0.1 m thick, of absorption
/// (3, 12, 30) /m, against the same slab clear. Per wavelength the slab transmits (1 − F)²·a / (1 − F²a²), a =
/// exp(−σ(λ)·0.1), F the normal Fresnel reflectance at n(λ) (every bounce between its faces), so each channel of its
/// caustic is the clear slab's times ∫ k_c T(λ, σ(λ)) dλ / ∫ k_c T(λ, 0) dλ. The coefficients taken as at the
/// C, d and F lines and linear between them (the earlier model) would give 0.537, 0.134 and 0.031 where the
/// spectrum gives 0.671, 0.294 and 0.030. Measured on lavapipe at level 5: within 0.04%, 0.01% and 0.17% (red,
/// green, blue); the test allows 1%. At levels 3 and 4 the dim blue channel, its wavelengths' negative lobes
/// included, is 1.4% off by the sampling of wavelengths alone. Flux is conserved per wavelength: the clear slab puts
/// E·A·mean_λ(k_c(λ)·T(λ, 0)) on the floor in each channel, measured within 2e-4 (the test allows 1e-3).
#[test]
fn spectral_photons_absorb_by_the_upsampled_spectrum() {
    use caustics::spectrum::{cauchy_ior, spectrum_rgb, RgbSpectrum, SPECTRUM_MAX_NM, SPECTRUM_MIN_NM};
    let (_gpu, device) = gpu();
    let dir = out_dir("color_spectral_absorption");
    let slab = |absorption: &str| {
        under_a_beam(&format!(
            r#"[[object]]
name = "slab"
shape = "cube"
size = [0.6, 0.1, 0.6]
translate = [0.0, 0.5, 0.0]
material = {{ kind = "dielectric", ior = 1.5, abbe = 10.0{absorption} }}
"#
        ))
    };
    let mut images = Vec::new();
    for (name, absorption) in [("clear", ""), ("amber", ", absorption = [3.0, 12.0, 30.0]")] {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, slab(absorption)).unwrap();
        let s = exact(&device, path.to_str().unwrap(), 128, 5, |_| ());
        assert_eq!(s.passes()[0], "spectral");
        images.push(s.img);
    }
    let rgb = [3.0, 12.0, 30.0];
    let sigma = RgbSpectrum::fit(rgb);
    let linear = |nm: f64| {
        let mix = |a: f64, b: f64, t: f64| a + (b - a) * t.clamp(0.0, 1.0);
        if nm >= 587.6 {
            mix(rgb[1], rgb[0], (nm - 587.6) / (656.3 - 587.6))
        } else {
            mix(rgb[2], rgb[1], (nm - 486.1) / (587.6 - 486.1))
        }
    };
    let ior = caustics::scene::Material::Dielectric { ior: 1.5, absorption: glam::Vec3::ZERO, abbe: 10.0 }.ior_rgb();
    let transmit = |nm: f64, s: f64| {
        let n = cauchy_ior(ior.map(f64::from), nm);
        let f = ((n - 1.0) / (n + 1.0)).powi(2);
        let a = (-s * 0.1).exp();
        (1.0 - f).powi(2) * a / (1.0 - f * f * a * a)
    };
    let ratio_of = |sigma_at: &dyn Fn(f64) -> f64| -> [f64; 3] {
        let n = 4000;
        let (mut num, mut den) = ([0.0; 3], [0.0; 3]);
        for i in 0..n {
            let nm = SPECTRUM_MIN_NM + (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) * (i as f64 + 0.5) / n as f64;
            let k = spectrum_rgb(nm);
            let (t, t0) = (transmit(nm, sigma_at(nm)), transmit(nm, 0.0));
            (0..3).for_each(|c| {
                num[c] += k[c] * t;
                den[c] += k[c] * t0;
            });
        }
        std::array::from_fn(|c| num[c] / den[c])
    };
    // Flux conserved per wavelength: the clear slab puts E·A·mean_λ(k_c(λ)·T(λ, 0)) on the floor in channel c.
    let n = 4000;
    for c in 0..3 {
        let mean: f64 = (0..n)
            .map(|i| SPECTRUM_MIN_NM + (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) * (i as f64 + 0.5) / n as f64)
            .map(|nm| spectrum_rgb(nm)[c] * transmit(nm, 0.0))
            .sum::<f64>()
            / n as f64;
        let (want, got) = (0.36 * mean, flux(&images[0], c) * (2.0f64 / 128.0).powi(2));
        eprintln!("clear slab, channel {c}: {got:.6} W, per wavelength {want:.6} W");
        assert!((got / want - 1.0).abs() < 1e-3, "clear slab, channel {c}: {got} W against {want} W");
    }
    let expect = ratio_of(&|nm| sigma.at(nm));
    let old = ratio_of(&linear);
    for c in 0..3 {
        let got = flux(&images[1], c) / flux(&images[0], c);
        eprintln!(
            "channel {c}: transmits {got:.5}, upsampled spectrum {:.5}, linear between lines {:.5}",
            expect[c], old[c]
        );
        assert!((got / expect[c] - 1.0).abs() < 0.01, "channel {c}: {got} vs {}", expect[c]);
    }
}

/// The color scenes against the CPU reference of every path (3M photons: for amber about a million per channel,
/// for the prisms each a wavelength drawn uniformly), per channel: rel-L1 at 64² and the flux ratio. Measured on
/// lavapipe at level 3: amber rel-L1 2.2%, 2.9%, 6.0% (red, green, blue: the dim blue channel is mostly the
/// reference's noise) with flux ratios within 0.3%; the prism's spectral photons 3.3%, 1.9%, 2.4% with flux ratios
/// within 0.33% (a wavelength's RGB has negative lobes, so the reference's channels are noisier than one channel's
/// photons were: 1.2% each); under the orange light 2.6%, 2.0%, 3.7%, flux ratios within 0.55%. The test allows
/// rel-L1 0.09 and flux ratios within 1.5%.
#[test]
fn color_matches_reference() {
    let (_gpu, device) = gpu();
    let dir = out_dir("color_reference");
    let orange = orange_prism(&dir);
    for (name, scene, level) in [("amber", COLORED, 3), ("prism", PRISM, 3), ("orange prism", &orange, 3)] {
        let img = exact(&device, scene, 256, level, |_| ()).img;
        let r = top_reference(scene, Aov::Caustics, Paths::All, 3_000_000, 256);
        for c in 0..3 {
            let m = compare(&channel(&img, c), &channel(&r, c), 64, 2.0);
            eprintln!("{name} channel {c}: {m:?}");
            assert!((m.flux_ratio - 1.0).abs() < 0.015, "{name} channel {c}: flux ratio {}", m.flux_ratio);
            assert!(m.rel_l1 < 0.09, "{name} channel {c}: rel-L1 {}", m.rel_l1);
        }
    }
}

/// Colored glass in the beauty image: an orthographic eye looks straight through an amber slab 0.1 m thick
/// (absorption 0.3, 1.2 and 3.0 per meter in red, green and blue) at the sky. Through the slab the linear radiance
/// of each channel is the sky's times F + (1 − F)·exp(−σ·0.1): the eye tracer's own path at normal incidence, a
/// front reflection of F = 0.04 (taken from the sky: below the eye's branch threshold), then the transmitted ray
/// absorbed along the slab, whose back surface reflects F of it (to the sky) and transmits the rest twice by
/// 1 − F (docs/design.md "Eye view"). Tracing the glass gray (the channels' mean absorption) gives 0.866 in every
/// channel, where this gives 0.972, 0.891 and 0.751. The tolerance, 1e-3 relative, is float rounding.
///
/// The same slab made dispersive (Abbe number 10) is traced spectrally, at one and at 2×2 samples a pixel: a
/// wavelength in each eye bin, at its Cauchy IOR and its absorption's upsampled spectrum, each channel the bins
/// weighed by their shares of its response (docs/design.md "Color"). A bin traced at another's wavelength, or
/// weighed by another's share, would be off by the absorption's change between them.
#[test]
fn colored_glass_tints_the_beauty_by_beer_lambert() {
    let (_gpu, device) = gpu();
    let dir = out_dir("color_beauty");
    let slab = |abbe: f64| {
        format!(
            r#"[[light]]
kind = "directional"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.0, 0.0]
intensity = 1.0

[[camera]]
name = "side"
kind = "orthographic"
position = [0.0, 0.5, 3.0]
target = [0.0, 0.5, 0.0]
up = [0.0, 1.0, 0.0]
half_height = 0.5

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = {{ kind = "diffuse", albedo = 0.8 }}

[[object]]
name = "amber"
shape = "cube"
size = [0.6, 0.6, 0.1]
translate = [0.0, 0.5, 0.0]
material = {{ kind = "dielectric", ior = 1.5, absorption = [0.3, 1.2, 3.0]{dispersion} }}
"#,
            dispersion = if abbe > 0.0 { format!(", abbe = {abbe}") } else { String::new() }
        )
    };
    // Cauchy through n_d = 1.5 at the C, d and F lines (src/scene/mod.rs, Material::ior_rgb).
    let iors = |abbe: f64| -> [f64; 3] {
        if abbe == 0.0 {
            return [1.5; 3];
        }
        let inv2 = |nm: f64| 1.0 / (nm * nm);
        let b = 0.5 / (abbe * (inv2(486.1) - inv2(656.3)));
        let a = 1.5 - b * inv2(587.6);
        [656.3, 587.6, 486.1].map(|nm| a + b * inv2(nm))
    };
    // The dispersive slab is traced spectrally: channel c is Σ_b share_b,c · v(λ_b), v the same formula at one
    // wavelength (its Cauchy IOR, its absorption's upsampled spectrum), λ_b the wavelength this pixel draws in bin b.
    use caustics::spectrum::{cauchy_ior, eye_bin_shares, eye_jitter, eye_wavelength, RgbSpectrum, EYE_BINS};
    let sigma = RgbSpectrum::fit([0.3, 1.2, 3.0]);
    let through_at = |n: f64, s: f64| {
        let f = ((n - 1.0) / (n + 1.0)).powi(2);
        f + (1.0 - f) * (-s * 0.1).exp()
    };
    let spectral = |abbe: f64| -> [f64; 3] {
        let (u, shares) = (eye_jitter(32, 32), eye_bin_shares());
        let mut out = [0.0; 3];
        for (b, share) in shares.iter().enumerate().take(EYE_BINS) {
            let nm = eye_wavelength(b, u);
            let v = through_at(cauchy_ior(iors(abbe), nm), sigma.at(nm));
            (0..3).for_each(|c| out[c] += share[c] * v);
        }
        out
    };
    for (name, abbe, aa) in [("slab", 0.0, 1), ("dispersive", 10.0, 1), ("dispersive_aa2", 10.0, 2)] {
        let img = beauty_aa(&device, &dir, name, &slab(abbe), "side", aa, |_| ());
        // The center pixel looks through the slab (|x|, |y - 0.5| < 0.3 m); a corner one at the sky alone.
        let (through, sky) = (img.at(32, 32), img.at(2, 2));
        let rgb_model: [f64; 3] = std::array::from_fn(|c| through_at(iors(abbe)[c], [0.3, 1.2, 3.0][c]));
        let expected = if abbe > 0.0 { spectral(abbe) } else { rgb_model };
        for c in 0..3 {
            let measured = through[c] as f64 / sky[c] as f64;
            eprintln!(
                "{name}, channel {c}: {measured:.5}, expected {:.5}, the RGB model {:.5}",
                expected[c], rgb_model[c]
            );
            assert!(
                (measured / expected[c] - 1.0).abs() < 2e-4,
                "{name}, channel {c}: through the slab {measured:.5} of the sky, expected {:.5} (the RGB model \
                 {:.5}; sky {sky:?}, through {through:?})",
                expected[c],
                rgb_model[c]
            );
        }
    }
}

/// Media in the beauty image (docs/design.md "Media"): a tile lies 0.15 m deep in a slab of water held in glass
/// (the water's surface names the glass as its `outside`). Light straight down reaches it through the glass and
/// 0.15 m of water (every photon path: the interreflections stay in the glass above), and an orthographic eye
/// straight down sees it through the same 0.15 m. Against the same tank of clear water, each channel of the tile's
/// radiance falls by exp(−σ·0.3) for the water's σ = 1.0, 0.5 and 0.1 /m: 0.741, 0.861 and 0.970. A renderer that
/// absorbed only where a ray leaves the water would leave the tile as bright as in clear water. The tolerance,
/// 1e-3 relative, is float rounding. The same media as two overlapping volumes, the water of higher priority than
/// the glass block, give the same pixel to 1e-4.
#[test]
fn a_tile_under_water_is_absorbed_along_both_ways() {
    let (_gpu, device) = gpu();
    let dir = out_dir("color_media");
    let tank = |absorption: &str| {
        format!(
            r#"[[light]]
kind = "directional"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.5, 0.0]
intensity = 1.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 0.5

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = {{ kind = "diffuse", albedo = 0.8 }}

[[object]]
name = "tank"
shape = "cube"
size = [0.8, 0.3, 0.8]
translate = [0.0, 0.5, 0.0]
material = {{ kind = "dielectric", ior = 1.5 }}

[[object]]
name = "water"
shape = "cube"
size = [0.7, 0.2, 0.7]
translate = [0.0, 0.5, 0.0]
material = {{ kind = "dielectric", ior = 1.33, absorption = {absorption}, outside = "tank" }}

[[object]]
name = "tile"
shape = "plane"
size = [0.4, 0.4]
translate = [0.0, 0.45, 0.0]
material = {{ kind = "diffuse", albedo = 0.8 }}
"#
        )
    };
    // No sky: its light on the tile comes from every side, not through the water along the light's one way.
    let render = |name: &str, text: &str| beauty(&device, &dir, name, text, "top", |s| s.quality.sky = Some(0.0));
    let (murky, clear) = (render("murky", &tank("[1.0, 0.5, 0.1]")), render("clear", &tank("0.0")));
    // By priority: the same media as two overlapping volumes (the water's wins where they overlap).
    let overlapping = tank("[1.0, 0.5, 0.1]")
        .replace("ior = 1.5 }", "ior = 1.5, priority = 1 }")
        .replace(r#"outside = "tank""#, "priority = 2");
    let by_priority = render("priority", &overlapping);
    // The center pixel sees the tile (|x|, |z| < 0.2 m of the 0.5 m half-window).
    let (m, c) = (murky.at(32, 32), clear.at(32, 32));
    assert!(c.iter().all(|&v| v > 0.0), "the tile is lit through clear water: {c:?}");
    for (k, sigma) in [1.0f64, 0.5, 0.1].iter().enumerate() {
        let expected = (-sigma * 0.3).exp();
        let measured = m[k] as f64 / c[k] as f64;
        assert!(
            (measured / expected - 1.0).abs() < 1e-3,
            "channel {k}: the tile in murky water at {measured:.5} of clear, Beer–Lambert both ways {expected:.5}"
        );
        let p = by_priority.at(32, 32)[k];
        assert!((p / m[k] - 1.0).abs() < 1e-4, "channel {k}: by priority {p}, by explicit interfaces {}", m[k]);
    }
}
