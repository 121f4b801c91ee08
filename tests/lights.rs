//! Several lights (assets/scenes/two_lights.toml): each light has its own light view, photons, caustic map and
//! shadow map, and the eye pass adds each light's radiance and irradiances. So the AOVs of the two-light scene are
//! the sums of the AOVs of each light alone (linearity), the photons are the sums of each light's, a reused frame
//! gives the same image, and the CPU reference of every path agrees.

mod common;
use caustics::image_io::RgbImage;
use caustics::settings::{Metric, Settings, Transport};
use caustics::Aov;
use common::*;
use std::path::{Path, PathBuf};
use std::sync::Arc;

const TWO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/two_lights.toml");

/// The two-light scene with only light `keep` (0 or 1), written next to the test's outputs.
fn one_light(dir: &Path, keep: usize) -> PathBuf {
    let text = std::fs::read_to_string(TWO).unwrap();
    let mut parts: Vec<&str> = text.split("[[light]]").collect();
    let (second, rest) = parts[2].split_once("# Orthographic").unwrap();
    let head = parts.remove(0);
    let light = if keep == 0 { parts[0] } else { second };
    let path = dir.join(format!("light{keep}.toml"));
    std::fs::write(&path, format!("{head}[[light]]{light}# Orthographic{rest}")).unwrap();
    path
}

/// Σ|a − b| / Σ|b| over the RGB channels.
fn rel_l1(a: &RgbImage, b: &RgbImage) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let (mut num, mut den) = (0.0, 0.0);
    for (p, q) in a.data.iter().zip(&b.data) {
        for c in 0..3 {
            num += (p[c] as f64 - q[c] as f64).abs();
            den += (q[c] as f64).abs();
        }
    }
    num / den.max(1e-30)
}

fn sum(a: &RgbImage, b: &RgbImage) -> RgbImage {
    let mut out = a.clone();
    for (p, q) in out.data.iter_mut().zip(&b.data) {
        for c in 0..3 {
            p[c] += q[c];
        }
    }
    out
}

/// Settings at `level` (adaptive flux-error, the default method) under `transport`.
fn at_level(level: u32, transport: Transport) -> Settings {
    let mut s = adaptive(level, Metric::FluxError);
    s.quality.transport = transport;
    s
}

/// `aov` of `scene`'s `top` camera at 128², level 2 under `transport`, rendered in process on the shared device;
/// validation stayed silent.
fn top(device: &Arc<caustics::gpu::Device>, scene: &str, transport: Transport, aov: Aov) -> Shot {
    shot_at(device, scene, at_level(2, transport), 0.0, aov, 128)
}

/// Each pass's photons.
fn light_photons(s: &Shot) -> Vec<u64> {
    s.report.lights.iter().map(|l| l.state.map_or(0, |x| x.photons_total as u64)).collect()
}

/// Both lights at once against each light alone: caustics and direct AOVs, exact and two-interface transport.
/// Measured on lavapipe: rel-L1 below 1e-6 (only the order of float additions differs); the test allows 1e-4.
#[test]
fn two_lights_add_up() {
    let (_gpu, device) = gpu();
    let dir = out_dir("lights_linear");
    let singles = [one_light(&dir, 0), one_light(&dir, 1)];
    for transport in [Transport::Exact, Transport::TwoInterface] {
        for aov in [Aov::Caustics, Aov::Direct] {
            let both = top(&device, TWO, transport, aov);
            let mut parts = Vec::new();
            let mut photons = 0;
            for (i, scene) in singles.iter().enumerate() {
                let s = top(&device, scene.to_str().unwrap(), transport, aov);
                photons += s.photons();
                assert_eq!(s.report.lights.len(), 1);
                assert_eq!(
                    light_photons(&s)[0],
                    light_photons(&both)[i],
                    "{transport:?}: light {i}'s photons alone and together"
                );
                parts.push(s.img);
            }
            let lights = &both.report.lights;
            assert_eq!(lights.len(), 2);
            assert!(lights.iter().all(|l| l.caustics && l.state.is_some_and(|x| x.photons_total > 0)));
            assert_eq!(both.photons(), photons, "photons: the sum over lights");
            assert_eq!(both.report.host_readbacks, 0);
            if transport == Transport::Exact {
                for l in lights {
                    let r = l.transport.expect("an exact-transport pass").residual();
                    assert!(r.abs() < 1e-6, "{transport:?}: energy account residual {r}");
                }
            }
            let e = rel_l1(&both.img, &sum(&parts[0], &parts[1]));
            eprintln!("{transport:?} {aov:?}: rel-L1(both, light 0 + light 1) = {e:.2e}");
            assert!(e <= 1e-4, "{transport:?} {aov:?}: rel-L1 {e}");
            // Each light contributes (the two are not the same light twice).
            let share = rel_l1(&parts[0], &sum(&parts[0], &parts[1]));
            assert!(share > 0.1, "{transport:?} {aov:?}: light 1 adds {share}");
        }
    }
}

