//! GPU-driven adaptive caustic maps: agreement with dense, GPU- against CPU-driven, batching under a tiny budget,
//! overflow accounting without batching, and exact photon positions at deep levels.

mod common;
use caustics::metrics::compare;
use common::*;
use serde_json::Value;

fn caustics_aov(
    dir: &std::path::Path,
    name: &str,
    scene: &str,
    extra: &[&str],
) -> (Value, caustics::image_io::RgbImage) {
    let mut args = vec!["--camera", "top", "--aov", "caustics", "--size", "256x256"];
    args.extend_from_slice(extra);
    let (s, out) = render(dir, name, scene, &args);
    (s, caustics::image_io::read_exr(&out).unwrap())
}

fn flux(s: &Value) -> f64 {
    s["aov_flux_w"].as_f64().unwrap()
}

/// Adaptive max-level at level L emits exactly the cells dense emits at 64·2^L, so the images agree.
#[test]
fn adaptive_max_level_matches_dense() {
    let dir = out_dir("adaptive_matches_dense");
    for level in ["1", "2", "3"] {
        let (d, di) = caustics_aov(&dir, &format!("dense{level}"), SPHERE, &["--method", "dense", "--level", level]);
        let extra = ["--method", "adaptive", "--metric", "max-level", "--level", level];
        let (a, ai) = caustics_aov(&dir, &format!("adapt{level}"), SPHERE, &extra);
        assert_eq!(d["photons_splatted"], a["photons_splatted"], "level {level}: photon counts");
        let m = compare(&ai, &di, 64, 2.0);
        // Same photons, same splats: only the order of the float additions differs (measured rel-L1 < 1e-6).
        assert!(m.rel_l1 <= 1e-3, "level {level}: rel-L1 {}", m.rel_l1);
        assert!((flux(&a) / flux(&d) - 1.0).abs() < 1e-5, "level {level}: flux {} vs {}", flux(&a), flux(&d));
        let levels = a["levels"].as_array().unwrap();
        let last = &levels[levels.len() - 1];
        assert_eq!(last["emitted"], a["photons_splatted"], "all photons come from the last level");
        for l in &levels[..levels.len() - 1] {
            // Each refined cell appends exactly four candidates to the next level.
            let next = &levels[l["level"].as_u64().unwrap() as usize + 1];
            assert_eq!(next["candidates"].as_u64().unwrap(), 4 * l["refined"].as_u64().unwrap());
            assert_eq!(l["candidates"].as_u64(), Some(l["refined"].as_u64().unwrap() + l["dropped"].as_u64().unwrap()));
        }
    }
}

/// The emitted cells themselves, not only their number and image: adaptive max-level emits exactly dense's set
/// of (level, x, y), also when a tiny budget splits the traversal into batches whose tiles start at deep levels.
/// The slab overflows the spot cone, so the cone test at the cell centers matters there.
#[test]
fn max_level_emits_exactly_dense_cells() {
    let dir = out_dir("max_level_cells");
    let cells = |s: &Value| -> Vec<(u64, u64, u64)> {
        let list = s["debug_photons"].as_array().unwrap();
        assert_eq!(list.len() as u64, s["photons_splatted"].as_u64().unwrap(), "every photon dumped");
        let mut v: Vec<_> = list
            .iter()
            .map(|p| (p["level"].as_u64().unwrap(), p["y"].as_u64().unwrap(), p["x"].as_u64().unwrap()))
            .collect();
        v.sort_unstable();
        v
    };
    let slab = scene("slab.toml");
    for (scene, name) in [(SPHERE, "sphere"), (slab.as_str(), "slab")] {
        let common = ["--transport", "two-interface", "--level", "2", "--debug-photons", "200000"];
        let (d, _) =
            caustics_aov(&dir, &format!("{name}_dense"), scene, &[&common[..], &["--method", "dense"]].concat());
        let dense = cells(&d);
        assert!(dense.len() > 1000, "{name}: {} photons", dense.len());
        assert!(dense.iter().all(|c| c.0 == 2));
        for (tag, budget) in [("one", "64"), ("tiny", "0.125")] {
            let extra =
                [&common[..], &["--method", "adaptive", "--metric", "max-level", "--photon-budget", budget]].concat();
            let (a, _) = caustics_aov(&dir, &format!("{name}_{tag}"), scene, &extra);
            if tag == "tiny" {
                assert!(a["batches"].as_u64().unwrap() > 1, "{name}: batches {}", a["batches"]);
            }
            assert!(cells(&a) == dense, "{name} ({tag}): max-level's cells differ from dense's");
        }
    }
}

