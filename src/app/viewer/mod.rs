//! `caustics view`: the windowed viewer. A winit window, an ash-window surface and a swapchain; every frame is the
//! headless renderer's frame (src/frame/), whose beauty image is copied into the acquired swapchain image just
//! before the frame's last submit (present.rs).
//!
//! Frames in flight (`--frames-in-flight`; 2 on GPUs, 1 on CPU devices): the CPU records frame N+1 while the GPU
//! works on frame N.
//! Each slot has its own command buffer, fence, timestamp queries, uniforms, readback buffer and acquire
//! semaphore; `Renderer::next_slot` waits for the frame that last used a slot before it is reused, and a frame's
//! report arrives when it completes (`take_reports`). The GPU-side targets are shared: every frame's first
//! access to them is a barrier against all earlier commands on the queue. A screenshot frame is waited for. Robustness: a resized window, an out-of-date or suboptimal
//! swapchain are recreated (the old swapchain passed as `old_swapchain`); a zero-extent (minimized) window is not
//! rendered and the loop waits for events; a device loss, or any other Vulkan failure, ends the viewer with an error
//! (exit code 1).

mod actions;
mod controls;
mod input;
mod open;
mod orbit;
mod overlay;
mod present;
mod refine;
mod resize;
mod script;
pub mod swapchain;

pub use controls::{help_markdown, help_text, Action};
pub use present::Capture;

use crate::app::commands::{first_picture_scene, load_options, MethodArgs};
use crate::app::profiler;
use ash::vk;
use caustics::consts::*;
use caustics::error::{Error, Result};
use caustics::gpu::{ContextDesc, Device, Instance, SubmitSync, VkError};
use caustics::image_io;
use caustics::overlay::OverlayPainter;
use caustics::scene::{Camera, Light, Material, Projection, Scene};
use caustics::settings::OnOff;
use caustics::settings::{parse_size, Method, Metric, Quality, Settings};
use caustics::{FrameDesc, FrameOutput, FrameReport, Renderer, SlotVerdict};
use glam::{Quat, Vec3};
use input::Input;
use orbit::Orbit;
use present::Presenter;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use resize::ResizeCycle;
use script::{Script, Verb};
use serde_json::{json, Value};
use std::collections::VecDeque;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};
use swapchain::{Acquired, LiveCounts, Presented, Surface, Swapchain, SwapchainDesc};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::window::{Window, WindowId};

/// Frames kept for the live profiler (P, T and the stats).
pub const PROFILE_FRAMES: usize = 120;
/// Light animation: one turn around the vertical axis in this many seconds...
const ANIMATION_PERIOD_S: f32 = 20.0;
/// ...counting at most this much per frame, so that slow frames (lavapipe) turn it in small steps and a pause
/// (a minimized window) does not make it jump.
const ANIMATION_MAX_STEP_S: f32 = 0.25;
/// GPU time per frame the interactive level aims at while the light or the glass moves (progressive
/// refinement), by default: about 80 fps on a GPU, at least 5 fps on a CPU device (`--interactive-ms`).
const INTERACTIVE_MS_GPU: f64 = 12.0;
const INTERACTIVE_MS_CPU: f64 = 150.0;

/// A light straight above its target is tilted by this much when animated, so that its orbit moves it.
const ANIMATION_TILT_DEG: f32 = 25.0;

