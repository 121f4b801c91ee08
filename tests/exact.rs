//! Exact transport on the GPU (`--transport exact`: rays through the scene BVH in waves, every glass path)
//! against the analytic sphere figures (docs/design.md) and the CPU reference with every path (`--paths all`).
//! Tolerances come from measurement on lavapipe with the same settings; each test states what it measured.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::{compare, Metrics};
use caustics::reference::{Aov, Paths};
use caustics::settings::{BvhLayout, CoopChecks, Metric};
use common::*;

const SIZE: u32 = 256;

fn reference_all(scene: &str, photons: u64) -> RgbImage {
    top_reference(scene, Aov::Caustics, Paths::All, photons, SIZE)
}

/// The account closes (emitted = every destination) to 1e-5, nothing overflowed, no host readback happened,
/// the waves' ray counts add up to the rays traced, and the AOV is finite.
fn assert_sound(name: &str, s: &Shot) {
    let t = s.transport();
    let waves = t.wave_rays();
    assert_eq!(waves.iter().map(|&n| n as u64).sum::<u64>(), t.rays_traced as u64, "{name}: rays per wave {waves:?}");
    assert!(waves.len() <= 33 && waves.len() as u32 <= t.waves, "{name}: {waves:?}");
    assert!(t.residual() < 1e-5, "{name}: energy account residual {}", t.residual());
    assert_eq!(s.energy("overflow"), 0.0, "{name}: overflow");
    assert_eq!(s.report.host_readbacks, 0, "{name}: host readbacks");
    assert!(s.img.data.iter().flatten().all(|v| v.is_finite()), "{name}: non-finite caustics");
}

/// Exact transport's account as the stats print it.
fn account(s: &Shot) -> serde_json::Map<String, serde_json::Value> {
    s.transport().account_json(s.intensity)
}

fn score(img: &RgbImage, r: &RgbImage) -> Metrics {
    compare(img, r, 64, 2.0)
}

/// Analytic sphere (docs/design.md): every path puts 0.111370 W on the floor, a single external reflection 0.005078 W.
/// Measured at dense level 3 (206,336 photons; the refractor g-buffer is fitted to the 512² grid and its coverage
/// dilated by a texel): caustics 0.111353 W (−0.015%), AOV 0.111374 W, one-interaction part 0.005087 W (+0.2%; the
/// reflection comes mostly from the grazing rim). With a 1024² g-buffer: 206,104 photons, 0.111306 W, 0.005043 W.
#[test]
fn sphere_all_paths_flux_matches_analytic() {
    let (_gpu, device) = gpu();
    let s = shot(&device, SPHERE, dense(3));
    assert_sound("sphere", &s);
    assert_eq!(s.photons(), 206336);
    let caustics = s.energy("caustics");
    let aov = s.aov_flux;
    eprintln!("sphere exact: caustics {caustics:.6} W, AOV {aov:.6} W, {:?}", account(&s));
    assert!((caustics / 0.111370 - 1.0).abs() < 0.005, "caustic flux {caustics} W");
    assert!((aov / 0.111370 - 1.0).abs() < 0.005, "AOV flux {aov} W");
    let one = s.energy("caustics_one_interaction");
    assert!((one / 0.005078 - 1.0).abs() < 0.015, "single external reflection {one} W");
    // Emitted = what the sphere intercepts (0.126946 W) plus the cells at its silhouette whose rays miss it.
    let emitted = s.energy("emitted");
    let direct = s.energy("direct");
    assert!((emitted - direct - 0.126946).abs() < 0.001, "intercepted {} W", emitted - direct);
}

struct Case {
    scene: &'static str,
    /// Measured rel-L1 (64²) and flux ratio against the all-paths reference (4M photons) at dense level 3.
    rel_l1: f64,
    ratio: f64,
}

