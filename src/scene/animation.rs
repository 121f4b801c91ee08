//! Animation: an object's transform as a function of time, from TOML keyframes or glTF node animation channels
//! (its node's own and its animated ancestors'), and the tracks of glTF morph-target weights. The renderer and the
//! CPU reference evaluate the same [`Animation::transform_at`], so any frame of an animation can be checked against
//! the reference at its time.
//!
//! A transform is scale, then rotation, then translation (TRS), each its own track of keyframes: translation and
//! scale interpolate linearly, rotation by spherical linear interpolation along the shorter arc (`linear`); or they
//! hold each keyframe's value until the next (`step`); or they follow glTF's cubic Hermite spline with the
//! keyframes' in and out tangents (`cubic`, glTF only: TOML keyframes carry no tangents). Outside its keyframes'
//! times a track holds its first or last value (`clamp`, and always in glTF, as Blender holds an action's ends), or
//! a TOML object's animation repeats with the period of its own longest track (`loop`).

use glam::{Mat4, Quat, Vec3};

/// How a track's value goes from one keyframe to the next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Linear (translation, scale) and spherical linear (rotation).
    Linear,
    /// Each keyframe's value until the next one's time.
    Step,
    /// glTF's cubic Hermite spline through the keyframes with their in and out tangents.
    Cubic,
}

/// What the animation does past its last keyframe.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Repeat {
    /// Hold the first and last values.
    Clamp,
    /// Start again: time is taken modulo the animation's duration.
    Loop,
}

/// One component's keyframes: strictly increasing times (s), a value per keyframe (and, for cubic, an in and an
/// out tangent per keyframe, in value units per second).
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T> {
    /// Keyframe times, s, strictly increasing.
    pub times: Vec<f32>,
    /// The value at each keyframe.
    pub values: Vec<T>,
    /// Cubic only: (in tangent, out tangent) per keyframe.
    pub tangents: Vec<(T, T)>,
    /// How it goes from one keyframe to the next.
    pub interpolation: Interpolation,
}

/// Values a track can interpolate.
pub trait Animated: Copy {
    /// `a` to `b` at fraction `s` (slerp for rotations).
    fn lerp(a: Self, b: Self, s: f32) -> Self;
    /// The cubic Hermite spline from `p0` (out tangent `m0`) to `p1` (in tangent `m1`) over `dt` seconds, at
    /// fraction `s`.
    fn hermite(p0: Self, m0: Self, p1: Self, m1: Self, s: f32, dt: f32) -> Self;
}

fn hermite_weights(s: f32) -> [f32; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2]
}

impl Animated for Vec3 {
    fn lerp(a: Vec3, b: Vec3, s: f32) -> Vec3 {
        a.lerp(b, s)
    }
    fn hermite(p0: Vec3, m0: Vec3, p1: Vec3, m1: Vec3, s: f32, dt: f32) -> Vec3 {
        let w = hermite_weights(s);
        p0 * w[0] + m0 * (w[1] * dt) + p1 * w[2] + m1 * (w[3] * dt)
    }
}

impl Animated for f32 {
    fn lerp(a: f32, b: f32, s: f32) -> f32 {
        a + (b - a) * s
    }
    fn hermite(p0: f32, m0: f32, p1: f32, m1: f32, s: f32, dt: f32) -> f32 {
        let w = hermite_weights(s);
        p0 * w[0] + m0 * (w[1] * dt) + p1 * w[2] + m1 * (w[3] * dt)
    }
}

impl Animated for Quat {
    fn lerp(a: Quat, b: Quat, s: f32) -> Quat {
        // Along the shorter arc.
        let b = if a.dot(b) < 0.0 { -b } else { b };
        a.slerp(b, s).normalize()
    }
    fn hermite(p0: Quat, m0: Quat, p1: Quat, m1: Quat, s: f32, dt: f32) -> Quat {
        let w = hermite_weights(s);
        let v = glam::Vec4::from(p0) * w[0]
            + glam::Vec4::from(m0) * (w[1] * dt)
            + glam::Vec4::from(p1) * w[2]
            + glam::Vec4::from(m1) * (w[3] * dt);
        // glTF: the spline's value is normalized.
        Quat::from_vec4(v).normalize()
    }
}

