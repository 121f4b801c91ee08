//! The windowed viewer (`caustics view`) in a real X11 window under Xvfb, with the validation layers and
//! synchronization validation on: frames presented, the last presented image saved, programmatic resizes (1x1
//! included) without leaks, a device loss ending the viewer cleanly, and the errors without a display.
//!
//! Each test starts its own Xvfb (`-displayfd` picks a free display) and kills it when it ends, even on failure.

mod common;
use common::*;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

/// Light settings for lavapipe: a 256²-photon grid (level 2), 512² light maps.
// No sky (`--sky 0`): the sphere test's shadowed annulus must see no light at all (docs/design.md "Environment").
const FAST: &[&str] = &["--level", "2", "--gbuffer-res", "512", "--caustic-res", "512", "--sky", "0"];

/// An Xvfb server on a free display, stopped on drop.
struct Xvfb {
    child: Child,
    display: String,
}

/// Xvfb servers start one at a time, and with -noreset. Without it a server regenerates whenever its last client
/// disconnects (the readiness probe, each `xdotool` poll), and a viewer connecting during the reset failed with
/// "Failed to open connection to X server" (three times in full runs).
static XVFB_START: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Whether X display `n` accepts a connection, on the abstract socket (what libxcb tries first) and on the path.
fn display_accepts(n: &str) -> bool {
    use std::os::linux::net::SocketAddrExt;
    let path = format!("/tmp/.X11-unix/X{n}");
    let abstract_ok = std::os::unix::net::SocketAddr::from_abstract_name(path.as_bytes())
        .and_then(|a| std::os::unix::net::UnixStream::connect_addr(&a))
        .is_ok();
    abstract_ok && std::os::unix::net::UnixStream::connect(&path).is_ok()
}