/// GPU exact transport against the CPU reference with every path, dense level 3 (lavapipe, a few seconds each).
/// The two-interface model cannot get near these at any level: against every path it stays at about 5% on the sphere,
/// 24% on the bunny and 47% on the tilted cube (docs/results.md). The remaining error here is the sampling of a level-3 grid (it halves
/// with each level: bunny 9.3% at level 2, 5.0% at level 3, under `--footprint cell`) plus the reference's own noise (about 0.2%).
#[test]
fn exact_matches_all_paths_reference() {
    let cases = [
        Case { scene: "sphere.toml", rel_l1: 0.0075, ratio: 1.0001 },
        // (3.60%, 1.0023 against the reference before it took the GPU's rule for interpolated normals.)
        Case { scene: "bunny.toml", rel_l1: 0.0312, ratio: 1.0001 },
        Case { scene: "tilted_cube.toml", rel_l1: 0.0100, ratio: 1.0000 },
        Case { scene: "ior24.toml", rel_l1: 0.0163, ratio: 0.9990 },
        // A convex mirror spreads the reflected light thinly: level 3's photons land far apart. Their differential
        // footprints follow that spread (under `--footprint cell` the tents follow the cell size instead, and the
        // ring caustic is sampled coarsely: 9.3% at 64², 86% at 256²). The flux ratio is 0.3% below 1 (0.9988
        // under `cell`): the wide tents move a little light to where the image does not count it.
        Case { scene: "mirror_sphere.toml", rel_l1: 0.0271, ratio: 0.9970 },
        // A curved receiver: the ball's caustic in a diffuse bowl (a lathe), whose sides tilt by up to 50°.
        Case { scene: "bowl.toml", rel_l1: 0.0066, ratio: 0.9991 },
        // Media: water in a glass, three kinds of interface (glass | air, water | glass, water | air). The light the
        // glass scatters beyond the lamp's receiver view (0.28 mW in the image, at the image's edges) is the eye
        // deposit's; without it rel-L1 was 3.28% and the flux ratio 0.9971 (2.85% and 1.0023 with it, against the
        // reference before it took the GPU's rule for interpolated normals).
        Case { scene: "glass_of_water.toml", rel_l1: 0.0250, ratio: 0.9993 },
    ];
    let (_gpu, device) = gpu();
    for c in &cases {
        let path = scene(c.scene);
        let s = shot(&device, &path, dense(3));
        assert_sound(c.scene, &s);
        let m = score(&s.img, &reference_all(&path, 4_000_000));
        eprintln!("{}: {m:?} (measured rel-L1 {}, flux ratio {})", c.scene, c.rel_l1, c.ratio);
        assert!(m.rel_l1 < c.rel_l1 * 1.15 + 0.002, "{}: rel-L1 {}", c.scene, m.rel_l1);
        assert!((m.flux_ratio - c.ratio).abs() < 0.003, "{}: flux ratio {}", c.scene, m.flux_ratio);
    }
}

/// Every hard case closes its energy account and stays finite; single surfaces (the open dome, the thin lens,
/// the slab) work as surfaces. The open dome refracts once: the two-interface method deposits nothing there, the
/// reference 0.105849 W (all paths). Measured here at dense level 2: see the eprintln.
#[test]
fn hard_cases_close_the_account() {
    let (_gpu, device) = gpu();
    for name in [
        "ior24.toml",
        "oblique.toml",
        "tilted_cube.toml",
        "vertex_above.toml",
        "thin.toml",
        "slab.toml",
        "directional.toml",
        "open_mesh.toml",
    ] {
        let path = scene(name);
        let s = shot(&device, &path, dense(2));
        assert_sound(name, &s);
        let flux = s.aov_flux;
        eprintln!("{name}: AOV {flux:.6} W, {:?}", account(&s));
        assert!(flux > 0.0, "{name}: no caustic");
        if name == "open_mesh.toml" {
            let m = score(&s.img, &reference_all(&path, 1_000_000));
            eprintln!("open dome vs all paths: {m:?}");
            assert!((m.flux_ratio - 1.0).abs() < 0.01, "open dome flux ratio {}", m.flux_ratio);
        }
    }
}

/// A tiny photon budget (batches split on overflow, ray queues of a few thousand rays that abort and split
/// batches too) gives the same image and the same account as a large one.
#[test]
fn tiny_budget_gives_the_same_image() {
    let (_gpu, device) = gpu();
    let settings = adaptive(2, Metric::MaxLevel);
    let big = shot(&device, SPHERE, settings.clone());
    let small = shot(&device, SPHERE, with(settings, |s| s.quality.photon_budget_mib = 0.05));
    assert_sound("small budget", &small);
    assert_eq!(big.photons(), small.photons());
    let batches = small.traversal().batches_committed;
    assert!(batches >= 4, "batches {batches}");
    let m = compare(&small.img, &big.img, 256, 2.0);
    assert!(m.rel_l1 <= 1e-4, "tiny budget rel-L1 {}", m.rel_l1);
    let (a, b) = (big.energy("caustics"), small.energy("caustics"));
    assert!((a / b - 1.0).abs() < 1e-5, "caustic flux {a} vs {b} W");
}

