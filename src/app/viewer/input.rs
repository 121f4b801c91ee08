//! The viewer's input: window events (mouse, keys, dropped files; the overlay takes its own first), scripted
//! input (`--script`), and the input gathered between frames applied when the next frame starts (the camera's
//! orbit and zoom, the light's and the glass's drags, a click's drop into water).

use super::*;

/// Mouse and key input gathered between frames, applied when the next frame starts.
#[derive(Default)]
pub(super) struct Input {
    pub(super) left: bool,
    pub(super) right: bool,
    pub(super) cursor: Option<(f64, f64)>,
    pub(super) orbit: (f32, f32),
    pub(super) zoom: f32,
    /// Light drag in pixels (x right, y down).
    pub(super) light_drag: (f32, f32),
    /// Light key steps: right, up, away.
    pub(super) light_keys: Vec3,
    /// Shift is held.
    pub(super) shift: bool,
    /// A Shift + left press at this cursor position: pick the glass under it.
    pub(super) pick: Option<(f64, f64)>,
    /// Glass drag in pixels (x right, y down).
    pub(super) glass_drag: (f32, f32),
    /// How far the cursor went since the left button went down (pixels): a short one is a click.
    pub(super) travel: f32,
    /// A click at this cursor position: a drop into the water under it.
    pub(super) drop: Option<(f64, f64)>,
}

/// A click's drop into simulated water: its radius and depth, m.
pub(super) const DROP_RADIUS: f32 = 0.08;
pub(super) const DROP_DEPTH: f32 = 0.02;

/// A left press and release within this many pixels is a click.
pub(super) const CLICK_PIXELS: f32 = 4.0;