#[derive(clap::Args, Debug, Clone)]
pub struct ViewArgs {
    /// Scene file: TOML (.toml) or glTF 2.0 (.gltf, .glb). Default: assets/scenes/swimming_pool.toml.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// An equirectangular environment map (.hdr or .exr) in place of the scene's (as `render --environment`).
    #[arg(long)]
    pub environment: Option<PathBuf>,
    /// Camera name (default: the scene's first perspective camera, else its first camera).
    #[arg(long)]
    pub camera: Option<String>,
    /// Window size WxH in pixels.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Scene time in seconds to start at (as `render --time`).
    #[arg(long, default_value_t = 0.0)]
    pub time: f32,
    /// The time to start at as the authoring tool's frame N: N / --frame-rate seconds (as `render --frame`).
    #[arg(long, conflicts_with = "time", allow_negative_numbers = true)]
    pub frame: Option<f32>,
    /// The frame rate --frame counts in, frames per second (glTF does not record it).
    #[arg(long, default_value_t = 24.0)]
    pub frame_rate: f32,
    /// glTF: the animation that plays, by name or index [default: all of them, together]; N switches.
    #[arg(long)]
    pub animation: Option<String>,
    #[command(flatten)]
    pub method: MethodArgs,
    /// Present without waiting for vertical blank: MAILBOX, else IMMEDIATE where available (default: FIFO).
    #[arg(long)]
    pub no_vsync: bool,
    /// Slowly orbit the light around the vertical axis through its target (Space pauses).
    #[arg(long)]
    pub animate: bool,
    /// Orbit the camera by this many degrees every frame (scripted input: repeatable frame-time measurements of
    /// a camera orbit, with --frames and --stats; --animate does the same for the light).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub orbit_camera: f32,
    /// Render every frame at the chosen level (by default, while the light or the glass changes the viewer renders
    /// at an interactive level, then refines one level per frame up to the chosen one).
    #[arg(long)]
    pub no_progressive: bool,
    /// GPU milliseconds per frame that the interactive level aims at while the light or the glass moves (default:
    /// 12 on GPUs, 150 on CPU devices such as lavapipe).
    #[arg(long)]
    pub interactive_ms: Option<f64>,
    /// Resolution of the preview frames drawn while the view moves, as a divisor per side: 1 (full), 2, 3 or 4,
    /// or 0 for automatic (full resolution while the eye view of a preview costs under 30 ms of GPU time,
    /// coarser when it costs more). Still frames are always drawn at full resolution.
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u32).range(0..=4))]
    pub preview_scale: u32,
    /// Frames in flight: the CPU records frame N+1 while the GPU still works on frame N (1 to 3; default: 2 on
    /// GPUs, 1 on CPU devices, where the driver's threads already use every core and a second frame in flight
    /// only adds a frame of latency).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=3))]
    pub frames_in_flight: Option<u32>,
    /// While the view and the scene hold still, each frame adds a fresh photon set to the caustic maps' average,
    /// up to this many (1: off); any change starts a new average (default: 64 on GPUs, 8 on CPU devices).
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub accumulate: Option<u32>,
    /// Scripted input: one step per line, `FRAMES VERB [ARGS]` with the verbs `orbit DEG`, `drag DX DY`,
    /// `key NAME` and `still`; the viewer quits after the last step, and --stats gains each step's frame rate and
    /// time to converge (docs/viewer.md).
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Present this many frames, then exit (0: run until the window is closed).
    #[arg(long, default_value_t = 0)]
    pub frames: u32,
    /// Save the last presented frame here (PNG) at exit.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Write stats JSON here at exit (frames, swapchain recreations, resizes, per-stage GPU ms, ...).
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Testing: resize the window programmatically K times while running (sizes include 1x1; the last is the
    /// initial size), with one simulated minimize halfway; --frames is extended until the cycle is done.
    #[arg(long, hide = true, default_value_t = 0)]
    pub resize_cycle: u32,
    /// Testing: prefer an sRGB swapchain format (exercises the intermediate-image path).
    #[arg(long, hide = true)]
    pub srgb_surface: bool,
    /// Testing: the scene's animation advances this many seconds per frame, not the frame's wall time
    /// (deterministic playback).
    #[arg(long, hide = true)]
    pub frame_dt: Option<f32>,
    /// Testing: fail with a device loss when frame N is about to be rendered (checks the error path and exit).
    #[arg(long, hide = true)]
    pub inject_device_loss: Option<u32>,
    /// Print the controls (keys and mouse) as a Markdown table and exit.
    #[arg(long)]
    pub print_controls: bool,
    /// The overlay over the frame: GPU ms per stage, the frame's photons and energy account, and buttons for the
    /// keys (F1 toggles it).
    #[arg(long, value_enum, default_value_t = OnOff::On)]
    pub overlay: OnOff,
}

/// Each object's transform as the scene placed it (a glTF node's world transform; the identity for a TOML
/// scene's still objects): what `R` puts a dragged object back to.
fn initial_placements(renderer: &Renderer) -> Vec<glam::Mat4> {
    (0..renderer.scene().objects.len())
        .map(|i| renderer.transform(caustics::InstanceId::from_index(i)).unwrap_or(glam::Mat4::IDENTITY))
        .collect()
}

fn pick_camera(scene: &Scene, name: Option<&str>) -> Result<Camera> {
    if name.is_none() {
        if let Some(c) = scene.cameras.iter().find(|c| matches!(c.projection, Projection::Perspective { .. })) {
            return Ok(c.clone());
        }
    }
    Ok(scene.camera(name).map_err(|e| crate::app::flags::camera_error(name, e))?.clone())
}

pub fn run(args: &ViewArgs) -> Result<()> {
    if args.print_controls {
        print!("{}", help_markdown());
        return Ok(());
    }
    let (width, height) = parse_size(&args.size, "--size")?;
    let settings = args.method.settings()?;
    if let Some(p) = &args.screenshot {
        if !p.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png")) {
            return Err(Error::BadInput(format!("--screenshot {}: screenshots are written as .png", p.display())));
        }
        image_io::check_output_dir(p)?;
    }
    if let Some(p) = &args.stats {
        image_io::check_output_dir(p)?;
    }
    if let Some(ms) = args.interactive_ms {
        if !(ms.is_finite() && ms > 0.0) {
            return Err(Error::BadInput(format!("--interactive-ms {ms}: expected a positive number of milliseconds")));
        }
    }
    let script = args.script.as_deref().map(Script::load).transpose()?;
    let scene_path = args.scene.clone().unwrap_or_else(first_picture_scene);
    let mut scene = Scene::load_with(&scene_path, &load_options(args.animation.as_deref()))?;
    crate::app::commands::apply_environment(&mut scene, args.environment.as_deref())?;
    let time = crate::app::commands::seconds(args.time, args.frame, args.frame_rate)?;
    if let Some(dt) = args.frame_dt.filter(|dt| !(dt.is_finite() && *dt >= 0.0)) {
        return Err(Error::BadInput(format!("--frame-dt {dt}: must be finite and >= 0")));
    }
    scene.set_time(time);
    let camera = pick_camera(&scene, args.camera.as_deref())?;
    let event_loop = EventLoop::new().map_err(|e| {
        Error::Failed(format!(
            "cannot open a window: {e}. `caustics view` needs a display (DISPLAY or WAYLAND_DISPLAY); \
             without one, run it under `xvfb-run -a`, or use `caustics render`"
        ))
    })?;
    let mut app = App {
        args,
        size: (width, height),
        pending: Some((scene, camera, settings, script)),
        viewer: None,
        outcome: None,
        error: None,
    };
    stop_on_signals();
    let run = event_loop.run_app(&mut app);
    app.finish(run)
}

