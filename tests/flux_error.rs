//! The flux-error metric (`--metric flux-error`, docs/design.md "The flux-error metric"): against dense at the
//! same maximal level on the sphere and the bunny (every path, exact transport), with batching under a tiny
//! budget, GPU-driven under both transports, and the `--target-error` knob's monotonicity and calibration.
//! Tolerances come from measurement on lavapipe with the same settings; each test states what it measured.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::{compare, Metrics};
use caustics::reference::{Aov, Paths};
use common::*;
use std::path::Path;

fn reference_image(scene: &str, paths: Paths, photons: u64) -> RgbImage {
    top_reference(scene, Aov::Caustics, paths, photons, 256)
}

fn caustics_aov(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> (serde_json::Value, RgbImage) {
    let mut args = vec!["--camera", "top", "--aov", "caustics", "--size", "256x256"];
    args.extend_from_slice(extra);
    let (s, out) = render(dir, name, scene, &args);
    (s, caustics::image_io::read_exr(&out).unwrap())
}

fn photons(s: &serde_json::Value) -> u64 {
    s["photons_splatted"].as_u64().unwrap()
}

fn score(img: &RgbImage, r: &RgbImage) -> Metrics {
    compare(img, r, 64, 2.0)
}

/// The target error the calibration table maps to tau = 0.3, the threshold these tests' photon counts and error
/// bounds are sized for.
const TAU_03: &str = "0.0158";

/// Dense and flux-error at level `level` under exact transport, scored against the every-path reference.
fn against_dense(name: &str, scene: &str, level: &str, target: &str) -> (u64, Metrics, u64, Metrics) {
    let dir = out_dir(name);
    let (sd, id) = caustics_aov(&dir, "dense", scene, &["--transport", "exact", "--method", "dense", "--level", level]);
    let (sf, i_f) = caustics_aov(
        &dir,
        "flux",
        scene,
        &["--transport", "exact", "--metric", "flux-error", "--target-error", target, "--level", level],
    );
    assert_eq!(sf["metric"], "flux-error");
    assert_eq!(sf["tau"].as_f64().unwrap() as f32, 0.3, "the calibration maps {target} to tau 0.3");
    assert_eq!(sf["host_readbacks_per_frame"], 0);
    let r = reference_image(scene, Paths::All, 4_000_000);
    let (a, b) = (score(&id, &r), score(&i_f, &r));
    eprintln!("{name}: dense {} photons {a:?}\nflux-error {} photons {b:?}", photons(&sd), photons(&sf));
    (photons(&sd), a, photons(&sf), b)
}

/// Sphere, exact transport, level 4, `--target-error 0.0158` (τ 0.3), every-path reference of 4M photons.
/// Measured: dense 824,416 photons, rel-L1 (64²) 0.742%; flux-error 232,204 photons (28.2% of dense's), 0.765%.
#[test]
fn sphere_matches_dense_with_fewer_photons() {
    let (pd, d, pf, f) = against_dense("flux_error_sphere", SPHERE, "4", TAU_03);
    assert!((pf as f64) < 0.35 * pd as f64, "flux-error {pf} photons vs dense {pd}");
    assert!(f.rel_l1 <= d.rel_l1 + 0.002, "flux-error rel-L1 {} vs dense {}", f.rel_l1, d.rel_l1);
    assert!((f.flux_ratio - 1.0).abs() < 0.005, "flux ratio {}", f.flux_ratio);
}

/// Bunny, exact transport, level 4, `--target-error 0.0158` (τ 0.3). Its thin parts send the children's dominant
/// paths different ways (escapes, different interfaces) far more often than on the sphere, so fewer cells
/// converge. Measured: dense 491,341 photons, rel-L1 3.28%; flux-error 254,110 (51.7%), 3.53% (251,887 before the
/// checks' cap of 8 interactions; before cells whose four dominant paths all end the same other way had to fit the
/// budget: 212,506 photons, 3.70%).
#[test]
fn bunny_matches_dense_with_fewer_photons() {
    let (pd, d, pf, f) = against_dense("flux_error_bunny", BUNNY, "4", TAU_03);
    assert!((pf as f64) < 0.55 * pd as f64, "flux-error {pf} photons vs dense {pd}");
    assert!(f.rel_l1 <= d.rel_l1 + 0.007, "flux-error rel-L1 {} vs dense {}", f.rel_l1, d.rel_l1);
}

/// GPU-driven (no readback) under both transports, and batching: a budget small enough to force many batches
/// gives the same photons, the same per-level counts and the same image as 64 MiB.
#[test]
fn batches_gpu_driven_under_both_transports() {
    let dir = out_dir("flux_error_batching");
    // Exact transport with 2×2 weak-branch blocks: the clusters of level 2 share their siblings' turns, which the
    // traversal marks; batches must not change which do.
    for (transport, level, block) in [("two-interface", "4", "4"), ("exact", "3", "4"), ("exact", "3", "2")] {
        let common = [
            "--transport",
            transport,
            "--metric",
            "flux-error",
            "--level",
            level,
            "--check-level",
            "2",
            "--weak-block",
            block,
        ];
        let tag = format!("{transport}-{block}");
        let (big, bi) = caustics_aov(&dir, &format!("{tag}-big"), SPHERE, &common);
        let mut tiny_args = common.to_vec();
        tiny_args.extend_from_slice(&["--photon-budget", "0.25"]);
        let (tiny, ti) = caustics_aov(&dir, &format!("{tag}-tiny"), SPHERE, &tiny_args);
        for s in [&big, &tiny] {
            assert_eq!(s["host_readbacks_per_frame"], 0, "{tag}");
            assert_eq!(s["unfinished_tiles"], 0, "{tag}");
        }
        assert!(tiny["batches"].as_u64().unwrap() >= 4, "{tag}: batches {}", tiny["batches"]);
        assert_eq!(big["photons_splatted"], tiny["photons_splatted"], "{tag}");
        assert_eq!(big["levels"], tiny["levels"], "{tag}: per-level counts do not depend on batching");
        let m = compare(&ti, &bi, 64, 2.0);
        assert!(m.rel_l1 <= 1e-4, "{tag}: rel-L1 {}", m.rel_l1);
        // Some cells converged before the maximal level.
        let levels = big["levels"].as_array().unwrap();
        let early: u64 = levels[..levels.len() - 1].iter().map(|l| l["emitted"].as_u64().unwrap()).sum();
        eprintln!("{tag}: {} photons, {early} before the last level", photons(&big));
        assert!(early > 0, "{tag}: nothing converged early");
    }
}

/// Flux-error at each target error and max-level at `level`: per target, the stats' tau, the photons and the
/// error merging added: rel-L1 (64²) against max-level's image at the same level (the error `--target-error`
/// bounds; against the reference, the differences at small targets would be below its noise).
fn added_errors(name: &str, scene: &str, base: &[&str], targets: &[&str]) -> Vec<(f64, f64, u64, f64)> {
    added_errors_and_skips(name, scene, base, targets)
        .into_iter()
        .map(|(e, tau, n, added, _)| (e, tau, n, added))
        .collect()
}

/// [`added_errors`], with the checks each run skipped by prediction (the stats' `levels[].checks_skipped`, summed).
fn added_errors_and_skips(name: &str, scene: &str, base: &[&str], targets: &[&str]) -> Vec<(f64, f64, u64, f64, u64)> {
    let dir = out_dir(name);
    let mut ml_args = base.to_vec();
    ml_args.extend_from_slice(&["--metric", "max-level"]);
    let (sm, r) = caustics_aov(&dir, "max-level", scene, &ml_args);
    assert!(sm["target_error"].is_null() && sm["tau"].is_null(), "max-level reports no target error");
    let skipped = |s: &serde_json::Value| -> u64 {
        s["levels"].as_array().unwrap().iter().map(|l| l["checks_skipped"].as_u64().unwrap()).sum()
    };
    assert_eq!(skipped(&sm), 0, "max-level checks nothing");
    let mut out = Vec::new();
    for target in targets {
        let mut args = base.to_vec();
        args.extend_from_slice(&["--metric", "flux-error", "--target-error", target]);
        let (s, img) = caustics_aov(&dir, &format!("e{target}"), scene, &args);
        let e: f64 = target.parse().unwrap();
        assert_eq!(s["target_error"].as_f64().unwrap() as f32, e as f32, "the stats report the target error");
        let tau = s["tau"].as_f64().unwrap();
        let (n, added) = (photons(&s), score(&img, &r).rel_l1);
        eprintln!(
            "{name}: target {target}: tau {tau:.4}, {n} photons (max-level {}), added rel-L1 64² {added:.6}",
            photons(&sm)
        );
        out.push((e, tau, n, added, skipped(&s)));
    }
    out
}

/// `--target-error` is monotonic: over a sweep, a smaller target never gives a larger tau, more added error or
/// fewer photons. Sphere, two-interface, level 4; the targets map to tau 0.3, 0.15, 0.1, 0.02 and 0.001, measured:
/// 222,778, 260,329, 289,234, 477,481 and 820,324 photons (max-level: 820,324), added rel-L1 0.156%, 0.062%,
/// 0.038%, below 1e-6 and below 1e-6.
#[test]
fn target_error_is_monotonic() {
    let base = ["--transport", "two-interface", "--level", "4"];
    let sweep = added_errors("flux_error_monotonic", SPHERE, &base, &["0.02", "0.01", "0.005", "0.001", "0.0003"]);
    for w in sweep.windows(2) {
        let ((e0, t0, n0, a0), (e1, t1, n1, a1)) = (w[0], w[1]);
        assert!(t1 <= t0, "target {e1}: tau {t1} above {t0} at {e0}");
        assert!(n1 >= n0, "target {e1}: {n1} photons, fewer than {n0} at {e0}");
        // 1e-6: the float atomics add the same photons in another order (measured 1e-7 to 2e-7 where nothing
        // merges differently).
        assert!(a1 <= a0 + 1e-6, "target {e1}: added rel-L1 {a1} above {a0} at {e0}");
    }
    for (e, _, _, added) in sweep {
        assert!(added <= e, "target {e}: added rel-L1 {added}");
    }
}

/// The calibration (src/calibration.rs): the error merging adds over max-level at the same level stays within
/// `--target-error` E. Exact transport, level 4, the sphere and the bunny, E = 0.001 (the default; τ 0.02) and
/// 0.005 (τ 0.1). Measured on lavapipe (both in their default 4×4 weak-branch blocks): sphere 0.0053% and 0.0583%
/// (481,480 and 293,314 photons of max-level's 824,416), bunny 0.0044% and 0.343% (472,471 and 338,029 of 491,341;
/// with prediction over one level only: 0.0053%, 0.0593%, 0.0053% and 0.406%). Margin 1 (the assertion is added ≤ E):
/// these runs are among those the table was built from, whose worst cases for these two τ are 0.081% (the tilted
/// cube under two-interface) and 0.46% (the bunny under exact transport), both at level 5
/// (docs/bench/llvmpipe-llvm-15-0-6-256-bits/calibration_target_error.md); the test guards the table, the mapping
/// and the metric against regressions.
#[test]
fn target_error_bounds_the_added_error() {
    // Both in the same (default) weak-branch blocks: E bounds what merging adds, and 4×4 blocks differ from 2×2 by
    // more (0.36% rel-L1 64² on the bunny at level 4, measured on lavapipe).
    let base = ["--transport", "exact", "--level", "4"];
    for (name, scene) in [("flux_error_calibration_sphere", SPHERE), ("flux_error_calibration_bunny", BUNNY)] {
        for (e, tau, _, added) in added_errors(name, scene, &base, &["0.001", "0.005"]) {
            assert!(added <= e, "{name}: target {e} (tau {tau}): merging added rel-L1 {added}");
        }
    }
}

/// Prediction (docs/design.md, "The flux-error metric"): the descendants of a cell whose merging error is over two
/// budgets (2^(d-1) of them d levels down) skip their checks and refine. That never merges more, so the error merging
/// adds over max-level stays within E. Sphere, level 4, check level 2 (so the early look-ahead at level 1 predicts
/// for level 2, and level 2 for level 3), E = 0.001, both transports; the stats must show skipped checks. Measured
/// on lavapipe: 110,960 checks skipped under each transport, 413,404 and 417,487 photons (411,268 and 415,321 with
/// no prediction; 412,108 and 416,287 with prediction over one level), added rel-L1 1e-6 and 2.0e-4. One level of
/// prediction skipped 88,880 and 88,928 checks: more than 100,000 shows the chains over two levels (from the early
/// look-ahead at level 1 down to level 3) at work.
#[test]
fn predicted_refinement_adds_no_error() {
    for transport in ["two-interface", "exact"] {
        let base = ["--transport", transport, "--level", "4", "--check-level", "2"];
        let name = format!("flux_error_prediction_{transport}");
        for (e, tau, n, added, skipped) in added_errors_and_skips(&name, SPHERE, &base, &["0.001"]) {
            eprintln!("{transport}: {skipped} checks skipped");
            assert!(skipped > 100_000, "{transport}: prediction skipped {skipped} checks (110,960 measured)");
            assert!(added <= e, "{transport}: target {e} (tau {tau}), {n} photons: merging added rel-L1 {added}");
        }
    }
}

/// Bad input: a target error outside (0, 1], or a tau outside (0, 1], is refused with exit code 2.
#[test]
fn bad_target_error_exits_2() {
    let dir = out_dir("flux_error_bad");
    let out = dir.join("x.exr");
    // The hidden --tau (calibration) is checked the same way.
    for (flag, bads) in [("--target-error", ["0", "-0.1", "2", "nan"]), ("--tau", ["0", "-1", "1.5", "inf"])] {
        for bad in bads {
            let o = caustics(&[
                "render",
                "--metric",
                "flux-error",
                flag,
                bad,
                "--aov",
                "caustics",
                "--out",
                out.to_str().unwrap(),
            ]);
            let stderr = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(2), "{flag} {bad}: {stderr}");
            assert!(stderr.contains(flag), "{stderr}");
            assert_no_output(&out);
        }
    }
}