/// A batch's photons are bounded apart from its candidates. Under exact transport a batch emits at most a quarter
/// of the photon buffer's entries (half a ray queue, for wave 0's two children a photon), and while it traverses,
/// its candidates may fill the rest of the buffer. At 7 MiB (917,504 entries, 229,376 photons a batch) max-level
/// level 3 on the sphere, 206,336 photons beside about 70,000 candidates (276,080 entries at the peak), runs in
/// one batch. When photons and candidates shared the quarter, it overflowed once and ran in four.
#[test]
fn candidates_do_not_count_against_a_batchs_photons() {
    let (_gpu, device) = gpu();
    let s = shot(&device, SPHERE, with(adaptive(3, Metric::MaxLevel), |s| s.quality.photon_budget_mib = 7.0));
    assert_sound("7 MiB", &s);
    assert_eq!(s.photons(), 206_336);
    let st = s.traversal();
    let overflows = st.batches_aborted + (st.overflow_dropped > 0) as u32;
    assert_eq!((st.batches_committed, overflows), (1, 0), "batches and overflows");
    let peak = st.peak_used;
    assert!(peak > 229_376 && peak <= 917_504, "peak entries {peak}: photons and candidates past a quarter");
}

/// The four BVH node layouts (`--bvh-layout`) find the same closest hits: at dense level 2 (256²) on the
/// sphere, the bunny, the tilted cube, the mirror sphere and the pool (its water deforming) they trace the same rays to the same account, and
/// their images differ only in the order of float additions (measured on lavapipe against pair at 256²: rel-L1
/// at most 3.7e-8 single and threaded (bunny), 8.6e-8 wide (the sphere; the rest 4e-9 to 3.5e-8); caustic flux
/// equal to 1e-8). GPUs run the single layout by
/// default (`auto`), which no other lavapipe test traces; lavapipe resolves `auto` to wide.
#[test]
fn bvh_layouts_trace_the_same_paths() {
    let (_gpu, device) = gpu();
    let scenes = [
        ("sphere", SPHERE.to_string()),
        ("bunny", BUNNY.to_string()),
        ("tilted_cube", scene("tilted_cube.toml")),
        ("mirror_sphere", scene("mirror_sphere.toml")),
        // Its water deforms: the wide walk takes the water's pair nodes, which the refit keeps.
        ("pool", scene("pool.toml")),
    ];
    for (name, path) in &scenes {
        let run = |layout: BvhLayout| {
            let settings = with(dense(2), |s| s.tuning.bvh_layout = layout);
            shot_at(&device, path, settings, 0.7, caustics::Aov::Caustics, 256)
        };
        if *name == "bunny" {
            let auto = run(BvhLayout::Auto);
            assert_eq!(auto.config.bvh_layout, BvhLayout::Wide, "auto on a CPU device resolves to wide");
        }
        let pair = run(BvhLayout::Pair);
        let layouts: &[BvhLayout] = if *name == "bunny" {
            &[BvhLayout::Single, BvhLayout::Threaded, BvhLayout::Wide]
        } else {
            &[BvhLayout::Wide]
        };
        for &layout in layouts {
            let s = run(layout);
            assert_sound(&format!("{layout:?}"), &s);
            assert_eq!(s.config.bvh_layout, layout);
            let rays = s.transport().rays_traced;
            assert_eq!(rays, pair.transport().rays_traced, "{name} {layout:?}: rays traced");
            assert_eq!(s.photons(), pair.photons(), "{name} {layout:?}: photons");
            let (a, b) = (pair.energy("caustics"), s.energy("caustics"));
            assert!((a / b - 1.0).abs() < 1e-6, "{name} {layout:?}: caustic flux {b} W against pair's {a} W");
            let m = compare(&s.img, &pair.img, 256, 2.0);
            eprintln!("{name} {layout:?}: rel-L1 {:.2e}, caustics {b} W (pair {a} W), {rays} rays", m.rel_l1);
            assert!(m.rel_l1 <= 1e-6, "{name} {layout:?}: rel-L1 {} against pair", m.rel_l1);
        }
    }
}

