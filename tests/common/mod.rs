//! Shared helpers for the integration tests: run the `caustics` binary with validation on (synchronization
//! validation included) and read what it wrote.
#![allow(dead_code)]

pub mod gltf_doc;
pub mod rig;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

pub const SPHERE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/sphere.toml");
pub const BUNNY: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/bunny.toml");

pub fn scene(name: &str) -> String {
    format!("{}/assets/scenes/{name}", env!("CARGO_MANIFEST_DIR"))
}

/// A scene under a directional beam of 1 W/m² straight down, over a 2 × 2 m diffuse floor (albedo 0.8) that the
/// `top` orthographic camera covers exactly (columns along +x, rows along +z), with `objects` (TOML) added.
pub fn under_a_beam(objects: &str) -> String {
    format!(
        r#"[[light]]
kind = "directional"
position = [0.0, 2.0, 0.0]
target = [0.0, 0.5, 0.0]
intensity = 1.0

[[camera]]
name = "top"
kind = "orthographic"
position = [0.0, 3.0, 0.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 0.0, -1.0]
half_height = 1.0

[[object]]
name = "floor"
shape = "plane"
size = [2.0, 2.0]
material = {{ kind = "diffuse", albedo = 0.8 }}

{objects}"#
    )
}

/// A fresh directory for one test's outputs.
pub fn out_dir(test: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(test);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create test dir");
    dir
}

/// Run `caustics` with the Khronos validation layer and synchronization validation enabled. A test runs the
/// default configuration (exact transport, adaptive flux-error, the device's level) unless it names another: the
/// tests of the papers' two-interface model name `--transport two-interface`.
pub fn caustics(args: &[&str]) -> Output {
    caustics_env(args, &[])
}

pub fn caustics_env(args: &[&str], env: &[(&str, &str)]) -> Output {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustics"));
    cmd.args(args).env("CAUSTICS_VALIDATION", "1").env("RUST_LOG", "warn");
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("run caustics")
}

/// Run and require success; returns stderr.
pub fn ok(args: &[&str]) -> String {
    let out = caustics(args);
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(out.status.success(), "caustics {args:?} failed ({:?}):\n{stderr}", out.status.code());
    stderr
}

pub fn read_json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("stats JSON")
}

/// The checks every GPU test makes on its stats: validation was on and said nothing.
pub fn assert_validation_clean(stats: &serde_json::Value) {
    assert_eq!(stats["validation"]["enabled"], true, "validation layer must be on in tests");
    assert_eq!(stats["validation"]["messages"], 0, "validation messages");
}

/// Render `scene` with extra args, returning the stats (validation checked) and the output path.
pub fn render(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> (serde_json::Value, PathBuf) {
    let out = dir.join(format!(
        "{name}.{}",
        if extra.windows(2).any(|w| w[0] == "--aov" && w[1] != "beauty") { "exr" } else { "png" }
    ));
    let stats = dir.join(format!("{name}.json"));
    let mut args = vec!["render", "--scene", scene, "--out", out.to_str().unwrap(), "--stats", stats.to_str().unwrap()];
    args.extend_from_slice(extra);
    ok(&args);
    let s = read_json(&stats);
    assert_validation_clean(&s);
    (s, out)
}

/// `render` of `scene` with extra args into `dir/NAME.exr` (validation checked): the EXR's image, the linear
/// beauty unless the args name another AOV.
pub fn render_exr(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> caustics::image_io::RgbImage {
    let out = dir.join(format!("{name}.exr"));
    let stats = dir.join(format!("{name}.json"));
    let mut args = vec!["render", "--scene", scene, "--out", out.to_str().unwrap(), "--stats", stats.to_str().unwrap()];
    args.extend_from_slice(extra);
    ok(&args);
    assert_validation_clean(&read_json(&stats));
    caustics::image_io::read_exr(&out).expect("read EXR")
}

/// The caustics AOV of the `top` camera at 256² under exact transport, with extra args: stats and image.
pub fn exact(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> (serde_json::Value, caustics::image_io::RgbImage) {
    let mut args = vec!["--transport", "exact", "--camera", "top", "--aov", "caustics", "--size", "256x256"];
    args.extend_from_slice(extra);
    let (s, out) = render(dir, name, scene, &args);
    (s, caustics::image_io::read_exr(&out).unwrap())
}

/// One term of exact transport's energy account in the stats, in W.
pub fn energy(s: &serde_json::Value, term: &str) -> f64 {
    s["exact_transport"]["energy"][format!("{term}_w")].as_f64().unwrap_or_else(|| panic!("energy term {term}"))
}

/// Channel 0 of an EXR as a row-major plane.
pub fn read_plane(path: &Path) -> (usize, usize, Vec<f64>) {
    let img = caustics::image_io::read_exr(path).expect("read EXR");
    (img.width as usize, img.height as usize, img.data.iter().map(|p| p[0] as f64).collect())
}

/// No file or partial file named after `out` exists in its directory.
pub fn assert_no_output(out: &Path) {
    assert!(!out.exists(), "{} must not exist", out.display());
    let dir = out.parent().unwrap();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let n = e.file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".partial"), "partial file left behind: {n}");
    }
}

