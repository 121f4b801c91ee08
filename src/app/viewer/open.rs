//! Opening a scene in a running viewer: a file dropped on the window (`.toml`, `.gltf`, `.glb`), or the open file
//! changed on disk (the viewer looks at its modification time twice a second and opens it again). The settings,
//! the window and the overlay stay; the camera, the light, the animation and any dragged objects become the new
//! scene's. A file that does not load leaves the current scene on screen, with its error printed: an editor that
//! saves in two steps, or a file dropped by mistake, costs nothing.

use super::{initial_placements, pick_camera, Viewer};
use caustics::error::{Error, Result};
use caustics::gpu::VkError;
use caustics::scene::{Camera, Scene};
use caustics::Renderer;
use glam::Vec3;
use std::path::Path;
use std::time::{Duration, Instant, SystemTime};

/// How often the open file's modification time is looked at.
const WATCH_EVERY: Duration = Duration::from_millis(500);

/// The open scene file's modification time, where the file system tells it.
pub fn modified(path: &Path) -> Option<SystemTime> {
    std::fs::metadata(path).and_then(|m| m.modified()).ok()
}

/// Load `path` as the viewer's next scene, with `--environment` in place of its own where given: its camera (the
/// first perspective one) and a light are required.
fn load(path: &Path, environment: Option<&Path>) -> Result<(Scene, Camera)> {
    let mut scene = Scene::load_with(path, &crate::app::commands::load_options(None))?;
    crate::app::commands::apply_environment(&mut scene, environment)?;
    let camera = pick_camera(&scene, None)?;
    if scene.lights.is_empty() {
        return Err(Error::BadInput(format!("{}: the scene has no [[light]]", path.display())));
    }
    Ok((scene, camera))
}

impl Viewer {
    /// Open the scene at `path` in place of the current one, with a renderer of its own (textures, environment
    /// and water are the new scene's). Returns whether it opened; a file that does not load, or a renderer that
    /// cannot be made for it, leaves the current scene (the error is printed). A lost device ends the viewer.
    pub(super) fn open_scene(&mut self, path: &Path) -> Result<bool> {
        let (scene, camera) = match load(path, self.environment.as_deref()) {
            Ok(loaded) => loaded,
            Err(e) => {
                eprintln!("{}: not opened: {e}", path.display());
                return Ok(false);
            }
        };
        // The frames in flight finish with the old renderer (their reports are taken in).
        self.finish_frames()?;
        let frames_in_flight = self.renderer.frames_in_flight();
        let (playing, time) = (scene.is_animated(), scene.time);
        let light = scene.lights[0].clone();
        let made = Renderer::new(self.device().clone(), scene, self.renderer.settings().clone())
            .and_then(|mut r| r.set_frames_in_flight(frames_in_flight).map(|()| r));
        let renderer = match made {
            Ok(r) => r,
            Err(e @ Error::Vk(VkError::DeviceLost(_))) => return Err(e),
            Err(e) => {
                eprintln!("{}: not opened: {e}", path.display());
                return Ok(false);
            }
        };
        self.renderer = renderer;
        self.scene_path = path.to_path_buf();
        self.scene_modified = modified(path);
        self.scene_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        self.camera_name = camera.name.clone();
        self.orbit = super::orbit::Orbit::new(&camera);
        self.initial_light = light;
        (self.scene_playing, self.scene_time) = (playing, time);
        self.placements = initial_placements(&self.renderer);
        self.offsets = vec![Vec3::ZERO; self.placements.len()];
        (self.grab, self.last_camera, self.animate) = (None, None, false);
        self.counters.scenes_opened += 1;
        self.window.set_title(&format!("caustics — {}", self.scene_name));
        eprintln!("opened {}", path.display());
        Ok(true)
    }

    /// Twice a second: open the scene file again if it changed on disk since it was opened.
    pub(super) fn watch_scene(&mut self) -> Result<()> {
        if self.scene_checked.elapsed() < WATCH_EVERY {
            return Ok(());
        }
        self.scene_checked = Instant::now();
        let now = modified(&self.scene_path);
        if now.is_some() && now != self.scene_modified {
            // Looked at once per change, whether or not it loads.
            self.scene_modified = now;
            let path = self.scene_path.clone();
            eprintln!("{} changed on disk: opening it again", path.display());
            self.open_scene(&path)?;
        }
        Ok(())
    }
}