impl Xvfb {
    /// Start Xvfb and wait until it accepts connections; a server that does not is replaced, up to three times.
    fn start() -> Xvfb {
        let _one = XVFB_START.lock().unwrap_or_else(|e| e.into_inner());
        for _ in 0..3 {
            let mut x = Xvfb::spawn();
            let n = x.display.trim_start_matches(':').to_string();
            let start = Instant::now();
            while start.elapsed() < Duration::from_secs(5) {
                let alive = matches!(x.child.try_wait(), Ok(None));
                if alive && display_accepts(&n) {
                    return x;
                }
                if !alive {
                    break;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            eprintln!("Xvfb on {} did not accept connections: starting another", x.display);
        }
        panic!("no Xvfb server accepted connections after three starts");
    }

    fn spawn() -> Xvfb {
        let mut child = Command::new("Xvfb")
            .args(["-displayfd", "1", "-screen", "0", "1280x1024x24", "-nolisten", "tcp", "-noreset"])
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("cannot start Xvfb: run tools/setup (Debian package xvfb)");
        // Xvfb writes the display number once it accepts connections (or exits, closing the pipe).
        let mut line = String::new();
        let read = BufReader::new(child.stdout.take().expect("Xvfb stdout")).read_line(&mut line);
        let n = line.trim().to_string();
        if read.is_err() || n.is_empty() || n.parse::<u32>().is_err() {
            let _ = child.kill();
            let _ = child.wait();
            panic!("Xvfb did not report a display number ({read:?}, {line:?})");
        }
        Xvfb { child, display: format!(":{n}") }
    }
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        // SIGTERM first, so that the server removes its lock and socket files (SIGKILL leaves them behind).
        let _ = Command::new("kill").args(["-TERM", &self.child.id().to_string()]).status();
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(3) {
            if !matches!(self.child.try_wait(), Ok(None)) {
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A child process killed on drop (a failed assertion must not leave a viewer running).
struct Guard(Child);

impl Drop for Guard {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

struct Run {
    status: ExitStatus,
    stderr: String,
}

/// Start `caustics view` on `display` (None: no display at all) with validation on; output goes to files in
/// `dir` (no pipe can fill up), which is also its working directory.
fn spawn_view(dir: &Path, name: &str, display: Option<&str>, args: &[&str]) -> (Guard, PathBuf) {
    let out = std::fs::File::create(dir.join(format!("{name}.stdout"))).unwrap();
    let err_path = dir.join(format!("{name}.stderr"));
    let err = std::fs::File::create(&err_path).unwrap();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_caustics"));
    cmd.arg("view")
        .args(args)
        // The viewer tests name the two-interface model unless they name a transport: they check presentation,
        // input and frames in flight, and its frames cost a fraction of exact transport's on lavapipe.
        .args(if args.iter().any(|a| a.starts_with("--transport")) {
            &[][..]
        } else {
            &["--transport", "two-interface"][..]
        })
        // Nor do they draw the overlay unless they name it: they compare the presented frame with the headless one.
        .args(if args.contains(&"--overlay") { &[][..] } else { &["--overlay", "off"][..] })
        .env("CAUSTICS_VALIDATION", "1")
        .env("RUST_LOG", "warn")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .stdin(Stdio::null())
        .stdout(out)
        .stderr(err)
        .current_dir(dir);
    match display {
        Some(d) => cmd.env("DISPLAY", d),
        None => cmd.env_remove("DISPLAY"),
    };
    (Guard(cmd.spawn().expect("run caustics")), err_path)
}

/// Wait for a viewer; one still running after `limit` is killed and fails the test.
fn wait_view(mut child: Guard, err_path: &Path, args: &[&str], limit: Duration) -> Run {
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.0.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > limit {
            let stderr = std::fs::read_to_string(err_path).unwrap_or_default();
            panic!("caustics view {args:?} still running after {limit:?} (hang?):\n{stderr}");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let stderr = std::fs::read_to_string(err_path).unwrap_or_default();
    eprintln!("caustics view {args:?}: {status:?} after {:.1} s", start.elapsed().as_secs_f64());
    Run { status, stderr }
}

/// Refused X connections are the test machine's problem, not the viewer's: such a start is tried again.
const X_REFUSED: &str = "Failed to open connection to X server";

fn view(dir: &Path, name: &str, display: Option<&str>, args: &[&str], limit: Duration) -> Run {
    for attempt in 0.. {
        let (child, err_path) = spawn_view(dir, name, display, args);
        let run = wait_view(child, &err_path, args, limit);
        if display.is_none() || attempt >= 2 || !run.stderr.contains(X_REFUSED) {
            return run;
        }
        eprintln!("{name}: the X server refused the connection; starting the viewer again");
        std::thread::sleep(Duration::from_secs(1));
    }
    unreachable!()
}

fn view_ok(dir: &Path, name: &str, display: &str, args: &[&str]) -> serde_json::Value {
    let stats = dir.join(format!("{name}.json"));
    let mut all = args.to_vec();
    all.extend(["--stats", stats.to_str().unwrap()]);
    let run = view(dir, name, Some(display), &all, Duration::from_secs(300));
    assert!(run.status.success(), "caustics view {all:?} failed ({:?}):\n{}", run.status.code(), run.stderr);
    let s = read_json(&stats);
    assert_validation_clean(&s);
    s
}

fn luma(png: &Path) -> (usize, usize, Vec<f64>, Vec<u8>) {
    let (w, h, rgba) = caustics::image_io::read_png(png).expect("read PNG");
    let y = rgba.chunks_exact(4).map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0).collect();
    (w as usize, h as usize, y, rgba)
}

/// Mean of `y` over pixels whose distance from the image center, in units of the image height, lies in [lo, hi).
fn ring_mean(w: usize, h: usize, y: &[f64], lo: f64, hi: f64) -> f64 {
    let (mut sum, mut n) = (0.0, 0usize);
    for (i, v) in y.iter().enumerate() {
        let (px, py) = ((i % w) as f64 + 0.5 - w as f64 / 2.0, (i / w) as f64 + 0.5 - h as f64 / 2.0);
        let r = px.hypot(py) / h as f64;
        if r >= lo && r < hi {
            sum += v;
            n += 1;
        }
    }
    assert!(n > 0, "no pixel in [{lo}, {hi})");
    sum / n as f64
}

/// The headless renderer's beauty image for the same camera, size and settings.
/// `sets`: the photon sets it averages (`--accumulate`), as many as the viewer's still frames averaged.
fn headless(dir: &Path, size: &str, sets: &str) -> PathBuf {
    let out = dir.join("headless.png");
    let mut args = vec!["render", "--scene", SPHERE, "--camera", "top", "--size", size, "--out", out.to_str().unwrap()];
    args.extend_from_slice(&["--accumulate", sets]);
    // The same transport as the viewer's (spawn_view names two-interface).
    args.extend_from_slice(&["--transport", "two-interface"]);
    args.extend_from_slice(FAST);
    ok(&args);
    out
}

/// Max per-channel difference of two PNGs of the same size (alpha ignored).
fn max_diff(a: &[u8], b: &[u8]) -> u8 {
    assert_eq!(a.len(), b.len(), "image sizes differ");
    a.chunks_exact(4).zip(b.chunks_exact(4)).flat_map(|(p, q)| (0..3).map(move |c| p[c].abs_diff(q[c]))).max().unwrap()
}

/// 60 frames of the sphere from the `top` camera, presented in a window; the last presented image is saved.
#[test]
fn presents_sphere_frames_and_saves_the_last_one() {
    let dir = out_dir("viewer_sphere");
    let x = Xvfb::start();
    let shot = dir.join("shot.png");
    let mut args = vec!["--scene", SPHERE, "--camera", "top", "--size", "480x360", "--frames", "60"];
    args.extend(["--screenshot", shot.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "sphere", &x.display, &args);
    assert_eq!(s["frames_presented"], 60);
    // fps is its definition: the frames presented over the wall time from the first frame to the last present.
    let (fps, wall) = (s["fps"].as_f64().unwrap(), s["wall_s"].as_f64().unwrap());
    assert!(wall > 0.0 && (fps - 60.0 / wall).abs() <= 1e-9 * fps, "fps {fps}, wall {wall} s");
    let interval_sum = s["present_interval_ms"]["mean"].as_f64().unwrap() * 59.0 * 1e-3;
    assert!(interval_sum <= wall * 1.000001, "59 present intervals ({interval_sum} s) within the wall time {wall} s");
    assert_eq!(s["screenshot"]["source"], "swapchain", "the screenshot copies the presented swapchain image");
    assert_eq!(s["screenshot"]["size"], serde_json::json!([480, 360]));
    assert_eq!(s["swapchain"]["present_mode"], "FIFO");
    assert!(s["gpu_ms"]["splat"]["median"].as_f64().unwrap() > 0.0, "per-stage GPU timings");

    let (w, h, y, rgba) = luma(&shot);
    assert_eq!((w, h), (480, 360));
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let var = y.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / y.len() as f64;
    // Measured 2529 (8-bit luma²); a blank or uniform frame gives 0.
    assert!(var > 500.0, "screenshot looks blank: luma variance {var:.1}");

    // The `top` camera is orthographic over the floor's 2 m (image height), so 1 m = h/2 pixels. The sphere
    // (r = 0.3 m) covers r < 15% of the height; its shadow on the floor reaches 2·tan(asin(0.3/1.5)) = 0.41 m,
    // 20.4%. So the annulus at 15-20% is shadowed floor: no direct light, no caustic. The disk r < 2% (0.04 m)
    // looks straight down through the sphere at the floor center, also in the shadow, where half the caustic
    // flux lands within 0.019 m (docs/design.md): it is bright only because of the caustic.
    // Measured: disk 255 (saturated), annulus 9.6.
    let disk = ring_mean(w, h, &y, 0.0, 0.02);
    let annulus = ring_mean(w, h, &y, 0.15, 0.20);
    eprintln!("caustic disk {disk:.1}, shadow annulus {annulus:.1}, variance {var:.0}");
    assert!(disk > 200.0 && annulus < 40.0 && disk > 4.0 * annulus, "disk {disk:.1} vs annulus {annulus:.1}");

    // Headless and windowed share the frame: the presented bytes are the headless beauty bytes (a second sRGB
    // encoding, or a channel swap, would change them by tens of levels), the viewer's still frames having averaged
    // 8 photon sets (its default on a CPU device) as `render --accumulate 8` does. Measured: identical.
    let (_, _, _, reference) = luma(&headless(&dir, "480x360", "8"));
    let d = max_diff(&rgba, &reference);
    assert!(d <= 2, "windowed frame differs from the headless one by {d} levels");
}

/// An sRGB swapchain format takes the intermediate-image path and must present the same bytes.
#[test]
fn srgb_surface_presents_the_same_bytes() {
    let dir = out_dir("viewer_srgb");
    let x = Xvfb::start();
    let shot = dir.join("shot.png");
    let mut args = vec!["--scene", SPHERE, "--camera", "top", "--size", "320x240", "--frames", "3", "--srgb-surface"];
    args.extend(["--accumulate", "1"]);
    args.extend(["--screenshot", shot.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "srgb", &x.display, &args);
    assert!(s["swapchain"]["format"].as_str().unwrap().ends_with("_SRGB"), "{}", s["swapchain"]);
    let (_, _, _, rgba) = luma(&shot);
    let (_, _, _, reference) = luma(&headless(&dir, "320x240", "1"));
    let d = max_diff(&rgba, &reference);
    assert!(d <= 2, "sRGB-surface frame differs from the headless one by {d} levels");
}

/// 100 programmatic resizes (1x1 among them, half of them while a frame is in flight) and a simulated minimize:
/// no validation message, every retired swapchain destroyed. Measured: 100 resizes, 101 swapchains, 152 frames
/// presented in about 5 s.
#[test]
fn survives_resizes_and_minimize_without_leaks() {
    let dir = out_dir("viewer_resize");
    let x = Xvfb::start();
    let args = [
        "--scene",
        SPHERE,
        "--size",
        "480x360",
        "--frames",
        "10",
        "--resize-cycle",
        "100",
        "--level",
        "2",
        "--gbuffer-res",
        "256",
        "--caustic-res",
        "256",
        "--frames-in-flight",
        "2",
    ];
    let s = view_ok(&dir, "resize", &x.display, &args);
    let c = &s["counters"];
    eprintln!("{}", serde_json::to_string(c).unwrap());
    let n = |v: &serde_json::Value| v.as_i64().unwrap();
    assert!(n(&c["resize_requests"]) >= 95, "resize requests {}", c["resize_requests"]);
    assert!(n(&s["resizes_seen"]) >= 95, "resizes seen {}", s["resizes_seen"]);
    assert!(n(&s["swapchain_recreations"]) >= 95, "recreations {}", s["swapchain_recreations"]);
    assert!(n(&s["minimized_frames_skipped"]) > 0, "the minimized window must not be rendered");
    assert!(n(&s["frames_presented"]) >= 10);
    let sc = &s["swapchain"];
    assert_eq!(sc["extent"], serde_json::json!([480, 360]), "the cycle ends at the initial size");
    // Live counts: at exit exactly the final swapchain's images; never more than a retiring swapchain plus its
    // replacement; nothing after teardown.
    assert_eq!(sc["live_at_exit"]["swapchains"], 1);
    assert_eq!(sc["live_at_exit"]["images"], sc["image_count"]);
    let per = n(&sc["max_images_per_swapchain"]);
    assert!(n(&sc["live_at_exit"]["max_images"]) <= 2 * per, "max live images {}", sc["live_at_exit"]);
    assert_eq!(sc["live_at_exit"]["created"], n(&s["swapchain_recreations"]) + 1);
    assert_eq!(sc["live_after_teardown"]["swapchains"], 0);
    assert_eq!(sc["live_after_teardown"]["images"], 0);
}

/// A device loss ends the viewer with exit code 1 and a clear message, promptly and without validation noise.
/// (The loss is injected at the start of a frame: a real one cannot be provoked on lavapipe.)
#[test]
fn device_loss_exits_with_code_1() {
    let dir = out_dir("viewer_device_loss");
    let x = Xvfb::start();
    let mut args = vec!["--scene", SPHERE, "--size", "320x240", "--frames", "20", "--inject-device-loss", "2"];
    args.extend_from_slice(FAST);
    let run = view(&dir, "loss", Some(&x.display), &args, Duration::from_secs(120));
    assert_eq!(run.status.code(), Some(1), "{}", run.stderr);
    assert!(run.stderr.contains("device lost"), "{}", run.stderr);
    assert!(!run.stderr.contains("[vulkan"), "validation messages:\n{}", run.stderr);
}

/// Without any display the viewer fails at once with a hint; a bad --screenshot name is bad input (exit 2).
#[test]
fn no_display_and_bad_arguments() {
    let dir = out_dir("viewer_errors");
    let run = view(&dir, "nodisplay", None, &["--frames", "1"], Duration::from_secs(60));
    assert_eq!(run.status.code(), Some(1), "{}", run.stderr);
    assert!(run.stderr.contains("xvfb-run"), "{}", run.stderr);
    let shot = dir.join("shot.jpg");
    let run = view(
        &dir,
        "badshot",
        None,
        &["--frames", "1", "--screenshot", shot.to_str().unwrap()],
        Duration::from_secs(60),
    );
    assert_eq!(run.status.code(), Some(2), "{}", run.stderr);
    assert!(run.stderr.contains("shot.jpg"), "{}", run.stderr);
    assert_no_output(&shot);
}

/// The input test times its key presses: on a 2-core machine it does not share the CPU with the signal test.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Start a viewer and wait for its window to present frames: its title shows the frame rate from then on (a key
/// pressed before the first frame, on a loaded machine, finds nothing to profile yet). A start whose X connection
/// was refused is tried again. Returns the viewer and its window.
fn spawn_with_frames(dir: &Path, name: &str, display: &str, args: &[&str]) -> (Guard, PathBuf, String) {
    for attempt in 0..3 {
        let (mut child, err_path) = spawn_view(dir, name, Some(display), args);
        let start = Instant::now();
        loop {
            if let Some(w) = xdotool(display, &["search", "--name", "^caustics.*fps"]) {
                return (child, err_path, w.lines().next().unwrap().trim().to_string());
            }
            if let Some(status) = child.0.try_wait().expect("wait") {
                let stderr = std::fs::read_to_string(&err_path).unwrap_or_default();
                assert!(attempt < 2 && stderr.contains(X_REFUSED), "the viewer exited ({status:?}):\n{stderr}");
                eprintln!("{name}: the X server refused the connection; starting the viewer again");
                std::thread::sleep(Duration::from_secs(1));
                break;
            }
            assert!(start.elapsed() < Duration::from_secs(120), "no viewer window with frames after 120 s");
            std::thread::sleep(Duration::from_millis(100));
        }
    }
    unreachable!()
}

/// xdotool on `display`; returns its stdout, or None when it fails.
fn xdotool(display: &str, args: &[&str]) -> Option<String> {
    let out = Command::new("xdotool")
        .args(args)
        .env("DISPLAY", display)
        .output()
        .expect("cannot run xdotool: run tools/setup (Debian package xdotool)");
    out.status.success().then(|| String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Real X input (XTEST, as a person's keyboard and mouse would send it): every key of the controls table that
/// changes something, an orbit drag, a scroll and a light drag, then Q. The stats prove each one took effect.
#[test]
fn keys_and_mouse_drive_the_viewer() {
    let _serial = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = out_dir("viewer_input");
    let x = Xvfb::start();
    let mut args = vec!["--scene", SPHERE, "--camera", "main", "--size", "480x360", "--stats", "input.json"];
    args.extend_from_slice(FAST);
    let (child, err_path, window) = spawn_with_frames(&dir, "input", &x.display, &args);
    let xdo = |a: &[&str]| {
        xdotool(&x.display, a).unwrap_or_else(|| panic!("xdotool {a:?} failed"));
        std::thread::sleep(Duration::from_millis(250));
    };
    xdo(&["windowfocus", "--sync", &window]);
    xdo(&["mousemove", "--window", &window, "200", "150"]);
    // H help, P profile table, S screenshot, T trace, ] IOR up, = level up, . caustic map x2, 3 max-error,
    // → light right, PgUp light up.
    for key in ["h", "p", "s", "t", "bracketright", "equal", "period", "3", "Right", "Prior"] {
        xdo(&["key", key]);
    }
    xdo(&["mousedown", "1", "mousemove_relative", "60", "0", "mouseup", "1"]);
    xdo(&["click", "4"]);
    xdo(&["mousedown", "3", "mousemove_relative", "30", "0", "mouseup", "3"]);
    // Input is applied when the next frame is rendered, and Q quits without rendering one: give the last inputs
    // a frame first (a frame takes up to about a second on 2 loaded cores).
    std::thread::sleep(Duration::from_secs(2));
    xdo(&["key", "q"]);
    let run = wait_view(child, &err_path, &args, Duration::from_secs(120));
    assert!(run.status.success(), "{}", run.stderr);
    let stdout = std::fs::read_to_string(dir.join("input.stdout")).unwrap();
    assert!(stdout.contains("caustics view controls"), "H: {stdout}");
    assert!(stdout.contains("gpu_total") && stdout.contains("splat"), "P: {stdout}");
    let (w, h, _) = caustics::image_io::read_png(&dir.join("caustics-screenshot-001.png")).expect("S: screenshot");
    assert_eq!((w, h), (480, 360));
    let trace = read_json(&dir.join("caustics-trace-001.json"));
    assert!(!trace["traceEvents"].as_array().unwrap().is_empty(), "T: empty trace");

    let s = read_json(&dir.join("input.json"));
    assert_validation_clean(&s);
    assert_eq!(s["method"], "adaptive");
    assert_eq!(s["metric"], "max-error");
    assert_eq!(s["level"], 3);
    assert_eq!(s["settings"]["caustic_res"], 1024);
    assert!((s["ior"].as_f64().unwrap() - 1.55).abs() < 1e-4, "IOR {}", s["ior"]);
    let v = |j: &serde_json::Value| -> Vec<f64> { j.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let light = v(&s["light"]["position"]);
    assert!(light[1] > 2.0 + 1e-3 && light[0].hypot(light[2]) > 1e-3, "light not moved: {light:?}");
    let cam = v(&s["camera_position"]);
    let d0 = (1.6f64.powi(2) + 1.15f64.powi(2) + 2.2f64.powi(2)).sqrt(); // to the target (0, 0.35, 0)
    let d = (cam[0].powi(2) + (cam[1] - 0.35).powi(2) + cam[2].powi(2)).sqrt();
    assert!((cam[0] - 1.6).abs() > 1e-3 || (cam[2] - 2.2).abs() > 1e-3, "camera not orbited: {cam:?}");
    assert!(d < d0 - 1e-3, "camera not zoomed in: distance {d} (was {d0})");
}

/// SIGTERM (and SIGINT) end the viewer like closing its window: `--screenshot` and `--stats` are still written.
#[test]
fn sigterm_still_writes_the_screenshot() {
    let _serial = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = out_dir("viewer_sigterm");
    let x = Xvfb::start();
    let shot = dir.join("shot.png");
    let stats = dir.join("stats.json");
    let mut args = vec!["--scene", SPHERE, "--camera", "top", "--size", "160x120"];
    args.extend(["--screenshot", shot.to_str().unwrap(), "--stats", stats.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    let (child, err_path, _) = spawn_with_frames(&dir, "sigterm", &x.display, &args);
    let pid = child.0.id().to_string();
    let kill = Command::new("kill").args(["-TERM", &pid]).status().expect("kill");
    assert!(kill.success());
    let run = wait_view(child, &err_path, &args, Duration::from_secs(120));
    assert!(run.status.success(), "{:?}:\n{}", run.status.code(), run.stderr);
    assert!(run.stderr.contains("signal received"), "{}", run.stderr);
    let (w, h, _, _) = luma(&shot);
    assert_eq!((w, h), (160, 120));
    assert_validation_clean(&read_json(&stats));
}

/// Two frames in flight (the default on GPUs; asked for here, since lavapipe's default is one) through 240 frames of scripted, mixed interaction: camera orbits, light
/// drags, an IOR change, a transport and a method switch, camera-driven refinement while orbiting, and still frames
/// in between. Validation (with
/// synchronization validation) must stay silent, every scripted frame must be presented, and the reuse the
/// viewer claims must have happened: still frames present the last image again, orbit frames reuse the caustic
/// map, and every step after a change converges to the chosen level at full quality.
#[test]
fn two_frames_in_flight_through_mixed_interaction() {
    let dir = out_dir("viewer_in_flight");
    let x = Xvfb::start();
    let script = dir.join("mixed.txt");
    std::fs::write(
        &script,
        "10 still\n40 orbit 3\n10 still\n40 drag 4 2\n20 still\n1 key ]\n19 still\n1 key x\n20 drag -4 0\n\
         1 key 3\n38 still\n1 key 4\n1 key c\n20 orbit 3\n18 still\n",
    )
    .unwrap();
    let args = [
        "--scene",
        SPHERE,
        "--size",
        "160x120",
        "--level",
        "1",
        "--gbuffer-res",
        "256",
        "--caustic-res",
        "256",
        "--sky",
        "0",
        "--no-vsync",
        "--frames-in-flight",
        "2",
        "--script",
        script.to_str().unwrap(),
    ];
    let s = view_ok(&dir, "mixed", &x.display, &args);
    let n = |v: &serde_json::Value| v.as_u64().unwrap_or_else(|| panic!("not a count: {v}"));
    assert_eq!(n(&s["frames_presented"]), 240);
    assert_eq!(n(&s["frames_in_flight"]), 2);
    let c = &s["counters"];
    eprintln!("{}", serde_json::to_string(c).unwrap());
    assert!(n(&c["caustics_reused_frames"]) >= 40, "orbit frames reuse the caustic map: {c}");
    assert!(n(&c["eye_reused_frames"]) >= 20, "still frames present the last image again: {c}");
    assert!(n(&c["preview_frames"]) >= 100, "moving frames are previews: {c}");
    let steps = s["script"].as_array().expect("script stats");
    assert_eq!(steps.len(), 15);
    for st in steps {
        assert_eq!(st["frames_presented"], st["frames_completed"], "{st}");
        let step = st["step"].as_str().unwrap();
        let frames: u64 = step.split_whitespace().next().unwrap().parse().unwrap();
        assert_eq!(n(&st["frames_presented"]), frames, "{st}");
        if step.ends_with("still") && frames >= 10 {
            assert!(st["converged_ms"].as_f64().is_some(), "{step}: never reached the chosen level: {st}");
            assert_eq!(st["levels"][1], 1, "{st}");
        }
    }
}

/// The pool's water plays in the viewer: every frame after the first displaces it (on the GPU; no BVH is built,
/// none is needed by two-interface previews), and a scripted `A` pauses it.
#[test]
fn the_pool_animates_and_pauses() {
    let dir = out_dir("viewer_pool");
    let x = Xvfb::start();
    let pool = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/pool.toml");
    let mut args = vec!["--scene", pool, "--size", "160x120", "--frames", "8"];
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "pool", &x.display, &args);
    assert_eq!(s["frames_presented"], 8);
    assert_eq!(s["scene_playing"], true);
    assert!(s["scene_time_s"].as_f64().unwrap() > 0.0, "{}", s["scene_time_s"]);
    assert_eq!(s["scene_update"]["deformed_objects"], 7, "{}", s["scene_update"]);
    assert_eq!(s["scene_update"]["blas_builds"], 0);
    // Paused by a key on the first frame: nothing moves after it.
    let script = dir.join("pause.txt");
    std::fs::write(&script, "1 key a\n7 still\n").unwrap();
    let mut args = vec!["--scene", pool, "--size", "160x120", "--script", script.to_str().unwrap()];
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "pool_paused", &x.display, &args);
    assert_eq!(s["scene_playing"], false);
    assert!(s["scene_update"]["deformed_objects"].as_u64().unwrap() <= 1, "{}", s["scene_update"]);
}

/// An animated glTF file plays in the viewer as its poses render: three frames at a fixed 0.125 s each bring the
/// rig of tests/common/rig.rs to 0.375 s, and the third frame (each frame at the chosen level and full quality) is
/// the headless beauty of the rig posed still at 0.375 s. Measured: identical bytes.
#[test]
fn an_animated_gltf_plays_as_its_poses_render() {
    let dir = out_dir("viewer_gltf_rig");
    let (animated, stills) = common::rig::write_rigs(&dir);
    let t = common::rig::TIMES[1];
    assert_eq!(t, 0.375);
    let x = Xvfb::start();
    let shot = dir.join("shot.png");
    let mut args = vec!["--scene", animated.to_str().unwrap(), "--camera", "main", "--size", "256x256"];
    args.extend(["--no-progressive", "--frame-dt", "0.125", "--frames", "3", "--level", "3", "--transport", "exact"]);
    args.extend(["--screenshot", shot.to_str().unwrap()]);
    let s = view_ok(&dir, "rig", &x.display, &args);
    assert_eq!(s["scene_time_s"].as_f64(), Some(t as f64), "{}", s["scene_time_s"]);
    assert!(s["scene_update"]["moved_objects"].as_u64().unwrap() >= 3, "{}", s["scene_update"]);
    let still = dir.join("still.png");
    let still_scene = stills[1].to_str().unwrap();
    ok(&[
        "render",
        "--scene",
        still_scene,
        "--camera",
        "main",
        "--size",
        "256x256",
        "--level",
        "3",
        "--out",
        still.to_str().unwrap(),
    ]);
    let (_, _, _, played) = luma(&shot);
    let (_, _, _, posed) = luma(&still);
    let d = max_diff(&played, &posed);
    assert!(d <= 1, "the played frame differs from the still pose's by {d} levels");
}

/// `N` plays a glTF file's animations one at a time, then all together again (Blender's two-object export).
#[test]
fn the_n_key_switches_gltf_animations() {
    let dir = out_dir("viewer_gltf_animations");
    let x = Xvfb::start();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/blender/two_objects.glb");
    for (presses, playing) in [
        (0, serde_json::Value::Null),
        (1, "SuzanneAction".into()),
        (2, "SliderAction".into()),
        (3, serde_json::Value::Null),
    ] {
        let script = dir.join(format!("n{presses}.txt"));
        let mut steps: String = (0..presses).map(|_| "1 key n\n").collect();
        steps.push_str("1 still\n");
        std::fs::write(&script, steps).unwrap();
        let mut args = vec!["--scene", scene, "--size", "96x54", "--script", script.to_str().unwrap()];
        args.extend_from_slice(FAST);
        let s = view_ok(&dir, &format!("n{presses}"), &x.display, &args);
        assert_eq!(s["scene_animation"], playing, "after {presses} presses of N");
    }
}

/// A click on the simulated water drops into it where the cursor is: the frame differs from the same frames
/// without the click around the click's point, and hardly elsewhere. A click beside the pool drops nothing.
#[test]
fn a_click_drops_into_the_water_under_it() {
    let dir = out_dir("viewer_drop");
    let x = Xvfb::start();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pool_drops.toml");
    let run = |name: &str, steps: &str| {
        let script = dir.join(format!("{name}.txt"));
        std::fs::write(&script, steps).unwrap();
        let png = dir.join(format!("{name}.png"));
        let mut args = vec!["--scene", scene, "--camera", "top", "--size", "160x160", "--frame-dt", "0.1"];
        args.extend(["--time", "3", "--script", script.to_str().unwrap(), "--screenshot", png.to_str().unwrap()]);
        // Every frame at the chosen level and one preview scale: the viewer would otherwise adapt both to the
        // frame times it measures, and the two runs, timed on a loaded machine, would differ everywhere.
        args.extend(["--no-progressive", "--preview-scale", "2"]);
        args.extend_from_slice(FAST);
        (view_ok(&dir, name, &x.display, &args), luma(&png).2)
    };
    // Beside the pool (its floor's corner), then at (0.3, 0.7) of the window: x = -0.44 m, z = 0.44 m.
    let (s, clicked) = run("click", "1 still\n1 click 0.02 0.02\n1 click 0.3 0.7\n5 still\n");
    let (_, still) = run("still", "1 still\n1 still\n1 still\n5 still\n");
    assert_eq!(s["counters"]["water_drops"], 1, "{}", s["counters"]);
    // Mean |difference| within 0.12 of the window's side of the click, and beyond 0.3 of it.
    let (mut near, mut far) = ((0.0, 0), (0.0, 0));
    for (i, (a, b)) in clicked.iter().zip(&still).enumerate() {
        let (px, py) = ((i % 160) as f64 / 160.0 - 0.3, (i / 160) as f64 / 160.0 - 0.7);
        let r = px.hypot(py);
        let acc = if r < 0.12 {
            &mut near
        } else if r > 0.3 {
            &mut far
        } else {
            continue;
        };
        acc.0 += (a - b).abs();
        acc.1 += 1;
    }
    let (near, far) = (near.0 / near.1 as f64, far.0 / far.1 as f64);
    eprintln!("mean |click - still| near the click {near:.3}, far from it {far:.3} (of 255)");
    assert!(near > 2.0 && near > 10.0 * far, "near {near}, far {far}");
}

/// The overlay (F1, `--overlay`) is drawn into the presented image over the frame, and only where its panel is:
/// the same frame with it off is the same bytes elsewhere. Its buttons act as their keys do: a scripted click on
/// "level +" (where the first run's stats put that button) raises the level, and drops nothing into the scene.
/// Validation, synchronization included, stays clean. Measured: the panel differs by a mean of 58 levels, the rest
/// by 0.
#[test]
fn the_overlay_is_presented_over_the_frame_and_its_buttons_act() {
    let dir = out_dir("viewer_overlay");
    let x = Xvfb::start();
    let (on_png, off_png) = (dir.join("on.png"), dir.join("off.png"));
    let base = ["--scene", SPHERE, "--camera", "top", "--size", "960x540", "--accumulate", "1"];
    let run = |name: &str, overlay: &str, extra: &[&str]| {
        let mut args = base.to_vec();
        args.extend(["--overlay", overlay]);
        args.extend_from_slice(extra);
        args.extend_from_slice(FAST);
        view_ok(&dir, name, &x.display, &args)
    };
    let on = run("on", "on", &["--frames", "3", "--screenshot", on_png.to_str().unwrap()]);
    run("off", "off", &["--frames", "3", "--screenshot", off_png.to_str().unwrap()]);
    let o = &on["overlay"];
    assert_eq!(o["visible"], true);
    assert!(o["triangles"].as_u64().unwrap() > 100 && o["textures"].as_u64().unwrap() >= 1, "{o}");
    let rect =
        |v: &serde_json::Value| -> Vec<f64> { v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let panel = rect(&o["panel"]);
    let (w, _, _, with) = luma(&on_png);
    let (_, _, _, without) = luma(&off_png);
    let (mut inside, mut n_inside, mut outside) = (0.0, 0usize, 0u8);
    for (i, (p, q)) in with.chunks_exact(4).zip(without.chunks_exact(4)).enumerate() {
        let (px, py) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let d = (0..3).map(|c| p[c].abs_diff(q[c])).max().unwrap();
        // The panel's shadow reaches up to 35 pixels past its rectangle (egui's offset of 20 and blur of 15).
        if px >= panel[0] - 40.0 && px <= panel[2] + 40.0 && py >= panel[1] - 40.0 && py <= panel[3] + 40.0 {
            inside += d as f64;
            n_inside += 1;
        } else {
            outside = outside.max(d);
        }
    }
    let inside = inside / n_inside as f64;
    eprintln!("overlay panel {panel:?}: mean difference inside {inside:.1}, largest outside {outside}");
    assert!(inside > 20.0, "the overlay is not in the presented image (mean difference {inside:.1})");
    assert!(outside <= 2, "the overlay changed the frame outside its panel by {outside} levels");

    let level_up = rect(&o["buttons"]["LevelUp"]);
    let (fx, fy) = ((level_up[0] + level_up[2]) / 2.0 / 960.0, (level_up[1] + level_up[3]) / 2.0 / 540.0);
    let script = dir.join("click.txt");
    std::fs::write(&script, format!("2 still\n1 click {fx:.4} {fy:.4}\n2 still\n")).unwrap();
    let clicked = run("clicked", "on", &["--script", script.to_str().unwrap()]);
    assert_eq!(clicked["level"], 3, "the click on level + did not raise the level from 2");
    assert_eq!(clicked["counters"]["water_drops"], 0, "a click on the panel is not a click into the scene");
}

/// A window shorter than the overlay's panel scrolls the panel: it stays within the window, with its buttons on
/// it. Measured: 960×300, the panel from y = 0 to 268 (to 435, past the window, before it scrolled).
#[test]
fn the_overlay_panel_fits_a_short_window() {
    let dir = out_dir("viewer_overlay_short");
    let x = Xvfb::start();
    let mut args = vec!["--scene", SPHERE, "--camera", "top", "--size", "960x300", "--accumulate", "1"];
    args.extend(["--overlay", "on", "--frames", "3"]);
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "short", &x.display, &args);
    let o = &s["overlay"];
    let rect =
        |v: &serde_json::Value| -> Vec<f64> { v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect() };
    let panel = rect(&o["panel"]);
    eprintln!("overlay panel in a 960x300 window: {panel:?}");
    assert!(panel[1] >= 0.0 && panel[3] <= 300.0, "the panel {panel:?} leaves the 300-pixel window");
    assert!(panel[3] - panel[1] > 150.0, "the panel {panel:?} shrank to nothing");
    let level_up = rect(&o["buttons"]["LevelUp"]);
    assert!(level_up[3] <= panel[3], "the level button {level_up:?} lies below the panel {panel:?}");
}

/// A scene file dropped on the window opens in place of the open one (a scripted drop, which takes the path that a
/// real drop's event carries), with the new scene's first perspective camera, and its frame is the headless
/// renderer's frame of that file from that camera. Measured: at most 1 level apart.
#[test]
fn a_dropped_scene_opens_and_renders_as_its_file() {
    let dir = out_dir("viewer_drop");
    let x = Xvfb::start();
    let bowl = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/bowl.toml");
    let script = dir.join("drop.txt");
    std::fs::write(&script, format!("2 still\n1 drop {bowl}\n3 still\n")).unwrap();
    let shot = dir.join("shot.png");
    let mut args = vec!["--scene", SPHERE, "--size", "320x240", "--no-progressive", "--accumulate", "1"];
    args.extend(["--script", script.to_str().unwrap(), "--screenshot", shot.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    let s = view_ok(&dir, "drop", &x.display, &args);
    assert_eq!(s["counters"]["scenes_opened"], 1, "{}", s["counters"]);
    assert!(s["scene"].as_str().unwrap().ends_with("bowl.toml"), "{}", s["scene"]);
    assert_eq!(s["camera"], "main", "the dropped scene's first perspective camera");
    let headless = dir.join("headless.png");
    let mut args = vec!["render", "--scene", bowl, "--camera", "main", "--size", "320x240", "--accumulate", "1"];
    args.extend(["--transport", "two-interface", "--out", headless.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    ok(&args);
    let (_, _, _, windowed) = luma(&shot);
    let (_, _, _, rendered) = luma(&headless);
    let d = max_diff(&windowed, &rendered);
    assert!(d <= 2, "the dropped scene's frame differs from its headless frame by {d} levels");
}

/// The open scene file, changed on disk, opens again: an edit of the glass's index of refraction in a copy of
/// sphere.toml reaches the running viewer within its half-second look at the file. A file that does not parse
/// leaves the scene on screen.
#[test]
fn a_scene_changed_on_disk_opens_again() {
    let _serial = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let dir = out_dir("viewer_reload");
    let x = Xvfb::start();
    let scene = dir.join("glass.toml");
    let text = std::fs::read_to_string(SPHERE).unwrap();
    std::fs::write(&scene, &text).unwrap();
    let stats = dir.join("stats.json");
    let mut args = vec!["--scene", scene.to_str().unwrap(), "--camera", "top", "--size", "160x120"];
    args.extend(["--stats", stats.to_str().unwrap()]);
    args.extend_from_slice(FAST);
    let (child, err_path, _) = spawn_with_frames(&dir, "reload", &x.display, &args);
    let wait_for = |needle: &str| {
        let start = Instant::now();
        while !std::fs::read_to_string(&err_path).unwrap_or_default().contains(needle) {
            assert!(start.elapsed() < Duration::from_secs(60), "no `{needle}` from the viewer after 60 s");
            std::thread::sleep(Duration::from_millis(50));
        }
    };
    std::fs::write(&scene, "[[object]]\nshape = ").unwrap();
    wait_for("not opened");
    std::fs::write(&scene, text.replace("ior = 1.5", "ior = 1.33")).unwrap();
    wait_for(&format!("opened {}", scene.display()));
    let kill = Command::new("kill").args(["-TERM", &child.0.id().to_string()]).status().expect("kill");
    assert!(kill.success());
    let run = wait_view(child, &err_path, &args, Duration::from_secs(120));
    assert!(run.status.success(), "{:?}:\n{}", run.status.code(), run.stderr);
    let s = read_json(&stats);
    assert_validation_clean(&s);
    assert_eq!(s["counters"]["scenes_opened"], 1, "{}", s["counters"]);
    assert!((s["ior"].as_f64().unwrap() - 1.33).abs() < 1e-6, "ior {}", s["ior"]);
}