/// The CPU reference of `scene` through its `top` camera at `side`² (cached in the test target directory, so each
/// configuration is traced once per machine).
pub fn top_reference(
    scene: &str,
    aov: caustics::reference::Aov,
    paths: caustics::reference::Paths,
    photons: u64,
    side: u32,
) -> caustics::image_io::RgbImage {
    top_reference_at(scene, aov, paths, photons, side, 0.0)
}

/// [`top_reference`] with the scene's animated objects placed at `time` s.
pub fn top_reference_at(
    scene: &str,
    aov: caustics::reference::Aov,
    paths: caustics::reference::Paths,
    photons: u64,
    side: u32,
    time: f32,
) -> caustics::image_io::RgbImage {
    camera_reference(scene, "top", aov, paths, photons, side, time)
}

/// [`top_reference_at`] through the scene's orthographic camera `camera`.
pub fn camera_reference(
    scene: &str,
    camera: &str,
    aov: caustics::reference::Aov,
    paths: caustics::reference::Paths,
    photons: u64,
    side: u32,
    time: f32,
) -> caustics::image_io::RgbImage {
    let p = caustics::reference::RefParams {
        camera: Some(camera.into()),
        aov,
        paths,
        photons,
        width: side,
        height: side,
        time,
        ..caustics::reference::RefParams::default()
    };
    let cache = Path::new(env!("CARGO_TARGET_TMPDIR")).join("reference-cache");
    caustics::reference::cached_in(&cache, Path::new(scene), &p).expect("reference")
}

/// The caustics AOV of an in-process renderer from its scene's `top` camera at `side`², with the frame's report.
pub fn top_caustics(r: &mut caustics::Renderer, side: u32) -> (caustics::image_io::RgbImage, caustics::FrameReport) {
    top_aov(r, side, caustics::Aov::Caustics)
}

/// A float AOV (caustics, direct, linear beauty) of an in-process renderer from its scene's `top` camera at
/// `side`², with the frame's report.
pub fn top_aov(
    r: &mut caustics::Renderer,
    side: u32,
    aov: caustics::Aov,
) -> (caustics::image_io::RgbImage, caustics::FrameReport) {
    camera_aov(r, "top", (side, side), aov)
}

/// A frame of an in-process renderer from its scene's camera `camera` at `width`×`height`, reading back `aov`;
/// validation stayed silent while it rendered.
pub fn camera_frame(
    r: &mut caustics::Renderer,
    camera: &str,
    (width, height): (u32, u32),
    aov: caustics::Aov,
) -> caustics::Frame {
    let cam = r.scene().camera(Some(camera)).unwrap_or_else(|e| panic!("{e}")).clone();
    let view = r.camera_view(&cam, width, height);
    let frame = r.render(&caustics::FrameDesc::new(&view, Some(aov))).expect("frame");
    assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages: a frame through `{camera}`");
    frame
}

/// A float AOV (caustics, direct, linear beauty) of [`camera_frame`], with the frame's report.
pub fn camera_aov(
    r: &mut caustics::Renderer,
    camera: &str,
    size: (u32, u32),
    aov: caustics::Aov,
) -> (caustics::image_io::RgbImage, caustics::FrameReport) {
    let frame = camera_frame(r, camera, size, aov);
    match frame.image {
        Some(caustics::AovData::Float { width, height, rgba }) => {
            let data = rgba.iter().map(|p| [p[0], p[1], p[2]]).collect();
            (caustics::image_io::RgbImage { width, height, data }, frame.report)
        }
        _ => panic!("a float AOV"),
    }
}