/// Set by SIGINT or SIGTERM: the viewer leaves its loop as if the window were closed, so that `--screenshot`
/// and `--stats` are still written.
static STOP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

#[cfg(unix)]
fn stop_on_signals() {
    extern "C" fn on_signal(_: i32) {
        STOP.store(true, std::sync::atomic::Ordering::SeqCst);
    }
    extern "C" {
        fn signal(signum: i32, handler: extern "C" fn(i32)) -> usize;
    }
    const SIGINT: i32 = 2;
    const SIGTERM: i32 = 15;
    // SAFETY: the handler only stores to an atomic, which is async-signal-safe.
    unsafe {
        signal(SIGINT, on_signal);
        signal(SIGTERM, on_signal);
    }
}

#[cfg(not(unix))]
fn stop_on_signals() {}

fn stop_requested() -> bool {
    STOP.load(std::sync::atomic::Ordering::SeqCst)
}

/// What the viewer measured, taken before teardown, plus what teardown left alive.
struct Outcome {
    stats: Value,
    capture: Option<Capture>,
    presented: u64,
    after_teardown: LiveCounts,
    validation: bool,
}

struct App<'a> {
    args: &'a ViewArgs,
    size: (u32, u32),
    pending: Option<(Scene, Camera, Settings, Option<Script>)>,
    viewer: Option<Viewer>,
    outcome: Option<Outcome>,
    error: Option<Error>,
}

impl App<'_> {
    fn fail(&mut self, el: &ActiveEventLoop, e: Error) {
        if self.error.is_none() {
            self.error = Some(e);
        }
        el.exit();
    }

    /// Tear down while the event loop still exists: every GPU object, then the surface, then the window.
    fn teardown(&mut self) {
        if let Some(mut v) = self.viewer.take() {
            if let Err(e) = v.finish_frames() {
                if self.error.is_none() {
                    self.error = Some(e);
                }
            }
            let stats = v.stats();
            let capture = v.capture.clone();
            let presented = v.counters.presented;
            let validation = v.validation;
            drop(v);
            self.outcome =
                Some(Outcome { stats, capture, presented, after_teardown: swapchain::live_counts(), validation });
        }
    }

    fn finish(mut self, run: Result<(), winit::error::EventLoopError>) -> Result<()> {
        self.teardown();
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        run.map_err(|e| Error::Failed(format!("window event loop: {e}")))?;
        let out = self.outcome.take().ok_or_else(|| Error::Failed("the viewer window was never created".into()))?;
        if let Some(p) = &self.args.screenshot {
            let c =
                out.capture.as_ref().ok_or_else(|| Error::Failed("no frame was presented: no screenshot".into()))?;
            image_io::write_png(p, c.width, c.height, &c.rgba)?;
            eprintln!("wrote {} ({}x{}, the last presented frame: #{})", p.display(), c.width, c.height, out.presented);
        }
        let messages = caustics::gpu::validation_message_count();
        if let Some(p) = &self.args.stats {
            let mut stats = out.stats;
            stats["validation"] = json!({"enabled": out.validation, "messages": messages});
            stats["swapchain"]["live_after_teardown"] = json!(out.after_teardown);
            stats["screenshot"] = match (&self.args.screenshot, &out.capture) {
                (Some(path), Some(c)) => {
                    json!({"path": path.display().to_string(), "size": [c.width, c.height], "source": c.source})
                }
                _ => Value::Null,
            };
            image_io::write_text(p, &serde_json::to_string_pretty(&stats).unwrap_or_default())?;
        }
        if out.validation && messages > 0 {
            return Err(Error::Failed(format!("{messages} Vulkan validation messages (see above)")));
        }
        Ok(())
    }
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        let Some((scene, camera, settings, script)) = self.pending.take() else {
            return;
        };
        match Viewer::new(el, self.args, scene, camera, settings, script, self.size) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(el, e),
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(v) = self.viewer.as_mut() else {
            return;
        };
        let result = v.window_event(event);
        let quit = v.quit;
        match result {
            Err(e) => self.fail(el, e),
            Ok(()) if quit => el.exit(),
            Ok(()) => {}
        }
    }

    fn about_to_wait(&mut self, el: &ActiveEventLoop) {
        let Some(v) = self.viewer.as_mut() else {
            return;
        };
        if v.quit || stop_requested() {
            if stop_requested() {
                eprintln!("signal received: closing the viewer");
            }
            el.exit();
        } else if v.minimized() {
            // Nothing to draw into: wait for events, looking again now and then (X11 reports no event when an
            // iconified window is restored by some window managers).
            v.counters.minimized_frames_skipped += 1;
            v.resize_tick();
            el.set_control_flow(ControlFlow::WaitUntil(Instant::now() + Duration::from_millis(50)));
        } else {
            v.window.request_redraw();
            el.set_control_flow(ControlFlow::Wait);
        }
    }

    fn exiting(&mut self, _el: &ActiveEventLoop) {
        self.teardown();
    }
}

