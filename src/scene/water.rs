//! Water: a height field over a rectangle, closed into a watertight block, displaced over time by a sum of
//! directional sine waves and, where the scene asks, a simulated surface: the damped wave equation stepped on the
//! grid's nodes, disturbed by drops and by the objects that move through it ([`Simulation`]). The same formulas
//! run on the GPU (glsl/water.comp and glsl/water_step.comp, every frame) and here (the CPU reference), so any time
//! of an animation can be checked.
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

/// A water block: `grid`×`grid` cells over `size` (x, z) m, `depth` m deep, displaced by `waves` and by its
/// `simulation` when it has one.
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
    /// The simulated surface, added to the waves.
    pub simulation: Option<Simulation>,
}

/// A drop: at `time` s the surface at (x, z) = `at` (object space, m) sinks by `depth` m at its center, in a
/// raised-cosine dimple of `radius` m, depth · (1 + cos(π r / radius)) / 2, at rest (the height and the height
/// one step before both change).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Drop {
    /// When it lands, s.
    pub time: f32,
    /// Where, (x, z) in the water's object space, m.
    pub at: Vec2,
    /// The dimple's radius, m.
    pub radius: f32,
    /// How far its center sinks, m.
    pub depth: f32,
}

/// A simulated surface: the damped wave equation
///
/// ```text
/// ∂²h/∂t² = c² ∇²h − γ ∂h/∂t
/// ```
///
/// on the grid's (grid + 1)² nodes, stepped `rate` times a second by the explicit leapfrog scheme
///
/// ```text
/// h⁺ = h + (1 − γ Δt)(h − h⁻) + Cx (h_e + h_w − 2h) + Cz (h_n + h_s − 2h),   Cx = (c Δt / Δx)², Cz = (c Δt / Δz)²
/// ```
///
/// which is stable while Cx + Cz ≤ 1 ([`Simulation::rate`] keeps it at most 1/2: a Courant number
/// c Δt √(1/Δx² + 1/Δz²) of at most 0.7). The walls reflect: a node
/// outside the grid mirrors the one inside (∂h/∂n = 0). Heights are held within ±`limit` m, the bound the light
/// views and the BVH's bounds rely on. Before each step the drops whose time falls in it are added, and each
/// moving body adds to every node the change of its submerged length in that node's column (the volume it takes
/// from the column rises on top of it; the wave equation spreads it as a ring).
#[derive(Clone, Debug, PartialEq)]
pub struct Simulation {
    /// c, m/s.
    pub speed: f32,
    /// γ, 1/s.
    pub damping: f32,
    /// The largest |h|, m.
    pub limit: f32,
    /// Scripted drops, in time order.
    pub drops: Vec<Drop>,
}

/// A moving body as the water sees it: a sphere in the water's object space (center, radius m) at the start and
/// at the end of a step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// At the step's start.
    pub from: (Vec3, f32),
    /// At its end.
    pub to: (Vec3, f32),
}

/// The most bodies that disturb one water object in a step (the first ones found in the scene's order).
pub const MAX_BODIES: usize = 2;

/// A sphere around `mesh`: (center, radius), about its box's center.
pub fn bounding_sphere(mesh: &Mesh) -> (Vec3, f32) {
    let (lo, hi) = mesh.bounds();
    let c = (lo + hi) * 0.5;
    (c, mesh.positions.iter().map(|p| (*p - c).length()).fold(0.0, f32::max))
}

/// Sphere `(c, r)` placed by `m` (a sphere around what it bounds, placed).
pub fn place_sphere((c, r): (Vec3, f32), m: glam::Mat4) -> (Vec3, f32) {
    (m.transform_point3(c), r * max_scale(m))
}

/// The largest factor by which `m` stretches a length.
fn max_scale(m: glam::Mat4) -> f32 {
    m.x_axis.truncate().length().max(m.y_axis.truncate().length()).max(m.z_axis.truncate().length())
}

/// The bodies that disturb `water` during a step: of the world-space spheres `moving` (at the step's start and
/// end), the first [`MAX_BODIES`] that reach into the block at either end, in the water's object space
/// (`object_from_world`, the inverse of its placement).
pub fn bodies_in(
    water: &Water,
    object_from_world: glam::Mat4,
    moving: impl Iterator<Item = ((Vec3, f32), (Vec3, f32))>,
) -> Vec<Body> {
    let s = max_scale(object_from_world);
    let local = |(c, r): (Vec3, f32)| (object_from_world.transform_point3(c), r * s);
    let reaches = |(c, r): (Vec3, f32)| {
        c.x.abs() < water.size.x * 0.5 + r && c.z.abs() < water.size.y * 0.5 + r && c.y < r && c.y > -water.depth - r
    };
    moving
        .map(|(a, b)| Body { from: local(a), to: local(b) })
        .filter(|b| b.from != b.to && (reaches(b.from) || reaches(b.to)))
        .take(MAX_BODIES)
        .collect()
}

