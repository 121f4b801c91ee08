//! Water: a height field over a rectangle, closed into a watertight block, displaced over time by a sum of
//! directional sine waves. The same formula runs on the GPU (glsl/water.comp, every frame) and here (the CPU
//! reference and the renderer's host copy), so any time of an animation can be checked.
//!
//! In object space the surface rests at y = 0 over [-x/2, x/2] × [-z/2, z/2] and the block's bottom at y = -depth.
//! At time t a surface point (x, z) rises to
//!
//! ```text
//! h(x, z, t) = Σ_i a_i · sin(k_i · (d_i · (x, z)) - ω_i · t),   k_i = 2π / λ_i,   ω_i = k_i · c_i
//! ```
//!
//! (amplitude a in m, wavelength λ in m, unit direction d in the xz plane, phase speed c in m/s) and its normal
//! is normalize(-∂h/∂x, 1, -∂h/∂z). The side walls' top edges follow the surface; their normals stay horizontal
//! and the bottom's stays -y. Which vertices move: those at y = 0 in object space (the surface, and the walls'
//! top edges); which normals follow the surface: those of the vertices at y = 0 whose rest normal is +y.

use super::mesh::Mesh;
use glam::{Vec2, Vec3};

/// One directional sine wave.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wave {
    /// Amplitude, m.
    pub amplitude: f32,
    /// Wavelength, m.
    pub wavelength: f32,
    /// Unit direction of travel in the xz plane (x, z).
    pub direction: Vec2,
    /// Phase speed, m/s.
    pub speed: f32,
}

impl Wave {
    /// Deep-water phase speed of a wave of `wavelength` m: sqrt(g·λ / 2π).
    pub fn deep_water_speed(wavelength: f32) -> f32 {
        (9.81 * wavelength / std::f32::consts::TAU).sqrt()
    }
}

/// The most waves a water object sums.
pub const MAX_WAVES: usize = 8;

/// The largest grid side (cells per side).
pub const MAX_GRID: u32 = 4096;

/// A water block: `grid`×`grid` cells over `size` (x, z) m, `depth` m deep, displaced by `waves`.
#[derive(Clone, Debug, PartialEq)]
pub struct Water {
    /// Extent in x and z, m.
    pub size: Vec2,
    /// Depth below the surface's rest height, m.
    pub depth: f32,
    /// Cells per side (1..=MAX_GRID).
    pub grid: u32,
    /// At most MAX_WAVES waves.
    pub waves: Vec<Wave>,
}

impl Water {
    /// The surface's height and its gradient (∂h/∂x, ∂h/∂z) at (x, z) and time t.
    pub fn height(&self, x: f32, z: f32, t: f32) -> (f32, Vec2) {
        let mut h = 0.0;
        let mut g = Vec2::ZERO;
        for w in &self.waves {
            let k = std::f32::consts::TAU / w.wavelength;
            let phase = k * (w.direction.x * x + w.direction.y * z) - k * w.speed * t;
            h += w.amplitude * phase.sin();
            g += w.direction * (w.amplitude * k * phase.cos());
        }
        (h, g)
    }

    /// The highest the surface can rise (and the lowest it can sink): Σ |a_i|.
    pub fn max_height(&self) -> f32 {
        self.waves.iter().map(|w| w.amplitude.abs()).sum()
    }

