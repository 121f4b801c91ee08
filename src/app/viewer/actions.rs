//! What the viewer's controls do: each [`Action`] of the keys and the overlay's buttons, and the changes they make
//! (settings, IOR, the light, the scene's animations, the glass's placement), with the settings' one-line
//! description that the title and the overlay show.

use super::*;

impl Viewer {
    pub(super) fn act(&mut self, action: Action) -> Result<()> {
        use Action::*;
        let c = self.renderer.config().clone();
        // A change asks for the current settings with one quality choice changed (the tuning stays).
        let with = |f: &dyn Fn(&mut Quality)| {
            let mut s = self.renderer.settings().clone();
            s.quality.level = Some(c.level);
            f(&mut s.quality);
            s
        };
        match action {
            LightLeft => self.input.light_keys.x -= 1.0,
            LightRight => self.input.light_keys.x += 1.0,
            LightDown => self.input.light_keys.y -= 1.0,
            LightUp => self.input.light_keys.y += 1.0,
            LightNear => self.input.light_keys.z -= 1.0,
            LightAway => self.input.light_keys.z += 1.0,
            IorDown => self.change_ior(-0.05)?,
            IorUp => self.change_ior(0.05)?,
            LevelDown => self.change_settings(with(&|q| q.level = Some(c.level.saturating_sub(1))))?,
            LevelUp => self.change_settings(with(&|q| q.level = Some(c.level + 1)))?,
            ResolutionDown => self.change_settings(with(&|q| q.caustic_res = (c.caustic_res / 2).max(64)))?,
            ResolutionUp => self.change_settings(with(&|q| q.caustic_res = (c.caustic_res * 2).min(4096)))?,
            Dense => self.change_settings(with(&|q| {
                q.method = Method::Dense;
                q.level = Some(c.level.min(12));
            }))?,
            AdaptiveMaxLevel => self.change_settings(with(&|q| {
                q.method = Method::Adaptive;
                q.metric = Metric::MaxLevel;
            }))?,
            AdaptiveMaxError => self.change_settings(with(&|q| {
                q.method = Method::Adaptive;
                q.metric = Metric::MaxError;
            }))?,
            AdaptiveFluxError => self.change_settings(with(&|q| {
                q.method = Method::Adaptive;
                q.metric = Metric::FluxError;
            }))?,
            Transport => {
                let transport = match c.transport {
                    caustics::settings::Transport::Exact => caustics::settings::Transport::TwoInterface,
                    caustics::settings::Transport::TwoInterface => caustics::settings::Transport::Exact,
                };
                self.change_settings(with(&|q| q.transport = transport))?
            }
            Refine => {
                // The requested refinement: the resolved one is light-driven under other methods.
                let refine = match self.renderer.settings().quality.refine {
                    caustics::settings::Refine::Light => caustics::settings::Refine::Camera,
                    caustics::settings::Refine::Camera => caustics::settings::Refine::Light,
                };
                self.change_settings(with(&|q| q.refine = refine))?
            }
            Animate => self.toggle_animation(),
            NextAnimation => self.next_animation()?,
            PlayScene => {
                if !self.renderer.scene().is_animated() {
                    eprintln!("the scene has no animated object (keyframes in TOML, animations in glTF)");
                } else {
                    self.scene_playing = !self.scene_playing;
                    let state = if self.scene_playing { "playing" } else { "paused" };
                    eprintln!("scene animation {state} at {:.2} s", self.scene_time);
                }
            }
            Screenshot => self.screenshot_request = true,
            Profile => {
                let frames: Vec<FrameReport> = self.ring.iter().cloned().collect();
                println!("{} | {}", self.describe(), self.device().info.name);
                let photons = frames.last().and_then(|f| f.state).map(|x| x.photons_total as u64);
                print!("{}", profiler::table(&profiler::stage_summaries(&frames), frames.len(), photons));
            }
            Trace => {
                let frames: Vec<FrameReport> = self.ring.iter().cloned().collect();
                let path = free_name("caustics-trace", "json");
                image_io::write_text(
                    &path,
                    &serde_json::to_string(&profiler::chrome_trace(&frames)).unwrap_or_default(),
                )?;
                eprintln!("wrote {} ({} frames; open in Perfetto or chrome://tracing)", path.display(), frames.len());
            }
            Reset => {
                self.orbit.reset();
                let light = self.initial_light.clone();
                self.set_light(light);
                if self.offsets.iter().any(|o| *o != Vec3::ZERO) {
                    self.offsets.iter_mut().for_each(|o| *o = Vec3::ZERO);
                    for (i, m) in self.placements.clone().into_iter().enumerate() {
                        if let Err(e) = self.renderer.set_transform(caustics::InstanceId::from_index(i), m) {
                            eprintln!("not moved back: {e}");
                        }
                    }
                    self.place_objects();
                }
                eprintln!("camera, light and glass reset");
            }
            Overlay => self.overlay.visible = !self.overlay.visible,
            Help => print!("{}", help_text()),
            Quit => self.quit = true,
        }
        Ok(())
    }