impl Viewer {
    pub(super) fn window_event(&mut self, event: WindowEvent) -> Result<()> {
        // What the overlay takes (a click on a button, a drag over its panel) the scene does not get too.
        if self.overlay.on_window_event(&self.window, &event) {
            if let WindowEvent::MouseInput { state: ElementState::Released, .. } = event {
                // A drag that began in the scene ends over the panel: it ends, and is no click.
                (self.input.left, self.input.right) = (false, false);
            }
            return Ok(());
        }
        match event {
            WindowEvent::CloseRequested | WindowEvent::Destroyed => self.quit = true,
            WindowEvent::Resized(size) => {
                if size != self.last_size {
                    self.counters.resizes_seen += 1;
                    self.last_size = size;
                }
                self.dirty = true;
            }
            WindowEvent::RedrawRequested => {
                self.watch_scene()?;
                self.redraw()?
            }
            WindowEvent::DroppedFile(path) => {
                self.open_scene(&path)?;
            }
            WindowEvent::KeyboardInput { event, is_synthetic: false, .. } if event.state == ElementState::Pressed => {
                if let Some(action) = controls::action_for(&event.logical_key) {
                    if !event.repeat || action.repeats() {
                        self.act(action)?;
                    }
                }
            }
            WindowEvent::ModifiersChanged(m) => self.input.shift = m.state().shift_key(),
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => {
                        if down {
                            self.input.travel = 0.0;
                        } else if self.input.left && !self.input.shift && self.input.travel < CLICK_PIXELS {
                            self.input.drop = self.input.cursor;
                        }
                        self.input.left = down;
                        if down && self.input.shift {
                            self.input.pick = self.input.cursor;
                        }
                    }
                    MouseButton::Right => self.input.right = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let Some((x, y)) = self.input.cursor {
                    let (dx, dy) = ((position.x - x) as f32, (position.y - y) as f32);
                    if self.input.left {
                        self.input.travel += dx.abs() + dy.abs();
                    }
                    if self.input.left && self.grab.is_some() {
                        self.input.glass_drag.0 += dx;
                        self.input.glass_drag.1 += dy;
                    } else if self.input.left && self.input.pick.is_none() {
                        self.input.orbit.0 += dx;
                        self.input.orbit.1 += dy;
                    }
                    if self.input.right {
                        self.input.light_drag.0 += dx;
                        self.input.light_drag.1 += dy;
                    }
                }
                self.input.cursor = Some((position.x, position.y));
            }
            WindowEvent::CursorLeft { .. } => self.input.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                self.input.zoom += match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
            }
            _ => {}
        }
        Ok(())
    }

    /// Apply the input gathered since the last frame and advance the light's animation.
    pub(super) fn apply_input(&mut self, dt: f32, extent: vk::Extent2D) {
        let input = std::mem::take(&mut self.input);
        self.input = Input {
            left: input.left,
            right: input.right,
            cursor: input.cursor,
            shift: input.shift,
            ..Input::default()
        };
        self.orbit.rotate(input.orbit.0 * 0.005, input.orbit.1 * 0.005);
        if self.orbit_step != 0.0 {
            // Scripted camera orbit (--orbit-camera): a fixed step per frame, for repeatable frame-time runs.
            self.orbit.rotate(self.orbit_step.to_radians(), 0.0);
        }
        if input.zoom != 0.0 {
            self.orbit.zoom(input.zoom);
        }
        let (lo, hi) = self.renderer.scene().bounds();
        let size = (hi - lo).length().max(1e-3);
        let view = self.renderer.camera_view(&self.orbit.camera(), extent.width.max(1), extent.height.max(1));
        let flat = |v: Vec3| Vec3::new(v.x, 0.0, v.z).normalize_or_zero();
        let right = flat(view.right);
        let away = if flat(view.forward) != Vec3::ZERO { flat(view.forward) } else { flat(view.up) };
        let per_pixel = size / extent.height.max(1) as f32;
        let step = 0.04 * size;
        let offset = right * (input.light_keys.x * step + input.light_drag.0 * per_pixel)
            + away * (input.light_keys.z * step - input.light_drag.1 * per_pixel)
            + Vec3::Y * input.light_keys.y * step;
        if let Some((x, y)) = input.pick {
            let (o, d) = view.ray(glam::Vec2::new(x as f32, y as f32));
            self.grab = self.renderer.scene().pick(o, d, |o| o.is_refractor()).map(|(i, _)| i);
            match self.grab {
                Some(i) => eprintln!("moving `{}` (Shift + drag)", self.renderer.scene().objects[i].name),
                None => eprintln!("no glass under the cursor"),
            }
        }
        if !input.left {
            self.grab = None;
        }
        if let Some((x, y)) = input.drop {
            let (o, d) = view.ray(glam::Vec2::new(x as f32, y as f32));
            match self.renderer.drop_into_water(o, d, DROP_RADIUS, DROP_DEPTH) {
                Ok(Some(_)) => self.counters.water_drops += 1,
                Ok(None) => {}
                Err(e) => eprintln!("{e}"),
            }
        }
        let mut moved = false;
        if let Some(i) = self.grab {
            let drag = right * input.glass_drag.0 * per_pixel - away * input.glass_drag.1 * per_pixel;
            if drag != Vec3::ZERO {
                self.offsets[i] += drag;
                moved = true;
            }
        }
        if self.scene_playing {
            self.scene_time += self.frame_dt.unwrap_or(dt);
            // A glTF file's timeline loops, as Blender plays it.
            let scene = self.renderer.scene();
            let period = scene.duration();
            if !scene.animations.is_empty() && period > 0.0 && self.scene_time > period {
                self.scene_time = self.scene_time.rem_euclid(period);
            }
            moved = true;
        }
        if moved {
            self.place_objects();
        }
        let mut light = self.renderer.scene().lights[0].clone();
        light.position += offset;
        if self.animate {
            let turn = Quat::from_rotation_y(dt * std::f32::consts::TAU / ANIMATION_PERIOD_S);
            light.position = light.target + turn * (light.position - light.target);
        }
        if light.position != self.renderer.scene().lights[0].position {
            if self.set_light(light) {
                self.interacting = true;
            } else if self.animate {
                self.animate = false;
                eprintln!("light animation paused");
            }
        }
    }

    /// --script: this frame's scripted input (a camera orbit, a light drag, a key).
    pub(super) fn script_input(&mut self) -> Result<()> {
        let Some((verb, first)) = self.script.as_mut().and_then(|s| s.begin_frame()) else {
            return Ok(());
        };
        match verb {
            Verb::Orbit(deg) => self.orbit.rotate(deg.to_radians(), 0.0),
            Verb::Drag(dx, dy) => {
                self.input.light_drag.0 += dx;
                self.input.light_drag.1 += dy;
            }
            Verb::Key(action) if first => self.act(action)?,
            Verb::Click(fx, fy) => {
                let e = self.swapchain.as_ref().map_or(vk::Extent2D { width: 1, height: 1 }, |s| s.extent);
                let at = (fx as f64 * e.width as f64, fy as f64 * e.height as f64);
                // A click on the overlay's panel is the panel's, as a real one is.
                if !self.overlay.click(at, self.window.scale_factor() as f32) {
                    self.input.drop = Some(at);
                }
            }
            Verb::Drop(i) if first => {
                if let Some(path) = self.script.as_ref().map(|s| s.files[i].clone()) {
                    self.open_scene(&path)?;
                }
            }
            Verb::Key(_) | Verb::Drop(_) | Verb::Still => {}
        }
        Ok(())
    }
}