/// The coefficients of one simulation's step, computed once on the host for the CPU and the GPU alike.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepCoefficients {
    /// Nodes per side (grid + 1).
    pub nodes: u32,
    /// Steps per second.
    pub rate: u32,
    /// 1 − γ Δt.
    pub keep: f32,
    /// (c Δt / Δx)².
    pub cx: f32,
    /// (c Δt / Δz)².
    pub cz: f32,
    /// The largest |h|, m.
    pub limit: f32,
    /// Node spacing in x and z, m.
    pub dx: f32,
    /// See `dx`.
    pub dz: f32,
    /// The water's depth below the rest surface, m (where a body's column ends).
    pub depth: f32,
}

/// The submerged length of sphere (c, r) in the water column at (x, z): its chord there, cut to [−depth, 0].
pub fn column_length(x: f32, z: f32, (c, r): (Vec3, f32), depth: f32) -> f32 {
    let d2 = (x - c.x) * (x - c.x) + (z - c.z) * (z - c.z);
    let s2 = r * r - d2;
    if s2 <= 0.0 {
        return 0.0;
    }
    let s = s2.sqrt();
    ((c.y + s).min(0.0) - (c.y - s).max(-depth)).max(0.0)
}

/// A drop's dimple at (x, z): −depth · (1 + cos(π r / radius)) / 2 within its radius.
pub fn drop_height(x: f32, z: f32, d: &Drop) -> f32 {
    let r = ((x - d.at.x) * (x - d.at.x) + (z - d.at.y) * (z - d.at.y)).sqrt();
    if r >= d.radius {
        return 0.0;
    }
    -d.depth * 0.5 * (1.0 + (std::f32::consts::PI * r / d.radius).cos())
}

/// The state of a simulated surface: its heights now and one step before, on (grid + 1)² nodes (row-major in z,
/// then x), after `steps` steps.
#[derive(Clone, Debug, PartialEq)]
pub struct HeightField {
    /// Its step.
    pub k: StepCoefficients,
    /// Heights now, m.
    pub h: Vec<f32>,
    /// Heights one step before, m.
    pub prev: Vec<f32>,
    /// Steps taken since rest.
    pub steps: u64,
}

impl HeightField {
    /// At rest.
    pub fn new(k: StepCoefficients) -> Self {
        let n = (k.nodes * k.nodes) as usize;
        HeightField { k, h: vec![0.0; n], prev: vec![0.0; n], steps: 0 }
    }

    /// Node (i, j)'s object-space (x, z).
    pub fn node_xz(&self, i: u32, j: u32, size: Vec2) -> (f32, f32) {
        let n = self.k.nodes - 1;
        (Water::coord(size.x, i, n), Water::coord(size.y, j, n))
    }

    /// Add a drop to both the heights and the heights before (it lands at rest).
    pub fn add_drop(&mut self, d: &Drop, size: Vec2) {
        for j in 0..self.k.nodes {
            for i in 0..self.k.nodes {
                let (x, z) = self.node_xz(i, j, size);
                let b = drop_height(x, z, d);
                let at = (j * self.k.nodes + i) as usize;
                self.h[at] = (self.h[at] + b).clamp(-self.k.limit, self.k.limit);
                self.prev[at] = (self.prev[at] + b).clamp(-self.k.limit, self.k.limit);
            }
        }
    }

    /// One step, with `bodies` moving through the water during it.
    pub fn step(&mut self, bodies: &[Body], size: Vec2) {
        let k = self.k;
        let n = k.nodes;
        let at = |i: u32, j: u32| (j * n + i) as usize;
        // The mirror of a node outside the grid (a grid of one node is still).
        let m = |i: i64| -> u32 {
            let last = n as i64 - 1;
            (if i < 0 {
                -i
            } else if i > last {
                2 * last - i
            } else {
                i
            })
            .clamp(0, last) as u32
        };
        let mut next = vec![0.0; self.h.len()];
        for j in 0..n {
            for i in 0..n {
                let (ii, jj) = (i as i64, j as i64);
                let h = self.h[at(i, j)];
                let lap_x = self.h[at(m(ii + 1), j)] + self.h[at(m(ii - 1), j)] - 2.0 * h;
                let lap_z = self.h[at(i, m(jj + 1))] + self.h[at(i, m(jj - 1))] - 2.0 * h;
                let mut v = h + k.keep * (h - self.prev[at(i, j)]) + k.cx * lap_x + k.cz * lap_z;
                let (x, z) = self.node_xz(i, j, size);
                for b in bodies {
                    v += column_length(x, z, b.to, k.depth) - column_length(x, z, b.from, k.depth);
                }
                next[at(i, j)] = v.clamp(-k.limit, k.limit);
            }
        }
        self.prev = std::mem::replace(&mut self.h, next);
        self.steps += 1;
    }

    /// The height at node (i, j) and its gradient (∂h/∂x, ∂h/∂z) by central differences (zero across a wall).
    pub fn at(&self, i: u32, j: u32) -> (f32, Vec2) {
        let n = self.k.nodes;
        let h = |i: u32, j: u32| self.h[(j * n + i) as usize];
        let gx = if i == 0 || i + 1 >= n { 0.0 } else { (h(i + 1, j) - h(i - 1, j)) / (2.0 * self.k.dx) };
        let gz = if j == 0 || j + 1 >= n { 0.0 } else { (h(i, j + 1) - h(i, j - 1)) / (2.0 * self.k.dz) };
        (h(i, j), Vec2::new(gx, gz))
    }
}