/// The tone-mapped 8-bit beauty of [`camera_frame`], as `render` writes it to a PNG: (width, height, RGBA8 bytes).
pub fn camera_beauty(r: &mut caustics::Renderer, camera: &str, size: (u32, u32)) -> (u32, u32, Vec<u8>) {
    match camera_frame(r, camera, size, caustics::Aov::Beauty).image {
        Some(caustics::AovData::Rgba8 { width, height, rgba }) => (width, height, rgba),
        _ => panic!("an 8-bit beauty"),
    }
}

/// One in-process frame: an AOV from the scene's `top` camera with its frame report, the settings as the renderer
/// resolved them, and the figures the CLI's stats would derive from them.
pub struct Shot {
    pub img: caustics::image_io::RgbImage,
    pub report: caustics::FrameReport,
    pub config: caustics::settings::ResolvedSettings,
    /// The first light's intensity (W/sr, or W/m² for a directional light): the energy account's unit.
    pub intensity: f64,
    /// The AOV's flux in W: its texels' first channel times the orthographic camera's texel area.
    pub aov_flux: f64,
}

impl Shot {
    /// Photons splatted, every light's.
    pub fn photons(&self) -> u64 {
        self.report.photons()
    }

    /// Exact transport's state: rays, waves, the energy account.
    pub fn transport(&self) -> &caustics::TransportState {
        self.report.transport.as_ref().expect("an exact-transport frame")
    }

    /// The photon traversal's state: batches, levels, the photon buffer's peak.
    pub fn traversal(&self) -> &caustics::TraversalState {
        self.report.state.as_ref().expect("a frame with photons")
    }

    /// One term of exact transport's energy account (`caustics`, `emitted`, ...: [`caustics::ACCOUNT_TERMS`]), W.
    pub fn energy(&self, term: &str) -> f64 {
        let k = caustics::ACCOUNT_TERMS.iter().position(|t| *t == term).unwrap_or_else(|| panic!("term {term}"));
        self.transport().account()[k] * self.intensity
    }

    /// The channel of each pass, as the stats name it (`gray`, `red`, `green`, `blue`, `rgb`, `spectral`).
    pub fn passes(&self) -> Vec<&'static str> {
        self.report.lights.iter().map(|l| l.channel_name()).collect()
    }

    /// Every level's counts up to the frame's level.
    pub fn levels(&self) -> Vec<caustics::LevelCounters> {
        self.traversal().levels[..=self.config.level as usize].to_vec()
    }
}

/// Render `scene_path` at `time` s with `settings` on the shared device, and read `aov` back from its `top` camera
/// at `side`².
pub fn shot_at(
    device: &std::sync::Arc<caustics::gpu::Device>,
    scene_path: &str,
    settings: caustics::settings::Settings,
    time: f32,
    aov: caustics::Aov,
    side: u32,
) -> Shot {
    let mut r = renderer(device, scene_path, settings);
    if time != 0.0 {
        r.set_time(time).expect("set_time");
    }
    let (img, report) = top_aov(&mut r, side, aov);
    let area = r.scene().camera(Some("top")).expect("a top camera").pixel_area(side, side);
    let aov_flux = img.data.iter().map(|p| p[0] as f64).sum::<f64>() * area.expect("an orthographic top camera");
    let intensity = r.scene().lights[0].intensity as f64;
    Shot { img, report, config: r.config().clone(), intensity, aov_flux }
}

/// The caustics AOV of `scene_path` from its `top` camera at 256², in process ([`shot_at`]).
pub fn shot(
    device: &std::sync::Arc<caustics::gpu::Device>,
    scene_path: &str,
    settings: caustics::settings::Settings,
) -> Shot {
    shot_at(device, scene_path, settings, 0.0, caustics::Aov::Caustics, 256)
}

/// Settings of a `--method`, `--level` and `--metric`, the rest default.
pub fn quality(
    method: caustics::settings::Method,
    level: u32,
    metric: caustics::settings::Metric,
) -> caustics::settings::Settings {
    let quality = caustics::settings::Quality { method, level: Some(level), metric, ..Default::default() };
    caustics::settings::Settings { quality, ..Default::default() }
}

/// `settings` changed by `f`.
pub fn with(
    mut settings: caustics::settings::Settings,
    f: impl FnOnce(&mut caustics::settings::Settings),
) -> caustics::settings::Settings {
    f(&mut settings);
    settings
}

/// Dense photons at `level`.
pub fn dense(level: u32) -> caustics::settings::Settings {
    quality(caustics::settings::Method::Dense, level, caustics::settings::Metric::FluxError)
}

