//! The beauty image as linear radiance (`--aov beauty --out x.exr`) and its exposure (`--exposure EV`).

mod common;
use common::*;

/// On a diffuse receiver the linear beauty is the reflected radiance (albedo/π)·(E_direct + E_caustics + E_env),
/// in W/(m²·sr), with E_env = π·L_sky·0.85 in the red channel on the upward floor under `--sky L_sky`
/// (docs/design.md "Environment"): checked on the floor pixels the top camera sees directly (outside the sphere's
/// 0.3 m disk, with a margin), one sample a pixel as the AOVs. Measured: agreement to float precision.
#[test]
fn linear_beauty_is_reflected_radiance() {
    let dir = out_dir("beauty_linear");
    let base = ["--camera", "top", "--size", "128x128", "--level", "2", "--transport", "two-interface", "--aa", "1"];
    let sky = 0.02;
    fn with<'a>(base: &[&'a str], aov: &'a str) -> Vec<&'a str> {
        let mut a = base.to_vec();
        a.extend(["--aov", aov]);
        a
    }
    let exr = dir.join("beauty.exr");
    ok(&[
        "render",
        "--scene",
        SPHERE,
        "--out",
        exr.to_str().unwrap(),
        "--camera",
        "top",
        "--size",
        "128x128",
        "--level",
        "2",
        "--transport",
        "two-interface",
        "--aa",
        "1",
        "--sky",
        "0.02",
    ]);
    let (_, direct) = render(&dir, "direct", SPHERE, &with(&base, "direct"));
    let (_, caustics) = render(&dir, "caustics", SPHERE, &with(&base, "caustics"));
    let (w, h, l) = read_plane(&exr);
    let (_, _, ed) = read_plane(&direct);
    let (_, _, ec) = read_plane(&caustics);
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
/// compress, and the environment counts too), and an out-of-range exposure is bad input.
#[test]
fn exposure_brightens_the_beauty() {
    let dir = out_dir("beauty_exposure");
    let args = ["--camera", "main", "--size", "96x96", "--level", "1", "--transport", "two-interface"];
    let (_, p0) = render(&dir, "ev0", SPHERE, &args);
    let mut plus = args.to_vec();
    plus.extend(["--exposure", "1"]);
    let (_, p1) = render(&dir, "ev1", SPHERE, &plus);
    let mean = |p: &std::path::Path| {
        let (_, _, rgba) = caustics::image_io::read_png(p).expect("png");
        let rgb: Vec<f64> = rgba.chunks_exact(4).flat_map(|p| p[..3].iter().map(|&v| v as f64)).collect();
        rgb.iter().sum::<f64>() / rgb.len() as f64
    };
    let (m0, m1) = (mean(&p0), mean(&p1));
    eprintln!("mean 8-bit value: {m0} at 0 EV, {m1} at +1 EV");
    assert!(m1 > m0 * 1.05, "+1 EV: mean {m1} against {m0}");
    let out = dir.join("bad.png");
    let o = caustics(&["render", "--scene", SPHERE, "--exposure", "100", "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("--exposure"), "{stderr}");
    assert_no_output(&out);
}