/// The beauty is linear in the lights too, the glass included: under exact transport each eye sample that meets
/// the glass is traced once per light, and the receivers it reaches are shaded with that light's shadow and
/// caustic maps, so with the environment off the two-light beauty (linear, main camera, one sample a pixel) is the
/// sum of each light's alone on every pixel. Before, the glass showed the receivers under the first light only:
/// the pixels that see the floor through the sphere (where the direct AOV, which holds the receivers seen
/// directly, is zero) held light 0's share alone: 35% short there. Measured on lavapipe: rel-L1 4e-9 over the
/// image, 3e-8 over its 272 glass pixels; the test allows 1e-4. A glass pass shades with three lights: four
/// lights (the two, twice) take a second, added pass, and give twice the two lights' glass.
#[test]
fn glass_shows_every_light() {
    let (_gpu, device) = gpu();
    let dir = out_dir("lights_glass");
    let singles = [one_light(&dir, 0), one_light(&dir, 1)];
    let mut settings = at_level(2, Transport::Exact);
    settings.quality.aa = 1;
    settings.quality.sky = Some(0.0);
    let view = |scene: &str, aov: Aov| {
        let mut r = renderer(&device, scene, settings.clone());
        let (img, _) = camera_aov(&mut r, "main", (96, 96), aov);
        img
    };
    let beauty = |scene: &str| view(scene, Aov::BeautyHdr);
    let both = beauty(TWO);
    let parts = [beauty(singles[0].to_str().unwrap()), beauty(singles[1].to_str().unwrap())];
    let total = sum(&parts[0], &parts[1]);
    let e = rel_l1(&both, &total);
    // The glass pixels: lit, but with no receiver seen directly (the direct AOV is zero there).
    let direct = view(TWO, Aov::Direct);
    let glass: Vec<usize> =
        (0..both.data.len()).filter(|&i| direct.data[i] == [0.0; 3] && both.data[i][0] > 0.0).collect();
    let sub = |img: &RgbImage| RgbImage {
        width: glass.len() as u32,
        height: 1,
        data: glass.iter().map(|&i| img.data[i]).collect(),
    };
    let eg = rel_l1(&sub(&both), &sub(&total));
    let share = rel_l1(&sub(&parts[0]), &sub(&total));
    eprintln!("beauty: rel-L1(both, light 0 + light 1) {e:.2e}; over {} glass pixels {eg:.2e}; light 1's share there {share:.3}", glass.len());
    assert!(glass.len() > 150, "{} glass pixels", glass.len());
    assert!(e <= 1e-4 && eg <= 1e-4, "rel-L1 {e} over the image, {eg} over the glass");
    assert!(share > 0.1, "the second light shows through the glass: {share}");
    // Four lights (the two, twice) take two glass passes, the second adding its lights: twice the two-light beauty.
    let text = std::fs::read_to_string(TWO).unwrap();
    let (head, rest) = text.split_once("# Orthographic").unwrap();
    let lights = &head[head.find("[[light]]").unwrap()..];
    let four = dir.join("four.toml");
    std::fs::write(&four, format!("{head}{lights}# Orthographic{rest}")).unwrap();
    let four = beauty(four.to_str().unwrap());
    let twice = sum(&both, &both);
    let e4 = rel_l1(&sub(&four), &sub(&twice));
    eprintln!("four lights over the glass pixels: rel-L1 against twice the two {e4:.2e}");
    assert!(e4 <= 1e-4, "four lights: rel-L1 {e4} over the glass");
}