/// Adaptive photons at `level` under `metric`.
pub fn adaptive(level: u32, metric: caustics::settings::Metric) -> caustics::settings::Settings {
    quality(caustics::settings::Method::Adaptive, level, metric)
}

/// The shared device's lock, held for a test's use of it. A test that ends without panicking asserts, when it
/// lets go of the device, that the validation layers (synchronization validation included) said nothing.
pub struct Gpu(#[allow(dead_code)] std::sync::MutexGuard<'static, ()>);

impl Drop for Gpu {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            assert_eq!(caustics::gpu::validation_message_count(), 0, "validation messages (see the test's output)");
        }
    }
}

/// In-process GPU tests share one device per test binary (instance and device creation with validation cost about
/// 0.3 s each) and its renderers' pipelines (about 0.5 s a renderer on lavapipe): `gpu()` returns it with a lock held, because the renderers on it submit to its one queue, which
/// Vulkan requires to be used from one thread at a time. Validation (with synchronization validation) is on.
pub fn gpu() -> (Gpu, std::sync::Arc<caustics::gpu::Device>) {
    use std::sync::{Mutex, OnceLock};
    static LOCK: Mutex<()> = Mutex::new(());
    static DEVICE: OnceLock<(std::sync::Arc<caustics::gpu::Device>, caustics::Pipelines)> = OnceLock::new();
    // A test that failed while holding the lock poisons it; the device is still usable by the next test.
    let guard = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    // Validation messages (and the library's warnings) on stderr, shown with a failing test's output.
    let _ =
        env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).is_test(true).try_init();
    let (device, _) = DEVICE.get_or_init(|| {
        let desc = caustics::gpu::ContextDesc { validation: true, ..caustics::gpu::ContextDesc::from_env() };
        let device =
            caustics::gpu::Context::headless(&desc).expect("a Vulkan device (tools/setup installs lavapipe)").device;
        // Held for the binary's life: every renderer of every test shares the pipelines the first compiled.
        let pipelines = caustics::Pipelines::new(&device).expect("pipelines");
        (device, pipelines)
    });
    (Gpu(guard), device.clone())
}

/// A renderer for `scene_path` on the shared device ([`gpu`]), with `settings`.
pub fn renderer(
    device: &std::sync::Arc<caustics::gpu::Device>,
    scene_path: &str,
    settings: caustics::settings::Settings,
) -> caustics::Renderer {
    let scene = caustics::scene::Scene::load(Path::new(scene_path)).expect("scene");
    caustics::Renderer::new(device.clone(), scene, settings).expect("renderer")
}

/// The block texture of the texture tests: 64 × 64 texels in 4 × 4 blocks of 16, block (i, j) (column i from the
/// left, row j from the top) of linear albedo (0.1 + 0.8 i/3, 0.1 + 0.8 j/3, 0.5) before its 8-bit sRGB encoding:
/// no two blocks alike, and no symmetry that a flipped or transposed uv would keep.
pub fn write_block_texture(path: &Path) {
    let enc = caustics::scene::texture::linear_to_srgb;
    let mut rgba = Vec::new();
    for y in 0..64u32 {
        for x in 0..64u32 {
            let (i, j) = (x / 16, y / 16);
            let c = [0.1 + 0.8 * i as f32 / 3.0, 0.1 + 0.8 * j as f32 / 3.0, 0.5];
            rgba.extend([enc(c[0]), enc(c[1]), enc(c[2]), 255]);
        }
    }
    caustics::image_io::write_png(path, 64, 64, &rgba).expect("write the block texture");
}

/// The block texture's linear albedo at texture coordinates `uv` (repeating), and whether `uv` lies at least
/// `margin` (a fraction of a block) inside its block, where filtering sees that block's color alone.
pub fn block_albedo(uv: glam::Vec2, margin: f32) -> (glam::Vec3, bool) {
    let dec = caustics::scene::texture::srgb_to_linear;
    let enc = caustics::scene::texture::linear_to_srgb;
    let f = (uv - uv.floor()) * 4.0;
    let (i, j) = (f.x.floor().min(3.0), f.y.floor().min(3.0));
    let inside = [f.x - i, f.y - j].iter().all(|t| *t >= margin && *t <= 1.0 - margin);
    // As the GPU holds it: decoded, to the nearest of 16 bits' steps.
    let c = [0.1 + 0.8 * i / 3.0, 0.1 + 0.8 * j / 3.0, 0.5].map(|v| (dec(enc(v)) * 65535.0 + 0.5).floor() / 65535.0);
    (glam::Vec3::from(c), inside)
}