/// Weak branches (`--weak-branches`, default 0.05): in each 4×4 block of the finest level's cells, one photon
/// traces the block's weak Fresnel branches at each depth. Against every photon tracing its own
/// (`--weak-branches 0`), at level 3: the account still closes, the flux the photons left equals what the carriers
/// took on to within a few 1e-3 (they differ only where a block's photons' branches differ), far fewer rays are
/// traced, and the image and its error against every path barely move. Under the merging metrics (check level 2)
/// a block holds clusters of level 2 beside level-3 photons, and the turns, which follow the block's cells, still
/// give each block one carrier per depth; in 2×2 blocks the clusters of level 2 are too large for them, and take
/// turns with their siblings where traversal found all four to be clusters. Measured on lavapipe (sphere dense,
/// bunny dense, bunny max-error, sphere flux-error, and sphere flux-error whose clusters share with their
/// siblings): rays 0.536, 0.472, 0.474, 0.598 and
/// 0.667 of off's (bunny max-error in 2×2 blocks before clusters took part: 0.577); carried / left within 0.2%;
/// caustic flux equal to 1e-4; rel-L1 (64²) on against off 0.0006, 0.0059, 0.0058, 0.0006 and 0.0003; against every
/// path the error rises by 0.004, 0.042, 0.048, 0.004 and 0.0005 points.
#[test]
fn weak_branches_are_traced_once_per_block() {
    let (_gpu, device) = gpu();
    let merging = |metric| with(adaptive(3, metric), |s| s.tuning.check_level = Some(2));
    let cases = [
        ("sphere", SPHERE.to_string(), dense(3)),
        ("bunny", scene("bunny.toml"), dense(3)),
        ("bunny_max_error", scene("bunny.toml"), merging(Metric::MaxError)),
        ("sphere_flux_error", SPHERE.to_string(), merging(Metric::FluxError)),
        // 2×2 blocks of the maximal level: the clusters of level 2 share with their siblings instead.
        (
            "sphere_flux_error_siblings",
            SPHERE.to_string(),
            with(merging(Metric::FluxError), |s| s.tuning.weak_block = 2),
        ),
    ];
    for (name, path, settings) in cases {
        let block = if name.ends_with("siblings") { 2 } else { 4 };
        let son = shot(&device, &path, settings.clone());
        let soff = shot(&device, &path, with(settings, |s| s.tuning.weak_branches = 0.0));
        assert_sound(name, &son);
        assert_eq!(son.config.weak_branches, 0.05);
        assert_eq!(son.config.weak_block(), block, "{name}: block side");
        assert_eq!(son.photons(), soff.photons(), "{name}: the same photons");
        if name.contains("error") {
            // Clusters of level 2 share blocks with level-3 photons, or their siblings' turns.
            let early = son.levels()[2].emitted;
            assert!(early > 1000, "{name}: {early} clusters of level 2");
        }
        assert_eq!(soff.energy("weak_left"), 0.0, "{name}: weak branches off");
        let (left, carried) = (son.energy("weak_left"), son.energy("weak_carried"));
        let rays = |s: &Shot| s.transport().rays_traced as f64;
        let (ron, roff) = (rays(&son), rays(&soff));
        let r = reference_all(&path, 4_000_000);
        let (mon, moff) = (score(&son.img, &r), score(&soff.img, &r));
        let between = compare(&son.img, &soff.img, 64, 2.0);
        let (con, coff) = (son.energy("caustics"), soff.energy("caustics"));
        eprintln!(
            "{name}: weak left {left:.6} W, carried {carried:.6} W; rays {ron} against {roff} ({:.3}); caustics \
             {con:.6} against {coff:.6} W; vs every path {mon:?} against {moff:?}; on against off {between:?}",
            ron / roff
        );
        assert!(left > 0.0 && (carried / left - 1.0).abs() < 0.01, "{name}: left {left} W, carried {carried} W");
        assert!(ron < 0.75 * roff, "{name}: {ron} rays against {roff}");
        assert!((con / coff - 1.0).abs() < 1e-3, "{name}: caustic flux {con} against {coff} W");
        assert!(between.rel_l1 < 0.008, "{name}: rel-L1 on against off {}", between.rel_l1);
        assert!(mon.rel_l1 < moff.rel_l1 + 0.001, "{name}: rel-L1 {} against {}", mon.rel_l1, moff.rel_l1);
    }
}

/// Max-error under exact transport follows each child's dominant path: at level 4 it needs fewer photons than
/// max-level for about the same error against every path. Measured on the sphere: see the eprintln.
#[test]
fn max_error_follows_dominant_paths() {
    let (_gpu, device) = gpu();
    let settings = |metric| with(adaptive(4, metric), |s| s.tuning.check_level = Some(2));
    let sl = shot(&device, SPHERE, settings(Metric::MaxLevel));
    let se = shot(&device, SPHERE, settings(Metric::MaxError));
    assert_sound("max-error", &se);
    let r = reference_all(SPHERE, 4_000_000);
    let (a, b) = (score(&sl.img, &r), score(&se.img, &r));
    let (pa, pb) = (sl.photons(), se.photons());
    eprintln!("max-level {pa} photons {a:?}\nmax-error {pb} photons {b:?}");
    assert!((pb as f64) < 0.6 * pa as f64, "max-error {pb} photons vs max-level {pa}");
    assert!(b.rel_l1 < a.rel_l1 + 0.01, "max-error rel-L1 {} vs max-level {}", b.rel_l1, a.rel_l1);
    assert!((b.flux_ratio - 1.0).abs() < 0.005, "max-error flux ratio {}", b.flux_ratio);
}