impl<T: Animated> Track<T> {
    /// A track of `values` at `times`, with `interpolation` (and no tangents: not for cubic).
    pub fn new(times: Vec<f32>, values: Vec<T>, interpolation: Interpolation) -> Track<T> {
        Track { times, values, tangents: Vec::new(), interpolation }
    }

    /// The last keyframe's time.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Its value at time `t` (clamped to its keyframes).
    pub fn at(&self, t: f32) -> T {
        let n = self.times.len();
        // (NaN takes the first keyframe too.)
        if n == 1 || t.partial_cmp(&self.times[0]) != Some(std::cmp::Ordering::Greater) {
            return self.values[0];
        }
        if t >= self.times[n - 1] {
            return self.values[n - 1];
        }
        // The keyframe interval [k, k + 1] that holds t.
        let k = self.times.partition_point(|&x| x <= t) - 1;
        // At a keyframe's time, its value exactly (a pose written at that time must render the same).
        if t == self.times[k] {
            return self.values[k];
        }
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = ((t - t0) / dt).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => self.values[k],
            Interpolation::Linear => T::lerp(self.values[k], self.values[k + 1], s),
            Interpolation::Cubic => {
                T::hermite(self.values[k], self.tangents[k].1, self.values[k + 1], self.tangents[k + 1].0, s, dt)
            }
        }
    }
}

/// One node's own transform over time: up to three tracks, each replacing that component of its rest pose.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    /// Translation, m.
    pub translation: Option<Track<Vec3>>,
    /// Rotation, a unit quaternion.
    pub rotation: Option<Track<Quat>>,
    /// Scale per axis.
    pub scale: Option<Track<Vec3>>,
    /// The components no track animates: (translation, rotation, scale).
    pub rest: (Vec3, Quat, Vec3),
    /// Its transform when no track animates it: the rest pose's TRS, or a glTF node's `matrix` exactly (shear and
    /// all; glTF only animates nodes written as TRS).
    pub still: Mat4,
}

impl Motion {
    /// A node that stands still at `rest` (translation, rotation, scale).
    pub fn rest(rest: (Vec3, Quat, Vec3)) -> Motion {
        Motion {
            translation: None,
            rotation: None,
            scale: None,
            rest,
            still: Mat4::from_scale_rotation_translation(rest.2, rest.1, rest.0),
        }
    }

    /// Whether a track animates it.
    pub fn is_animated(&self) -> bool {
        self.translation.is_some() || self.rotation.is_some() || self.scale.is_some()
    }

    /// Its longest track's last keyframe time (s; 0 when it stands still).
    pub fn end(&self) -> f32 {
        let ends = [
            self.translation.as_ref().map(Track::end),
            self.rotation.as_ref().map(Track::end),
            self.scale.as_ref().map(Track::end),
        ];
        ends.into_iter().flatten().fold(0.0, f32::max)
    }

    /// Its own transform (parent space from its space) at time `t` (s), clamped to its keyframes.
    pub fn local_at(&self, t: f32) -> Mat4 {
        if !self.is_animated() {
            return self.still;
        }
        let tr = self.translation.as_ref().map_or(self.rest.0, |k| k.at(t));
        let rot = self.rotation.as_ref().map_or(self.rest.1, |k| k.at(t));
        let sc = self.scale.as_ref().map_or(self.rest.2, |k| k.at(t));
        Mat4::from_scale_rotation_translation(sc, rot, tr)
    }
}

