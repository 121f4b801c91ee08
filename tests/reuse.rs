//! Reuse by dependency: a frame whose light, geometry, materials and settings did not change reuses the last
//! frame's caustic map (only the eye and composite passes run); anything they depend on changing recomputes them.
//! Runs the library in-process with validation (and synchronization validation) on.

mod common;
use caustics::image_io::RgbImage;
use caustics::metrics::compare;
use caustics::scene::Material;
use caustics::settings::{Method, Quality, Settings, Transport};
use caustics::{Aov, AovData, FrameDesc, FrameReport, Renderer};

const SPHERE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml");

/// The sphere under exact transport, dense level 1 (the transport is named: these tests assert reuse, not the
/// default configuration's numbers).
fn open(device: &std::sync::Arc<caustics::gpu::Device>, reuse: bool) -> Renderer {
    let quality = Quality { transport: Transport::Exact, method: Method::Dense, level: Some(1), ..Quality::default() };
    let mut r = common::renderer(device, SPHERE, Settings { quality, ..Settings::default() });
    r.set_reuse(reuse);
    r
}

fn rgb(img: AovData) -> RgbImage {
    match img {
        AovData::Float { width, height, rgba } => {
            RgbImage { width, height, data: rgba.iter().map(|p| [p[0], p[1], p[2]]).collect() }
        }
        AovData::Rgba8 { .. } => panic!("the caustics AOV is float"),
    }
}

fn frame(r: &mut Renderer, camera: &str) -> (FrameReport, RgbImage) {
    let cam = r.scene().camera(Some(camera)).unwrap().clone();
    let view = r.camera_view(&cam, 128, 128);
    let f = r.render(&FrameDesc::new(&view, Some(Aov::Caustics))).expect("frame");
    (f.report, rgb(f.image.unwrap()))
}

fn same(a: &RgbImage, b: &RgbImage, what: &str, tol: f64) {
    let m = compare(a, b, 128, 2.0);
    eprintln!("{what}: rel-L1 {:.3e}", m.rel_l1);
    assert!(m.rel_l1 <= tol && m.flux_ratio.is_finite(), "{what}: rel-L1 {} (tolerance {tol})", m.rel_l1);
}

