//! The examples run on lavapipe with validation (and synchronization validation) on: `headless` writes its EXR and
//! PNG; `embed` records a frame into a Vulkan device and command buffer it created itself (the import path) and
//! checks that its image is byte for byte the one `Renderer::render` gives; `wgpu` does the same inside a wgpu
//! application's device. `cargo test` builds the examples; this runs them.

mod common;
use std::path::PathBuf;
use std::process::Command;

/// target/<profile>/examples/<name>, next to this test's own target/<profile>/deps/.
fn example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("the test's path");
    let profile = exe.parent().and_then(|deps| deps.parent()).expect("target/<profile>");
    let path = profile.join("examples").join(name);
    assert!(path.is_file(), "{} is not built (cargo test builds the examples)", path.display());
    path
}

fn run(name: &str, args: &[&str]) -> String {
    run_env(name, args, &[])
}

/// [`run`] with more environment variables.
fn run_env(name: &str, args: &[&str], env: &[(&str, &str)]) -> String {
    let out = Command::new(example(name))
        .args(args)
        .env("CAUSTICS_VALIDATION", "1")
        .env("RUST_LOG", "warn")
        .envs(env.iter().copied())
        .output()
        .expect("run the example");
    let text = format!("{}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "example {name} failed ({:?}):\n{text}", out.status.code());
    assert!(!text.contains("validation messages"), "{text}");
    text
}

#[test]
fn headless_example_writes_its_images() {
    let dir = common::out_dir("example_headless");
    let scene = common::scene("bunny.toml");
    let text = run("headless", &[&scene, dir.to_str().unwrap()]);
    let exr = caustics::image_io::read_exr(&dir.join("caustics.exr")).expect("the caustics EXR");
    assert_eq!((exr.width, exr.height), (256, 256));
    let sum: f64 = exr.data.iter().map(|p| p[0] as f64).sum();
    assert!(sum > 0.0, "a caustic on the floor: {text}");
    let (w, h, rgba) = caustics::image_io::read_png(&dir.join("beauty.png")).expect("the beauty PNG");
    assert_eq!((w, h, rgba.len()), (480, 360, 4 * 480 * 360));
    assert!(text.contains("caustics reused: true"), "the beauty frame reuses the caustic maps:\n{text}");
}

#[test]
fn embed_example_matches_render() {
    let text = run("embed", &[&common::scene("sphere.toml")]);
    assert!(text.contains(" 0 of 76800 bytes differ from Renderer::render"), "{text}");
}

/// A wgpu application on lavapipe, with validation and synchronization validation on: caustics records into
/// wgpu's command encoder and texture, and wgpu's readback of the texture is byte for byte `Renderer::render`'s
/// image of the same frame (the example fails itself on a difference or on any validation message wgpu reports).
#[test]
fn wgpu_example_matches_render() {
    let sync = ("VK_LAYER_ENABLES", "VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT");
    let text = run_env("wgpu", &["--headless", &common::scene("sphere.toml")], &[sync]);
    assert!(text.contains(" 0 of 98304 bytes differ from Renderer::render"), "{text}");
    assert!(!text.contains("wgpu_hal::vulkan::instance"), "a validation message:\n{text}");
}

/// The shipped environment map is the `sky` example's output, byte for byte (so it can be made again, and its
/// license is the project's own); a smaller one loads as a valid 2:1 map.
#[test]
fn sky_example_writes_the_shipped_map() {
    let dir = common::out_dir("example_sky");
    let out = dir.join("sky.hdr");
    run("sky", &[out.to_str().unwrap()]);
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/environments/sky.hdr");
    assert!(std::fs::read(&out).unwrap() == std::fs::read(&shipped).unwrap(), "assets/environments/sky.hdr is stale");
    let small = dir.join("small.hdr");
    run("sky", &[small.to_str().unwrap(), "64"]);
    let map = caustics::scene::EnvironmentMap::load(&small).expect("load");
    assert_eq!((map.width, map.height), (64, 32));
    assert!(map.irradiance(glam::Vec3::Y).min_element() > 0.0);
}
