//! The eye deposit (docs/design.md "The eye deposit"): light that lands where the light's own caustic map cannot hold
//! it is deposited where the camera sees it. A glass retroreflector under a lamp (assets/scenes/ceiling.toml) sends
//! light back up past the lamp onto the ceiling, which the lamp's maps never see; an orthographic camera looking up
//! at the ceiling measures it against the CPU reference, which bins every receiver the camera sees.

mod common;
use caustics::metrics::compare;
use caustics::reference::{Aov, Paths, RefParams};
use caustics::settings::{Metric, Settings};
use common::*;
use std::path::Path;

const CEILING: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/ceiling.toml");
const SIDE: u32 = 128;

/// The CPU reference's caustics through the scene's `up` camera (every path), cached like the `top` references.
fn up_reference(photons: u64) -> caustics::image_io::RgbImage {
    let p = RefParams {
        camera: Some("up".into()),
        aov: Aov::Caustics,
        paths: Paths::All,
        photons,
        width: SIDE,
        height: SIDE,
        ..RefParams::default()
    };
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference-cache");
    caustics::reference::cached_in(&cache, Path::new(CEILING), &p).expect("reference")
}

/// The caustics AOV through the `up` camera, its flux (W), and exact transport's account (W per term).
fn up_shot(
    device: &std::sync::Arc<caustics::gpu::Device>,
    settings: Settings,
) -> (caustics::image_io::RgbImage, f64, Vec<f64>) {
    let mut r = renderer(device, CEILING, settings);
    let (img, report) = camera_aov(&mut r, "up", (SIDE, SIDE), caustics::Aov::Caustics);
    let area = r.scene().camera(Some("up")).expect("an up camera").pixel_area(SIDE, SIDE).expect("orthographic");
    let flux = img.data.iter().map(|p| p[0] as f64).sum::<f64>() * area;
    let t = report.transport.expect("exact transport");
    assert!(t.residual() < 1e-5, "energy account residual {}", t.residual());
    let intensity = r.scene().lights[0].intensity as f64;
    (img, flux, t.account().iter().map(|x| x * intensity).collect())
}

fn term(account: &[f64], name: &str) -> f64 {
    account[caustics::ACCOUNT_TERMS.iter().position(|t| *t == name).expect("a term")]
}

/// The panel's caustic against the reference (8M photons), adaptive flux-error at level 4. Measured on lavapipe:
/// rel-L1 5.1% at 64², flux ratio 0.9987; the reference's own noise is most of that (two 8M references differ by
/// 5.1%; against a 32M one this frame is at 3.4%, an 8M reference at 4.1%). Before the eye deposit the frame
/// showed nothing there, and the account held the panel's 0.0042 W as `unseen`.
#[test]
fn light_sent_past_the_lamp_lands_on_the_ceiling() {
    let (_gpu, device) = gpu();
    let (img, flux, account) = up_shot(&device, adaptive(4, Metric::FluxError));
    let reference = up_reference(8_000_000);
    let m = compare(&img, &reference, 64, 2.0);
    let eye = term(&account, "caustics_eye");
    eprintln!("ceiling: AOV {flux:.6} W, eye deposit {eye:.6} W, unseen {:.6} W, {m:?}", term(&account, "unseen"));
    assert!((m.flux_ratio - 1.0).abs() < 0.01, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.056, "rel-L1 {}", m.rel_l1);
    // What the camera shows is what the eye deposit took, less what it holds elsewhere in the image (nothing: the
    // camera sees only the ceiling).
    assert!((flux / eye - 1.0).abs() < 0.01, "AOV {flux} W against the eye deposit's {eye} W");
}

/// With the eye deposit off the ceiling stays dark, and its light is the account's `unseen` term: switching the
/// deposit on moves it from `unseen` to `caustics_eye`, watt for watt, and changes nothing else.
#[test]
fn the_eye_deposit_takes_what_was_unseen() {
    let (_gpu, device) = gpu();
    let on = up_shot(&device, adaptive(3, Metric::FluxError));
    let off = up_shot(&device, with(adaptive(3, Metric::FluxError), |s| s.tuning.eye_deposit = false));
    let (eye_on, eye_off) = (term(&on.2, "caustics_eye"), term(&off.2, "caustics_eye"));
    let (unseen_on, unseen_off) = (term(&on.2, "unseen"), term(&off.2, "unseen"));
    eprintln!("on: eye {eye_on:.6} W, unseen {unseen_on:.6} W; off: unseen {unseen_off:.6} W, AOV {:.3e} W", off.1);
    assert_eq!(off.1, 0.0, "the ceiling without the eye deposit");
    assert_eq!(eye_off, 0.0);
    assert!(eye_on > 0.003, "eye deposit {eye_on} W");
    assert!(((eye_on + unseen_on) / unseen_off - 1.0).abs() < 1e-5, "{eye_on} + {unseen_on} against {unseen_off}");
    for name in ["emitted", "direct", "escaped", "cut_threshold"] {
        let (a, b) = (term(&on.2, name), term(&off.2, name));
        assert!((a - b).abs() <= 1e-6 * a.abs().max(b.abs()), "{name}: {a} against {b}");
    }
    let caustics_on = term(&on.2, "caustics");
    let caustics_off = term(&off.2, "caustics");
    assert!(
        ((caustics_on - caustics_off) / eye_on - 1.0).abs() < 1e-5,
        "caustics {caustics_on} against {caustics_off}"
    );
}

