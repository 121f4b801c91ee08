//! GPU-driven adaptive caustic maps: agreement with dense, GPU- against CPU-driven, batching under a tiny budget,
//! overflow accounting without batching, and exact photon positions at deep levels. The tests render in process
//! on the test binary's shared device (`common::gpu`) and read its frame reports.

mod common;
use caustics::metrics::compare;
use caustics::settings::{Driven, Metric, Settings, Transport};
use common::*;

/// The default settings (exact transport, adaptive flux-error) at `level`.
fn level(level: u32) -> Settings {
    adaptive(level, Metric::FluxError)
}

/// The photons a debug run dumped.
fn debug_photons(s: &Shot) -> Vec<caustics::DebugPhoton> {
    assert!(s.report.guard_intact.is_some(), "a debug run");
    s.report.debug_photons()
}

/// Adaptive max-level at level L emits exactly the cells dense emits at 64·2^L, so the images agree.
#[test]
fn adaptive_max_level_matches_dense() {
    let (_gpu, device) = gpu();
    for level in 1..=3 {
        let d = shot(&device, SPHERE, dense(level));
        let a = shot(&device, SPHERE, adaptive(level, Metric::MaxLevel));
        assert_eq!(d.photons(), a.photons(), "level {level}: photon counts");
        let m = compare(&a.img, &d.img, 64, 2.0);
        // Same photons, same splats: only the order of the float additions differs (measured rel-L1 < 1e-6).
        assert!(m.rel_l1 <= 1e-3, "level {level}: rel-L1 {}", m.rel_l1);
        let (fa, fd) = (a.aov_flux, d.aov_flux);
        assert!((fa / fd - 1.0).abs() < 1e-5, "level {level}: flux {fa} vs {fd}");
        let levels = a.levels();
        let last = &levels[levels.len() - 1];
        assert_eq!(last.emitted as u64, a.photons(), "all photons come from the last level");
        for (l, c) in levels[..levels.len() - 1].iter().enumerate() {
            // Each refined cell appends exactly four candidates to the next level.
            let next = &levels[l + 1];
            assert_eq!(next.candidates, 4 * c.refined);
            assert_eq!(c.candidates, c.refined + c.dropped);
        }
    }
}

/// The emitted cells themselves, not only their number and image: adaptive max-level emits exactly dense's set
/// of (level, x, y), also when a tiny budget splits the traversal into batches whose tiles start at deep levels.
/// The slab overflows the spot cone, so the cone test at the cell centers matters there.
#[test]
fn max_level_emits_exactly_dense_cells() {
    let (_gpu, device) = gpu();
    let cells = |s: &Shot| -> Vec<(u32, u32, u32)> {
        let list = debug_photons(s);
        assert_eq!(list.len() as u64, s.photons(), "every photon dumped");
        let mut v: Vec<_> = list.iter().map(|p| (p.level, p.y, p.x)).collect();
        v.sort_unstable();
        v
    };
    let slab = scene("slab.toml");
    for (scene, name) in [(SPHERE, "sphere"), (slab.as_str(), "slab")] {
        let common = |s: &mut Settings| {
            s.quality.transport = Transport::TwoInterface;
            s.tuning.debug_photons = 200_000;
        };
        let dense = cells(&shot(&device, scene, with(dense(2), common)));
        assert!(dense.len() > 1000, "{name}: {} photons", dense.len());
        assert!(dense.iter().all(|c| c.0 == 2));
        for (tag, budget) in [("one", 64.0), ("tiny", 0.125)] {
            let settings = with(adaptive(2, Metric::MaxLevel), |s| {
                common(s);
                s.quality.photon_budget_mib = budget;
            });
            let a = shot(&device, scene, settings);
            if tag == "tiny" {
                let batches = a.traversal().batches_committed;
                assert!(batches > 1, "{name}: batches {batches}");
            }
            assert!(cells(&a) == dense, "{name} ({tag}): max-level's cells differ from dense's");
        }
    }
}

/// GPU-driven traversal reads nothing back; the CPU-driven baseline reads each level's count back. The images
/// are the same up to float summation order.
#[test]
fn gpu_driven_and_cpu_driven_agree() {
    let (_gpu, device) = gpu();
    let g = shot(&device, SPHERE, with(level(4), |s| s.tuning.driven = Driven::Gpu));
    let c = shot(&device, SPHERE, with(level(4), |s| s.tuning.driven = Driven::Cpu));
    assert_eq!(g.report.host_readbacks, 0);
    // One readback per traversal level (after init, then after levels 0..3), plus one after the batch that finds
    // no tile left.
    assert_eq!(c.report.host_readbacks, 6);
    assert_eq!(g.photons(), c.photons());
    let m = compare(&c.img, &g.img, 64, 2.0);
    assert!(m.rel_l1 <= 1e-5, "rel-L1 {}", m.rel_l1);
    assert_eq!(g.levels(), c.levels());
}

/// A budget small enough to force many batches gives the same photons and the same image as 64 MiB.
#[test]
fn tiny_budget_batches_to_the_same_image() {
    let (_gpu, device) = gpu();
    let big = shot(&device, SPHERE, level(4));
    let tiny = shot(&device, SPHERE, with(level(4), |s| s.quality.photon_budget_mib = 0.25));
    let (b, t) = (big.traversal(), tiny.traversal());
    assert_eq!(b.batches_committed, 1);
    assert!(t.batches_committed >= 4, "batches {}", t.batches_committed);
    let overflow_events = t.batches_aborted + (t.overflow_dropped > 0) as u32;
    assert!(overflow_events > 0, "overflows must be counted");
    assert_eq!(tiny.report.unfinished_tiles, 0);
    assert!(8 * t.peak_used as u64 <= 256 * 1024);
    assert_eq!(big.photons(), tiny.photons());
    assert_eq!(big.levels(), tiny.levels(), "committed per-level counts do not depend on batching");
    let m = compare(&tiny.img, &big.img, 64, 2.0);
    assert!(m.rel_l1 <= 1e-4, "rel-L1 {}", m.rel_l1);
}