/// Cooperative checks (`--coop-checks on`: four lanes trace a cell's four children's dominant paths, then one lane
/// decides; `auto` turns them on for GPUs only) give the verdicts of one lane tracing the four in a row: the same
/// photons level by level, and images that differ only in the order of float additions. Bunny at level 3, check
/// level 1 (the metrics check levels 1 and 2, flux-error looks ahead from level 0), 256²; measured on lavapipe:
/// max-error 97,309 and flux-error 122,992 photons both ways, rel-L1 2.2e-8 and 2.4e-8 (at level 4: 3.6e-8 and
/// 4.4e-8).
#[test]
fn coop_checks_give_the_same_photons() {
    let (_gpu, device) = gpu();
    for metric in [Metric::MaxError, Metric::FluxError] {
        let run = |coop: CoopChecks| {
            let settings = with(adaptive(3, metric), |s| {
                s.tuning.check_level = Some(1);
                s.tuning.coop_checks = coop;
            });
            shot(&device, BUNNY, settings)
        };
        let off = run(CoopChecks::Off);
        let on = run(CoopChecks::On);
        assert_sound(&format!("{metric:?}"), &on);
        assert_eq!(off.config.coop_checks, CoopChecks::Off);
        assert_eq!(on.config.coop_checks, CoopChecks::On);
        assert_eq!(on.photons(), off.photons(), "{metric:?}: photons");
        assert_eq!(on.levels(), off.levels(), "{metric:?}: every level's candidates, refinements, photons, skips");
        let m = compare(&on.img, &off.img, 256, 2.0);
        eprintln!("{metric:?}: {} photons both ways, rel-L1 {:.2e}", on.photons(), m.rel_l1);
        assert!(m.rel_l1 <= 1e-6, "{metric:?}: rel-L1 {} between the two", m.rel_l1);
    }
    // The default on lavapipe: one lane.
    let s = renderer(&device, BUNNY, adaptive(2, Metric::MaxError));
    assert_eq!(s.config().coop_checks, CoopChecks::Off, "auto on a CPU device");
}

