//! The error metric (src/metrics.rs) on synthetic images, and `caustics compare`'s exit codes.

use caustics::image_io::{write_exr, RgbImage};
use caustics::metrics::{box_filter, compare};
use std::path::PathBuf;
use std::process::Command;

fn image(w: u32, h: u32, f: impl Fn(u32, u32) -> f32) -> RgbImage {
    let mut img = RgbImage::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let v = f(x, y);
            img.data[(y * w + x) as usize] = [v, v, v];
        }
    }
    img
}

/// A smooth blob plus a floor, so every pixel is non-zero.
fn blob(w: u32, h: u32) -> RgbImage {
    image(w, h, |x, y| {
        let (u, v) = ((x as f32 + 0.5) / w as f32 - 0.4, (y as f32 + 0.5) / h as f32 - 0.55);
        0.1 + 5.0 * (-(u * u + v * v) / 0.01).exp()
    })
}

#[test]
fn identity_is_zero_error() {
    let a = blob(512, 512);
    for res in [64, 256] {
        let m = compare(&a, &a, res, 2.0);
        assert_eq!(m.rel_l1, 0.0);
        assert_eq!(m.flux_ratio, 1.0);
        assert_eq!(m.peak_offset_m, 0.0);
        assert_eq!(m.res, res);
    }
}

#[test]
fn scaled_image_gives_the_exact_flux_ratio() {
    let b = blob(300, 300);
    for s in [2.0f32, 0.5, 1.7] {
        let a = image(300, 300, |x, y| b.at(x, y)[0] * s);
        let m = compare(&a, &b, 64, 2.0);
        // Powers of two scale f32 exactly; 1.7 rounds each pixel by up to 2^-24 relative.
        let tol = if s == 1.7 { 1e-6 } else { 1e-12 };
        assert!((m.flux_ratio - s as f64).abs() < tol, "s = {s}: {m:?}");
        assert!((m.rel_l1 - (s as f64 - 1.0).abs()).abs() < tol, "s = {s}: {m:?}");
        // The peak centroid is scale-invariant up to the f32 rounding of the scaled pixels.
        assert!(m.peak_offset_m < 1e-9, "s = {s}: {m:?}");
    }
}

#[test]
fn shifted_peak_gives_the_right_offset() {
    // One bright pixel in each image: in 64² cell (10, 20) for A and (13, 24) for B, 5 cells apart; 512 px, so a
    // cell is 8 px; at 2 m across, a 64² cell is 2/64 m.
    let a = image(512, 512, |x, y| if (x, y) == (8 * 10 + 3, 8 * 20 + 4) { 100.0 } else { 0.01 });
    let b = image(512, 512, |x, y| if (x, y) == (8 * 13 + 7, 8 * 24) { 100.0 } else { 0.01 });
    let m = compare(&a, &b, 64, 2.0);
    assert!((m.peak_offset_m - 5.0 * 2.0 / 64.0).abs() < 1e-9, "{m:?}");
    // At 256², cells are 2 px: A's peak is in cell (41, 82), B's in (55, 96).
    let m = compare(&a, &b, 256, 2.0);
    let want = ((14.0f64).powi(2) + 14.0f64.powi(2)).sqrt() * 2.0 / 256.0;
    assert!((m.peak_offset_m - want).abs() < 1e-9, "{m:?}");
    // The extent scales it.
    let m = compare(&a, &b, 64, 4.0);
    assert!((m.peak_offset_m - 5.0 * 4.0 / 64.0).abs() < 1e-9, "{m:?}");
}