/// The second frame reuses both lights' caustic maps (nothing changed) and gives the same image.
#[test]
fn two_lights_reuse() {
    let (_gpu, device) = gpu();
    let mut r = renderer(&device, TWO, at_level(2, Transport::Exact));
    let (a, one) = top_caustics(&mut r, 128);
    let (b, two) = top_caustics(&mut r, 128);
    assert!(!one.reused);
    assert!(two.reused);
    assert_eq!(two.photons(), one.photons(), "a reused frame reports the photons it reused");
    let e = rel_l1(&b, &a);
    assert!(e <= 1e-6, "reused frame: rel-L1 {e}");
}

/// More lights than the renderer handles: a clear error naming the light, exit 2.
#[test]
fn five_lights_are_refused() {
    let dir = out_dir("lights_five");
    let text = std::fs::read_to_string(TWO).unwrap();
    let (head, rest) = text.split_once("[[light]]").unwrap();
    let (light, rest) = rest.split_once("[[light]]").unwrap();
    let many = format!("{head}{}[[light]]{rest}", format!("[[light]]{light}").repeat(4));
    let path = dir.join("five.toml");
    std::fs::write(&path, many).unwrap();
    let out = caustics(&["render", "--scene", path.to_str().unwrap(), "--out", dir.join("x.png").to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("light[4]") && err.contains("at most 4"), "{err}");
    assert_no_output(&dir.join("x.png"));
}

/// Two lights on the GPU (exact transport, adaptive flux-error at level 3) against the CPU reference of every path
/// (2M photons per light), rel-L1 at 64² on luminance and the flux ratio. Measured on lavapipe: rel-L1 0.0109, flux
/// ratio 1.00007 (0.0129 and 1.00045 before the spectral light model; the level's sampling error plus the
/// reference's noise); the test allows 0.02 and 0.005.
#[test]
fn two_lights_match_reference() {
    use caustics::metrics::compare;
    use caustics::reference::{Aov, Paths};
    let (_gpu, device) = gpu();
    let s = shot(&device, TWO, at_level(3, Transport::Exact));
    assert_eq!(s.report.lights.len(), 2);
    let r = top_reference(TWO, Aov::Caustics, Paths::All, 2_000_000, 256);
    let m = compare(&s.img, &r, 64, 2.0);
    eprintln!("two lights, exact level 3 vs reference: {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.005, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.02, "rel-L1 {}", m.rel_l1);
}

/// A plano-convex lens (n = 1.5, R = 0.5 m: f = 1 m, 50 mm across) under a sun of `diameter_deg`, with the floor at
/// its back focus, written to `dir`.
fn lens_under_sun(dir: &Path, diameter_deg: f32) -> PathBuf {
    let (rc, a, e) = (0.5f64, 0.025f64, 0.002f64);
    let sag = rc - (rc * rc - a * a).sqrt();
    let yc = e + sag - rc;
    let mut profile = vec![[0.0, 0.0], [a, 0.0], [a, e]];
    profile.extend((0..48).rev().map(|k| {
        let r = a * k as f64 / 48.0;
        [r, yc + (rc * rc - r * r).sqrt()]
    }));
    let profile: Vec<String> = profile.iter().map(|[r, y]| format!("[{r:.7}, {y:.7}]")).collect();
    // Back focal length from the flat face: f − t/n, t the center thickness.
    let bfl = 1.0 - (e + sag) / 1.5;
    let text = format!(
        r#"[[light]]
kind = "sun"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
intensity = 1000.0
angular_diameter_deg = {diameter_deg}

[[object]]
name = "floor"
shape = "plane"
size = [0.12, 0.12]
material = {{ kind = "diffuse", albedo = 0.8 }}

[[object]]
name = "lens"
shape = "lathe"
segments = 256
profile = [{}]
translate = [0.0, {bfl:.6}, 0.0]
material = {{ kind = "dielectric", ior = 1.5 }}

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 0.5, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 0.06
"#,
        profile.join(", ")
    );
    let path = dir.join(format!("lens_{diameter_deg}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// The flux (W) of a caustics AOV over the disk of radius `r` m around its centroid, and its mean squared distance
/// from the centroid there (m²), from the `top` camera's 0.12 m square.
fn spot(img: &RgbImage, r: f64) -> (f64, f64) {
    let px = 0.12 / img.width as f64;
    let n = img.width as usize;
    let at = |i: usize| ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
    let (mut w, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for (i, p) in img.data.iter().enumerate() {
        let (x, y) = at(i);
        w += p[0] as f64;
        cx += x * p[0] as f64;
        cy += y * p[0] as f64;
    }
    let (cx, cy) = (cx / w, cy / w);
    let (mut flux, mut m2) = (0.0, 0.0);
    for (i, p) in img.data.iter().enumerate() {
        let (x, y) = at(i);
        let d2 = ((x - cx).powi(2) + (y - cy).powi(2)) * px * px;
        if d2 <= r * r {
            flux += p[0] as f64;
            m2 += p[0] as f64 * d2;
        }
    }
    (flux * px * px, m2 / flux)
}

/// A sun's caustic under a thin lens blurs as its angular size says: a sun of 2° focuses through a lens of f = 1 m
/// into a uniform disk of radius f tan 1° = 17.45 mm, whose mean squared radius is half its radius squared (less
/// the point sun's own focal spot, from the lens's aberration and the splats). It keeps the point sun's flux, and
/// agrees with the CPU reference, which samples the same disk of directions.
#[test]
fn a_suns_focal_spot_is_its_angular_size() {
    let (_gpu, device) = gpu();
    let dir = out_dir("sun_lens");
    let settings = || adaptive(5, Metric::FluxError);
    let point = lens_under_sun(&dir, 0.0);
    let sun = lens_under_sun(&dir, 2.0);
    let p = shot_at(&device, point.to_str().unwrap(), settings(), 0.0, Aov::Caustics, 512);
    let s = shot_at(&device, sun.to_str().unwrap(), settings(), 0.0, Aov::Caustics, 512);
    assert_eq!(p.photons(), s.photons(), "the sun's cells refine as its center's");
    let (fp, m2p) = spot(&p.img, 0.03);
    let (fs, m2s) = spot(&s.img, 0.03);
    let radius = (2.0 * (m2s - m2p)).sqrt();
    let expected = 1.0f64.to_radians().tan();
    eprintln!(
        "point sun: {fp:.6} W, rms {:.3} mm; 2° sun: {fs:.6} W, rms {:.3} mm; disk radius {:.3} mm (expected {:.3})",
        m2p.sqrt() * 1e3,
        m2s.sqrt() * 1e3,
        radius * 1e3,
        expected * 1e3
    );
    assert!((radius / expected - 1.0).abs() < 0.05, "focal spot radius {radius} m, expected {expected} m");
    assert!((fs / fp - 1.0).abs() < 0.01, "the sun's spot holds {fs} W, the point sun's {fp} W");
}

/// The GPU's sun against the CPU reference's, both sampling its 2° disk of directions: the lens's caustic and the
/// floor's direct light, whose shadow's penumbra (35 mm wide, 1 m under the lens) the eye's shading finds by
/// percentage-closer soft shadows. Measured on lavapipe at 64²: caustics 1.0% (a 4M-photon reference), direct 0.95%
/// (64M photons: a sun's tilted rays leave the reference's strata, and 8M of them are themselves 2.6% apart).
#[test]
fn a_suns_caustic_and_soft_shadow_match_the_reference() {
    use caustics::reference::Aov as RefAov;
    let (_gpu, device) = gpu();
    let dir = out_dir("sun_reference");
    let sun = lens_under_sun(&dir, 2.0);
    let cases = [(Aov::Caustics, RefAov::Caustics, 4_000_000, 0.03), (Aov::Direct, RefAov::Direct, 64_000_000, 0.025)];
    matches_reference(&device, sun.to_str().unwrap(), 5, 0.12, &cases);
}

/// `scene`'s `top` AOVs at 256², adaptive flux-error at `level`, against the CPU reference of every path at 64² (a
/// top camera `extent` m across): per case, the AOV, the reference's, its photons and the bound on rel-L1; the
/// flux within 1%.
fn matches_reference(
    device: &Arc<caustics::gpu::Device>,
    scene: &str,
    level: u32,
    extent: f32,
    cases: &[(Aov, caustics::reference::Aov, u64, f64)],
) {
    for &(aov, ref_aov, photons, bound) in cases {
        let gpu = shot_at(device, scene, adaptive(level, Metric::FluxError), 0.0, aov, 256);
        let reference = top_reference(scene, ref_aov, caustics::reference::Paths::All, photons, 256);
        let m = caustics::metrics::compare(&gpu.img, &reference, 64, extent);
        eprintln!("{aov:?}: rel-L1 {:.4} at 64², flux ratio {:.5}", m.rel_l1, m.flux_ratio);
        assert!(m.rel_l1 < bound, "{aov:?}: rel-L1 {} against the reference at 64²", m.rel_l1);
        assert!((m.flux_ratio - 1.0).abs() < 0.01, "{aov:?}: flux ratio {}", m.flux_ratio);
    }
}

/// A sphere light (sphere.toml's spot with a 0.1 m bulb) against the CPU reference, both starting each ray at a
/// point of the sphere's disk across its direction: the ball's caustic and the floor's direct light, whose shadow
/// of the ball has a penumbra. Measured on lavapipe at 64², level 4: caustics 1.7% against the test's 4M photons
/// (1.4% against 8M), flux 0.9984; direct 2.2% against the test's 16M photons, 1.7% against 32M (an 8M reference
/// is itself 2.8% from that: the sphere's points leave the reference's strata), flux 1.0006.
#[test]
fn a_sphere_light_matches_the_reference() {
    use caustics::reference::Aov as RefAov;
    let (_gpu, device) = gpu();
    let dir = out_dir("sphere_light");
    let text = std::fs::read_to_string(scene("sphere.toml")).unwrap();
    let bulb = text.replacen("intensity = 1.0", "intensity = 1.0\nradius = 0.1", 1);
    assert_ne!(bulb, text);
    let path = dir.join("sphere_light.toml");
    std::fs::write(&path, bulb).unwrap();
    let cases = [(Aov::Caustics, RefAov::Caustics, 4_000_000, 0.03), (Aov::Direct, RefAov::Direct, 16_000_000, 0.035)];
    matches_reference(&device, path.to_str().unwrap(), 4, 2.0, &cases);
}

/// `Renderer::set_light` refuses what the scene file refuses, and keeps the light it had: a radius that is negative
/// or not finite, an angular radius past 10°, a radius on a directional light (a sun has an angular size), an
/// angular radius on a spot or point light (a bulb has a radius), and a spot's cone too narrow for its light view.
#[test]
fn set_light_refuses_a_size_the_light_cannot_have() {
    let (_gpu, device) = gpu();
    let mut r = renderer(&device, &scene("sphere.toml"), Settings::default());
    let spot = r.scene().lights[0].clone();
    let mut sun = spot.clone();
    sun.kind = caustics::scene::LightKind::Directional;
    let cases = [
        (caustics::scene::Light { radius: -0.1, ..spot.clone() }, "a radius must be finite"),
        (caustics::scene::Light { radius: f32::NAN, ..spot.clone() }, "a radius must be finite"),
        (caustics::scene::Light { angular_radius: 0.3, ..sun.clone() }, "an angular radius within [0, 10]"),
        (caustics::scene::Light { radius: 0.1, ..sun.clone() }, "a directional light (a sun) has an angular radius"),
        (caustics::scene::Light { angular_radius: 0.01, ..spot.clone() }, "a spot or point light a radius"),
        (caustics::scene::Light { cone: 1e-30, ..spot.clone() }, "light 0: a spot light's cone half-angle"),
    ];
    for (light, needle) in cases {
        let e = r.set_light(0, light).expect_err("refused").to_string();
        assert!(e.contains(needle), "{e}");
        assert_eq!(r.scene().lights[0], spot, "the light it had is kept");
    }
    r.set_light(0, caustics::scene::Light { radius: 0.05, ..spot.clone() }).expect("a bulb");
    r.set_light(0, caustics::scene::Light { angular_radius: 0.01, ..sun }).expect("a sun");
}