/// The two-interface model only refracts: a scene with a mirror is refused with exit code 2, naming the object.
#[test]
fn mirrors_need_exact_transport() {
    let dir = out_dir("exact_mirror_refused");
    let out = dir.join("m.png");
    let scene_path = scene("mirror_sphere.toml");
    let o =
        caustics(&["render", "--scene", &scene_path, "--transport", "two-interface", "--out", out.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    let named = stderr.contains("--transport two-interface: ") && stderr.contains("need exact transport");
    assert!(stderr.contains("`mirror` is a mirror") && named, "{stderr}");
    assert_no_output(&out);
}

/// Beer–Lambert absorption (`absorption` on a dielectric, 1/m), exactly: under a directional light at normal
/// incidence every interior path through the 5 cm slab is 0.05 m long, so against the same slab of clear glass the
/// caustic flux falls by exp(-0.1) (1 + F² exp(-0.2)) / (1 + F²) = 0.904575 with F = 0.04 (the internally reflected
/// part runs three times as far). Measured 0.904604 at dense level 2. Against the CPU reference (which absorbs by
/// Russian roulette): flux ratio 0.99975, rel-L1 0.7% at 64² (128² AOV).
#[test]
fn absorption_follows_beer_lambert() {
    let dir = out_dir("exact_absorption");
    let tinted = scene("absorbing_slab.toml");
    let text = std::fs::read_to_string(&tinted).unwrap();
    let clear = dir.join("clear_slab.toml");
    std::fs::write(&clear, text.replace(", absorption = 2.0 }", " }")).unwrap();
    let (_gpu, device) = gpu();
    let st = shot(&device, &tinted, dense(2));
    let sc = shot(&device, clear.to_str().unwrap(), dense(2));
    assert_sound("tinted", &st);
    assert_sound("clear", &sc);
    assert_eq!(sc.energy("absorbed"), 0.0);
    // The deepest deposited path: in, reflected inside at the bottom and then at the top (F² = 0.0016 of the flux,
    // above the 1e-3 cut), out: four interactions; two more reflections (F⁴) are cut. The waves count it once per
    // work group.
    for (name, s) in [("tinted", &st), ("clear", &sc)] {
        assert_eq!(s.transport().max_depth, 4, "{name}: max_depth");
    }
    let ratio = st.energy("caustics") / sc.energy("caustics");
    let f: f64 = 0.04;
    let want = (-0.1f64).exp() * (1.0 + f * f * (-0.2f64).exp()) / (1.0 + f * f);
    eprintln!("absorbing slab: ratio {ratio}, expected {want}, account {:?}", account(&st));
    assert!((ratio - want).abs() < 2e-4, "flux ratio {ratio}, Beer–Lambert gives {want}");
    let m = score(&st.img, &reference_all(&tinted, 2_000_000));
    eprintln!("absorbing slab vs reference: {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.003, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.02, "rel-L1 {}", m.rel_l1);
}

/// Media (docs/design.md "Media"): light through a tank of water in glass meets four stacked interfaces (air |
/// glass, glass | water, water | glass, glass | air: the water's surface names the glass as its `outside`), and
/// the water absorbs 0.5 /m over its 0.2 m. Under a directional light straight down, the flux through, against the
/// same block with the water made glass (IOR 1.5, no absorption: its surface then bends and reflects nothing), is
/// the ratio of the stacks' incoherent transmissions, interreflections included: 0.898522. Were the water's
/// interfaces with air instead, it would be 0.8899. Measured at dense level 2: 0.898050 (−5e-4; the flux threshold
/// cut 0.066% of the water's paths' flux, 0.0066% of the glass's), 0.898598 with the cut flux counted as passed
/// (+8e-5). Against the CPU reference: flux ratio and rel-L1 in the test's output.
#[test]
fn a_water_tank_transmits_as_its_stacked_interfaces() {
    let dir = out_dir("exact_water_tank");
    let tank = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/water_tank.toml").to_string();
    let text = std::fs::read_to_string(&tank).unwrap();
    let glass = dir.join("glass_tank.toml");
    std::fs::write(&glass, text.replace("ior = 1.33, absorption = 0.5, outside", "ior = 1.5, outside")).unwrap();
    let (_gpu, device) = gpu();
    let sw = shot(&device, &tank, dense(2));
    let sg = shot(&device, glass.to_str().unwrap(), dense(2));
    assert_sound("water", &sw);
    assert_sound("glass", &sg);
    assert_eq!(sg.energy("absorbed"), 0.0);
    // Incoherent stacking: (front reflectance, back reflectance, transmittance) of an interface, and of two elements
    // with a layer of internal transmittance t between them.
    let interface = |n1: f64, n2: f64| {
        let r = ((n1 - n2) / (n1 + n2)).powi(2);
        (r, r, 1.0 - r)
    };
    let stack = |(ra, rab, ta): (f64, f64, f64), t: f64, (rb, rbb, tb): (f64, f64, f64)| {
        let d = 1.0 - rab * rb * t * t;
        (ra + ta * ta * t * t * rb / d, rbb + tb * tb * t * t * rab / d, ta * t * tb / d)
    };
    let water = stack(
        stack(stack(interface(1.0, 1.5), 1.0, interface(1.5, 1.33)), (-0.5f64 * 0.2).exp(), interface(1.33, 1.5)),
        1.0,
        interface(1.5, 1.0),
    );
    let solid = stack(interface(1.0, 1.5), 1.0, interface(1.5, 1.0));
    let want = water.2 / solid.2;
    let ratio = sw.energy("caustics") / sg.energy("caustics");
    let passed = |s: &Shot| s.energy("caustics") + s.energy("cut_threshold");
    let with_cut = passed(&sw) / passed(&sg);
    eprintln!("water tank: ratio {ratio}, with the cut flux {with_cut}, stacked interfaces give {want}");
    assert!((ratio - want).abs() < 1e-3, "flux ratio {ratio}, the stacked interfaces give {want}");
    assert!((with_cut - want).abs() < 3e-4, "flux ratio with the cut flux {with_cut}, the stack gives {want}");
    assert!(sw.energy("absorbed") > 0.05, "the water absorbs: {}", sw.energy("absorbed"));
    let m = score(&sw.img, &reference_all(&tank, 2_000_000));
    eprintln!("water tank vs reference: {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.003, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.02, "rel-L1 {}", m.rel_l1);
}

/// Media by priority (docs/design.md "Media"): the glass of water modelled as an artist would, a closed glass and
/// a closed cylinder of water reaching 1 mm into its wall and base, with the glass the higher priority
/// (tests/data/glass_of_water_overlap.toml). Where they overlap the glass's medium is the one there, so light
/// meets the interfaces that assets/scenes/glass_of_water.toml models explicitly. Dense level 3, against the CPU
/// reference of the explicit scene: rel-L1 3.34%, flux ratio 0.9965 (the explicit scene itself: 3.28%, 0.9971);
/// against the overlapping scene's own reference 3.40%, 0.9969. The two references (4M photons each) differ by
/// 2.53%, flux ratio 0.9995, as two seeds of the explicit one do (2.34%). Before the water followed the wall's
/// slope it stood out of the glass near the base, and the references differed by 11%: the test sees geometry.
#[test]
fn overlapping_volumes_resolve_by_priority() {
    let (_gpu, device) = gpu();
    let overlap = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/glass_of_water_overlap.toml");
    let explicit = scene("glass_of_water.toml");
    let s = shot(&device, overlap, dense(3));
    assert_sound("overlap", &s);
    let img = &s.img;
    let r_explicit = reference_all(&explicit, 4_000_000);
    let r_overlap = reference_all(overlap, 4_000_000);
    let refs = score(&r_overlap, &r_explicit);
    let m = score(img, &r_explicit);
    let own = score(img, &r_overlap);
    eprintln!("overlap vs explicit reference: {m:?}\noverlap vs its own reference: {own:?}\nreferences: {refs:?}");
    assert!(refs.rel_l1 < 0.035 && (refs.flux_ratio - 1.0).abs() < 0.005, "the references differ: {refs:?}");
    assert!(m.rel_l1 < 0.0328 * 1.15 + 0.002, "rel-L1 {}", m.rel_l1);
    assert!((m.flux_ratio - 0.9971).abs() < 0.01, "flux ratio {}", m.flux_ratio);
    assert!(own.rel_l1 < 0.0328 * 1.15 + 0.002, "rel-L1 {}", own.rel_l1);
}

/// Total internal reflection at a glass | water interface (docs/design.md "Media"): a wedge of water (IOR 1.333,
/// its surface naming the glass as its `outside`; flat faces) inside a glass block (1.5), its top face tilted by α.
/// Light straight down meets that face from the glass at α; the critical angle is asin(1.333 / 1.5) = 62.7°,
/// against air's 41.8°. At α = 60° the water transmits: the light leaves the block's bottom bent towards −x and lands
/// on the floor at x in [−0.36, −0.25] m, with (1 − F) at each of the four interfaces it crosses (air | glass,
/// glass | water at 60°, water | glass, glass | air; unpolarized Fresnel); what the tilted face reflects leaves
/// through the block's left side and lands beyond x = −0.4 m. At α = 64° nothing crosses: the region stays dark.
/// Measured on lavapipe at dense level 4: at 60° 0.020823 W against 0.020837 from the interfaces (−0.07%), the CPU
/// reference 0.020831; at 64° nothing, in both. The test allows 2% at 60° (and from the reference), and at 64° 1%
/// of the flux at 60°. (Without its normals, an OBJ wedge takes averaged vertex normals and bends light like a lens.)
#[test]
fn total_internal_reflection_at_glass_water_only_past_the_critical_angle() {
    let dir = out_dir("exact_tir_water");
    let (_gpu, device) = gpu();
    let fresnel = |n1: f64, n2: f64, cos_i: f64| {
        let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
        if sin_t >= 1.0 {
            return 1.0;
        }
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = ((n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t)).powi(2);
        let rp = ((n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i)).powi(2);
        0.5 * (rs + rp)
    };
    let (ng, nw) = (1.5f64, 1.333f64);
    let mut measured = Vec::new();
    for alpha_deg in [60.0f64, 64.0] {
        let alpha = alpha_deg.to_radians();
        // The water wedge: (x, y) corners A top right, B bottom left, C bottom right, across z in [-0.095, 0.095],
        // each face with its own normal.
        let (ya, yb) = (0.9, 0.9 - 0.14 * alpha.tan());
        let mut obj = String::new();
        // A B C, then A' B' C'.
        for z in [0.095, -0.095] {
            obj += &format!("v 0.07 {ya} {z}\nv -0.07 {yb} {z}\nv 0.07 {yb} {z}\n");
        }
        obj += &format!("vn 0 0 1\nvn 0 0 -1\nvn 0 -1 0\nvn 1 0 0\nvn {} {} 0\n", -alpha.sin(), alpha.cos());
        obj += "f 2//1 3//1 1//1\nf 5//2 4//2 6//2\nf 2//3 5//3 3//3\nf 3//3 5//3 6//3\n";
        obj += "f 3//4 6//4 1//4\nf 1//4 6//4 4//4\nf 1//5 4//5 2//5\nf 2//5 4//5 5//5\n";
        let mesh = dir.join(format!("wedge{alpha_deg}.obj"));
        std::fs::write(&mesh, obj).unwrap();
        let scene = under_a_beam(&format!(
            r#"[[object]]
name = "block"
shape = "cube"
size = [0.275, 0.5, 0.2]
translate = [-0.0625, 0.75, 0.0]
material = {{ kind = "dielectric", ior = {ng} }}

[[object]]
name = "water"
shape = "mesh"
path = "{}"
material = {{ kind = "dielectric", ior = {nw}, outside = "block" }}
"#,
            mesh.display()
        ));
        let path = dir.join(format!("tir{alpha_deg}.toml"));
        std::fs::write(&path, scene).unwrap();
        let path = path.to_str().unwrap().to_string();
        let s = shot(&device, &path, dense(4));
        assert_sound(&format!("tir{alpha_deg}"), &s);
        let img = &s.img;
        // The floor's flux over x in [-0.38, -0.22] m (columns along +x over [-1, 1] m): light that went through
        // the water, and nothing else (light through the glass alone lands at x in [-0.2, 0.075] m).
        let region = |img: &RgbImage| {
            let (n, px) = (SIZE as usize, (2.0 / SIZE as f64).powi(2));
            let mut sum = 0.0;
            for y in 0..n {
                for x in 0..n {
                    if (-0.38..-0.22).contains(&(-1.0 + 2.0 * (x as f64 + 0.5) / SIZE as f64)) {
                        sum += img.data[y * n + x][0] as f64 * px;
                    }
                }
            }
            sum
        };
        // The light on the tilted face (1 W/m² over 0.14 × 0.19 m) through the four interfaces.
        let sin_t = ng / nw * alpha.sin();
        let expected = if sin_t >= 1.0 {
            0.0
        } else {
            let theta_w = sin_t.asin() - alpha;
            let theta_g = (nw / ng * theta_w.sin()).asin();
            0.14 * 0.19
                * (1.0 - fresnel(1.0, ng, 1.0))
                * (1.0 - fresnel(ng, nw, alpha.cos()))
                * (1.0 - fresnel(nw, ng, theta_w.cos()))
                * (1.0 - fresnel(ng, 1.0, theta_g.cos()))
        };
        let (got, r) = (region(img), region(&reference_all(&path, 1_000_000)));
        eprintln!(
            "α = {alpha_deg}°: {got:.6} W through the water, the interfaces give {expected:.6}, reference {r:.6}"
        );
        measured.push((got, expected, r));
    }
    let (got, expected, r) = measured[0];
    assert!((got / expected - 1.0).abs() < 0.02, "60°: {got} W, the interfaces give {expected}");
    assert!((r / got - 1.0).abs() < 0.02, "60°: {got} W, the reference {r}");
    let (got64, _, r64) = measured[1];
    assert!(got64 < 0.01 * got && r64 < 0.01 * r, "64°: {got64} W (reference {r64}) against {got} at 60°");
}

/// A glass shelf on a wall (assets/scenes/shelf.toml): the light's caustic map sees the wall at a slant, and the
/// wall behind the shelf takes the slab's and the ball's light. The `front` camera's caustics against the CPU
/// reference (4M photons), adaptive flux-error at level 4, 256². Measured on lavapipe: rel-L1 2.1% at 64² (most
/// of it the reference's noise), flux ratio 0.9997. Allowed: 3.5% and 1%.
#[test]
fn a_glass_shelf_casts_onto_the_wall_behind_it() {
    let shelf = scene("shelf.toml");
    let (_gpu, device) = gpu();
    let mut r = renderer(&device, &shelf, adaptive(4, Metric::FluxError));
    let (img, _) = camera_aov(&mut r, "front", (SIZE, SIZE), caustics::Aov::Caustics);
    let reference = camera_reference(&shelf, "front", Aov::Caustics, Paths::All, 4_000_000, SIZE, 0.0);
    let m = compare(&img, &reference, 64, 1.2);
    eprintln!("shelf: {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.01 && m.rel_l1 < 0.035, "{m:?}");
}