#[derive(Default, Debug, Clone, serde::Serialize)]
struct Counters {
    presented: u64,
    /// Swapchains created after the first one.
    swapchain_recreations: u64,
    resizes_seen: u64,
    minimized_frames_skipped: u64,
    acquire_out_of_date: u64,
    present_out_of_date: u64,
    suboptimal: u64,
    /// Frames whose GPU-driven batching ran out of slots (the next frame records more).
    incomplete_frames: u64,
    resize_requests: u64,
    simulated_minimizes: u64,
    /// Frames (completed) that reused the caustic map, that presented the last beauty image again, and previews.
    caustics_reused_frames: u64,
    eye_reused_frames: u64,
    preview_frames: u64,
    max_images_per_swapchain: u64,
    /// Clicks that dropped into simulated water.
    water_drops: u64,
    /// Scenes opened after the first: dropped on the window, or changed on disk.
    scenes_opened: u64,
}

/// What the viewer keeps of a frame until its report arrives.
struct InFlight {
    /// The preview scale it was drawn at.
    scale: u32,
    /// Its --script step.
    step: Option<usize>,
}

struct Viewer {
    // Declaration order is drop order: every GPU object before the surface, the surface before the window.
    renderer: Renderer,
    presenter: Presenter,
    swapchain: Option<Swapchain>,
    surface: Arc<Surface>,
    window: Window,

    validation: bool,
    frames: u32,
    vsync: bool,
    prefer_srgb: bool,
    inject_device_loss: Option<u32>,
    capture_every_frame: bool,
    scene_name: String,
    camera_name: String,
    initial_light: Light,
    orbit: Orbit,
    input: Input,
    animate: bool,
    /// The scene's animation plays (A pauses it), at `scene_time` seconds.
    scene_playing: bool,
    scene_time: f32,
    /// --frame-dt: the seconds each frame advances the scene's animation (None: the frame's wall time).
    frame_dt: Option<f32>,
    /// The scene file and the options it was loaded with (N reloads it with another glTF animation).
    scene_path: PathBuf,
    environment: Option<PathBuf>,
    /// Per object: how far the user dragged it (Shift + left drag), on top of its own placement.
    offsets: Vec<Vec3>,
    /// Each still object's placement before any drag.
    placements: Vec<glam::Mat4>,
    /// The object being dragged.
    grab: Option<usize>,
    /// Progressive refinement: on unless --no-progressive.
    progressive: bool,
    /// The light or the glass changed since the last frame.
    interacting: bool,
    /// Degrees the camera orbits every frame (--orbit-camera).
    orbit_step: f32,
    /// The camera of the last frame drawn (a change draws the next frame without supersampling).
    last_camera: Option<caustics::scene::Camera>,
    /// The level rendered while interacting (adapted to keep those frames near `interactive_ms`).
    interactive_level: u32,
    /// GPU ms per frame the interactive level aims at.
    interactive_ms: f64,
    /// Preview frames are drawn at 1/preview_scale of the window's resolution per side, upscaled when presented.
    preview_scale: u32,
    /// The photon sets a still view's caustic maps average (`--accumulate`).
    accumulate: u32,
    /// --preview-scale N (N > 0): fixed; else adapted to keep a preview's eye view near `refine::PREVIEW_EYE_MS`.
    preview_scale_fixed: bool,
    /// Each frame submitted and not yet reported, oldest first (frames complete in the order they were submitted).
    in_flight: VecDeque<InFlight>,
    /// The level the last frame rendered.
    shown_level: u32,
    last_frame_start: Option<Instant>,
    /// The swapchain must be recreated before the next frame.
    dirty: bool,
    last_size: PhysicalSize<u32>,
    counters: Counters,
    ring: VecDeque<FrameReport>,
    intervals: VecDeque<f64>,
    last_present: Option<Instant>,
    /// When the first frame started (the viewer's fps is the frames presented over the wall time since then).
    first_frame_start: Option<Instant>,
    title_since: Instant,
    title_frames: u32,
    title_gpu_ms: f64,
    screenshot_request: bool,
    capture: Option<Capture>,
    /// The open scene file's modification time, and when it was last looked at (open.rs).
    scene_modified: Option<std::time::SystemTime>,
    scene_checked: Instant,
    /// The overlay (overlay.rs) and what draws it.
    overlay: overlay::Overlay,
    painter: OverlayPainter,
    resize: Option<ResizeCycle>,
    /// --script: scripted input, step by step.
    script: Option<Script>,
    simulated_minimize_until: Option<Instant>,
    quit: bool,
}

