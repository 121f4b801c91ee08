//! In process: the compute splats (`--splat compute`: float atomics, dispatched indirectly; `--splat tiled`: the same with a
//! work group's taps gathered in a shared-memory window first) against the point splat (`--splat raster`:
//! vkCmdDrawIndirect with additive blending). All evaluate the same tent at the same texel centers, so only the
//! order of the float additions differs. Measured on lavapipe: flux ratio 1.000004 and rel-L1 4e-6 at 256² on the
//! sphere and the bunny (both compute splats); the tests allow 1e-5 and 1e-4.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::settings::{Footprint, Method, Metric, Settings, Splat, Transport};
use common::*;
use std::sync::Arc;

/// Settings: `transport`, `method` and `metric` at `level`, the rest default.
fn settings(transport: Transport, method: Method, metric: Metric, level: u32) -> Settings {
    let mut s = quality(method, level, metric);
    s.quality.transport = transport;
    s
}

/// The caustics AOV from the top camera at 256², splatted `how`, in process.
fn splat(device: &Arc<caustics::gpu::Device>, scene: &str, how: Splat, settings: &Settings) -> Shot {
    let mut settings = settings.clone();
    settings.tuning.splat = how;
    let s = shot(device, scene, settings);
    assert_eq!(s.config.splat, how, "the settings name the splat that ran");
    s
}

fn assert_same(name: &str, a: &Shot, b: &Shot) {
    assert_eq!(a.photons(), b.photons(), "{name}: photons");
    assert_eq!(a.report.host_readbacks, 0, "{name}: readbacks");
    assert_eq!(b.report.host_readbacks, 0, "{name}: readbacks");
    let (fa, fb) = (a.aov_flux, b.aov_flux);
    assert!(fa > 0.0 && (fa / fb - 1.0).abs() < 1e-5, "{name}: flux {fa} (compute splat) vs {fb} (raster) W");
    let m = compare(&a.img, &b.img, 256, 2.0);
    eprintln!("{name}: compute vs raster {m:?}");
    assert!(m.rel_l1 <= 1e-4, "{name}: rel-L1 {}", m.rel_l1);
}

#[test]
fn compute_splat_matches_raster() {
    let (_gpu, device) = gpu();
    let two = Transport::TwoInterface;
    let mut exact_cell = settings(Transport::Exact, Method::Dense, Metric::FluxError, 2);
    exact_cell.tuning.footprint = Footprint::Cell;
    let cases = [
        // Level 0: radii wider than the tiled splat's window, so its taps spill to global atomics.
        ("sphere-coarse", SPHERE, settings(two, Method::Dense, Metric::FluxError, 0)),
        ("sphere-dense", SPHERE, settings(two, Method::Dense, Metric::FluxError, 3)),
        ("bunny-dense", BUNNY, settings(two, Method::Dense, Metric::FluxError, 3)),
        ("sphere-max-error", SPHERE, settings(two, Method::Adaptive, Metric::MaxError, 4)),
        ("bunny-max-level", BUNNY, settings(two, Method::Adaptive, Metric::MaxLevel, 3)),
        // Under differential footprints (exact transport's default) the compute splats put wide tents on coarse
        // levels where the raster splat draws them whole; tests/footprint.rs bounds that difference.
        ("sphere-exact", SPHERE, exact_cell),
    ];
    for (name, scene, s) in cases {
        let r = splat(&device, scene, Splat::Raster, &s);
        for how in [Splat::Compute, Splat::Tiled] {
            let c = splat(&device, scene, how, &s);
            assert_same(&format!("{name} {how:?}"), &c, &r);
        }
    }
}

/// Batching with a tiny budget (batches split on overflow) gives the same image with the compute splat, and no
/// host readback.
#[test]
fn compute_splat_with_tiny_budget() {
    let (_gpu, device) = gpu();
    let s = settings(Transport::TwoInterface, Method::Adaptive, Metric::MaxLevel, 4);
    let big = splat(&device, SPHERE, Splat::Raster, &s);
    let mut tiny = s.clone();
    tiny.quality.photon_budget_mib = 0.25;
    for how in [Splat::Compute, Splat::Tiled] {
        let small = splat(&device, SPHERE, how, &tiny);
        let batches = small.traversal().batches_committed;
        assert!(batches >= 4, "batches {batches}");
        assert_same(&format!("tiny budget {how:?}"), &small, &big);
    }
}

/// Photons that carry their color (docs/design.md "Color"): the tiled splat's window holds a plane per channel, as
/// the map does, so each channel equals the untiled splat's. Color photons (the amber sphere) and spectral ones
/// (the prism), exact transport at level 3. Measured on lavapipe: rel-L1 at most 1.3e-7 per channel, fluxes equal to
/// 7 digits; the test allows 1e-5 in flux and 1e-4 rel-L1 per channel.
#[test]
fn tiled_splat_matches_compute_for_photons_that_carry_color() {
    let (_gpu, device) = gpu();
    let scenes = [
        (
            "amber",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/colored_glass.toml"),
            caustics::consts::CHANNEL_RGB,
        ),
        ("prism", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/prism.toml"), caustics::consts::CHANNEL_SPECTRAL),
    ];
    let s = settings(Transport::Exact, Method::Adaptive, Metric::FluxError, 3);
    for (name, scene, pass) in scenes {
        let a = splat(&device, scene, Splat::Compute, &s);
        let b = splat(&device, scene, Splat::Tiled, &s);
        for s in [&a, &b] {
            assert_eq!(s.report.lights[0].channel, pass, "{name}: one pass that carries color");
        }
        assert_eq!(a.photons(), b.photons(), "{name}: photons");
        let (ia, ib) = (&a.img, &b.img);
        for c in 0..3 {
            let plane = |img: &RgbImage| {
                let mut out = img.clone();
                out.data.iter_mut().for_each(|p| *p = [p[c]; 3]);
                out
            };
            let (pa, pb) = (plane(ia), plane(ib));
            let flux = |img: &RgbImage| img.data.iter().map(|p| p[0] as f64).sum::<f64>();
            let (fa, fb) = (flux(&pa), flux(&pb));
            let m = compare(&pb, &pa, 256, 2.0);
            eprintln!("{name} channel {c}: tiled {fb:.6e}, untiled {fa:.6e}, rel-L1 {:.2e}", m.rel_l1);
            assert!(fa > 0.0 && (fb / fa - 1.0).abs() < 1e-5, "{name} channel {c}: flux {fb} vs {fa}");
            assert!(m.rel_l1 <= 1e-4, "{name} channel {c}: rel-L1 {}", m.rel_l1);
        }
    }
}