/// An object's transform over time: its own node's [`Motion`] under those of its ancestors up to the outermost
/// that animates (a glTF node hierarchy; a TOML object is a chain of one), under a parent placement that stands
/// still.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// The nodes from the outermost animated ancestor down to the object's own, outermost first.
    pub chain: Vec<Motion>,
    /// World from the outermost chain node's parent space (the identity in TOML).
    pub parent: Mat4,
    /// Past the period: clamp or loop.
    pub repeat: Repeat,
    /// Its duration (s), the loop's period: in TOML the object's last keyframe time; in glTF the last keyframe time
    /// of all the animations that play (the scene's timeline, which the viewer loops over).
    pub period: f32,
}

impl Animation {
    /// A chain of one node (TOML keyframes) that loops, if it does, with its own last keyframe time.
    pub fn single(motion: Motion, repeat: Repeat) -> Animation {
        let period = motion.end();
        Animation { chain: vec![motion], parent: Mat4::IDENTITY, repeat, period }
    }

    /// The loop's period (s): its animation's duration.
    pub fn duration(&self) -> f32 {
        self.period
    }

    /// The time (s) its tracks are read at for scene time `t`.
    pub fn local_time(&self, t: f32) -> f32 {
        match self.repeat {
            Repeat::Loop if self.period > 0.0 => t.rem_euclid(self.period),
            _ => t,
        }
    }

    /// Object → world at time `t` (s).
    pub fn transform_at(&self, t: f32) -> Mat4 {
        let t = self.local_time(t);
        self.chain.iter().fold(self.parent, |m, node| m * node.local_at(t))
    }
}

/// A TOML rotation: degrees about x, then y, then z.
pub fn euler_deg(r: Vec3) -> Quat {
    Quat::from_euler(glam::EulerRot::ZYX, r.z.to_radians(), r.y.to_radians(), r.x.to_radians())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn track(interpolation: Interpolation) -> Track<Vec3> {
        Track::new(vec![0.0, 1.0, 3.0], vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 2.0, 0.0)], interpolation)
    }

    #[test]
    fn tracks_interpolate_clamp_and_step() {
        let t = track(Interpolation::Linear);
        assert_eq!(t.at(-1.0), Vec3::ZERO);
        assert_eq!(t.at(0.5), Vec3::new(0.5, 0.0, 0.0));
        assert_eq!(t.at(2.0), Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(t.at(9.0), Vec3::new(1.0, 2.0, 0.0));
        let s = track(Interpolation::Step);
        assert_eq!(s.at(0.99), Vec3::ZERO);
        assert_eq!(s.at(1.0), Vec3::X);
    }

    #[test]
    fn rotation_takes_the_shorter_arc_and_loops() {
        let q0 = Quat::IDENTITY;
        // The same 90° turn about y, given as its negated quaternion.
        let q1 = -Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let a = Animation::single(
            Motion {
                rotation: Some(Track::new(vec![0.0, 2.0], vec![q0, q1], Interpolation::Linear)),
                ..Motion::rest((Vec3::new(0.0, 1.0, 0.0), Quat::IDENTITY, Vec3::ONE))
            },
            Repeat::Loop,
        );
        let half = a.transform_at(1.0).transform_vector3(Vec3::X);
        let expect = Quat::from_rotation_y(std::f32::consts::FRAC_PI_4) * Vec3::X;
        assert!((half - expect).length() < 1e-5, "{half} against {expect}");
        // Looping: t = 3 is t = 1.
        assert!(a.transform_at(3.0).abs_diff_eq(a.transform_at(1.0), 1e-6));
        assert_eq!(a.transform_at(0.0).w_axis.truncate(), Vec3::new(0.0, 1.0, 0.0));
    }

    #[test]
    fn cubic_passes_through_its_keyframes_with_their_tangents() {
        let mut t = track(Interpolation::Cubic);
        t.tangents = vec![(Vec3::ZERO, Vec3::X); 3];
        assert!((t.at(1.0) - Vec3::X).length() < 1e-6);
        // Slope at the start of [0, 1] is the out tangent.
        let e = 1e-3;
        let slope = (t.at(e) - t.at(0.0)) / e;
        assert!((slope - Vec3::X).length() < 1e-2, "{slope}");
    }
}
