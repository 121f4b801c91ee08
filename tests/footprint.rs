//! Footprint-aware splats (`--footprint differential`, rendered in process): under exact transport each ray carries its ray
//! differentials (Igehy 1999) for one cell width of its emitting cell, and the splat radii per map axis come from
//! the parallelogram the cell covers where it lands, as a sheared tent of integer radii fitted to the lattice of
//! landings (docs/design.md step 5), so flux is conserved exactly; only where it goes changes.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::reference::{Aov, Paths};
use caustics::settings::{Footprint, Metric, Settings, Splat};
use common::*;

fn reference_all(scene: &str, photons: u64) -> RgbImage {
    top_reference(scene, Aov::Caustics, Paths::All, photons, 256)
}

fn footprint(settings: &Settings, footprint: Footprint) -> Settings {
    with(settings.clone(), |s| s.tuning.footprint = footprint)
}

/// The differential footprint moves no flux: the same photons, the same energy account (residual below 1e-5, the
/// deposited caustic flux equal to the cell kernel's to 1e-5; each record's tent sums to exactly 1, at level 0 or,
/// for a tent wider than SPLAT_FINE_RADIUS under the compute splats, normalized at its coarse level, whose collapse
/// conserves flux too; at the caustic map's edge a tent's weights are renormalized over its taps on the map, where
/// the sphere's single external reflection lands). So the AOV's flux is the cell kernel's but for the float sums:
/// measured 6.7e-6 (dense) and 2.5e-5 (flux-error) on lavapipe, allowed 1e-4. The
/// two compute splats agree (rel-L1 <= 1e-4 at 256², as tests/splat.rs asks of the cell kernel). The raster splat
/// draws every tent at level 0, so it differs from them by the coarse tents' smoother shape only (a coarse level
/// keeps a sheared tent's radius across its rows at one of its texels or more, so a thin one is wider there):
/// measured 6.2e-3 (dense) and 3.7e-3 (flux-error) at 256² on lavapipe, allowed 8e-3. The same holds for flux-error's
/// clusters, which take their own cell's parallelogram too, clamped around their children's spread (level 3, check
/// level 2, E = 0.0158: clusters of levels 2 and 3; AOV flux measured 5.0e-4 from the cell footprint's).
#[test]
fn differential_conserves_flux_and_the_splats_agree() {
    let (_gpu, device) = gpu();
    let flux_error = with(adaptive(3, Metric::FluxError), |s| s.quality.target_error = 0.0158);
    for (tag, base) in [("dense", dense(2)), ("flux_error", flux_error)] {
        conserves_flux_and_the_splats_agree(&device, tag, &base);
    }
}

fn conserves_flux_and_the_splats_agree(device: &std::sync::Arc<caustics::gpu::Device>, tag: &str, base: &Settings) {
    let cell = shot(device, SPHERE, footprint(base, Footprint::Cell));
    let mut runs = Vec::new();
    for how in [Splat::Raster, Splat::Compute, Splat::Tiled] {
        let s = shot(device, SPHERE, with(footprint(base, Footprint::Differential), |s| s.tuning.splat = how));
        assert_eq!(s.config.footprint, Footprint::Differential);
        assert_eq!(s.config.splat, how);
        assert_eq!(s.photons(), cell.photons(), "{tag} {how:?}: photons");
        assert_eq!(s.report.host_readbacks, 0, "{tag} {how:?}: readbacks");
        let residual = s.transport().residual();
        assert!(residual < 1e-5, "{tag} {how:?}: energy account residual {residual}");
        assert_eq!(s.energy("overflow"), 0.0, "{tag} {how:?}: overflow");
        let (a, b) = (s.energy("caustics"), cell.energy("caustics"));
        assert!((a / b - 1.0).abs() < 1e-5, "{tag} {how:?}: caustic flux {a} vs {b} W (cell)");
        let (fa, fb) = (s.aov_flux, cell.aov_flux);
        assert!(fa > 0.0 && (fa / fb - 1.0).abs() < 1e-4, "{tag} {how:?}: AOV flux {fa} vs {fb} W (cell)");
        assert!(s.img.data.iter().flatten().all(|v| v.is_finite()), "{tag} {how:?}: non-finite caustics");
        if how == Splat::Raster {
            eprintln!("{tag}: AOV flux {fa} W against {fb} W (cell)");
        }
        runs.push((how, s.img));
    }
    let cell_img = cell.img;
    // The footprint changed the image (else this test checks nothing).
    let d = compare(&runs[0].1, &cell_img, 256, 2.0);
    assert!(d.rel_l1 > 0.01, "{tag}: differential vs cell rel-L1 {}", d.rel_l1);
    let m = compare(&runs[2].1, &runs[1].1, 256, 2.0);
    eprintln!("{tag}: differential tiled vs compute: {m:?}");
    assert!(m.rel_l1 <= 1e-4, "{tag} tiled vs compute rel-L1 {}", m.rel_l1);
    let m = compare(&runs[1].1, &runs[0].1, 256, 2.0);
    eprintln!("{tag}: differential compute vs raster (every tent at level 0): {m:?}");
    assert!(m.rel_l1 <= 8e-3, "{tag} compute vs raster rel-L1 {}", m.rel_l1);
}