#[test]
fn camera_moves_reuse_and_changes_recompute() {
    let (_gpu, device) = common::gpu();
    let mut s = open(&device, true);
    let (r0, top0) = frame(&mut s, "top");
    assert!(!r0.reused);
    // Camera only: the caustic stages are not recorded.
    let (r1, main1) = frame(&mut s, "main");
    assert!(r1.reused, "a camera change must reuse the caustic map");
    assert!(!r1.stages.iter().any(|(l, _)| l.starts_with("transport") || *l == "light_gbuffer" || *l == "splat"));
    let (r2, top2) = frame(&mut s, "top");
    assert!(r2.reused);
    assert_eq!(r2.state.map(|x| x.photons_total), r0.state.map(|x| x.photons_total), "cached state");
    same(&top2, &top0, "top after a camera round trip", 1e-6);
    // The reused main view equals a full recompute of it (measured 5.6e-8 to 1.1e-7: only the order of the splat's
    // float atomic additions differs).
    let mut fresh = open(&device, false);
    let (rf, main_fresh) = frame(&mut fresh, "main");
    assert!(!rf.reused);
    same(&main1, &main_fresh, "main view, reused against recomputed", 1e-6);

    // The light moves: everything that depends on it runs again, and the image equals a fresh render.
    let mut scene = s.scene().clone();
    scene.lights[0].position.x += 0.1;
    s.set_scene(scene.clone()).unwrap();
    let (r3, moved) = frame(&mut s, "top");
    assert!(!r3.reused, "a light change must recompute");
    fresh.set_scene(scene.clone()).unwrap();
    let (_, moved_fresh) = frame(&mut fresh, "top");
    same(&moved, &moved_fresh, "moved light", 1e-6);
    let m = compare(&moved, &top0, 128, 2.0);
    assert!(m.rel_l1 > 0.01, "the caustic must move with the light (rel-L1 {})", m.rel_l1);

    // IOR: the photon stages run again.
    for o in scene.objects.iter_mut() {
        if let Material::Dielectric { ior, .. } = &mut o.material {
            *ior = 1.6;
        }
    }
    s.set_scene(scene).unwrap();
    assert!(!frame(&mut s, "top").0.reused, "an IOR change must recompute");
    assert!(frame(&mut s, "top").0.reused);

    // Settings: a new level recomputes.
    let mut settings = s.settings().clone();
    settings.quality.level = Some(2);
    s.set_settings(settings).unwrap();
    assert!(!frame(&mut s, "top").0.reused, "a settings change must recompute");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

/// Progressive refinement (the viewer's): frames below the chosen level are complete frames at their own level,
/// and the frame at the chosen level equals a fresh render at it. Measured: the level-0 and level-1 frames' flux
/// is within 0.2% of the level-2 frame's (exact transport conserves flux at every level).
#[test]
fn progressive_refinement_converges_to_render() {
    let (_gpu, device) = common::gpu();
    let mut s = open(&device, true);
    let mut settings = s.settings().clone();
    settings.quality.level = Some(2);
    s.set_settings(settings).unwrap();
    let cam = s.scene().camera(Some("top")).unwrap().clone();
    let view = s.camera_view(&cam, 128, 128);
    let flux = |img: &RgbImage| img.data.iter().map(|p| p[0] as f64).sum::<f64>();
    let mut steps = Vec::new();
    for level in 0..=2 {
        let desc = FrameDesc { level: Some(level), ..FrameDesc::new(&view, Some(Aov::Caustics)) };
        let f = s.render(&desc).unwrap();
        let (r, img) = (f.report, f.image);
        assert_eq!(r.level, level);
        assert!(!r.reused, "each refinement step recomputes");
        steps.push(rgb(img.unwrap()));
    }
    assert_eq!(s.config().level, 2, "the chosen level is kept");
    let mut fresh = open(&device, false);
    let mut settings = fresh.settings().clone();
    settings.quality.level = Some(2);
    fresh.set_settings(settings).unwrap();
    let (_, final_fresh) = frame(&mut fresh, "top");
    same(&steps[2], &final_fresh, "refined against a fresh render", 1e-4);
    for (level, img) in steps.iter().enumerate() {
        let ratio = flux(img) / flux(&final_fresh);
        assert!((ratio - 1.0).abs() < 0.005, "level {level}: flux ratio {ratio}");
    }
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

fn beauty(r: &mut Renderer, camera: &str) -> (FrameReport, Vec<u8>) {
    let cam = r.scene().camera(Some(camera)).unwrap().clone();
    let view = r.camera_view(&cam, 128, 128);
    let f = r.render(&FrameDesc::new(&view, Some(Aov::Beauty))).expect("frame");
    match f.image.unwrap() {
        AovData::Rgba8 { rgba, .. } => (f.report, rgba),
        _ => panic!("the beauty AOV is 8-bit"),
    }
}

/// A frame in which nothing changed at all records neither the caustic stages nor the eye view: it presents the
/// last beauty image again, byte for byte. A camera move re-runs the eye view only; an exposure change too; an
/// AOV the composite does not write (caustics) always runs the eye view's receivers, and records no glass pass
/// and no composite.
#[test]
fn nothing_changed_reuses_the_eye_view() {
    let (_gpu, device) = common::gpu();
    let mut s = open(&device, true);
    let (r0, b0) = beauty(&mut s, "main");
    assert!(!r0.reused && !r0.eye_reused);
    let (r1, b1) = beauty(&mut s, "main");
    assert!(r1.reused && r1.eye_reused, "nothing changed: both the caustics and the eye view are reused");
    assert!(!r1.stages.iter().any(|(l, _)| *l == "eye" || *l == "composite"), "{:?}", r1.stages);
    assert!(r1.stages.iter().any(|(l, _)| *l == "eye_reused"));
    assert_eq!(b1, b0, "a reused eye view presents the same bytes");
    let (r2, b2) = beauty(&mut s, "top");
    assert!(r2.reused && !r2.eye_reused, "a camera move re-runs the eye view");
    assert_ne!(b2, b0);
    let (r3, _) = beauty(&mut s, "main");
    assert!(!r3.eye_reused, "the eye view reused is only the last frame's");
    let mut settings = s.settings().clone();
    settings.quality.exposure_ev += 1.0;
    s.set_settings(settings).unwrap();
    let (r4, b4) = beauty(&mut s, "main");
    assert!(r4.reused && !r4.eye_reused, "an exposure change re-runs the eye view, not the caustics");
    assert_ne!(b4, b0);
    let (r5, _) = frame(&mut s, "main");
    assert!(!r5.eye_reused, "the caustics AOV comes from the eye pass: it runs");
    // It needs no glass and no beauty: neither the glass passes nor the composite are recorded, so the next beauty
    // frame composites again, the same bytes as the last beauty frame's.
    assert!(!r5.substages.iter().any(|(l, _)| *l == "eye.glass"), "{:?}", r5.substages);
    let (r6, b6) = beauty(&mut s, "main");
    assert!(r6.reused && !r6.eye_reused, "after a caustics frame the eye view runs again");
    assert_eq!(b6, b4, "the beauty the last beauty frame showed");
    // The profiler's sessions reuse nothing.
    let mut off = open(&device, false);
    beauty(&mut off, "main");
    assert!(!beauty(&mut off, "main").0.eye_reused);
}

/// Progressive accumulation: while nothing changes, each frame traces a fresh photon set (every cell sampled at the
/// next point of a low-discrepancy sequence, its footprint narrowed) and the caustic map averages it with the sets
/// before. The average keeps the flux, and it converges: its distance to the 64-set average falls as
/// sqrt(1/n - 1/64), as the mean of n independent sets would (the 1/sqrt(frames) law). A camera move keeps the
/// average; a change of what the maps depend on starts a new one. Measured on lavapipe (the sphere, dense level 1,
/// 128², at 64²): 1 set 1.14e-2 from the 64-set average, 4 sets 6.2e-3 (0.545 of it, law 0.488), 16 sets 2.9e-3
/// (0.253, law 0.218); the first set's flux 1.0016 of the average's.
#[test]
fn a_still_scene_converges_as_photon_sets_accumulate() {
    let (_gpu, device) = common::gpu();
    let mut s = open(&device, true);
    s.set_accumulation(64);
    let flux = |img: &RgbImage| img.data.iter().map(|p| p[0] as f64).sum::<f64>();
    let mut kept = Vec::new();
    let mut photons = None;
    for n in 1..=64u32 {
        let (r, img) = frame(&mut s, "top");
        assert!(!r.reused && r.photon_sets == n, "set {n}: reused {}, sets {}", r.reused, r.photon_sets);
        let count = r.state.map(|x| x.photons_total);
        assert!(photons.is_none() || photons == Some(count), "every set traces the same cells");
        photons = Some(count);
        if [1, 4, 16, 64].contains(&n) {
            kept.push((n, img));
        }
    }
    let limit = &kept[3].1;
    let e1 = compare(&kept[0].1, limit, 64, 2.0).rel_l1;
    for (n, img) in &kept {
        let ratio = flux(img) / flux(limit);
        // (A set's flux varies where its samples leave cells that straddle the ball's silhouette: measured 0.16%
        // for the first set, whose samples are the cells' centers.)
        assert!((ratio - 1.0).abs() < 4e-3, "{n} sets: flux ratio {ratio} to the 64-set average");
        let law = ((1.0 / *n as f64 - 1.0 / 64.0) / (1.0 - 1.0 / 64.0)).sqrt();
        let e = compare(img, limit, 64, 2.0).rel_l1;
        eprintln!(
            "{n} sets: rel-L1 {e:.3e} to the 64-set average, {:.3} of one set's (law {law:.3}), flux {ratio:.5}",
            e / e1
        );
        assert!((e / e1 - law).abs() <= 0.2 * law + 1e-9, "{n} sets: {:.3} of one set's error, law {law:.3}", e / e1);
    }
    // Full: the next frame reuses the average.
    let (r, img) = frame(&mut s, "top");
    assert!(r.reused && r.photon_sets == 64);
    same(&img, limit, "the kept average", 1e-6);
    // A camera move keeps it (every landing is in the light's map); a new level starts a new average.
    let (r, _) = frame(&mut s, "main");
    assert!(r.reused && r.photon_sets == 64, "a camera move keeps the average");
    let mut settings = s.settings().clone();
    settings.quality.level = Some(2);
    s.set_settings(settings).unwrap();
    let (r, _) = frame(&mut s, "top");
    assert!(!r.reused && r.photon_sets == 1, "a change starts a new average");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}

/// No ghost: after a still glass's maps have averaged 16 photon sets, the glass jumps 0.25 m; the next frame is a
/// new average of one set, equal to a fresh renderer's frame of the moved glass (nothing of the old caustic is
/// left), and the sets then accumulate again from there.
#[test]
fn a_glass_that_jumps_leaves_no_ghost() {
    let (_gpu, device) = common::gpu();
    let mut s = open(&device, true);
    s.set_accumulation(16);
    let glass = (0..s.scene().objects.len())
        .map(caustics::InstanceId::from_index)
        .find(|&i| s.scene().objects[i.index()].name == "glass")
        .expect("the glass ball");
    for n in 1..=16 {
        assert_eq!(frame(&mut s, "top").0.photon_sets, n);
    }
    let (_, before) = frame(&mut s, "top");
    let moved = glam::Mat4::from_translation(glam::Vec3::new(0.25, 0.0, 0.0)) * s.transform(glass).unwrap();
    s.set_transform(glass, moved).unwrap();
    let (r, after) = frame(&mut s, "top");
    assert!(!r.reused && r.photon_sets == 1, "the jump starts a new average");
    let mut fresh = open(&device, true);
    fresh.set_transform(glass, moved).unwrap();
    let (_, expected) = frame(&mut fresh, "top");
    same(&after, &expected, "the frame after the jump against a fresh render of the moved glass", 1e-5);
    let m = compare(&after, &before, 64, 2.0);
    assert!(m.peak_offset_m > 0.15, "the caustic moved with the glass: {m:?}");
    assert_eq!(frame(&mut s, "top").0.photon_sets, 2, "and accumulates again");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages");
}
