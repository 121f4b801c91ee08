//! The dense pipeline end to end on the analytic sphere scene (docs/design.md), in physical units. In process on
//! the test binary's shared device: the CLI's default size (512², for a scene without an authored aspect) and
//! level (the device's) where a test names none.

mod common;
use caustics::settings::{Settings, Transport};
use common::*;

/// The CLI's output size for a TOML scene's camera when `--size` is not given.
const DEFAULT_SIDE: u32 = 512;

/// `settings` under `transport`.
fn under(transport: Transport, settings: Settings) -> Settings {
    with(settings, |s| s.quality.transport = transport)
}

/// [`shot_at`] at time 0 with validation checked after the frame.
fn top(
    device: &std::sync::Arc<caustics::gpu::Device>,
    scene: &str,
    settings: Settings,
    aov: caustics::Aov,
    side: u32,
) -> Shot {
    shot_at(device, scene, settings, 0.0, aov, side)
}

/// Caustic flux from the `top` camera's caustics AOV (Σ E · pixel area), dense level 3 (512² photon grid,
/// 205,081 photons), 1024² refractor g-buffers and caustic map, under the papers' two-interface model (named: the
/// figure it checks is the two-refraction one; tests/exact.rs checks the default transport's every-path figure).
#[test]
fn sphere_caustic_flux_matches_two_refraction_figure() {
    let (_gpu, device) = gpu();
    let s = top(&device, SPHERE, under(Transport::TwoInterface, dense(3)), caustics::Aov::Caustics, DEFAULT_SIDE);
    let flux = s.aov_flux;
    // docs/design.md: light refracted exactly twice puts 0.105980 W on the floor; a two-interface method can reach only
    // that part. Measured: 0.105989 W (+0.01%). The 1% band covers silhouette sampling at this grid and is
    // tight enough that losing a Fresnel factor (~4%) or the solid-angle weighting fails it.
    let rel = (flux - 0.105980) / 0.105980;
    assert!(rel.abs() < 0.01, "caustic flux {flux} W ({:+.2}%)", 100.0 * rel);
    assert_eq!(s.photons(), 205081);
    assert!(s.report.caustics, "caustic passes recorded");
    assert_eq!(s.report.host_readbacks, 0);
}

/// Direct irradiance on the floor, outside the sphere's shadow (docs/design.md: 0.678486 W for the 40° cone).
#[test]
fn sphere_direct_flux_matches_figure() {
    let (_gpu, device) = gpu();
    let s = top(&device, SPHERE, dense(3), caustics::Aov::Direct, DEFAULT_SIDE);
    let flux = s.aov_flux;
    let rel = (flux - 0.678486) / 0.678486;
    eprintln!("direct flux {flux} ({:+.3}%)", 100.0 * rel);
    assert!(rel.abs() < 0.005, "direct flux {flux} W ({:+.3}%)", 100.0 * rel);
}