/// The default pool (t = 1.6 s): refraction carries sunlight under the rim, where the sun's map sees the rim's
/// deck instead. The camera sees that floor through the water, so the glass pass reads the eye deposit there: the
/// linear beauty gains light, and loses none. Measured on lavapipe at 128², level 2: +4.62% of the beauty's light
/// (0.00% when the glass pass does not read the deposit: the camera sees that floor only through the water).
#[test]
fn the_pool_floor_under_the_rim_is_lit_through_the_water() {
    let (_gpu, device) = gpu();
    let pool = scene("swimming_pool.toml");
    let hdr = |deposit: bool| {
        let settings = with(adaptive(2, Metric::FluxError), |s| s.tuning.eye_deposit = deposit);
        let mut r = renderer(&device, &pool, settings);
        r.set_time(1.6).expect("set_time");
        let (img, report) = camera_aov(&mut r, "main", (128, 128), caustics::Aov::BeautyHdr);
        let account: Vec<f64> = report.transport.expect("exact transport").account().to_vec();
        (img, term(&account, "caustics_eye"))
    };
    let ((on, eye_on), (off, eye_off)) = (hdr(true), hdr(false));
    assert_eq!(eye_off, 0.0);
    let luminance = |p: &[f32; 3]| (p[0] + p[1] + p[2]) as f64;
    let (mut added, mut lost, mut total) = (0.0, 0.0, 0.0);
    for (a, b) in on.data.iter().zip(&off.data) {
        let d = luminance(a) - luminance(b);
        total += luminance(b);
        if d > 0.0 {
            added += d
        } else {
            lost -= d
        }
    }
    eprintln!(
        "pool: eye deposit {eye_on:.4} (account units), linear beauty +{:.2}% (-{:.2e} of it lost)",
        100.0 * added / total,
        lost / total
    );
    assert!(eye_on > 0.0, "the pool's eye deposit");
    assert!(added / total > 0.01, "the beauty gains {} of its light", added / total);
    assert!(lost / total < 1e-4, "the beauty loses {} of its light", lost / total);
}

/// The default pool's ripples reflect about 2% of the sunlight up onto the coping's underside, which no straight ray
/// from the sun reaches (swimming_pool.toml's `coping` camera looks up at it from under the north-west corner). The
/// eye deposit holds all of that light, and the sun's map none of it: within the distance test's four texels of the
/// coping's front, the underside is as far from the sun as the front is, but faces away from it
/// (`same_side_as_view`, glsl/common/gbuffer.glsl). Against the reference (32M photons) at t = 1.6 s, level 4,
/// measured on lavapipe: flux ratio 0.9962, rel-L1 17% at 16² under the pool's sun, 0.53° across (0.9998 and 21%
/// under a parallel beam; the reference's own noise: about 1,600 of its photons land in view, and an 8M reference
/// is 29% from it). Before the side test the frame held 0.87 of the flux, and the
/// map's light on the front seeped onto the underside along its edge (0.18 of the reference's flux).
#[test]
fn the_pool_reflects_sunlight_onto_the_coping_underside() {
    let (_gpu, device) = gpu();
    let pool = scene("swimming_pool.toml");
    let shot = |deposit: bool| {
        let settings = with(adaptive(4, Metric::FluxError), |s| s.tuning.eye_deposit = deposit);
        let mut r = renderer(&device, &pool, settings);
        r.set_time(1.6).expect("set_time");
        let (img, report) = camera_aov(&mut r, "coping", (256, 256), caustics::Aov::Caustics);
        let area =
            r.scene().camera(Some("coping")).expect("a coping camera").pixel_area(256, 256).expect("orthographic");
        let flux = img.data.iter().map(|p| p[0] as f64).sum::<f64>() * area;
        let t = report.transport.expect("exact transport");
        let eye = term(&t.account(), "caustics_eye") * r.scene().lights[0].intensity as f64;
        (img, flux, eye)
    };
    let reference = common::camera_reference(&pool, "coping", Aov::Caustics, Paths::All, 32_000_000, 256, 1.6);
    let (img, flux, eye) = shot(true);
    let m = compare(&img, &reference, 16, 0.4);
    let (_, map_only, _) = shot(false);
    eprintln!("coping: AOV {flux:.3e} W, eye deposit {eye:.3e} W, the map alone {map_only:.3e} W, {m:?}");
    assert!((m.flux_ratio - 1.0).abs() < 0.05, "flux ratio {}", m.flux_ratio);
    assert!(m.rel_l1 < 0.25, "rel-L1 at 16² {}", m.rel_l1);
    assert!((flux / eye - 1.0).abs() < 0.01, "AOV {flux} W against the eye deposit's {eye} W");
    assert!(map_only < 0.01 * flux, "the sun's map shows {map_only} W on the underside");
}