impl Simulation {
    /// Steps per second for `water`: at least 60, and enough that its Courant number stays at most 0.7.
    pub fn rate(&self, water: &Water) -> u32 {
        let (dx, dz) = water.spacing();
        let need = self.speed * (1.0 / (dx * dx) + 1.0 / (dz * dz)).sqrt() / 0.7;
        (need.ceil() as u32).max(60)
    }

    /// The steps taken by time `t` s (none before 0).
    pub fn steps_at(rate: u32, t: f32) -> u64 {
        if t <= 0.0 {
            0
        } else {
            (t as f64 * rate as f64 + 1e-6).floor() as u64
        }
    }

    /// The drops that land in step `s` (between its start and its end).
    pub fn drops_in(&self, rate: u32, s: u64) -> impl Iterator<Item = &Drop> {
        self.drops.iter().filter(move |d| Self::steps_at(rate, d.time) == s)
    }
}

impl Water {
    /// Node spacing (x, z), m.
    pub fn spacing(&self) -> (f32, f32) {
        (self.size.x / self.grid as f32, self.size.y / self.grid as f32)
    }

    /// The coefficients of its simulation's step (None without one).
    pub fn step_coefficients(&self) -> Option<StepCoefficients> {
        let sim = self.simulation.as_ref()?;
        let rate = sim.rate(self);
        let dt = 1.0 / rate as f32;
        let (dx, dz) = self.spacing();
        let c = |d: f32| (sim.speed * dt / d) * (sim.speed * dt / d);
        Some(StepCoefficients {
            nodes: self.grid + 1,
            rate,
            keep: 1.0 - sim.damping * dt,
            cx: c(dx),
            cz: c(dz),
            limit: sim.limit,
            dx,
            dz,
            depth: self.depth,
        })
    }

    /// Its simulated surface at time `t`: stepped from rest, with its drops and with `bodies(t0, t1)` moving
    /// through it during each step from t0 to t1 (None without a simulation).
    pub fn simulate(&self, t: f32, bodies: &dyn Fn(f32, f32) -> Vec<Body>) -> Option<HeightField> {
        let sim = self.simulation.as_ref()?;
        let mut f = HeightField::new(self.step_coefficients()?);
        let rate = f.k.rate;
        for s in 0..Simulation::steps_at(rate, t) {
            for d in sim.drops_in(rate, s) {
                f.add_drop(d, self.size);
            }
            let (t0, t1) = (s as f32 / rate as f32, (s + 1) as f32 / rate as f32);
            f.step(&bodies(t0, t1), self.size);
        }
        Some(f)
    }

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

    /// The highest the surface can rise (and the lowest it can sink): Σ |a_i|, and the simulation's limit.
    pub fn max_height(&self) -> f32 {
        let sim = self.simulation.as_ref().map_or(0.0, |s| s.limit);
        self.waves.iter().map(|w| w.amplitude.abs()).sum::<f32>() + sim
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

    /// The grid node nearest (x, z).
    fn node(&self, x: f32, z: f32) -> (u32, u32) {
        let f = |v: f32, s: f32| ((v / s + 0.5) * self.grid as f32).round().clamp(0.0, self.grid as f32) as u32;
        (f(x, self.size.x), f(z, self.size.y))
    }

    /// A vertex of the rest mesh at time t: (position, normal), with the simulated surface `field` added.
    pub fn displace(&self, p: Vec3, n: Vec3, t: f32, field: Option<&HeightField>) -> (Vec3, Vec3) {
        if p.y != 0.0 {
            return (p, n);
        }
        let (mut h, mut g) = self.height(p.x, p.z, t);
        if let Some(f) = field {
            let (i, j) = self.node(p.x, p.z);
            let (fh, fg) = f.at(i, j);
            h += fh;
            g += fg;
        }
        let q = Vec3::new(p.x, h, p.z);
        if n == Vec3::Y {
            (q, Vec3::new(-g.x, 1.0, -g.y).normalize())
        } else {
            (q, n)
        }
    }

    /// The rest mesh `rest` displaced to time t, with the simulated surface `field` added.
    pub fn displaced(&self, rest: &Mesh, t: f32, field: Option<&HeightField>) -> Mesh {
        let mut m = rest.clone();
        for (p, n) in m.positions.iter_mut().zip(m.normals.iter_mut()) {
            (*p, *n) = self.displace(*p, *n, t, field);
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
            simulation: None,
        }
    }

    #[test]
    fn the_block_is_closed_at_any_time() {
        let w = water(8);
        let rest = w.rest_mesh();
        assert_eq!(rest.triangle_count(), 2 * 64 + 2 * 32 + 32);
        // No texture coordinates: glsl/water.comp's BVH gather writes zeros in their lanes.
        assert!(rest.uvs.is_empty());
        for t in [0.0, 0.37, 5.0] {
            let m = w.displaced(&rest, t, None);
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