/// Peak at the floor center and mirror symmetry in x and z.
#[test]
fn sphere_caustic_peak_centered_and_symmetric() {
    let (_gpu, device) = gpu();
    let s = top(&device, SPHERE, dense(3), caustics::Aov::Caustics, 1024);
    let (w, h) = (s.img.width as usize, s.img.height as usize);
    let e: Vec<f64> = s.img.data.iter().map(|p| p[0] as f64).collect();
    let px = 2.0 / w as f64; // meters per pixel: the top camera covers the 2 m floor
    let (imax, _) = e.iter().enumerate().fold((0, f64::MIN), |a, (i, &v)| if v > a.1 { (i, v) } else { a });
    let (x, z) = ((imax % w) as f64 + 0.5, (imax / w) as f64 + 0.5);
    let (x, z) = (x * px - 1.0, z * px - 1.0);
    // Centroid of the brightest region (E above half the peak): sub-pixel.
    let peak = e[imax];
    let (mut cx, mut cz, mut m) = (0.0, 0.0, 0.0);
    for (i, &v) in e.iter().enumerate() {
        if v > 0.5 * peak {
            let (xi, zi) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            cx += v * (xi * px - 1.0);
            cz += v * (zi * px - 1.0);
            m += v;
        }
    }
    let (cx, cz) = (cx / m, cz / m);
    // Caustic-map texel on the floor: the receiver window spans the 2 m floor (plus one texel of padding) over
    // 1024 texels.
    let texel = 2.0 * (1.0 + 2.0 / 1024.0) / 1024.0;
    eprintln!("peak pixel at ({x:.5}, {z:.5}) m, centroid ({cx:.6}, {cz:.6}) m, texel {texel:.5} m");
    assert!(x.abs() <= texel + px && z.abs() <= texel + px, "argmax at ({x}, {z})");
    assert!(cx.abs() <= texel && cz.abs() <= texel, "centroid at ({cx}, {cz})");
    // Mirror symmetry: rel-L1 between the image and its mirror images, box-filtered to 64².
    let filt = |f: &dyn Fn(usize, usize) -> f64| {
        let b = w / 64;
        let mut o = vec![0.0; 64 * 64];
        for y in 0..h {
            for x in 0..w {
                o[(y / b) * 64 + x / b] += f(x, y);
            }
        }
        o
    };
    let base = filt(&|x, y| e[y * w + x]);
    let mx = filt(&|x, y| e[y * w + (w - 1 - x)]);
    let mz = filt(&|x, y| e[(h - 1 - y) * w + x]);
    let total: f64 = base.iter().sum();
    let rel = |m: &[f64]| base.iter().zip(m).map(|(a, b)| (a - b).abs()).sum::<f64>() / total;
    eprintln!("mirror rel-L1: x {:.2e}, z {:.2e}", rel(&mx), rel(&mz));
    assert!(rel(&mx) < 1e-3 && rel(&mz) < 1e-3, "asymmetric: x {:.2e}, z {:.2e}", rel(&mx), rel(&mz));
}

/// A scene without a dielectric records no caustic pass and has an all-zero caustics AOV.
#[test]
fn no_dielectric_records_no_caustic_pass() {
    let (_gpu, device) = gpu();
    let dir = out_dir("no_dielectric");
    let text = std::fs::read_to_string(SPHERE).unwrap();
    let cut = text.find("[[object]]\nname = \"glass\"").expect("glass object");
    let scene = dir.join("floor_only.toml");
    std::fs::write(&scene, &text[..cut]).unwrap();
    let scene = scene.to_str().unwrap();
    let s = top(&device, scene, Settings::default(), caustics::Aov::Caustics, DEFAULT_SIDE);
    assert!(!s.report.caustics, "no caustic passes");
    assert_eq!(s.photons(), 0);
    // The stats' `gpu_ms` stages: the frame report's.
    let stages: Vec<&str> = s.report.stages.iter().map(|(l, _)| *l).collect();
    for caustic_stage in ["coverage", "photon_init", "photon_trace", "splat", "resolve", "dense_emit", "stats"] {
        assert!(!stages.contains(&caustic_stage), "{caustic_stage} recorded: {stages:?}");
    }
    assert!(stages.contains(&"eye"), "{stages:?}");
    assert!(s.img.data.iter().all(|p| p[0] == 0.0), "caustics AOV must be zero without a dielectric");
    // The direct light is still there: the whole floor, no shadow.
    let d = top(&device, scene, Settings::default(), caustics::Aov::Direct, DEFAULT_SIDE);
    // Without the shadow the floor gets I·Ω of the 2 m square seen from 2 m: Ω = 4 atan(a² / (h √(2a² + h²))).
    let omega = 4.0 * (1.0f64 / (2.0 * 6.0f64.sqrt())).atan();
    let flux = d.aov_flux;
    assert!((flux / omega - 1.0).abs() < 0.005, "direct flux without the sphere {flux}, expected {omega}");
}

/// A directional light of 1 W/m² straight down: the floor (4 m²) receives 4 W less the sphere's shadow, πR².
#[test]
fn directional_light_direct_flux() {
    let (_gpu, device) = gpu();
    let s = top(&device, &scene("directional.toml"), Settings::default(), caustics::Aov::Direct, 256);
    let expected = 4.0 - std::f64::consts::PI * 0.09;
    let flux = s.aov_flux;
    // Measured 3.71779 W (+0.013%): the shadow of the tessellated sphere, sampled at 256² pixels.
    assert!((flux / expected - 1.0).abs() < 0.003, "direct flux {flux} W, expected {expected} W");
}
