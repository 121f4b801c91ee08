//! The GPU methods against the exact CPU reference (src/reference), with the project's metric
//! (src/metrics.rs): box-filtered rel-L1, flux ratio. Numbers in comments were measured on lavapipe with the
//! same settings (`caustics bench --methods dense --levels 3-4 --reference-photons 4000000` and the like). The
//! tests render in process on the test binary's shared device (`common::gpu`) and read its frame reports.
//!
//! These tests name the papers' two-interface model (`Transport::TwoInterface`, the CLI's `--transport
//! two-interface`; exact transport, the default, is tested in tests/exact.rs). It models light refracted exactly
//! twice (front surface in, back surface out), so its natural reference is `--paths two-refractions`; the gap to
//! the all-paths reference is the light they cannot represent (internal reflections, more interfaces, single
//! interfaces), and the tests state it.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::{compare, Metrics};
use caustics::reference::{self, Aov, Paths, RefParams};
use caustics::settings::{Metric, Settings, Transport};
use common::*;
use std::path::Path;

const SIZE: u32 = 256;

fn reference_image(scene: &str, paths: Paths, photons: u64) -> RgbImage {
    top_reference(scene, Aov::Caustics, paths, photons, SIZE)
}

/// `settings` under the two-interface model.
fn two_interface(mut settings: Settings) -> Settings {
    settings.quality.transport = Transport::TwoInterface;
    settings
}

/// The caustics AOV of `scene` from its `top` camera at 256² under the two-interface model with `settings`, in
/// process ([`shot`]), validation silent.
fn caustics_aov(device: &std::sync::Arc<caustics::gpu::Device>, scene: &str, settings: Settings) -> Shot {
    shot(device, scene, two_interface(settings))
}

fn score(img: &RgbImage, r: &RgbImage) -> Metrics {
    compare(img, r, 64, 2.0)
}

/// Sphere, dense level 4 (1024² grid, 820,324 photons): measured rel-L1 (64²) 0.0042 and flux ratio 1.0003
/// against the two-refraction reference (4M photons, whose own noise is about 0.002 at 64²).
#[test]
fn dense_sphere_matches_reference() {
    let (_gpu, device) = gpu();
    let s = caustics_aov(&device, SPHERE, dense(4));
    assert_eq!(s.photons(), 820324);
    let img = &s.img;
    let m = score(img, &reference_image(SPHERE, Paths::TwoRefractions, 4_000_000));
    eprintln!("sphere vs two refractions: {m:?}");
    assert!(m.rel_l1 < 0.01, "rel-L1 {}", m.rel_l1);
    assert!((m.flux_ratio - 1.0).abs() < 0.01, "flux ratio {}", m.flux_ratio);
    // The peak sits on the corner of four 64² pixels (31 mm), so the argmax may pick any of them: at most one
    // diagonal pixel apart (measured 0.044 m).
    assert!(m.peak_offset_m < 0.045, "peak offset {} m", m.peak_offset_m);
    // All paths: internal reflections and the external reflection add 0.111370 - 0.105980 W (4.8%) that no
    // two-interface method can reach. Measured ratio 0.9518.
    let all = score(img, &reference_image(SPHERE, Paths::All, 4_000_000));
    assert!((all.flux_ratio - 0.105980 / 0.111370).abs() < 0.01, "all-paths flux ratio {}", all.flux_ratio);
}

/// Bunny, dense level 4: the two-interface model is genuinely approximate on a non-convex mesh. The light-view
/// back buffer holds one layer (the nearest back face), and paths that leave the glass and enter it again are
/// treated as if they left for good. Measured: rel-L1 (64²) 0.137 and flux ratio 1.066 against the
/// two-refraction reference, independent of the g-buffer resolution (512²: 0.138, 2048²: 0.137), i.e. the
/// error is the method's, not the sampling's. The band documents it and fails if it grows.
#[test]
fn dense_bunny_documents_two_interface_error() {
    let (_gpu, device) = gpu();
    let img = caustics_aov(&device, BUNNY, dense(4)).img;
    let m = score(&img, &reference_image(BUNNY, Paths::TwoRefractions, 4_000_000));
    eprintln!("bunny vs two refractions: {m:?}");
    assert!(m.rel_l1 < 0.16, "rel-L1 {}", m.rel_l1);
    assert!(m.flux_ratio > 1.03 && m.flux_ratio < 1.10, "flux ratio {}", m.flux_ratio);
    // Against every path the GPU misses 17% (measured ratio 0.831).
    let all = score(&img, &reference_image(BUNNY, Paths::All, 4_000_000));
    assert!(all.flux_ratio > 0.79 && all.flux_ratio < 0.87, "all-paths flux ratio {}", all.flux_ratio);
}