    pub(super) fn describe(&self) -> String {
        let s = &self.renderer.config();
        let method = match (s.method, s.metric, s.refine) {
            (Method::Dense, ..) => "dense",
            (Method::Adaptive, Metric::MaxLevel, _) => "adaptive max-level",
            (Method::Adaptive, Metric::MaxError, _) => "adaptive max-error",
            (Method::Adaptive, Metric::FluxError, caustics::settings::Refine::Light) => "adaptive flux-error",
            (Method::Adaptive, Metric::FluxError, caustics::settings::Refine::Camera) => "adaptive flux-error (camera)",
        };
        let ior = self.ior();
        let transport = match s.transport {
            caustics::settings::Transport::Exact => "exact",
            caustics::settings::Transport::TwoInterface => "two-interface",
        };
        format!(
            "{transport} {method}, level {} ({}²), caustic map {}²{}",
            s.level,
            LEVEL0_RES << s.level,
            s.caustic_res,
            ior.map(|i| format!(", IOR {i:.2}")).unwrap_or_default()
        )
    }

    /// The first dielectric's index of refraction (all of them change together).
    pub(super) fn ior(&self) -> Option<f32> {
        self.renderer.scene().refractors().find_map(|o| match o.material {
            Material::Dielectric { ior, .. } => Some(ior),
            _ => None,
        })
    }

    pub(super) fn change_settings(&mut self, settings: Settings) -> Result<()> {
        match self.renderer.set_settings(settings) {
            Ok(()) => eprintln!("{}", self.describe()),
            Err(e @ (Error::BadInput(_) | Error::Setting { .. })) => {
                eprintln!("not changed: {}", crate::app::flags::message(&e))
            }
            Err(e) => return Err(e),
        }
        Ok(())
    }

    pub(super) fn change_ior(&mut self, delta: f32) -> Result<()> {
        let mut scene = self.renderer.scene().clone();
        let mut changed = false;
        for o in scene.objects.iter_mut() {
            if let Material::Dielectric { ior, .. } = &mut o.material {
                *ior = (*ior + delta).clamp(1.0, 4.0);
                changed = true;
            }
        }
        if !changed {
            eprintln!("the scene has no dielectric");
            return Ok(());
        }
        self.renderer.set_scene(scene)?;
        self.interacting = true;
        eprintln!("{}", self.describe());
        Ok(())
    }

    /// Play the next of a glTF file's animations alone (all of them together after the last): the file is loaded
    /// again with that choice, at the same time.
    pub(super) fn next_animation(&mut self) -> Result<()> {
        let scene = self.renderer.scene();
        let n = scene.animations.len();
        if n < 2 {
            eprintln!("the scene has {} glTF animation{}: nothing to switch", n, if n == 1 { "" } else { "s" });
            return Ok(());
        }
        let next = match scene.playing {
            None => Some(0),
            Some(i) if i + 1 < n => Some(i + 1),
            Some(_) => None,
        };
        let choice = next.map_or(caustics::scene::AnimationChoice::All, caustics::scene::AnimationChoice::Index);
        let mut scene = Scene::load_with(&self.scene_path, &caustics::scene::LoadOptions { animation: choice })?;
        crate::app::commands::apply_environment(&mut scene, self.environment.as_deref())?;
        scene.set_time(self.scene_time);
        let name = next.map_or("all animations".to_string(), |i| format!("animation {i} \"{}\"", scene.animations[i]));
        self.renderer.set_scene(scene)?;
        self.placements = initial_placements(&self.renderer);
        self.place_objects();
        eprintln!("playing {name}");
        Ok(())
    }

    pub(super) fn toggle_animation(&mut self) {
        self.animate = !self.animate;
        if !self.animate {
            eprintln!("light animation paused");
            return;
        }
        let light = self.renderer.scene().lights[0].clone();
        let d = light.position - light.target;
        if Vec3::new(d.x, 0.0, d.z).length() < 1e-3 * d.length().max(1e-6) {
            // Straight above (or below) its target, the light would turn in place: lean it first.
            let tilt = Quat::from_rotation_z(-ANIMATION_TILT_DEG.to_radians());
            let moved = Light { position: light.target + tilt * d, ..light };
            if self.set_light(moved) {
                eprintln!("light tilted {ANIMATION_TILT_DEG}° off the vertical so that its orbit moves it");
            }
        }
        eprintln!("light animation on: one turn in {ANIMATION_PERIOD_S} s around the vertical axis through its target");
    }

    /// Place the objects at the scene's time, each dragged by its offset (the next frame's scene update moves them
    /// on the GPU).
    pub(super) fn place_objects(&mut self) {
        if let Err(e) = self.renderer.set_time(self.scene_time) {
            eprintln!("animation paused: {e}");
            self.scene_playing = false;
        }
        // An animated camera carries the view with it (orbited as the user orbited it).
        let scene = self.renderer.scene();
        if let Some(c) = scene.cameras.iter().find(|c| c.name == self.camera_name) {
            let k = scene.cameras.iter().position(|x| x.name == c.name);
            if scene.movers.iter().any(|m| Some(m.what) == k.map(caustics::scene::Moved::Camera)) {
                self.orbit.follow(c);
            }
        }
        for (i, &offset) in self.offsets.iter().enumerate() {
            if offset == Vec3::ZERO {
                continue;
            }
            let o = &self.renderer.scene().objects[i];
            let base = o.animation.as_ref().map_or(self.placements[i], |a| a.transform_at(self.scene_time));
            let m = glam::Mat4::from_translation(offset) * base;
            if let Err(e) = self.renderer.set_transform(caustics::InstanceId::from_index(i), m) {
                eprintln!("not moved: {e}");
            }
        }
        self.interacting = true;
    }

    /// Move the light if every refractor stays in front of it (else the frame could not be rendered).
    pub(super) fn set_light(&mut self, light: Light) -> bool {
        match self.renderer.set_light(0, light) {
            Ok(()) => true,
            Err(e) => {
                eprintln!("light not moved: {e}");
                false
            }
        }
    }
}