/// GPU-driven traversal reads nothing back; the CPU-driven baseline reads each level's count back. The images
/// are the same up to float summation order.
#[test]
fn gpu_driven_and_cpu_driven_agree() {
    let dir = out_dir("gpu_vs_cpu");
    let (g, gi) = caustics_aov(&dir, "gpu", SPHERE, &["--level", "4", "--driven", "gpu"]);
    let (c, ci) = caustics_aov(&dir, "cpu", SPHERE, &["--level", "4", "--driven", "cpu"]);
    assert_eq!(g["host_readbacks_per_frame"], 0);
    // One readback per traversal level (after init, then after levels 0..3), plus one after the batch that finds
    // no tile left.
    assert_eq!(c["host_readbacks_per_frame"], 6);
    assert_eq!(g["photons_splatted"], c["photons_splatted"]);
    let m = compare(&ci, &gi, 64, 2.0);
    assert!(m.rel_l1 <= 1e-5, "rel-L1 {}", m.rel_l1);
    assert_eq!(g["levels"], c["levels"]);
}

/// A budget small enough to force many batches gives the same photons and the same image as 64 MiB.
#[test]
fn tiny_budget_batches_to_the_same_image() {
    let dir = out_dir("tiny_budget");
    let (big, bi) = caustics_aov(&dir, "big", SPHERE, &["--level", "4"]);
    let (tiny, ti) = caustics_aov(&dir, "tiny", SPHERE, &["--level", "4", "--photon-budget", "0.25"]);
    assert_eq!(big["batches"], 1);
    assert!(tiny["batches"].as_u64().unwrap() >= 4, "batches {}", tiny["batches"]);
    assert!(tiny["overflow_events"].as_u64().unwrap() > 0, "overflows must be counted");
    assert_eq!(tiny["unfinished_tiles"], 0);
    assert!(tiny["photon_buffer_bytes"].as_u64().unwrap() <= 256 * 1024);
    assert_eq!(big["photons_splatted"], tiny["photons_splatted"]);
    assert_eq!(big["levels"], tiny["levels"], "committed per-level counts do not depend on batching");
    let m = compare(&ti, &bi, 64, 2.0);
    assert!(m.rel_l1 <= 1e-4, "rel-L1 {}", m.rel_l1);
}

/// A frame whose batch slots run out keeps the batches it committed and traces the remaining tiles in a further
/// submission (a continuation), instead of being rendered again: two batch slots a submission and a tiny budget
/// force several, and the image, the photons and the rays traced equal the one-batch frame's (the rays are the
/// whole frame's: a discarded first attempt would show fewer), with one host round trip per continuation.
#[test]
fn a_frame_out_of_batch_slots_is_finished_not_rendered_again() {
    let dir = out_dir("continuation");
    let base = ["--transport", "exact", "--level", "3"];
    let (one, oi) = caustics_aov(&dir, "one", SPHERE, &base);
    let (cont, ci) =
        caustics_aov(&dir, "cont", SPHERE, &[&base[..], &["--photon-budget", "0.25", "--batch-slots", "2"]].concat());
    assert_eq!(one["continuations"], 0);
    let n = cont["continuations"].as_u64().unwrap();
    assert!(n >= 2, "continuations {n}");
    assert_eq!(cont["host_readbacks_per_frame"].as_u64(), Some(n), "one round trip per continuation");
    assert_eq!(cont["unfinished_tiles"], 0);
    assert_eq!(one["photons_splatted"], cont["photons_splatted"]);
    assert_eq!(one["exact_transport"]["rays_traced"], cont["exact_transport"]["rays_traced"]);
    assert_eq!(one["levels"], cont["levels"], "the per-level counts accumulate across the submissions");
    let residual = cont["exact_transport"]["energy"]["residual"].as_f64().unwrap();
    assert!(residual <= 1e-6, "the energy account closes across the submissions: {residual}");
    let m = compare(&ci, &oi, 64, 2.0);
    assert!(m.rel_l1 <= 1e-4 && (m.flux_ratio - 1.0).abs() <= 1e-5, "{m:?}");
}

/// With batching off, an overflowing traversal drops work, counts it, and writes nothing past the buffer (a
/// canary after the capacity survives).
#[test]
fn overflow_without_batching_is_counted_and_bounded() {
    let dir = out_dir("no_batching");
    let (full, _) = caustics_aov(&dir, "full", SPHERE, &["--level", "4"]);
    let (s, _) = caustics_aov(
        &dir,
        "nobatch",
        SPHERE,
        &["--level", "4", "--photon-budget", "0.25", "--no-batching", "--debug-photons", "16"],
    );
    assert!(s["overflow_dropped_entries"].as_u64().unwrap() > 0);
    assert!(s["overflow_events"].as_u64().unwrap() > 0);
    assert_eq!(s["photon_guard_intact"], true, "a shader wrote past the photon buffer's capacity");
    let capacity = 256 * 1024 / 8;
    assert!(s["photons_splatted"].as_u64().unwrap() <= capacity);
    assert!(s["photons_splatted"].as_u64() < full["photons_splatted"].as_u64());
}