#[test]
fn sizes_that_are_not_multiples_compare_by_area() {
    // The same step edge at 37% of the width, rasterized at 100² and 300²: 37 and 111 columns lit. At 64² the edge
    // falls inside column 23 (23.68), which both filters must split 68/32 by area.
    let a = image(100, 100, |x, _| if x < 37 { 1.0 } else { 0.0 });
    let b = image(300, 300, |x, _| if x < 111 { 1.0 } else { 0.0 });
    let m = compare(&a, &b, 64, 2.0);
    assert!(m.rel_l1 < 1e-6, "{m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 1e-6, "{m:?}");
    // Flux is preserved by the filter: the mean of the filtered plane equals the mean of the source.
    let plane: Vec<f64> = (0..97 * 61).map(|i| ((i * 7919) % 101) as f64).collect();
    let mean = plane.iter().sum::<f64>() / plane.len() as f64;
    for (ow, oh) in [(64, 64), (256, 256), (10, 7), (97, 61), (200, 3)] {
        let f = box_filter(&plane, 97, 61, ow, oh);
        let fm = f.iter().sum::<f64>() / f.len() as f64;
        assert!((fm - mean).abs() < 1e-9 * mean, "{ow}x{oh}: {fm} vs {mean}");
    }
    // A coarse image upsampled to a finer comparison grid keeps its values.
    let c = image(10, 10, |x, y| (x + 10 * y) as f32);
    let f = box_filter(&c.channel(0).iter().map(|&v| v as f64).collect::<Vec<_>>(), 10, 10, 64, 64);
    assert_eq!(f[0], 0.0);
    assert!((f[63 * 64 + 63] - 99.0).abs() < 1e-12);
}

#[test]
fn rel_l1_is_symmetric_in_the_numerator_only() {
    // rel-L1 divides by the reference: doubling the test image is 1.0, halving it is 0.5.
    let b = blob(64, 64);
    let a2 = image(64, 64, |x, y| b.at(x, y)[0] * 2.0);
    let a5 = image(64, 64, |x, y| b.at(x, y)[0] * 0.5);
    assert!((compare(&a2, &b, 64, 2.0).rel_l1 - 1.0).abs() < 1e-12);
    assert!((compare(&a5, &b, 64, 2.0).rel_l1 - 0.5).abs() < 1e-12);
}

#[test]
fn empty_images() {
    let z = RgbImage::new(32, 32);
    let m = compare(&z, &z, 64, 2.0);
    assert_eq!((m.rel_l1, m.flux_ratio), (0.0, 1.0));
    let m = compare(&blob(32, 32), &z, 64, 2.0);
    assert!(m.rel_l1.is_infinite() && m.flux_ratio.is_infinite());
}

#[test]
fn channel_mean_is_compared() {
    // The metric works on the mean of R, G and B.
    let mut a = RgbImage::new(8, 8);
    let mut b = RgbImage::new(8, 8);
    for p in &mut a.data {
        *p = [3.0, 0.0, 0.0];
    }
    for p in &mut b.data {
        *p = [1.0, 1.0, 1.0];
    }
    let m = compare(&a, &b, 8, 2.0);
    assert!(m.rel_l1.abs() < 1e-12 && (m.flux_ratio - 1.0).abs() < 1e-12, "{m:?}");
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("caustics-metrics-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run_compare(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_caustics")).arg("compare").args(args).output().unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn compare_cli_exit_codes() {
    let dir = temp_dir("cli");
    let (pa, pb) = (dir.join("a.exr"), dir.join("b.exr"));
    let b = blob(128, 128);
    write_exr(&pb, &b).unwrap();
    write_exr(&pa, &image(128, 128, |x, y| b.at(x, y)[0] * 1.1)).unwrap();
    let (a, bs) = (pa.to_str().unwrap(), pb.to_str().unwrap());

    let (code, out, err) = run_compare(&[a, bs]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("rel-L1 (64²)") && out.contains("rel-L1 (256²)") && out.contains("flux ratio"), "{out}");

    // Within thresholds: 0.1 rel-L1 and ratio 1.1.
    let (code, out, err) = run_compare(&[a, bs, "--max-rel-l1", "0.11", "--max-flux-ratio", "1.11", "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!((v["at_res"]["flux_ratio"].as_f64().unwrap() - 1.1).abs() < 1e-6, "{out}");

    // Above a threshold: exit 1, naming the check.
    let (code, _, err) = run_compare(&[a, bs, "--max-rel-l1", "0.05"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("--max-rel-l1"), "{err}");
    let (code, _, err) = run_compare(&[a, bs, "--max-flux-ratio", "1.05"]);
    assert_eq!(code, 1, "{err}");
    let (code, _, err) = run_compare(&[bs, a, "--min-flux-ratio", "0.95"]);
    assert_eq!(code, 1, "{err}");

    // Unreadable input: exit 2, naming the file.
    let missing = dir.join("missing.exr");
    let (code, _, err) = run_compare(&[missing.to_str().unwrap(), bs]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("missing.exr"), "{err}");
    let junk = dir.join("junk.exr");
    std::fs::write(&junk, b"not an exr").unwrap();
    let (code, _, err) = run_compare(&[a, junk.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("junk.exr"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn compare_refuses_an_empty_or_non_finite_reference() {
    let dir = temp_dir("refuse");
    let (pa, pz, pn) = (dir.join("a.exr"), dir.join("zero.exr"), dir.join("nan.exr"));
    write_exr(&pa, &blob(32, 32)).unwrap();
    write_exr(&pz, &RgbImage::new(32, 32)).unwrap();
    let mut n = blob(32, 32);
    n.data[5] = [f32::NAN, 0.0, 0.0];
    write_exr(&pn, &n).unwrap();
    let (a, z, nn) = (pa.to_str().unwrap(), pz.to_str().unwrap(), pn.to_str().unwrap());
    // Two all-zero images would score rel-L1 0 and flux ratio 1: a reference must not be all zero.
    for (test, reference, needle) in
        [(z, z, "all zero"), (a, z, "all zero"), (a, nn, "non-finite"), (nn, a, "non-finite")]
    {
        let (code, out, err) = run_compare(&[test, reference]);
        assert_eq!(code, 2, "{test} vs {reference}: {out}{err}");
        assert!(err.contains(needle), "{err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn exr_metadata_round_trips_and_compare_checks_it() {
    use caustics::image_io::{read_exr_meta, write_exr_meta, ExrMeta};
    let dir = temp_dir("meta");
    let meta = |camera: &str, kind: &str, aov: &str, hash: &str| -> ExrMeta {
        [("camera", camera), ("camera_kind", kind), ("aov", aov), ("units", "W/m^2"), ("scene_hash", hash)]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let b = blob(32, 32);
    let top = meta("top", "orthographic", "caustics", "1234");
    let p = |n: &str| dir.join(n);
    write_exr_meta(&p("ref.exr"), &b, &top).unwrap();
    let (img, back) = read_exr_meta(&p("ref.exr")).unwrap();
    assert_eq!(back, top);
    assert_eq!(img.data, b.data);
    write_exr_meta(&p("same.exr"), &b, &top).unwrap();
    write_exr_meta(&p("persp.exr"), &b, &meta("main", "perspective", "caustics", "1234")).unwrap();
    write_exr_meta(&p("direct.exr"), &b, &meta("top", "orthographic", "direct", "1234")).unwrap();
    write_exr_meta(&p("other_scene.exr"), &b, &meta("top", "orthographic", "caustics", "99")).unwrap();
    let s = |n: &str| p(n).to_str().unwrap().to_string();
    let (code, _, err) = run_compare(&[&s("same.exr"), &s("ref.exr")]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("warning"), "{err}");
    for (name, needle) in [("persp.exr", "camera `main`"), ("direct.exr", "aov `direct`")] {
        let (code, _, err) = run_compare(&[&s(name), &s("ref.exr")]);
        assert_eq!(code, 2, "{name}: {err}");
        assert!(err.contains(needle), "{err}");
    }
    let (code, _, err) = run_compare(&[&s("other_scene.exr"), &s("ref.exr")]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("warning") && err.contains("scene_hash"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn peak_offset_is_stable() {
    // A broad caustic with a flat top: the argmax lands on whichever near-equal pixel a little noise favours, and
    // jumped by several pixels between two renders of the same caustic. The peak centroid does not.
    let flat = |w: u32, seed: u32| {
        image(w, w, move |x, y| {
            let (u, v) = ((x as f32 + 0.5) / w as f32 - 0.5, (y as f32 + 0.5) / w as f32 - 0.5);
            let r2 = u * u + v * v;
            let noise = (((x * 7919 + y * 104729 + seed * 31) % 1000) as f32 / 1000.0 - 0.5) * 1e-3;
            if r2 < 0.04 {
                1.0 + noise
            } else {
                0.01
            }
        })
    };
    let a = flat(256, 1);
    let b = flat(256, 2);
    assert_eq!(compare(&a, &a, 64, 2.0).peak_offset_m, 0.0);
    for res in [64, 256] {
        let m = compare(&a, &b, res, 2.0);
        assert!(m.peak_offset_m < 0.002, "res {res}: {m:?}");
    }
}

/// `compare` reports only the resolutions both images carry: 64×64 images have no 256² rel-L1 (a box filter up to
/// 256² measured 0.616 where the 64² error was 0.063), `--res` finer than the images is refused (exit 2), and two
/// sizes that differ get a warning.
#[test]
fn compare_reports_only_the_resolutions_the_images_carry() {
    let dir = temp_dir("carry");
    let b = blob(64, 64);
    let (pa, pb, pbig) = (dir.join("a.exr"), dir.join("b.exr"), dir.join("big.exr"));
    write_exr(&pb, &b).unwrap();
    write_exr(&pa, &image(64, 64, |x, y| b.at(x, y)[0] * 1.1)).unwrap();
    let big = blob(256, 256);
    write_exr(&pbig, &big).unwrap();
    let (a, bs, bg) = (pa.to_str().unwrap(), pb.to_str().unwrap(), pbig.to_str().unwrap());
    let (code, out, err) = run_compare(&[a, bs, "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!((v["rel_l1_64"].as_f64().unwrap() - 0.1).abs() < 1e-6, "{out}");
    assert!(v["rel_l1_256"].is_null(), "{out}");
    let (code, out, _) = run_compare(&[a, bs]);
    assert_eq!(code, 0);
    assert!(out.contains("rel-L1 (256²): – (finer than the images: 64 columns)"), "{out}");
    let (code, _, err) = run_compare(&[a, bs, "--res", "128"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--res 128") && err.contains("64 columns"), "{err}");
    // A 64² image against a 256² one: compared at 64², with a warning that the sizes differ.
    let (code, out, err) = run_compare(&[a, bg, "--json"]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(err.contains("warning") && err.contains("64x64") && err.contains("256x256"), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert!(v["rel_l1_64"].is_number() && v["rel_l1_256"].is_null(), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}