/// Max-error at level 5 reaches max-level's error with far fewer photons. Measured on the sphere: max-level
/// 3,281,296 photons, max-error 761,375 (23%), both rel-L1 (64²) 0.0040 against the two-refraction reference.
#[test]
fn max_error_matches_max_level_with_fewer_photons() {
    let (_gpu, device) = gpu();
    let ml = caustics_aov(&device, SPHERE, adaptive(5, Metric::MaxLevel));
    let me = caustics_aov(&device, SPHERE, adaptive(5, Metric::MaxError));
    let r = reference_image(SPHERE, Paths::TwoRefractions, 4_000_000);
    let (a, b) = (score(&ml.img, &r), score(&me.img, &r));
    let (pa, pb) = (ml.photons(), me.photons());
    eprintln!("max-level {pa} photons {a:?}\nmax-error {pb} photons {b:?}");
    assert!((pb as f64) < 0.3 * pa as f64, "max-error {pb} photons vs max-level {pa}");
    assert!(b.rel_l1 <= a.rel_l1 + 0.002, "max-error rel-L1 {} vs max-level {}", b.rel_l1, a.rel_l1);
    assert!((b.flux_ratio / a.flux_ratio - 1.0).abs() < 0.002, "flux {} vs {}", b.flux_ratio, a.flux_ratio);
}

struct Hard {
    scene: &'static str,
    /// Measured GPU / two-refraction-reference flux ratio at dense level 3 (4M-photon references).
    ratio: f64,
    why: &'static str,
}

/// The hard cases: every AOV value finite, the caustic flux no more than the refractor intercepts, and the
/// flux ratio against the two-refraction reference inside a band around its measured value.
#[test]
fn hard_cases_are_finite_bounded_and_close_to_reference() {
    let cases = [
        Hard {
            scene: "ior24.toml",
            ratio: 0.9996,
            why: "IOR 2.4: strong bending; all paths add 13% (internal bounces)",
        },
        Hard { scene: "oblique.toml", ratio: 1.0003, why: "light at (0.8, 2, 0.3): skewed frustum" },
        Hard {
            scene: "tilted_cube.toml",
            ratio: 0.9979,
            why: "sharp edges; TIR inside (half the all-paths flux is after TIR)",
        },
        Hard { scene: "vertex_above.toml", ratio: 1.0025, why: "a vertex straight under the light" },
        Hard { scene: "thin.toml", ratio: 1.0001, why: "a 1 cm lens: front and back almost coincide" },
        Hard { scene: "slab.toml", ratio: 0.9999, why: "no silhouette inside the cone" },
        Hard { scene: "directional.toml", ratio: 0.9998, why: "directional light: an orthographic light frustum" },
    ];
    let (_gpu, device) = gpu();
    for c in &cases {
        let path = scene(c.scene);
        let s = caustics_aov(&device, &path, dense(3));
        let img = &s.img;
        let direct = shot_at(&device, &path, two_interface(dense(3)), 0.0, caustics::Aov::Direct, SIZE).img;
        assert!(img.data.iter().flatten().all(|v| v.is_finite()), "{}: non-finite caustics", c.scene);
        assert!(direct.data.iter().all(|v| v[0].is_finite()), "{}: non-finite direct", c.scene);
        // Intercepted flux: whatever the reference saw touch the glass (caustics deposited + escaped + cut).
        let scene_obj = caustics::scene::Scene::load(Path::new(&path)).unwrap();
        let p = RefParams {
            camera: Some("top".into()),
            photons: 1_000_000,
            width: SIZE,
            height: SIZE,
            ..RefParams::default()
        };
        let t = reference::trace(&scene_obj, &p).unwrap().stats.counts;
        let intercepted = t.flux_caustics + t.flux_escaped + t.flux_cut;
        let flux = s.aov_flux;
        assert!(flux <= intercepted, "{}: caustic flux {flux} W > intercepted {intercepted} W", c.scene);
        let m = score(img, &reference_image(&path, Paths::TwoRefractions, 4_000_000));
        eprintln!(
            "{}: flux {flux:.6} W, intercepted {intercepted:.6} W, vs two refractions {m:?} ({})",
            c.scene, c.why
        );
        assert!(
            (m.flux_ratio - c.ratio).abs() < 0.01,
            "{}: flux ratio {} (measured {})",
            c.scene,
            m.flux_ratio,
            c.ratio
        );
        assert!(m.rel_l1 < 0.05, "{}: rel-L1 {}", c.scene, m.rel_l1);
    }
}

/// An open mesh (a dome shell) has one interface: a two-interface method finds no back surface, so it
/// deposits no caustic at all, while the reference puts 0.1058 W through the shell. The test documents that
/// gap rather than hiding it.
#[test]
fn open_mesh_is_beyond_a_two_interface_method() {
    let (_gpu, device) = gpu();
    let path = scene("open_mesh.toml");
    let s = caustics_aov(&device, &path, dense(3));
    assert!(s.img.data.iter().flatten().all(|v| v.is_finite()));
    assert_eq!(s.aov_flux, 0.0);
    let all = reference_image(&path, Paths::All, 1_000_000);
    let flux: f64 = all.data.iter().map(|p| p[0] as f64).sum::<f64>() * 4.0 / (SIZE * SIZE) as f64;
    assert!(flux > 0.09, "reference through the open dome: {flux} W");
}
