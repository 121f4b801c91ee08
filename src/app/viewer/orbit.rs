//! The viewer's camera: the scene's camera, orbited around its target and zoomed.

use caustics::scene::{Camera, Projection};
use glam::Vec3;

const MAX_PITCH: f32 = 89.0 * std::f32::consts::PI / 180.0;

pub struct Orbit {
    base: Camera,
    radius: f32,
    yaw: f32,
    pitch: f32,
    base_yaw: f32,
    base_pitch: f32,
    zoom: f32,
    /// Until the first drag the scene's camera is used as it is (exactly, up vector included).
    moved: bool,
}

impl Orbit {
    pub fn new(camera: &Camera) -> Self {
        let d = camera.position - camera.target;
        let radius = d.length().max(1e-4);
        let pitch = (d.y / radius).clamp(-1.0, 1.0).asin();
        // A camera straight above or below its target: orbit as if it leaned away from its up vector, so that
        // the first drag does not spin the image.
        let h = if d.x.hypot(d.z) > 1e-4 * radius { Vec3::new(d.x, 0.0, d.z) } else { -camera.up };
        let yaw = h.x.atan2(h.z);
        Orbit { base: camera.clone(), radius, yaw, pitch, base_yaw: yaw, base_pitch: pitch, zoom: 1.0, moved: false }
    }

    /// Follow the scene's camera where an animation moved it: exactly, until the user orbits; then about its new
    /// target, with its new projection.
    pub fn follow(&mut self, camera: &Camera) {
        if self.moved {
            self.base = camera.clone();
        } else {
            let zoom = self.zoom;
            *self = Orbit::new(camera);
            self.zoom = zoom;
        }
    }

    /// Rotate by `dx`, `dy` radians (yaw about the vertical axis, pitch).
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        if dx == 0.0 && dy == 0.0 {
            return;
        }
        self.moved = true;
        self.yaw -= dx;
        self.pitch = (self.pitch + dy).clamp(-MAX_PITCH, MAX_PITCH);
    }

    /// Zoom in (positive steps) or out.
    pub fn zoom(&mut self, steps: f32) {
        self.zoom = (self.zoom * 0.9f32.powf(steps)).clamp(0.02, 50.0);
    }

    pub fn reset(&mut self) {
        self.yaw = self.base_yaw;
        self.pitch = self.base_pitch;
        self.zoom = 1.0;
        self.moved = false;
    }

    pub fn camera(&self) -> Camera {
        let mut c = self.base.clone();
        let target = c.target;
        let (dir, up) = if self.moved {
            let (sy, cy) = self.yaw.sin_cos();
            let (sp, cp) = self.pitch.sin_cos();
            (Vec3::new(cp * sy, sp, cp * cy), Vec3::Y)
        } else {
            ((c.position - target) / self.radius, c.up)
        };
        c.up = up;
        match &mut c.projection {
            Projection::Perspective { .. } => c.position = target + dir * self.radius * self.zoom,
            Projection::Orthographic { half_height } => {
                *half_height *= self.zoom;
                c.position = target + dir * self.radius;
            }
        }
        c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam(position: Vec3, up: Vec3) -> Camera {
        Camera {
            name: "c".into(),
            projection: Projection::Perspective { fov: 0.7 },
            position,
            target: Vec3::ZERO,
            up,
            aspect: None,
        }
    }

    #[test]
    fn unmoved_is_the_scene_camera() {
        let c = cam(Vec3::new(1.6, 1.5, 2.2), Vec3::Y);
        let o = Orbit::new(&c);
        assert!((o.camera().position - c.position).length() < 1e-6);
    }

    #[test]
    fn first_drag_from_top_keeps_the_view_direction() {
        let c = cam(Vec3::new(0.0, 3.0, 0.0), Vec3::NEG_Z);
        let mut o = Orbit::new(&c);
        o.rotate(0.0, -0.01);
        let p = o.camera().position;
        // Leaning away from up (-z) means moving towards +z, so the image's up stays -z.
        assert!(p.z > 0.0 && p.x.abs() < 1e-6 && (p.length() - 3.0).abs() < 1e-4, "{p}");
    }
}
