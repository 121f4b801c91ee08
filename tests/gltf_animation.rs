//! Animated glTF renders as its pose renders still. A rig of nodes with non-identity rest transforms (a moving,
//! turning parent; a child whose scale follows a cubic spline; a grandchild turned by steps; a mesh instanced by two
//! nodes; a moving camera and a tilting spot light), animated by three animations as Blender writes them (one per
//! animated thing), is rendered at three times and compared with the
//! same file with each node's TRS at that time written in and the animations removed: the same photon count and a
//! rel-L1 at 256² of at most 1e-4 on the caustics AOV and the linear beauty, under both transports; placed as
//! `render --time` places it, and as playback moves it (the renderer's scene update: `render --sequence` and the
//! viewer), and through the viewer itself.

mod common;
use caustics::scene::Scene;
use caustics::settings::{Quality, Settings, Transport};
use caustics::{Aov, Renderer};
use common::rig::*;
use common::*;

/// A frame of `r` through camera `camera` at 256²: the float AOV and the photon count.
fn frame(r: &mut Renderer, camera: &str, aov: Aov) -> (caustics::image_io::RgbImage, u64) {
    let (image, report) = camera_aov(r, camera, (256, 256), aov);
    (image, report.photons())
}

fn settings(transport: Transport) -> Settings {
    Settings { quality: Quality { transport, level: Some(3), ..Quality::default() }, ..Settings::default() }
}

/// The caustics (top camera) and linear beauty (main camera) frames of `r`, with their photon counts.
fn frames(r: &mut Renderer) -> [(caustics::image_io::RgbImage, u64); 2] {
    [frame(r, "top", Aov::Caustics), frame(r, "main", Aov::BeautyHdr)]
}

/// `got` renders as `want` does: the same photons, rel-L1 ≤ 1e-4 at 256² on both AOVs.
fn assert_same_frames(
    got: &[(caustics::image_io::RgbImage, u64); 2],
    want: &[(caustics::image_io::RgbImage, u64); 2],
    what: &str,
) {
    for (k, aov) in ["caustics", "beauty"].iter().enumerate() {
        let m = caustics::metrics::compare(&got[k].0, &want[k].0, 256, 2.0);
        eprintln!("{what}, {aov}: rel-L1 {:.2e}, photons {} against {}", m.rel_l1, got[k].1, want[k].1);
        assert!(want[k].0.data.iter().any(|p| p[0] > 0.0), "{what}, {aov}: the still frame is black");
        assert_eq!(got[k].1, want[k].1, "{what}, {aov}: photon count");
        assert!(m.rel_l1 <= 1e-4, "{what}, {aov}: rel-L1 {:.3e} at 256²", m.rel_l1);
    }
}

#[test]
fn animated_gltf_renders_as_its_pose_renders_still() {
    let dir = out_dir("gltf_animation_pose");
    let (animated, stills) = write_rigs(&dir);
    let scene = Scene::load(&animated).expect("the animated rig loads");
    assert_eq!(scene.animations, vec!["Rig".to_string(), "Glass".to_string(), "Lights".to_string()]);
    assert_eq!(scene.duration(), 1.5, "both animations play: the longer ends at 1.5 s");
    assert_eq!(scene.objects.len(), 4, "floor, cube, bead, and the cube's second instance");
    let (_lock, device) = gpu();
    for transport in [Transport::Exact, Transport::TwoInterface] {
        // Playback: one renderer whose scene update moves the rig from time to time.
        let mut playing = Renderer::new(device.clone(), scene.clone(), settings(transport)).expect("renderer");
        for (&t, still) in TIMES.iter().zip(&stills) {
            let want = frames(
                &mut Renderer::new(device.clone(), Scene::load(still).unwrap(), settings(transport)).expect("renderer"),
            );
            // As `render --time t` places it: loaded, set to t, then rendered.
            let got = frames(&mut Renderer::new(device.clone(), scene.at_time(t), settings(transport)).expect("r"));
            assert_same_frames(&got, &want, &format!("{transport:?} at {t} s, placed"));
            playing.set_time(t).expect("set_time");
            let got = frames(&mut playing);
            assert_same_frames(&got, &want, &format!("{transport:?} at {t} s, played"));
        }
    }
}

/// `render --sequence` plays the rig as the renderer's scene update moves it, its camera included: the second of
/// two frames from 0.25 s at 8 fps is the rig posed still at 0.375 s (rendered in process with the sequence's
/// settings; measured: the same bytes).
#[test]
fn a_sequence_plays_the_rig_as_its_poses_render() {
    let dir = out_dir("gltf_animation_sequence");
    let (animated, stills) = write_rigs(&dir);
    assert_eq!(TIMES[1], 0.375);
    let frame = ["--camera", "main", "--size", "128x128", "--level", "3"];
    let sequence = ["--sequence", "2", "--fps", "8", "--time", "0.25"];
    let (s, _) = render(&dir, "frame_#", animated.to_str().unwrap(), &[&frame[..], &sequence[..]].concat());
    assert_eq!(s["sequence"]["frames"], 2);
    let played = caustics::image_io::read_png(&dir.join("frame_1.png")).expect("PNG");
    // `--level 3`, the rest default: the settings of the other test's exact transport.
    let (_lock, device) = gpu();
    let mut r = Renderer::new(device.clone(), Scene::load(&stills[1]).unwrap(), settings(Transport::Exact)).unwrap();
    let still = camera_beauty(&mut r, "main", (128, 128));
    assert!(played == still, "the sequence's second frame differs from the pose at 0.375 s");
}