/// The default check level (src/settings.rs, `Settings::check_level`): 3, and under flux-error at most `--level` - 1,
/// so that the metric merges at levels 3 and below too instead of emitting max-level's photons through a traversal.
/// Max-error keeps 3; `--check-level` overrides both. The stats report the level used. Sphere, two-interface.
#[test]
fn default_check_level_follows_the_level() {
    let dir = out_dir("flux_error_check_level");
    // (name, metric, --level, extra arguments, the check level expected)
    let cases: [(&str, &str, &str, &[&str], u64); 4] = [
        ("fe2", "flux-error", "2", &[], 1),
        ("fe4", "flux-error", "4", &[], 3),
        ("fe2_given", "flux-error", "2", &["--check-level", "2"], 2),
        ("me2", "max-error", "2", &[], 3),
    ];
    let mut level2 = Vec::new();
    for (name, metric, level, extra, want) in cases {
        let base = ["--transport", "two-interface", "--method", "adaptive", "--metric", metric, "--level", level];
        let (s, _) = caustics_aov(&dir, name, SPHERE, &[&base[..], extra].concat());
        assert_eq!(s["check_level"].as_u64(), Some(want), "{name}: {}", s["check_level"]);
        let levels = s["levels"].as_array().unwrap();
        let early: u64 = levels[..levels.len() - 1].iter().map(|l| l["emitted"].as_u64().unwrap()).sum();
        if level == "2" {
            level2.push((name, photons(&s), early));
        }
    }
    assert_eq!(level2.len(), 3, "the three cases at level 2");
    let (dense, _) =
        caustics_aov(&dir, "dense2", SPHERE, &["--transport", "two-interface", "--method", "dense", "--level", "2"]);
    assert!(dense["check_level"].is_null(), "dense checks nothing: {}", dense["check_level"]);
    // At level 2 flux-error merges (photons before the last level, fewer photons than dense); with the check level
    // at 2, and under max-error's 3, nothing is checked and the photons are dense's.
    for (name, n, early) in level2 {
        if name == "fe2" {
            assert!(early > 0 && n < photons(&dense), "{name}: {n} photons ({early} early), dense {}", photons(&dense));
        } else {
            assert!(
                early == 0 && n == photons(&dense),
                "{name}: {n} photons ({early} early), dense {}",
                photons(&dense)
            );
        }
    }
}