/// A frame whose batch slots run out keeps the batches it committed and traces the remaining tiles in a further
/// submission (a continuation), instead of being rendered again: two batch slots a submission and a tiny budget
/// force several, and the image, the photons and the rays traced equal the one-batch frame's (the rays are the
/// whole frame's: a discarded first attempt would show fewer), with one host round trip per continuation.
#[test]
fn a_frame_out_of_batch_slots_is_finished_not_rendered_again() {
    let (_gpu, device) = gpu();
    let base = with(level(3), |s| s.quality.transport = Transport::Exact);
    let one = shot(&device, SPHERE, base.clone());
    let cont = shot(
        &device,
        SPHERE,
        with(base, |s| {
            s.quality.photon_budget_mib = 0.25;
            s.tuning.batch_slots = 2;
        }),
    );
    assert_eq!(one.report.continuations, 0);
    let n = cont.report.continuations;
    assert!(n >= 2, "continuations {n}");
    assert_eq!(cont.report.host_readbacks, n, "one round trip per continuation");
    assert_eq!(cont.report.unfinished_tiles, 0);
    assert_eq!(one.photons(), cont.photons());
    assert_eq!(one.transport().rays_traced, cont.transport().rays_traced);
    assert_eq!(one.levels(), cont.levels(), "the per-level counts accumulate across the submissions");
    let residual = cont.transport().residual();
    assert!(residual <= 1e-6, "the energy account closes across the submissions: {residual}");
    let m = compare(&cont.img, &one.img, 64, 2.0);
    assert!(m.rel_l1 <= 1e-4 && (m.flux_ratio - 1.0).abs() <= 1e-5, "{m:?}");
}

/// With batching off, an overflowing traversal drops work, counts it, and writes nothing past the buffer (a
/// canary after the capacity survives).
#[test]
fn overflow_without_batching_is_counted_and_bounded() {
    let (_gpu, device) = gpu();
    let full = shot(&device, SPHERE, level(4));
    let settings = with(level(4), |s| {
        s.quality.photon_budget_mib = 0.25;
        s.tuning.batching = false;
        s.tuning.debug_photons = 16;
    });
    let s = shot(&device, SPHERE, settings);
    let st = s.traversal();
    assert!(st.overflow_dropped > 0);
    assert!(st.batches_aborted + (st.overflow_dropped > 0) as u32 > 0);
    assert_eq!(s.report.guard_intact, Some(true), "a shader wrote past the photon buffer's capacity");
    let capacity = 256 * 1024 / 8;
    assert!(s.photons() <= capacity);
    assert!(s.photons() < full.photons());
}

/// Level 12 (a 262,144² grid) runs, and deep photons sit exactly where integer addressing puts them: the cell
/// center computed on the GPU equals the Rust value bit for bit, and the landing point equals an analytic
/// trace through the slab's two parallel interfaces. It names the two-interface model: its trace writes the
/// debug dump of photons that the positions are read from.
#[test]
fn deep_levels_have_exact_positions() {
    let (_gpu, device) = gpu();
    let slab = scene("slab.toml");
    let settings = with(adaptive(12, Metric::MaxError), |s| {
        s.quality.transport = Transport::TwoInterface;
        s.tuning.debug_photons = 20000;
        s.tuning.debug_min_level = 12;
    });
    let s = shot(&device, &slab, settings);
    let levels = s.levels();
    assert_eq!(levels.len(), 13);
    assert!(levels[12].emitted > 1000, "level 12 emitted {}", levels[12].emitted);
    let pv = s.report.photon_view.expect("a photon view");
    let v = |a: glam::Vec3| a.to_array().map(|x| x as f64);
    let (o, r, d, f) = (v(pv.origin), v(pv.right), v(pv.down), v(pv.forward));
    let win = [pv.window.x0, pv.window.y0, pv.window.w].map(|x| x as f64);
    let photons = debug_photons(&s);
    assert!(photons.len() > 1000, "dumped {}", photons.len());
    let n = 64.0 * 4096.0;
    let mut worst: f64 = 0.0;
    let mut landed = 0;
    for p in &photons {
        assert_eq!(p.level, 12);
        let (x, y) = (p.x as f64, p.y as f64);
        assert!(x < n && y < n);
        let uv = p.uv.map(|c| c as f64);
        // Bit-exact: (x + 0.5) / 2^18 is representable in f32.
        assert_eq!(p.uv[0], ((x + 0.5) / n) as f32, "cell center u of x = {x}");
        assert_eq!(p.uv[1], ((y + 0.5) / n) as f32, "cell center v of y = {y}");
        if p.status != 0 {
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
        let hit = [p.hit[0] as f64, p.hit[2] as f64];
        let err = ((hit[0] - x3).powi(2) + (hit[1] - z3).powi(2)).sqrt();
        worst = worst.max(err);
        landed += 1;
    }
    eprintln!("{landed} landed level-12 photons, worst landing error {:.2} um", worst * 1e6);
    assert!(landed > 1000);
    // A level-12 cell is 3.3 um wide on the floor; landing points agree to a fraction of a cell.
    assert!(worst < 2e-6, "worst landing error {} m", worst);
    assert!(s.img.data.iter().all(|v| v[0].is_finite()));
}
