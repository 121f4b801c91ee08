//! Smooth-dielectric optics: Snell refraction, exact unpolarized Fresnel reflectance, total internal reflection.
//!
//! Conventions: `d` is the unit propagation direction, `n` the unit normal on the side the light comes from
//! (`d · n < 0`), `cos_i = −d · n > 0`, and `eta = n1 / n2` (incident over transmitted index).

use glam::DVec3;

/// The outcome of the Fresnel equations at one interface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fresnel {
    /// Reflectance for unpolarized light, (R_s + R_p) / 2, in [0, 1]. 1 under total internal reflection.
    pub reflectance: f64,
    /// Cosine of the refraction angle; `None` under total internal reflection.
    pub cos_t: Option<f64>,
}

/// Exact dielectric Fresnel reflectance for unpolarized light (no absorption).
///
/// r_s = (n1 cos_i − n2 cos_t) / (n1 cos_i + n2 cos_t), r_p = (n2 cos_i − n1 cos_t) / (n2 cos_i + n1 cos_t),
/// both divided through by n2 here, and R = (r_s² + r_p²) / 2.
pub fn fresnel(cos_i: f64, eta: f64) -> Fresnel {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return Fresnel { reflectance: 1.0, cos_t: None };
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    Fresnel { reflectance: (0.5 * (rs * rs + rp * rp)).clamp(0.0, 1.0), cos_t: Some(cos_t) }
}

/// Mirror reflection of `d` about `n`.
pub fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - 2.0 * d.dot(n) * n
}

/// Snell refraction of `d` through a surface with normal `n` (on the incident side), given `cos_i = −d · n` and
/// the `cos_t` from [`fresnel`]. The result is a unit vector when `d` and `n` are.
pub fn refract(d: DVec3, n: DVec3, eta: f64, cos_i: f64, cos_t: f64) -> DVec3 {
    eta * d + (eta * cos_i - cos_t) * n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflectance() {
        // ((n − 1) / (n + 1))² from either side.
        let f = fresnel(1.0, 1.0 / 1.5);
        assert!((f.reflectance - 0.04).abs() < 1e-12, "{f:?}");
        let f = fresnel(1.0, 1.5);
        assert!((f.reflectance - 0.04).abs() < 1e-12, "{f:?}");
    }

    #[test]
    fn brewster_angle_has_no_p_reflection() {
        // At Brewster's angle tan θ_B = n2/n1, r_p = 0, so R = r_s² / 2.
        let theta = 1.5f64.atan();
        let f = fresnel(theta.cos(), 1.0 / 1.5);
        let cos_t = f.cos_t.unwrap();
        let rs = (theta.cos() / 1.5 - cos_t) / (theta.cos() / 1.5 + cos_t);
        assert!((f.reflectance - 0.5 * rs * rs).abs() < 1e-12);
        assert!((theta + cos_t.acos() - std::f64::consts::FRAC_PI_2).abs() < 1e-12, "θi + θt = 90° at Brewster");
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let critical = (1.0f64 / 1.5).asin();
        let below = fresnel((critical - 1e-6).cos(), 1.5);
        assert!(below.cos_t.is_some() && below.reflectance < 1.0);
        let above = fresnel((critical + 1e-6).cos(), 1.5);
        assert_eq!(above, Fresnel { reflectance: 1.0, cos_t: None });
    }

    #[test]
    fn refraction_obeys_snell_and_stays_unit() {
        let n = DVec3::Y;
        for deg in [0.0f64, 10.0, 45.0, 80.0] {
            let th = deg.to_radians();
            let d = DVec3::new(th.sin(), -th.cos(), 0.0);
            let eta = 1.0 / 2.4;
            let f = fresnel(-d.dot(n), eta);
            let t = refract(d, n, eta, -d.dot(n), f.cos_t.unwrap());
            assert!((t.length() - 1.0).abs() < 1e-12);
            let sin_t = t.x;
            assert!((th.sin() - 2.4 * sin_t).abs() < 1e-12, "Snell at {deg}°");
            assert!(t.y < 0.0);
        }
        let r = reflect(DVec3::new(0.6, -0.8, 0.0), n);
        assert!((r - DVec3::new(0.6, 0.8, 0.0)).length() < 1e-15);
    }
}