/// Where light spreads (the sphere's caustic outside its focus, a convex mirror's reflection), low-level photons
/// land several cell sizes apart and the cell kernel leaves moiré and speckles; the differential footprint widens
/// each splat to the spacing of its neighbours. Measured on lavapipe (dense, rel-L1 at 256² against the 4M-photon
/// all-paths reference used here; with 8M, `caustics bench` in docs/experiments.md: 0.2204/0.0374 and 0.8564/0.1935):
/// sphere level 1 0.2211 (cell) against 0.0456 (differential), mirror_sphere level 3 0.8596 against 0.1379 (the
/// tent of each parallelogram's bounding box, before the sheared tent fitted to the lattice: 0.0374 and 0.1353). The
/// test asks the differential footprint to win by half the measured margin and to stay within 15% of its measure.
#[test]
fn differential_lowers_the_error_where_light_spreads() {
    let (_gpu, device) = gpu();
    for (name, level, cell_l1, diff_l1) in
        [("sphere.toml", 1, 0.2211, 0.0456), ("mirror_sphere.toml", 3, 0.8596, 0.1379)]
    {
        let path = scene(name);
        let r = reference_all(&path, 4_000_000);
        let cell = shot(&device, &path, footprint(&dense(level), Footprint::Cell)).img;
        let diff = shot(&device, &path, footprint(&dense(level), Footprint::Differential)).img;
        let (mc, md) = (compare(&cell, &r, 256, 2.0), compare(&diff, &r, 256, 2.0));
        eprintln!("{name} level {level}, 256²: cell {mc:?}, differential {md:?} (measured {cell_l1}, {diff_l1})");
        let margin = 0.5 * (cell_l1 - diff_l1);
        assert!(md.rel_l1 < mc.rel_l1 - margin, "{name}: cell {} differential {}", mc.rel_l1, md.rel_l1);
        assert!(md.rel_l1 < diff_l1 * 1.15 + 0.002, "{name}: differential rel-L1 {}", md.rel_l1);
    }
}

/// Moiré: where photons land farther apart than their splats are wide, the cell footprint draws fringes, a
/// residual against the reference whose power sits in a few frequencies of each tile (`metrics::periodic_share`);
/// the differential footprint's residual is nearer noise. The mirror sphere's wide, dim halo at level 3 (the
/// default flux-error traversal), against the 16M-photon all-paths reference at 256², on lavapipe: periodic share
/// 0.340 with the cell footprint, 0.141 with the differential one (0.187 with bounding-box tents), and 0.12 for a second reference against the
/// first (the floor noise sets). The test asks the cell footprint's share to stay above 0.30 (the measure sees
/// the fringes) and the differential one's below 0.25.
#[test]
fn differential_leaves_no_moire() {
    let (_gpu, device) = gpu();
    let path = scene("mirror_sphere.toml");
    let r = reference_all(&path, 16_000_000);
    let mut shares = Vec::new();
    for kind in [Footprint::Cell, Footprint::Differential] {
        let s = shot(&device, &path, footprint(&adaptive(3, Metric::FluxError), kind));
        assert_eq!(s.config.footprint, kind);
        let share = caustics::metrics::periodic_share(&s.img, &r, 256);
        let m = compare(&s.img, &r, 256, 2.0);
        eprintln!("mirror sphere level 3, {kind:?}: periodic share {share:.4}, rel-L1 256² {:.4}", m.rel_l1);
        shares.push(share);
    }
    assert!(shares[0] > 0.30, "cell footprint: periodic share {} (the measure should see its fringes)", shares[0]);
    assert!(shares[1] < 0.25, "differential footprint: periodic share {}", shares[1]);
}

/// A tiny photon budget (batches and ray queues of a few thousand 48-byte rays that abort and split) gives the
/// same image and account with the differential footprint as a large one.
#[test]
fn differential_with_tiny_budget_gives_the_same_image() {
    let (_gpu, device) = gpu();
    let settings = footprint(&adaptive(2, Metric::MaxLevel), Footprint::Differential);
    let big = shot(&device, SPHERE, settings.clone());
    let small = shot(&device, SPHERE, with(settings, |s| s.quality.photon_budget_mib = 0.05));
    assert_eq!(big.photons(), small.photons());
    let batches = small.traversal().batches_committed;
    assert!(batches >= 4, "batches {batches}");
    assert_eq!(small.energy("overflow"), 0.0);
    let m = compare(&small.img, &big.img, 256, 2.0);
    assert!(m.rel_l1 <= 1e-4, "tiny budget rel-L1 {}", m.rel_l1);
    let (a, b) = (big.energy("caustics"), small.energy("caustics"));
    assert!((a / b - 1.0).abs() < 1e-5, "caustic flux {a} vs {b} W");
}