impl Viewer {
    fn new(
        el: &ActiveEventLoop,
        args: &ViewArgs,
        scene: Scene,
        camera: Camera,
        settings: Settings,
        script: Option<Script>,
        (width, height): (u32, u32),
    ) -> Result<Self> {
        let scene_name = scene.path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let scene_path = args.scene.clone().unwrap_or_else(first_picture_scene);
        let attrs = Window::default_attributes()
            .with_title(format!("caustics — {scene_name}"))
            .with_inner_size(PhysicalSize::new(width, height));
        let window = el.create_window(attrs).map_err(|e| Error::Failed(format!("cannot create a window: {e}")))?;
        let handle_err = |e: raw_window_handle::HandleError| Error::Failed(format!("window handle: {e}"));
        let display = window.display_handle().map_err(handle_err)?.as_raw();
        let window_handle = window.window_handle().map_err(handle_err)?.as_raw();
        let mut desc = ContextDesc::from_env();
        desc.instance_extensions = swapchain::required_instance_extensions(display)?;
        desc.swapchain = true;
        let instance = Instance::new(&desc)?;
        // SAFETY: the surface is dropped before the window (Viewer's field order).
        let surface = unsafe { Surface::new(&instance, display, window_handle)? };
        let present_filter = |physical: vk::PhysicalDevice, family: u32| surface.supports(physical, family);
        let device = Device::new(instance, &desc, Some(&present_filter))?;
        let initial_light = scene
            .lights
            .first()
            .cloned()
            .ok_or_else(|| Error::BadInput(format!("{}: the scene has no [[light]]", scene.path.display())))?;
        let (scene_playing, scene_time) = (scene.is_animated(), scene.time);
        let mut renderer = Renderer::new(device.clone(), scene, settings)?;
        let placements = initial_placements(&renderer);
        let cpu_device = device.info.is_cpu();
        renderer.set_frames_in_flight(args.frames_in_flight.unwrap_or(if cpu_device { 1 } else { 2 }) as usize)?;
        let presenter = Presenter::new(&device);
        let painter = OverlayPainter::new(&device, caustics::MAX_FRAMES_IN_FLIGHT)?;
        let overlay = overlay::Overlay::new(&window, args.overlay == OnOff::On, 4096);
        eprintln!(
            "caustics view: {} on {} ({}){}",
            scene_name,
            device.info.name,
            if desc.validation { "validation on" } else { "validation off" },
            if args.frames == 0 { "; press H for the controls" } else { "" }
        );
        let mut viewer = Viewer {
            renderer,
            presenter,
            swapchain: None,
            surface,
            last_size: window.inner_size(),
            window,
            validation: desc.validation,
            frames: args.frames,
            vsync: !args.no_vsync,
            prefer_srgb: args.srgb_surface,
            inject_device_loss: args.inject_device_loss,
            // Every frame, so that a viewer stopped by a signal (or a closed window) still has its last frame.
            capture_every_frame: args.screenshot.is_some(),
            scene_name,
            camera_name: camera.name.clone(),
            initial_light,
            orbit: Orbit::new(&camera),
            input: Input::default(),
            animate: false,
            scene_playing,
            scene_time,
            frame_dt: args.frame_dt,
            scene_modified: open::modified(&scene_path),
            scene_checked: Instant::now(),
            scene_path,
            environment: args.environment.clone(),
            offsets: vec![Vec3::ZERO; placements.len()],
            placements,
            grab: None,
            progressive: !args.no_progressive,
            interacting: false,
            orbit_step: args.orbit_camera,
            last_camera: None,
            interactive_level: 2,
            interactive_ms: args.interactive_ms.unwrap_or(if device.info.is_cpu() {
                INTERACTIVE_MS_CPU
            } else {
                INTERACTIVE_MS_GPU
            }),
            preview_scale: args.preview_scale.max(1),
            accumulate: args.accumulate.unwrap_or(if device.info.is_cpu() { 8 } else { 64 }),
            preview_scale_fixed: args.preview_scale > 0,
            in_flight: VecDeque::new(),
            shown_level: 0,
            last_frame_start: None,
            dirty: false,
            counters: Counters::default(),
            ring: VecDeque::with_capacity(PROFILE_FRAMES),
            intervals: VecDeque::with_capacity(PROFILE_FRAMES),
            last_present: None,
            first_frame_start: None,
            title_since: Instant::now(),
            title_frames: 0,
            title_gpu_ms: 0.0,
            screenshot_request: false,
            capture: None,
            overlay,
            painter,
            resize: (args.resize_cycle > 0).then(|| ResizeCycle::new(args.resize_cycle, (width, height))),
            script,
            simulated_minimize_until: None,
            quit: false,
        };
        if args.animate {
            viewer.toggle_animation();
        }
        if let (Some(s), Some(path)) = (&viewer.script, &args.script) {
            eprintln!("script {}: {} steps, {} frames", path.display(), s.steps.len(), s.frames_left());
        }
        Ok(viewer)
    }

    fn device(&self) -> &Arc<Device> {
        self.renderer.device()
    }

    /// Zero extent, minimized, or (testing) a simulated minimize.
    fn minimized(&mut self) -> bool {
        if let Some(until) = self.simulated_minimize_until {
            if Instant::now() < until {
                return true;
            }
            // A real restore reports a resize; the simulated one asks for the same recreation.
            self.simulated_minimize_until = None;
            self.dirty = true;
        }
        let size = self.window.inner_size();
        size.width == 0 || size.height == 0 || self.window.is_minimized() == Some(true)
    }