    /// Bounds of the block at any time, in object space.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let h = self.max_height();
        (
            Vec3::new(-self.size.x * 0.5, -self.depth.max(h), -self.size.y * 0.5),
            Vec3::new(self.size.x * 0.5, h, self.size.y * 0.5),
        )
    }

    /// The grid's coordinate `i` of `n` along an extent `s` (the surface and the walls use the same expression,
    /// so their shared vertices are the same floats, and the block stays watertight once displaced).
    fn coord(s: f32, i: u32, n: u32) -> f32 {
        -0.5 * s + s * (i as f32 / n as f32)
    }

    /// The block at rest: the surface at y = 0 ((grid + 1)² vertices, 2·grid² triangles), four walls and a
    /// bottom fanned from its center, counter-clockwise seen from outside.
    pub fn rest_mesh(&self) -> Mesh {
        let n = self.grid;
        let mut m = Mesh::default();
        let (sx, sz, d) = (self.size.x, self.size.y, self.depth);
        // Push a triangle so that it faces `out`.
        let tri = |m: &mut Mesh, a: u32, b: u32, c: u32, out: Vec3| {
            let (pa, pb, pc) = (m.positions[a as usize], m.positions[b as usize], m.positions[c as usize]);
            if (pb - pa).cross(pc - pa).dot(out) >= 0.0 {
                m.indices.extend_from_slice(&[a, b, c]);
            } else {
                m.indices.extend_from_slice(&[a, c, b]);
            }
        };
        // The surface.
        for j in 0..=n {
            for i in 0..=n {
                m.positions.push(Vec3::new(Self::coord(sx, i, n), 0.0, Self::coord(sz, j, n)));
                m.normals.push(Vec3::Y);
            }
        }
        let at = |i: u32, j: u32| j * (n + 1) + i;
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, e) = (at(i, j), at(i, j + 1), at(i + 1, j + 1), at(i + 1, j));
                tri(&mut m, a, b, c, Vec3::Y);
                tri(&mut m, a, c, e, Vec3::Y);
            }
        }
        // The boundary, once around: (x, z) of each of its 4n points.
        let mut ring = Vec::new();
        for i in 0..n {
            ring.push((Self::coord(sx, i, n), Self::coord(sz, 0, n), Vec3::NEG_Z));
        }
        for j in 0..n {
            ring.push((Self::coord(sx, n, n), Self::coord(sz, j, n), Vec3::X));
        }
        for i in (1..=n).rev() {
            ring.push((Self::coord(sx, i, n), Self::coord(sz, n, n), Vec3::Z));
        }
        for j in (1..=n).rev() {
            ring.push((Self::coord(sx, 0, n), Self::coord(sz, j, n), Vec3::NEG_X));
        }
        // The walls: one quad per boundary segment, its own vertices (horizontal normals).
        let k = ring.len();
        for s in 0..k {
            let (x0, z0, out) = ring[s];
            let (x1, z1, _) = ring[(s + 1) % k];
            let base = m.positions.len() as u32;
            for (x, y, z) in [(x0, 0.0, z0), (x0, -d, z0), (x1, -d, z1), (x1, 0.0, z1)] {
                m.positions.push(Vec3::new(x, y, z));
                m.normals.push(out);
            }
            tri(&mut m, base, base + 1, base + 2, out);
            tri(&mut m, base, base + 2, base + 3, out);
        }
        // The bottom: a fan from its center.
        let center = m.positions.len() as u32;
        m.positions.push(Vec3::new(0.0, -d, 0.0));
        m.normals.push(Vec3::NEG_Y);
        for &(x, z, _) in &ring {
            m.positions.push(Vec3::new(x, -d, z));
            m.normals.push(Vec3::NEG_Y);
        }
        for s in 0..k as u32 {
            tri(&mut m, center, center + 1 + s, center + 1 + (s + 1) % k as u32, Vec3::NEG_Y);
        }
        m
    }

    /// A vertex of the rest mesh at time t: (position, normal).
    pub fn displace(&self, p: Vec3, n: Vec3, t: f32) -> (Vec3, Vec3) {
        if p.y != 0.0 {
            return (p, n);
        }
        let (h, g) = self.height(p.x, p.z, t);
        let q = Vec3::new(p.x, h, p.z);
        if n == Vec3::Y {
            (q, Vec3::new(-g.x, 1.0, -g.y).normalize())
        } else {
            (q, n)
        }
    }

    /// The rest mesh `rest` displaced to time t.
    pub fn displaced(&self, rest: &Mesh, t: f32) -> Mesh {
        let mut m = rest.clone();
        for (p, n) in m.positions.iter_mut().zip(m.normals.iter_mut()) {
            (*p, *n) = self.displace(*p, *n, t);
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn water(grid: u32) -> Water {
        Water {
            size: Vec2::new(2.0, 1.0),
            depth: 0.3,
            grid,
            waves: vec![
                Wave { amplitude: 0.02, wavelength: 0.5, direction: Vec2::X, speed: 0.3 },
                Wave { amplitude: 0.01, wavelength: 0.3, direction: Vec2::new(0.6, 0.8), speed: 0.2 },
            ],
        }
    }

    #[test]
    fn the_block_is_closed_at_any_time() {
        let w = water(8);
        let rest = w.rest_mesh();
        assert_eq!(rest.triangle_count(), 2 * 64 + 2 * 32 + 32);
        for t in [0.0, 0.37, 5.0] {
            let m = w.displaced(&rest, t);
            // Every edge is shared by exactly two triangles, by position (the walls have their own vertices).
            let key = |p: Vec3| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
            let mut edges = std::collections::HashMap::new();
            for tri in m.indices.chunks_exact(3) {
                for e in 0..3 {
                    let (a, b) = (key(m.positions[tri[e] as usize]), key(m.positions[tri[(e + 1) % 3] as usize]));
                    *edges.entry(if a < b { (a, b) } else { (b, a) }).or_insert(0) += 1;
                }
            }
            assert!(edges.values().all(|&c| c == 2), "t = {t}: an edge is not shared by two triangles");
            // Outward: the enclosed volume is positive and equals the prism under the surface.
            let vol: f32 = m
                .indices
                .chunks_exact(3)
                .map(|t| {
                    let [a, b, c] = [0, 1, 2].map(|k| m.positions[t[k] as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!((vol / (2.0 * 1.0 * 0.3) - 1.0).abs() < 0.05, "t = {t}: volume {vol}");
        }
    }

    #[test]
    fn the_surface_normal_is_the_gradients() {
        let w = water(4);
        let (h, g) = w.height(0.3, -0.2, 1.1);
        let e = 1e-3;
        let dx = (w.height(0.3 + e, -0.2, 1.1).0 - w.height(0.3 - e, -0.2, 1.1).0) / (2.0 * e);
        let dz = (w.height(0.3, -0.2 + e, 1.1).0 - w.height(0.3, -0.2 - e, 1.1).0) / (2.0 * e);
        assert!((g - Vec2::new(dx, dz)).length() < 1e-2, "{g} against {dx}, {dz}");
        assert!(h.abs() <= w.max_height());
    }
}
