//! Morph targets (glTF's blend shapes; Blender's shape keys): a mesh deformed by a weighted sum of per-vertex
//! displacements, p = p₀ + Σₖ wₖ·Δpₖ and n = normalize(n₀ + Σₖ wₖ·Δnₖ), with weights that stand still or follow
//! animation tracks. The renderer deforms the mesh on the GPU each frame whose weights changed and refits its BVH
//! there, as it does for water (glsl/morph.comp); the host evaluates the same formula ([`Morph::apply`]) for its own
//! copy and the CPU reference.

use super::animation::{Interpolation, Track};
use super::Mesh;
use glam::Vec3;

/// One morph target: a displacement per vertex of the mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphTarget {
    /// Position displacements, m (one per vertex).
    pub positions: Vec<Vec3>,
    /// Normal displacements (one per vertex), or empty: the target leaves the normals as they are.
    pub normals: Vec<Vec3>,
}

/// A mesh's morph targets and their weights over time.
#[derive(Clone, Debug, PartialEq)]
pub struct Morph {
    /// The targets, each with a displacement per vertex of the base mesh.
    pub targets: Vec<MorphTarget>,
    /// The weights where no track animates them (glTF: the node's `weights`, else the mesh's, else 0).
    pub weights: Vec<f32>,
    /// One track per target (all animated together, each holding its end values past its keyframes), or none:
    /// the weights stand still.
    pub tracks: Vec<Track<f32>>,
    /// The duration (s) of the animations that play (the scene's timeline, as glTF's other tracks have).
    pub period: f32,
}

impl Morph {
    /// Whether tracks animate the weights.
    pub fn is_animated(&self) -> bool {
        !self.tracks.is_empty()
    }

    /// Its animations' duration (s; 0 when the weights stand still).
    pub fn duration(&self) -> f32 {
        if self.is_animated() {
            self.period
        } else {
            0.0
        }
    }

    /// The weights at scene time `t` (s).
    pub fn weights_at(&self, t: f32) -> Vec<f32> {
        if self.tracks.is_empty() {
            return self.weights.clone();
        }
        self.tracks.iter().map(|k| k.at(t)).collect()
    }

    /// `base` deformed by `weights`: positions displaced, normals displaced and renormalized (left as they are
    /// where the sum vanishes).
    pub fn apply(&self, base: &Mesh, weights: &[f32]) -> Mesh {
        let mut m = base.clone();
        for (target, &w) in self.targets.iter().zip(weights) {
            if w == 0.0 {
                continue;
            }
            for (p, d) in m.positions.iter_mut().zip(&target.positions) {
                *p += w * *d;
            }
            for (n, d) in m.normals.iter_mut().zip(&target.normals) {
                *n += w * *d;
            }
        }
        for (n, n0) in m.normals.iter_mut().zip(&base.normals) {
            *n = n.try_normalize().unwrap_or(*n0);
        }
        m
    }

    /// Each target's weight range over time: its tracks' keyframe values (a cubic spline's overshoot included),
    /// or its still weight.
    pub fn weight_ranges(&self) -> Vec<(f32, f32)> {
        if self.tracks.is_empty() {
            return self.weights.iter().map(|&w| (w, w)).collect();
        }
        self.tracks
            .iter()
            .map(|k| {
                let mut lo = f32::INFINITY;
                let mut hi = f32::NEG_INFINITY;
                let mut see = |v: f32| {
                    lo = lo.min(v);
                    hi = hi.max(v);
                };
                k.values.iter().for_each(|&v| see(v));
                if k.interpolation == Interpolation::Cubic {
                    for w in k.times.windows(2) {
                        for s in 1..64 {
                            see(k.at(w[0] + (w[1] - w[0]) * s as f32 / 64.0));
                        }
                    }
                }
                (lo, hi)
            })
            .collect()
    }

    /// The object-space box `base` stays in whatever its weights do (within their ranges), padded by a part in
    /// 10⁵ of its size: the BVH refit's instance bounds.
    pub fn bounds(&self, base: &Mesh) -> (Vec3, Vec3) {
        let ranges = self.weight_ranges();
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        for (v, p) in base.positions.iter().enumerate() {
            let (mut a, mut b) = (*p, *p);
            for (target, &(w0, w1)) in self.targets.iter().zip(&ranges) {
                let d = target.positions[v];
                a += (d * w0).min(d * w1);
                b += (d * w0).max(d * w1);
            }
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let pad = (hi - lo).max_element() * 1e-5 + 1e-6;
        (lo - pad, hi + pad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> Mesh {
        Mesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Z],
            normals: vec![Vec3::Y; 3],
            indices: vec![0, 2, 1],
            uvs: Vec::new(),
        }
    }

    #[test]
    fn weights_blend_displacements_and_bound_them() {
        let base = tri();
        let up = MorphTarget { positions: vec![Vec3::Y, Vec3::ZERO, Vec3::ZERO], normals: Vec::new() };
        let side = MorphTarget { positions: vec![Vec3::ZERO, Vec3::X, Vec3::ZERO], normals: vec![Vec3::X; 3] };
        let m = Morph {
            targets: vec![up, side],
            weights: vec![0.0, 0.0],
            tracks: vec![
                Track::new(vec![0.0, 1.0], vec![0.0, 1.0], Interpolation::Linear),
                Track::new(vec![0.0, 1.0], vec![-0.5, 0.5], Interpolation::Linear),
            ],
            period: 1.0,
        };
        let w = m.weights_at(0.25);
        assert_eq!(w, vec![0.25, -0.25]);
        let d = m.apply(&base, &w);
        assert_eq!(d.positions[0], Vec3::new(0.0, 0.25, 0.0));
        assert_eq!(d.positions[1], Vec3::new(0.75, 0.0, 0.0));
        assert!((d.normals[0] - Vec3::new(-0.25, 1.0, 0.0).normalize()).length() < 1e-6);
        let (lo, hi) = m.bounds(&base);
        assert!(lo.x <= 0.5 && hi.x >= 1.5 && hi.y >= 1.0 && lo.y <= 0.0, "{lo} {hi}");
        assert!(hi.x < 1.5 + 1e-4 && hi.y < 1.0 + 1e-4, "tight: {lo} {hi}");
    }
}
