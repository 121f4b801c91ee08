//! The beauty image as linear radiance (`--aov beauty --out x.exr`) and its exposure (`--exposure EV`).

mod common;
use caustics::settings::{Settings, Transport};
use common::*;
use std::sync::Arc;

/// The frame of `aov` from the sphere scene's camera `camera` at `side`² (level `level`, two-interface), with the
/// settings changed by `f`, rendered in process on the shared device; validation stayed silent.
fn frame(
    device: &Arc<caustics::gpu::Device>,
    camera: &str,
    side: u32,
    level: u32,
    aov: caustics::Aov,
    f: impl FnOnce(&mut Settings),
) -> caustics::AovData {
    let settings = with(Settings::default(), |s| {
        s.quality.level = Some(level);
        s.quality.transport = Transport::TwoInterface;
        f(s);
    });
    let mut r = renderer(device, SPHERE, settings);
    camera_frame(&mut r, camera, (side, side), aov).image.expect("an image")
}

/// Channel 0 of a float AOV as a row-major plane.
fn plane(data: caustics::AovData) -> (usize, usize, Vec<f64>) {
    match data {
        caustics::AovData::Float { width, height, rgba } => {
            (width as usize, height as usize, rgba.iter().map(|p| p[0] as f64).collect())
        }
        _ => panic!("a float AOV"),
    }
}

/// On a diffuse receiver the linear beauty is the reflected radiance (albedo/π)·(E_direct + E_caustics + E_env),
/// in W/(m²·sr), with E_env = π·L_sky·0.85 in the red channel on the upward floor under `--sky L_sky`
/// (docs/design.md "Environment"): checked on the floor pixels the top camera sees directly (outside the sphere's
/// 0.3 m disk, with a margin), one sample a pixel as the AOVs. Measured: agreement to float precision.
#[test]
fn linear_beauty_is_reflected_radiance() {
    let (_gpu, device) = gpu();
    let sky = 0.02;
    // The top camera at 128², level 2, one sample a pixel.
    let top = |aov, f: fn(&mut Settings)| {
        plane(frame(&device, "top", 128, 2, aov, |s| {
            s.quality.aa = 1;
            f(s);
        }))
    };
    let (w, h, l) = top(caustics::Aov::BeautyHdr, |s| s.quality.sky = Some(0.02));
    let (_, _, ed) = top(caustics::Aov::Direct, |_| ());
    let (_, _, ec) = top(caustics::Aov::Caustics, |_| ());
    let mut n = 0;
    for y in 0..h {
        for x in 0..w {
            // Pixel centers on the floor square [-1, 1]² (columns +x, rows +z).
            let (px, pz) = ((x as f64 + 0.5) / w as f64 * 2.0 - 1.0, (y as f64 + 0.5) / h as f64 * 2.0 - 1.0);
            if (px * px + pz * pz).sqrt() < 0.4 {
                continue;
            }
            let i = y * w + x;
            let want = 0.8 / std::f64::consts::PI * (ed[i] + ec[i]) + 0.8 * 0.85 * sky;
            assert!(l[i].is_finite() && l[i] >= 0.0);
            assert!((l[i] - want).abs() <= 1e-4 * want.max(1e-3), "pixel ({x}, {y}): L {} vs {want}", l[i]);
            n += 1;
        }
    }
    assert!(n > 10_000, "{n} floor pixels checked");
}

/// +1 EV doubles the exposure: the tone-mapped beauty gets brighter (not twice: the tone map and the sRGB curve
/// compress, and the environment counts too), and an out-of-range exposure is bad input (that part a CLI run: its
/// exit code, message and the file it must not write).
#[test]
fn exposure_brightens_the_beauty() {
    {
        let (_gpu, device) = gpu();
        // The 8-bit beauty (as the CLI writes it to a PNG) of the main camera at 96², level 1.
        let mean = |exposure_ev: f32| match frame(&device, "main", 96, 1, caustics::Aov::Beauty, |s| {
            s.quality.exposure_ev = exposure_ev
        }) {
            caustics::AovData::Rgba8 { rgba, .. } => {
                let rgb: Vec<f64> = rgba.chunks_exact(4).flat_map(|p| p[..3].iter().map(|&v| v as f64)).collect();
                rgb.iter().sum::<f64>() / rgb.len() as f64
            }
            _ => panic!("an 8-bit beauty"),
        };
        let (m0, m1) = (mean(0.0), mean(1.0));
        eprintln!("mean 8-bit value: {m0} at 0 EV, {m1} at +1 EV");
        assert!(m1 > m0 * 1.05, "+1 EV: mean {m1} against {m0}");
    }
    let dir = out_dir("beauty_exposure");
    let out = dir.join("bad.png");
    let o = caustics(&["render", "--scene", SPHERE, "--exposure", "100", "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--exposure"), "{stderr}");
    assert_no_output(&out);
}
