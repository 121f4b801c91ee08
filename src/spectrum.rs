//! Spectral photons (docs/design.md "Color"): the wavelengths a photon of dispersive glass samples, the CIE 1931
//! observer that turns its flux into linear sRGB, and a dielectric's IOR and absorption at a wavelength. The
//! same numbers as glsl/common/spectrum.glsl, which the tests below read.

/// The shortest wavelength a photon samples (uniformly, nm).
pub const SPECTRUM_MIN_NM: f64 = 380.0;
/// The longest.
pub const SPECTRUM_MAX_NM: f64 = 780.0;

/// The CIE 1931 2° colour matching functions as Wyman, Sloan and Shirley's multi-lobe fit (JCGT 2013): lobes of
/// (weight, mean nm, sigma below the mean, sigma above it), x̄ from the first three, ȳ and z̄ from two each.
pub const CIE_LOBES: [[f64; 4]; 7] = [
    [1.056, 599.8, 37.9, 31.0],
    [0.362, 442.0, 16.0, 26.7],
    [-0.065, 501.1, 20.4, 26.2],
    [0.821, 568.8, 46.9, 40.5],
    [0.286, 530.9, 16.3, 31.1],
    [1.217, 437.0, 11.8, 36.0],
    [0.681, 459.0, 26.0, 13.8],
];

/// XYZ to linear sRGB (its D65 primaries), row by row.
pub const XYZ_TO_SRGB: [[f64; 3]; 3] =
    [[3.2404542, -1.5371385, -0.4985314], [-0.9692660, 1.8760108, 0.0415560], [0.0556434, -0.2040259, 1.0572252]];

/// Each channel's scale: the range's width over the integral of its response, so that an equal-energy spectrum,
/// sampled uniformly, deposits (1, 1, 1) per watt (white balanced to illuminant E).
pub const SPECTRUM_WHITE: [f64; 3] = [3.116211, 3.939409, 4.120958];

fn lobe(nm: f64, l: [f64; 4]) -> f64 {
    let t = (nm - l[1]) / if nm < l[1] { l[2] } else { l[3] };
    l[0] * (-0.5 * t * t).exp()
}

/// The colour matching functions x̄, ȳ, z̄ at `nm`.
pub fn cie_xyz(nm: f64) -> [f64; 3] {
    let l = |k: usize| lobe(nm, CIE_LOBES[k]);
    [l(0) + l(1) + l(2), l(3) + l(4), l(5) + l(6)]
}

/// The RGB a photon of wavelength `nm` deposits per watt (some channels negative outside sRGB's gamut); its mean
/// over the range is (1, 1, 1).
pub fn spectrum_rgb(nm: f64) -> [f64; 3] {
    let xyz = cie_xyz(nm);
    std::array::from_fn(|r| SPECTRUM_WHITE[r] * (0..3).map(|c| XYZ_TO_SRGB[r][c] * xyz[c]).sum::<f64>())
}

/// Cauchy's n(λ) = A + B/λ² through a dielectric's IORs at the Fraunhofer C, d and F lines (red to blue,
/// `Material::ior_rgb`), at `nm`.
pub fn cauchy_ior(n_cdf: [f64; 3], nm: f64) -> f64 {
    let (c2, f2) = (1.0 / (656.3f64 * 656.3), 1.0 / (486.1f64 * 486.1));
    let b = (n_cdf[2] - n_cdf[0]) / (f2 - c2);
    n_cdf[0] + b * (1.0 / (nm * nm) - c2)
}