    /// Render and present one frame.
    fn redraw(&mut self) -> Result<()> {
        if self.quit || self.minimized() {
            return Ok(());
        }
        if self.inject_device_loss.is_some_and(|n| self.counters.presented >= n as u64) {
            return Err(VkError::DeviceLost("vkQueueSubmit2 (injected by --inject-device-loss)").into());
        }
        if !self.ensure_swapchain()? {
            self.counters.minimized_frames_skipped += 1;
            return Ok(());
        }
        let start = Instant::now();
        let dt = self.last_frame_start.map(|t| (start - t).as_secs_f32().min(ANIMATION_MAX_STEP_S)).unwrap_or(0.0);
        self.last_frame_start = Some(start);
        self.first_frame_start.get_or_insert(start);
        let extent = self.swapchain.as_ref().expect("swapchain").extent;
        // Everything that may fail for reasons other than a broken device happens before the acquire: once an image
        // is acquired, its semaphore must be waited on by a submit.
        self.script_input()?;
        let drawn = self.build_overlay()?;
        self.apply_input(dt, extent);
        let capture = self.screenshot_request
            || self.capture_every_frame
            || (self.frames > 0 && self.counters.presented + 1 >= self.frames as u64);
        let overlay_on = !drawn.meshes.is_empty();
        let Viewer { renderer, presenter, swapchain, orbit, counters, painter, .. } = self;
        let sc = swapchain.as_ref().expect("swapchain");
        counters.max_images_per_swapchain = counters.max_images_per_swapchain.max(sc.images.len() as u64);
        // The frame-in-flight slot this frame takes: this waits for the frame that last used it, so that its
        // acquire semaphore, uniforms and readback buffer are free again.
        let slot = renderer.next_slot()?;
        presenter.prepare(sc, capture, overlay_on)?;
        let index = match sc.acquire(slot)? {
            Acquired::OutOfDate => {
                counters.acquire_out_of_date += 1;
                self.dirty = true;
                return self.take_reports();
            }
            Acquired::Image { index, suboptimal } => {
                if suboptimal {
                    counters.suboptimal += 1;
                    self.dirty = true;
                }
                index
            }
        };
        if let Some((w, h)) = self.resize.as_mut().and_then(|r| r.mid_frame.take()) {
            counters.resize_requests += 1;
            // The answer (Some only where resizes apply at once) is handled by the Resized event or the present.
            let _ = self.window.request_inner_size(PhysicalSize::new(w, h));
        }
        let sync = SubmitSync {
            // The first access to the swapchain image is the copy into it (present.rs).
            wait: vec![(sc.acquire_semaphores[slot], vk::PipelineStageFlags2::ALL_TRANSFER)],
            signal: vec![sc.render_done[index as usize]],
        };
        let meshes = drawn.meshes();
        let pixels_per_point = drawn.pixels_per_point;
        let mut overlay = overlay_on.then_some(present::Overlay { painter, slot, meshes: &meshes, pixels_per_point });
        let mut recorded = Ok(());
        let mut finish = |_: &Device, cmd: vk::CommandBuffer, out: &FrameOutput| {
            recorded = presenter.record(cmd, out.beauty, (sc, index), capture, overlay.take());
        };
        // Progressive refinement and previews (refine.rs).
        let chosen = renderer.config().level;
        let interacting = std::mem::take(&mut self.interacting);
        let level =
            refine::frame_level(self.progressive, interacting, chosen, self.interactive_level, self.shown_level);
        let camera = orbit.camera();
        let moved = self
            .last_camera
            .as_ref()
            .is_some_and(|c| c.position != camera.position || c.target != camera.target || c.up != camera.up);
        self.last_camera = Some(camera.clone());
        let preview = refine::is_preview(self.progressive, moved, interacting, level, chosen);
        let scale = refine::draw_scale(preview, capture, self.preview_scale);
        renderer.set_accumulation(refine::photon_sets(moved || interacting, level, chosen, self.accumulate));
        let view = renderer.camera_view(&camera, (extent.width / scale).max(1), (extent.height / scale).max(1));
        renderer.submit(
            &FrameDesc { camera: &view, aov: None, level: Some(level), preview },
            Some(&mut finish),
            &sync,
        )?;
        recorded?;
        self.in_flight.push_back(InFlight { scale, step: self.script.as_ref().map(|s| s.current_step()) });
        self.shown_level = level;
        if capture {
            // The screenshot buffer is read once this frame is done.
            renderer.finish_frames()?;
        }
        let presented = match sc.present(index)? {
            Presented::Optimal => true,
            Presented::Suboptimal => {
                counters.suboptimal += 1;
                self.dirty = true;
                true
            }
            Presented::OutOfDate => {
                counters.present_out_of_date += 1;
                self.dirty = true;
                false
            }
        };
        if !presented {
            return self.take_reports();
        }
        self.presented(capture)
    }

    /// The swapchain at the window's size: created, or recreated where the last frame found it out of date. False
    /// while the window has no area (minimized).
    fn ensure_swapchain(&mut self) -> Result<bool> {
        let size = self.window.inner_size();
        let window_extent = vk::Extent2D { width: size.width, height: size.height };
        if let Some(sc) = self.swapchain.as_mut() {
            if self.dirty {
                if !sc.recreate(window_extent)? {
                    return Ok(false);
                }
                self.counters.swapchain_recreations += 1;
                self.dirty = false;
            }
        } else {
            let desc = SwapchainDesc { extent: window_extent, vsync: self.vsync, prefer_srgb: self.prefer_srgb };
            let Some(sc) = Swapchain::new(self.device(), &self.surface, desc)? else {
                return Ok(false);
            };
            let (format, mode, images, e) = (sc.format.format, sc.present_mode, sc.images.len(), sc.extent);
            eprintln!("swapchain: {format:?} {mode:?}, {images} images, {}x{}", e.width, e.height);
            self.swapchain = Some(sc);
            self.dirty = false;
        }
        Ok(true)
    }

    /// What follows a presented frame: the counters, the present interval, the screenshot (`capture`), the reports,
    /// the resize cycle, and whether the viewer quits (its frame count, or its script, done).
    fn presented(&mut self, capture: bool) -> Result<()> {
        self.counters.presented += 1;
        if let Some(s) = self.script.as_mut() {
            s.presented();
        }
        let now = Instant::now();
        if let Some(t) = self.last_present.replace(now) {
            push_bounded(&mut self.intervals, (now - t).as_secs_f64() * 1e3);
        }
        if capture {
            self.save_capture()?;
        }
        self.take_reports()?;
        self.resize_tick();
        let cycle_done = self.resize.as_ref().is_none_or(|r| r.finished());
        if self.frames > 0 && self.counters.presented >= self.frames as u64 && cycle_done {
            self.quit = true;
        }
        if self.script.as_ref().is_some_and(|s| s.finished()) {
            self.quit = true;
        }
        Ok(())
    }

