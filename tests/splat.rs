//! The compute splats (`--splat compute`: float atomics, dispatched indirectly; `--splat tiled`: the same with a
//! work group's taps gathered in a shared-memory window first) against the point splat (`--splat raster`:
//! vkCmdDrawIndirect with additive blending). All evaluate the same tent at the same texel centers, so only the
//! order of the float additions differs. Measured on lavapipe: flux ratio 1.000004 and rel-L1 4e-6 at 256² on the
//! sphere and the bunny (both compute splats); the tests allow 1e-5 and 1e-4.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use common::*;
use std::path::Path;

fn splat(dir: &Path, name: &str, scene: &str, how: &str, extra: &[&str]) -> (serde_json::Value, RgbImage) {
    let mut args = vec!["--splat", how, "--camera", "top", "--aov", "caustics", "--size", "256x256"];
    args.extend_from_slice(extra);
    let (s, out) = render(dir, &format!("{name}-{how}"), scene, &args);
    assert_eq!(s["splat"], how, "{name}: the stats report the splat that ran");
    (s, caustics::image_io::read_exr(&out).unwrap())
}

fn assert_same(name: &str, (a, ia): &(serde_json::Value, RgbImage), (b, ib): &(serde_json::Value, RgbImage)) {
    assert_eq!(a["photons_splatted"], b["photons_splatted"], "{name}: photons");
    assert_eq!(a["host_readbacks_per_frame"], 0, "{name}: readbacks");
    assert_eq!(b["host_readbacks_per_frame"], 0, "{name}: readbacks");
    let (fa, fb) = (a["aov_flux_w"].as_f64().unwrap(), b["aov_flux_w"].as_f64().unwrap());
    assert!(fa > 0.0 && (fa / fb - 1.0).abs() < 1e-5, "{name}: flux {fa} (compute splat) vs {fb} (raster) W");
    let m = compare(ia, ib, 256, 2.0);
    eprintln!("{name}: compute vs raster {m:?}");
    assert!(m.rel_l1 <= 1e-4, "{name}: rel-L1 {}", m.rel_l1);
}

#[test]
fn compute_splat_matches_raster() {
    let dir = out_dir("splat_match");
    let cases: [(&str, &str, &[&str]); 6] = [
        // Level 0: radii wider than the tiled splat's window, so its taps spill to global atomics.
        ("sphere-coarse", SPHERE, &["--transport", "two-interface", "--method", "dense", "--level", "0"]),
        ("sphere-dense", SPHERE, &["--transport", "two-interface", "--method", "dense", "--level", "3"]),
        ("bunny-dense", BUNNY, &["--transport", "two-interface", "--method", "dense", "--level", "3"]),
        ("sphere-max-error", SPHERE, &["--transport", "two-interface", "--metric", "max-error", "--level", "4"]),
        ("bunny-max-level", BUNNY, &["--transport", "two-interface", "--metric", "max-level", "--level", "3"]),
        // Under differential footprints (exact transport's default) the compute splats put wide tents on coarse
        // levels where the raster splat draws them whole; tests/footprint.rs bounds that difference.
        ("sphere-exact", SPHERE, &["--transport", "exact", "--footprint", "cell", "--method", "dense", "--level", "2"]),
    ];
    for (name, scene, extra) in cases {
        let r = splat(&dir, name, scene, "raster", extra);
        for how in ["compute", "tiled"] {
            let c = splat(&dir, name, scene, how, extra);
            assert_same(&format!("{name} {how}"), &c, &r);
        }
    }
}

/// Batching with a tiny budget (batches split on overflow) gives the same image with the compute splat, and no
/// host readback.
#[test]
fn compute_splat_with_tiny_budget() {
    let dir = out_dir("splat_budget");
    let args = ["--transport", "two-interface", "--metric", "max-level", "--level", "4"];
    let big = splat(&dir, "big", SPHERE, "raster", &args);
    let mut tiny = args.to_vec();
    tiny.extend_from_slice(&["--photon-budget", "0.25"]);
    for how in ["compute", "tiled"] {
        let small = splat(&dir, "small", SPHERE, how, &tiny);
        assert!(small.0["batches"].as_u64().unwrap() >= 4, "batches {}", small.0["batches"]);
        assert_same(&format!("tiny budget {how}"), &small, &big);
    }
}

/// Photons that carry their color (docs/design.md "Color"): the tiled splat's window holds a plane per channel, as
/// the map does, so each channel equals the untiled splat's. Color photons (the amber sphere) and spectral ones
/// (the prism), exact transport at level 3. Measured on lavapipe: rel-L1 at most 1.3e-7 per channel, fluxes equal to
/// 7 digits; the test allows 1e-5 in flux and 1e-4 rel-L1 per channel.
#[test]
fn tiled_splat_matches_compute_for_photons_that_carry_color() {
    let dir = out_dir("splat_color");
    let scenes = [
        ("amber", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/colored_glass.toml"), "rgb"),
        ("prism", concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/prism.toml"), "spectral"),
    ];
    let args = ["--transport", "exact", "--level", "3"];
    for (name, scene, pass) in scenes {
        let (a, ia) = splat(&dir, name, scene, "compute", &args);
        let (b, ib) = splat(&dir, name, scene, "tiled", &args);
        for s in [&a, &b] {
            assert_eq!(s["lights"][0]["channel"], pass, "{name}: one pass that carries color");
        }
        assert_eq!(a["photons_splatted"], b["photons_splatted"], "{name}: photons");
        for c in 0..3 {
            let plane = |img: &RgbImage| {
                let mut out = img.clone();
                out.data.iter_mut().for_each(|p| *p = [p[c]; 3]);
                out
            };
            let (pa, pb) = (plane(&ia), plane(&ib));
            let flux = |img: &RgbImage| img.data.iter().map(|p| p[0] as f64).sum::<f64>();
            let (fa, fb) = (flux(&pa), flux(&pb));
            let m = compare(&pb, &pa, 256, 2.0);
            eprintln!("{name} channel {c}: tiled {fb:.6e}, untiled {fa:.6e}, rel-L1 {:.2e}", m.rel_l1);
            assert!(fa > 0.0 && (fb / fa - 1.0).abs() < 1e-5, "{name} channel {c}: flux {fb} vs {fa}");
            assert!(m.rel_l1 <= 1e-4, "{name} channel {c}: rel-L1 {}", m.rel_l1);
        }
    }
}