/// An absorption coefficient given per channel as at the C, d and F lines (red, green, blue), at `nm`: linear
/// between them, constant beyond.
pub fn sigma_at(s_rgb: [f64; 3], nm: f64) -> f64 {
    let mix = |a: f64, b: f64, t: f64| a + (b - a) * t.clamp(0.0, 1.0);
    if nm >= 587.6 {
        mix(s_rgb[1], s_rgb[0], (nm - 587.6) / (656.3 - 587.6))
    } else {
        mix(s_rgb[2], s_rgb[1], (nm - 486.1) / (587.6 - 486.1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The numbers of every `const` in glsl/common/spectrum.glsl, in order.
    fn glsl_numbers(name: &str) -> Vec<f64> {
        let text = include_str!("../glsl/common/spectrum.glsl");
        let start = [format!(" {name} ="), format!(" {name}[")]
            .iter()
            .find_map(|p| text.find(p.as_str()))
            .unwrap_or_else(|| panic!("{name} in spectrum.glsl"));
        let body = &text[start..];
        let body = &body[body.find('=').expect("its =") + 1..];
        let body = &body[..body.find(';').expect("its ;")];
        let body = body.split_once('(').map_or(body, |(_, b)| b);
        body.split(|c: char| !(c.is_ascii_digit() || c == '.' || c == '-'))
            .filter(|s| s.parse::<f64>().is_ok() && s.contains('.'))
            .map(|s| s.parse().unwrap())
            .collect()
    }

    #[test]
    fn the_shaders_use_the_same_numbers() {
        assert_eq!(glsl_numbers("SPECTRUM_MIN_NM"), [SPECTRUM_MIN_NM]);
        assert_eq!(glsl_numbers("SPECTRUM_MAX_NM"), [SPECTRUM_MAX_NM]);
        assert_eq!(glsl_numbers("CIE_LOBES"), CIE_LOBES.concat());
        assert_eq!(glsl_numbers("SPECTRUM_WHITE"), SPECTRUM_WHITE);
        // GLSL's mat3 takes columns.
        let columns: Vec<f64> = (0..3).flat_map(|c| (0..3).map(move |r| XYZ_TO_SRGB[r][c])).collect();
        assert_eq!(glsl_numbers("XYZ_TO_SRGB"), columns);
    }

    /// An equal-energy spectrum deposits (1, 1, 1): each channel's mean over the range is 1 (midpoint rule, 0.01 nm).
    #[test]
    fn white_is_white() {
        let n = 40_000;
        let step = (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) / n as f64;
        let mut sum = [0.0; 3];
        for i in 0..n {
            let rgb = spectrum_rgb(SPECTRUM_MIN_NM + (i as f64 + 0.5) * step);
            (0..3).for_each(|c| sum[c] += rgb[c] / n as f64);
        }
        for (c, s) in sum.iter().enumerate() {
            assert!((s - 1.0).abs() < 2e-6, "channel {c}: mean {s}");
        }
        // The fit's Y peaks near 555 nm, and red, green and blue lie where they should.
        let argmax =
            |c: usize| (380..=780).max_by(|&a, &b| spectrum_rgb(a as f64)[c].total_cmp(&spectrum_rgb(b as f64)[c]));
        assert!((595..=615).contains(&argmax(0).unwrap()), "red peaks at {:?}", argmax(0));
        assert!((535..=555).contains(&argmax(1).unwrap()), "green peaks at {:?}", argmax(1));
        assert!((440..=460).contains(&argmax(2).unwrap()), "blue peaks at {:?}", argmax(2));
    }

    /// Cauchy through the C, d and F lines gives back the three IORs a dispersive material traces per channel.
    #[test]
    fn cauchy_passes_through_the_lines() {
        use crate::scene::{Material, CHANNEL_NM};
        let m = Material::Dielectric { ior: 1.5, absorption: glam::Vec3::ZERO, abbe: 15.0 };
        let n = m.ior_rgb().map(f64::from);
        for c in 0..3 {
            let got = cauchy_ior(n, CHANNEL_NM[c] as f64);
            assert!((got - n[c]).abs() < 1e-6, "channel {c}: {got} vs {}", n[c]);
        }
        for (nm, sigma) in [(656.3, 0.3), (587.6, 1.2), (486.1, 3.0), (400.0, 3.0), (700.0, 0.3)] {
            assert!((sigma_at([0.3, 1.2, 3.0], nm) - sigma).abs() < 1e-12, "{nm} nm");
        }
    }
}
