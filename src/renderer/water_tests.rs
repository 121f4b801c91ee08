//! The simulated water surface on the GPU against the host's steps (src/scene/water.rs): a water block with
//! scripted drops and a keyframed ball sinking through it is stepped on the GPU (lavapipe, validation on) to a
//! time, forward again, and back (from rest), and after each frame its heights are read back and compared node by
//! node with `Water::simulate` at the same time, bodies placed by the same keyframes.

use super::refit_tests::BASE;
use super::{FrameDesc, Renderer};

/// A ball and the water, added to the tests' base scene.
const OBJECTS: &str = r#"
[[object]]
name = "ball"
shape = "sphere"
radius = 0.12
subdivisions = 3
material = { kind = "dielectric", ior = 1.5 }

[[object.keyframe]]
time = 0.0
translate = [-0.4, 0.75, 0.1]

[[object.keyframe]]
time = 0.6
translate = [0.2, 0.45, -0.1]

[[object]]
name = "water"
shape = "water"
size = [1.6, 1.4]
depth = 0.3
grid = 40
translate = [0.05, 0.4, 0.0]
rotate_deg = [0.0, 20.0, 0.0]
waves = [{ amplitude = 0.01, wavelength = 0.5, direction_deg = 10.0, speed = 0.4 }]
simulation = { speed = 0.5, damping = 0.4, limit = 0.04 }
drops = [
    { time = 0.02, at = [0.3, -0.2], radius = 0.1, depth = 0.02 },
    { time = 0.31, at = [-0.5, 0.5], radius = 0.07, depth = 0.01 },
]
material = { kind = "dielectric", ior = 1.33 }
"#;

/// The GPU's heights of water object `w` now, and the host's at the renderer's time: the largest difference (m)
/// and the largest height (m).
fn compare(r: &mut Renderer, w: usize) -> (f32, f32) {
    r.finish_frames().unwrap();
    let first = r.heights_now(w).expect("a simulated surface");
    let all: Vec<f32> =
        crate::vk::cmd::download_buffer(&r.device, &mut r.recorder, &r.scene_buffers.heights, first as usize + 41 * 41)
            .unwrap();
    let gpu = &all[first as usize..];
    let a = r.scene.objects[w].animation.clone().unwrap();
    let water = a.water.as_ref().unwrap();
    let spheres = r.scene.body_spheres();
    let t = r.scene.time;
    let host = water.simulate(t, &|t0, t1| r.scene.water_bodies(w, t0, t1, &spheres)).unwrap();
    let diff = gpu.iter().zip(&host.h).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    (diff, host.h.iter().map(|h| h.abs()).fold(0.0, f32::max))
}

#[test]
fn gpu_steps_agree_with_the_host() {
    let (mut r, _, view) = super::refit_tests::test_renderer(&format!("{BASE}{OBJECTS}"), "water.toml");
    let water = 2;
    // Forward in two frames (the ball enters the water at about 0.35 s), then back to a time before the second
    // drop: the surface starts again from rest.
    for (t, steps) in [(0.27f32, 16u64), (0.55, 33), (0.2, 12)] {
        r.set_time(t).unwrap();
        let f = r.render(&FrameDesc::new(&view, None)).unwrap();
        assert_eq!(f.report.scene.deformed_objects, 1);
        let state = r.scene_buffers.simulations[water].unwrap();
        let rate = r.scene.objects[water].animation.as_ref().unwrap().water.as_ref().unwrap().step_coefficients();
        assert_eq!(rate.map(|k| k.rate), Some(60), "steps per second (the least)");
        assert_eq!(state.steps, steps, "t = {t} s");
        let (diff, peak) = compare(&mut r, water);
        eprintln!("t = {t} s: {steps} steps, largest |h| {peak:.5} m, largest GPU - host {diff:.3e} m");
        assert!(peak > 2e-3, "t = {t} s: the drops and the ball moved the surface ({peak} m)");
        // The step is exact in both (no fused multiply-adds); the drops' cos and the bodies' sqrt may differ
        // in their last bits.
        assert!(diff < 1e-6, "t = {t} s: the GPU's heights are {diff} m off the host's");
    }
    assert_eq!(crate::gpu::validation_message_count(), 0, "validation messages");
}