    /// Read the screenshot the frame recorded (it is done), and save it where S asked for one.
    fn save_capture(&mut self) -> Result<()> {
        self.capture = self.presenter.read_capture()?;
        if std::mem::take(&mut self.screenshot_request) {
            if let Some(c) = &self.capture {
                let path = free_name("caustics-screenshot", "png");
                image_io::write_png(&path, c.width, c.height, &c.rgba)?;
                eprintln!("wrote {} ({}x{})", path.display(), c.width, c.height);
            }
        }
        Ok(())
    }

    /// Build this frame's overlay (nothing while it is hidden), and act on its buttons' clicks.
    fn build_overlay(&mut self) -> Result<overlay::Drawn> {
        let fps = match self.intervals.iter().rev().take(30).sum::<f64>() {
            ms if ms > 0.0 => self.intervals.len().min(30) as f64 * 1e3 / ms,
            _ => 0.0,
        };
        let shown = overlay::Shown {
            scene: &self.scene_name,
            settings: self.describe(),
            last: self.ring.back(),
            playing: self.renderer.scene().is_animated().then_some(self.scene_playing),
            fps,
            light: self.renderer.scene().lights[0].position,
            target_error: crate::app::commands::flux_error(self.renderer.config())
                .then_some(self.renderer.config().target_error),
        };
        let (drawn, clicked) = self.overlay.build(&self.window, &shown, &mut self.painter);
        for action in clicked.actions {
            self.act(action)?;
        }
        if let Some(position) = clicked.light {
            let light = Light { position, ..self.renderer.scene().lights[0].clone() };
            self.set_light(light);
        }
        Ok(drawn)
    }

    /// Wait for every frame in flight and take in their reports (before reading the stats at exit).
    fn finish_frames(&mut self) -> Result<()> {
        self.renderer.finish_frames()?;
        self.take_reports()
    }

    /// Take in the reports of the frames that completed (a frame's report arrives when a later frame needs its
    /// slot): the title, the profiler's ring, the batch slots and the interactive level follow them.
    fn take_reports(&mut self) -> Result<()> {
        for report in self.renderer.take_completed() {
            let chosen = self.renderer.config().level;
            let frame = self.in_flight.pop_front().unwrap_or(InFlight { scale: 1, step: None });
            if let (Some(s), Some(step)) = (self.script.as_mut(), frame.step) {
                s.completed(step, report.level, chosen, report.preview);
            }
            self.counters.caustics_reused_frames += report.reused as u64;
            self.counters.eye_reused_frames += report.eye_reused as u64;
            self.counters.preview_frames += report.preview as u64;
            let drawn_at = frame.scale;
            if report.preview && !report.eye_reused && !self.preview_scale_fixed && drawn_at == self.preview_scale {
                let stage = |name: &str| report.stages.iter().find(|(l, _)| *l == name).map_or(0.0, |(_, ms)| *ms);
                self.preview_scale = refine::adapt_preview_scale(self.preview_scale, stage("eye") + stage("composite"));
            }
            let interactive = self.interactive_level.min(chosen);
            if self.progressive && report.preview && !report.reused && report.level == interactive {
                let next = refine::adapt_interactive_level(interactive, chosen, report.gpu_ms, self.interactive_ms);
                if next != interactive {
                    self.interactive_level = next;
                }
            }
            // The shared slot policy; an incomplete frame is still presented (its image can be presented once).
            if self.renderer.adapt_batch_slots(&report) != SlotVerdict::Complete {
                self.counters.incomplete_frames += 1;
            }
            self.update_title(&report, drawn_at);
            self.overlay.add_frame(&report);
            push_bounded(&mut self.ring, report);
        }
        Ok(())
    }

    /// `scale`: the preview scale the report's frame was drawn at.
    fn update_title(&mut self, report: &FrameReport, scale: u32) {
        self.title_frames += 1;
        self.title_gpu_ms += report.gpu_ms;
        let elapsed = self.title_since.elapsed().as_secs_f64();
        if elapsed < 0.5 {
            return;
        }
        let fps = self.title_frames as f64 / elapsed;
        let gpu = self.title_gpu_ms / self.title_frames as f64;
        let refining = if report.level < self.renderer.config().level {
            format!(" — refining: level {}", report.level)
        } else {
            String::new()
        };
        let preview = if report.preview && scale > 1 { format!(" — preview 1/{scale}") } else { String::new() };
        let converging = match report.photon_sets {
            n if n > 1 && n < self.accumulate => format!(" — converging: {n}/{} photon sets", self.accumulate),
            _ => String::new(),
        };
        self.window.set_title(&format!(
            "caustics — {} — {}{refining}{preview}{converging} — {fps:.1} fps — GPU {gpu:.1} ms",
            self.scene_name,
            self.describe()
        ));
        self.title_since = Instant::now();
        self.title_frames = 0;
        self.title_gpu_ms = 0.0;
    }

