//! Photon emission: a counter-based random number generator and stratified (jittered-grid) sampling of spot
//! cones and directional beams.
//!
//! Every photon's random numbers depend only on (seed, light, photon index), never on which thread traces it,
//! so a run is bit-identical for any thread count.

use glam::DVec3;

/// SplitMix64's finalizer: a bijective 64-bit mix.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A counter-based stream: SplitMix64 seeded from a hash of (seed, stream, index).
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
}

impl Rng {
    pub fn new(seed: u64, stream: u64, index: u64) -> Self {
        Rng { state: mix64(seed ^ mix64(stream.wrapping_add(0x6a09_e667_f3bc_c909) ^ mix64(index))) }
    }

    pub fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        mix64(self.state)
    }

    /// Uniform in [0, 1), 53 bits.
    pub fn next_f64(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// An equal-area stratification of [0, 1)² into exactly `n` cells: `rows` rows in u, row r holding k_r cells in v,
/// with row heights k_r / n, so every cell has area 1/n whatever n is.
#[derive(Clone, Copy, Debug)]
pub struct Strata {
    n: u64,
    rows: u64,
}

impl Strata {
    pub fn new(n: u64) -> Self {
        let rows = ((n as f64).sqrt().ceil() as u64).clamp(1, n.max(1));
        Strata { n: n.max(1), rows }
    }

    fn row_start(&self, r: u64) -> u64 {
        ((r as u128 * self.n as u128) / self.rows as u128) as u64
    }

    /// The point of cell `i` at offset (ju, jv) ∈ [0, 1)² inside the cell.
    pub fn point(&self, i: u64, ju: f64, jv: f64) -> (f64, f64) {
        // The row of i: the largest r with floor(r·n / rows) <= i.
        let r = ((i as u128 + 1) * self.rows as u128).div_ceil(self.n as u128) as u64 - 1;
        let (s0, s1) = (self.row_start(r), self.row_start(r + 1));
        debug_assert!(s0 <= i && i < s1, "stratum row of {i}");
        let k = (s1 - s0) as f64;
        let u = (s0 as f64 + ju * k) / self.n as f64;
        let v = ((i - s0) as f64 + jv) / k;
        (u.min(1.0), v.min(1.0))
    }
}

/// An orthonormal frame around `w`.
pub fn frame(w: DVec3) -> (DVec3, DVec3) {
    let hint = if w.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = hint.cross(w).normalize();
    (u, w.cross(u))
}

/// Where photons leave a light: a cone of directions (spot) or a rectangle of a parallel beam (directional).
#[derive(Clone, Copy, Debug)]
pub enum Emission {
    Cone {
        origin: DVec3,
        /// Sampling frame: `axis` is the cone's axis.
        u: DVec3,
        v: DVec3,
        axis: DVec3,
        cos_half: f64,
        /// The light's own cone: directions outside it carry nothing.
        spot_axis: DVec3,
        cos_spot: f64,
        /// A sphere light's radius (0: a point): each ray starts at a point of the sphere's disk across its
        /// direction, uniform in area (the rays of one direction leaving a sphere of uniform radiance).
        radius: f64,
    },
    Beam {
        /// The beam rectangle's corner, on a plane in front of all geometry.
        corner: DVec3,
        /// Edges of the rectangle (u → columns, v → rows).
        eu: DVec3,
        ev: DVec3,
        dir: DVec3,
        /// A sun's angular radius, radians (0: parallel rays): its directions are uniform in solid angle within
        /// this cone around `dir` (the cos θ that weighs each across the rectangle, within 1 − cos of 1, is left
        /// out: 4e-5 for 1°).
        radius: f64,
    },
}

impl Emission {
    /// The sampled measure: solid angle (sr) of the cone, or area (m²) of the beam rectangle.
    pub fn measure(&self) -> f64 {
        match *self {
            Emission::Cone { cos_half, .. } => 2.0 * std::f64::consts::PI * (1.0 - cos_half),
            Emission::Beam { eu, ev, .. } => eu.length() * ev.length(),
        }
    }

    /// A sun: its directions take a point of their own.
    pub fn has_size(&self) -> bool {
        match *self {
            Emission::Beam { radius, .. } | Emission::Cone { radius, .. } => radius > 0.0,
        }
    }

    /// The ray for a point (a, b) ∈ [0, 1)² of the stratified domain, uniform in solid angle (cone) or in area
    /// (beam), and (c, d) ∈ [0, 1)² for a sun's direction; `None` when the direction falls outside the spot cone.
    pub fn ray(&self, a: f64, b: f64, c: f64, d_: f64) -> Option<(DVec3, DVec3)> {
        match *self {
            Emission::Cone { origin, u, v, axis, cos_half, spot_axis, cos_spot, radius } => {
                // (cos θ, φ) parametrization: cos θ uniform in [cos_half, 1] is uniform in solid angle.
                let cos_t = 1.0 - a * (1.0 - cos_half);
                let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                let phi = 2.0 * std::f64::consts::PI * b;
                let d = (u * (sin_t * phi.cos()) + v * (sin_t * phi.sin()) + axis * cos_t).normalize();
                let mut o = origin;
                if radius > 0.0 {
                    let (e1, e2) = frame(d);
                    let (r, t) = (radius * c.sqrt(), 2.0 * std::f64::consts::PI * d_);
                    o += e1 * (r * t.cos()) + e2 * (r * t.sin());
                }
                (d.dot(spot_axis) >= cos_spot).then_some((o, d))
            }
            Emission::Beam { corner, eu, ev, dir, radius } => {
                let dir = if radius > 0.0 {
                    let cos_t = 1.0 - c * (1.0 - radius.cos());
                    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
                    let phi = 2.0 * std::f64::consts::PI * d_;
                    let (u, v) = (eu.normalize(), ev.normalize());
                    (u * (sin_t * phi.cos()) + v * (sin_t * phi.sin()) + dir * cos_t).normalize()
                } else {
                    dir
                };
                Some((corner + eu * b + ev * a, dir))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_cover_the_square_once() {
        for n in [1u64, 2, 3, 7, 10, 99, 1000, 1001] {
            let s = Strata::new(n);
            let mut area = 0.0;
            for i in 0..n {
                let (u0, v0) = s.point(i, 0.0, 0.0);
                let (u1, v1) = s.point(i, 1.0, 1.0);
                assert!(u0 >= 0.0 && u1 <= 1.0 && v0 >= 0.0 && v1 <= 1.0 && u1 > u0 && v1 > v0);
                area += (u1 - u0) * (v1 - v0);
                assert!(((u1 - u0) * (v1 - v0) * n as f64 - 1.0).abs() < 1e-9, "cell {i} of {n} is not 1/n");
            }
            assert!((area - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn rng_is_a_function_of_its_counter() {
        let a: Vec<u64> = (0..4).map(|_| Rng::new(7, 1, 42).next_u64()).collect();
        assert!(a.iter().all(|&x| x == a[0]));
        assert_ne!(Rng::new(7, 1, 42).next_u64(), Rng::new(7, 1, 43).next_u64());
        assert_ne!(Rng::new(7, 1, 42).next_u64(), Rng::new(8, 1, 42).next_u64());
        let mut r = Rng::new(1, 0, 0);
        let mean = (0..100_000).map(|_| r.next_f64()).sum::<f64>() / 100_000.0;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }

    #[test]
    fn cone_directions_stay_in_the_cone() {
        let axis = DVec3::new(0.3, -1.0, 0.1).normalize();
        let (u, v) = frame(axis);
        let cos_half = 10f64.to_radians().cos();
        let e = Emission::Cone {
            origin: DVec3::ZERO,
            u,
            v,
            axis,
            cos_half,
            spot_axis: DVec3::NEG_Y,
            cos_spot: 40f64.to_radians().cos(),
            radius: 0.0,
        };
        let s = Strata::new(1000);
        for i in 0..1000 {
            let (a, b) = s.point(i, 0.5, 0.5);
            let (_, d) = e.ray(a, b, 0.0, 0.0).unwrap();
            assert!(d.dot(axis) >= cos_half - 1e-12);
        }
    }
}