/// Level 12 (a 262,144² grid) runs, and deep photons sit exactly where integer addressing puts them: the cell
/// center computed on the GPU equals the Rust value bit for bit, and the landing point equals an analytic
/// trace through the slab's two parallel interfaces. It names the two-interface model: its trace writes the
/// debug dump of photons that the positions are read from.
#[test]
fn deep_levels_have_exact_positions() {
    let dir = out_dir("deep_levels");
    let slab = scene("slab.toml");
    let (s, out) = render(
        &dir,
        "deep",
        &slab,
        &[
            "--transport",
            "two-interface",
            "--camera",
            "top",
            "--aov",
            "caustics",
            "--size",
            "256x256",
            "--method",
            "adaptive",
            "--metric",
            "max-error",
            "--level",
            "12",
            "--debug-photons",
            "20000",
            "--debug-min-level",
            "12",
        ],
    );
    let levels = s["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 13);
    assert!(levels[12]["emitted"].as_u64().unwrap() > 1000, "level 12 emitted {}", levels[12]["emitted"]);
    let pv = &s["photon_view"];
    let v = |k: &str| -> [f64; 3] {
        let a = pv[k].as_array().unwrap();
        [a[0].as_f64().unwrap(), a[1].as_f64().unwrap(), a[2].as_f64().unwrap()]
    };
    let (o, r, d, f) = (v("origin"), v("right"), v("down"), v("forward"));
    let win: Vec<f64> = pv["window"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect();
    let photons = s["debug_photons"].as_array().unwrap();
    assert!(photons.len() > 1000, "dumped {}", photons.len());
    let n = 64.0 * 4096.0;
    let mut worst: f64 = 0.0;
    let mut landed = 0;
    for p in photons {
        assert_eq!(p["level"], 12);
        let (x, y) = (p["x"].as_u64().unwrap() as f64, p["y"].as_u64().unwrap() as f64);
        assert!(x < n && y < n);
        let bits = |i: usize| f32::from_bits(p["uv_bits"][i].as_u64().unwrap() as u32);
        let uv = [bits(0) as f64, bits(1) as f64];
        // Bit-exact: (x + 0.5) / 2^18 is representable in f32.
        assert_eq!(bits(0), ((x + 0.5) / n) as f32, "cell center u of x = {x}");
        assert_eq!(bits(1), ((y + 0.5) / n) as f32, "cell center v of y = {y}");
        if p["status"] != 0 {
            continue;
        }
        // Analytic: the ray through the cell center refracts into the slab (n = 1.5) and out again, parallel to
        // itself, then meets the floor.
        let (ix, iy) = (win[0] + uv[0] * win[2], win[1] + uv[1] * win[2]);
        let mut dir = [0.0; 3];
        for k in 0..3 {
            dir[k] = ix * r[k] + iy * d[k] + f[k];
        }
        let len = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
        let dir = [dir[0] / len, dir[1] / len, dir[2] / len];
        let p1 = (0.525 - o[1]) / dir[1];
        let (x1, z1) = (o[0] + p1 * dir[0], o[2] + p1 * dir[2]);
        let sin_i = (1.0 - dir[1] * dir[1]).sqrt();
        let sin_t = sin_i / 1.5;
        let tan_t = sin_t / (1.0 - sin_t * sin_t).sqrt();
        let h = if sin_i > 0.0 { 0.05 * tan_t / sin_i } else { 0.0 };
        let (x2, z2) = (x1 + h * dir[0], z1 + h * dir[2]);
        let p3 = 0.475 / -dir[1];
        let (x3, z3) = (x2 + p3 * dir[0], z2 + p3 * dir[2]);
        let hit = [p["hit"][0].as_f64().unwrap(), p["hit"][2].as_f64().unwrap()];
        let err = ((hit[0] - x3).powi(2) + (hit[1] - z3).powi(2)).sqrt();
        worst = worst.max(err);
        landed += 1;
    }
    eprintln!("{landed} landed level-12 photons, worst landing error {:.2} um", worst * 1e6);
    assert!(landed > 1000);
    // A level-12 cell is 3.3 um wide on the floor; landing points agree to a fraction of a cell.
    assert!(worst < 2e-6, "worst landing error {} m", worst);
    let (_, _, e) = read_plane(&out);
    assert!(e.iter().all(|v| v.is_finite()));
}