    /// The stats JSON (before teardown).
    fn stats(&self) -> Value {
        let frames: Vec<FrameReport> = self.ring.iter().cloned().collect();
        let mut updates = caustics::SceneUpdateReport::default();
        frames.iter().for_each(|f| updates.add(&f.scene));
        let summaries = profiler::stage_summaries(&frames);
        let stage = |name: &str| summaries.iter().find(|(l, _)| l == name).map(|(_, v)| *v).unwrap_or_default();
        let intervals: Vec<f64> = self.intervals.iter().copied().collect();
        let interval = profiler::Summary::of(&intervals);
        let wall_s = match (self.first_frame_start, self.last_present) {
            (Some(a), Some(b)) => (b - a).as_secs_f64(),
            _ => 0.0,
        };
        let info = &self.device().info;
        let s = &self.renderer.config();
        let last = frames.last();
        let st = last.and_then(|r| r.state);
        let light = &self.renderer.scene().lights[0];
        json!({
            "device": {"name": info.name, "driver": info.driver, "kind": caustics::gpu::kind_name(info.kind)},
            "scene": self.scene_path.display().to_string(),
            "camera": self.camera_name,
            "camera_position": self.orbit.camera().position.to_array(),
            "light": {"position": light.position.to_array(), "target": light.target.to_array()},
            "ior": self.ior(),
            "overlay": {
                "visible": self.overlay.visible,
                "build_ms": self.overlay.build_ms,
                "triangles": self.overlay.triangles,
                "textures": self.painter.texture_count(),
                "panel": self.overlay.panel.map(|r| [r.min.x, r.min.y, r.max.x, r.max.y]),
                "buttons": self.overlay.buttons.iter().map(|(name, r)| (name.clone(), json!([r.min.x, r.min.y, r.max.x, r.max.y]))).collect::<serde_json::Map<_, _>>(),
            },
            "method": s.method,
            "metric": if s.method == Method::Adaptive { json!(s.metric) } else { Value::Null },
            "target_error": crate::app::commands::flux_error(s).then_some(s.target_error),
            "tau": crate::app::commands::flux_error(s).then(|| s.tau()),
            "level": s.level,
            "equivalent_resolution": LEVEL0_RES << s.level,
            "settings": s,
            "frames_presented": self.counters.presented,
            "frames_in_flight": self.renderer.frames_in_flight(),
            "preview_scale": self.preview_scale,
            "interactive_level": self.interactive_level,
            "interactive_ms": self.interactive_ms,
            "counters": self.counters,
            "swapchain_recreations": self.counters.swapchain_recreations,
            "resizes_seen": self.counters.resizes_seen,
            "minimized_frames_skipped": self.counters.minimized_frames_skipped,
            "swapchain": {
                "format": self.swapchain.as_ref().map(|s| format!("{:?}", s.format.format)),
                "present_mode": self.swapchain.as_ref().map(|s| format!("{:?}", s.present_mode)),
                "extent": self.swapchain.as_ref().map(|s| [s.extent.width, s.extent.height]),
                "image_count": self.swapchain.as_ref().map(|s| s.images.len()),
                "transfer_src": self.swapchain.as_ref().map(|s| s.usage.contains(vk::ImageUsageFlags::TRANSFER_SRC)),
                "live_at_exit": swapchain::live_counts(),
                "max_images_per_swapchain": self.counters.max_images_per_swapchain,
            },
            "photons_splatted": st.map(|x| x.photons_total).unwrap_or(0),
            "host_readbacks_per_frame": last.map(|r| r.host_readbacks).unwrap_or(0),
            // The scene's animation: where it stands, whether it plays, and what the frames moved and displaced.
            "scene_time_s": self.scene_time,
            "scene_playing": self.scene_playing,
            // A glTF file's animations: the one that plays (null: all of them).
            "scene_animation": self.renderer.scene().playing.map(|i| self.renderer.scene().animations[i].clone()),
            "scene_update": {
                "moved_objects": updates.moved_objects,
                "deformed_objects": updates.deformed_objects,
                "blas_builds": updates.blas_builds,
                "wait_idles": updates.wait_idles,
            },
            "photon_buffer_bytes": st.map(|x| 8 * x.peak_used as u64).unwrap_or(0),
            "profiled_frames": frames.len(),
            "gpu_ms": profiler::gpu_json(&summaries),
            "gpu_substages_ms": profiler::summaries_json(&profiler::substage_summaries(&frames)),
            "wall_ms": profiler::summary_json(&summaries, "frame_wall"),
            "gpu_total_ms": stage("gpu_total"),
            "frame_ms": stage("frame_wall"),
            "present_interval_ms": interval,
            "wall_s": wall_s,
            // Frames over wall time: every frame presented, divided by the time from the first frame's start to
            // the last present (a median interval would hide slow frames among reused ones).
            "fps": if wall_s > 0.0 { self.counters.presented as f64 / wall_s } else { 0.0 },
            "script": self.script.as_ref().map(|s| s.stats()),
        })
    }
}

fn push_bounded<T>(q: &mut VecDeque<T>, v: T) {
    if q.len() == PROFILE_FRAMES {
        q.pop_front();
    }
    q.push_back(v);
}

/// `prefix-001.ext`, `prefix-002.ext`, ...: the first name not taken in the current directory.
fn free_name(prefix: &str, ext: &str) -> PathBuf {
    (1..).map(|i| PathBuf::from(format!("{prefix}-{i:03}.{ext}"))).find(|p| !p.exists()).expect("a free file name")
}
