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

/// CIE standard illuminant D65, relative spectral power at 5 nm steps from 380 to 780 nm (CIE 015:2018; linear
/// between the steps): the spectrum of white light, a white light's and the one colors are upsampled against.
pub const SPECTRUM_D65: [f64; 81] = [
    49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736, 104.865,
    110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082, 109.354, 108.578,
    107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023, 100.0, 98.1671, 96.3342,
    96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489, 87.6987, 85.4936, 83.2886, 83.4939,
    83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091,
    72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087, 69.3398, 63.5927, 55.0054, 46.4182, 56.6118,
    66.8054, 65.0941, 63.3828,
];

/// Each channel's scale: one over the mean of its response times D65 over the range, so that D65, sampled
/// uniformly, deposits (1, 1, 1) per watt. sRGB's white is D65: the three agree within 0.03% (the observer is a fit).
pub const SPECTRUM_WHITE: [f64; 3] = [0.037859876, 0.037839598, 0.037864591];

/// D65's relative power at `nm` (constant beyond the table).
pub fn d65(nm: f64) -> f64 {
    let u = ((nm - SPECTRUM_MIN_NM) / 5.0).clamp(0.0, 80.0);
    let i = (u as usize).min(79);
    let f = u - i as f64;
    SPECTRUM_D65[i] * (1.0 - f) + SPECTRUM_D65[i + 1] * f
}

fn lobe(nm: f64, l: [f64; 4]) -> f64 {
    let t = (nm - l[1]) / if nm < l[1] { l[2] } else { l[3] };
    l[0] * (-0.5 * t * t).exp()
}

/// The colour matching functions x̄, ȳ, z̄ at `nm`.
pub fn cie_xyz(nm: f64) -> [f64; 3] {
    let l = |k: usize| lobe(nm, CIE_LOBES[k]);
    [l(0) + l(1) + l(2), l(3) + l(4), l(5) + l(6)]
}

/// The RGB a photon of wavelength `nm` deposits per watt of white light (D65; some channels negative outside
/// sRGB's gamut); its mean over the range is (1, 1, 1).
pub fn spectrum_rgb(nm: f64) -> [f64; 3] {
    let xyz = cie_xyz(nm);
    let d = d65(nm);
    std::array::from_fn(|r| SPECTRUM_WHITE[r] * d * (0..3).map(|c| XYZ_TO_SRGB[r][c] * xyz[c]).sum::<f64>())
}

/// Wavelength bins of the eye view's dispersive glass (docs/design.md "Color"): each pixel traces one wavelength in
/// each, drawn from the bin by the response mass below.
pub const EYE_BINS: usize = 6;

/// Steps of the response-mass table (`spectrum_quantiles`): a multiple of `EYE_BINS`, so that bins end on steps.
pub const QUANTILE_STEPS: usize = 60;

/// The response mass at `nm`: Σ_c |k_c(λ)|, k = `spectrum_rgb`, the density the eye view draws its wavelengths by.
fn response_mass(nm: f64) -> f64 {
    spectrum_rgb(nm).iter().map(|k| k.abs()).sum()
}

/// The wavelengths (nm) below which lie 0, 1/60, …, 1 of the response mass over the range (midpoint rule at
/// 0.01 nm, linear within a step), integrated once.
pub fn spectrum_quantiles() -> [f64; QUANTILE_STEPS + 1] {
    static TABLE: std::sync::OnceLock<[f64; QUANTILE_STEPS + 1]> = std::sync::OnceLock::new();
    *TABLE.get_or_init(integrate_quantiles)
}

fn integrate_quantiles() -> [f64; QUANTILE_STEPS + 1] {
    let n = 40_000;
    let step = (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) / n as f64;
    let mass: Vec<f64> = (0..n).map(|i| response_mass(SPECTRUM_MIN_NM + (i as f64 + 0.5) * step)).collect();
    let total: f64 = mass.iter().sum();
    let mut out = [SPECTRUM_MAX_NM; QUANTILE_STEPS + 1];
    out[0] = SPECTRUM_MIN_NM;
    let (mut acc, mut j) = (0.0, 1);
    for (i, m) in mass.iter().enumerate() {
        while j < QUANTILE_STEPS && acc + m >= total * j as f64 / QUANTILE_STEPS as f64 {
            let f = (total * j as f64 / QUANTILE_STEPS as f64 - acc) / m;
            out[j] = SPECTRUM_MIN_NM + (i as f64 + f) * step;
            j += 1;
        }
        acc += m;
    }
    out
}

/// Each eye bin's share of each channel's response, ∫_bin k_c / ∫ k_c (midpoint rule at 0.01 nm): a pixel's channel c
/// is Σ_b `share[b][c]` times its trace at bin b's wavelength, so the shares of a channel sum to 1 and a pixel whose
/// wavelengths all see the same takes exactly that. Some are negative (a channel's response has negative lobes).
pub fn eye_bin_shares() -> [[f64; 3]; EYE_BINS] {
    let q = spectrum_quantiles();
    let n = 40_000;
    let step = (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) / n as f64;
    let (mut share, mut total) = ([[0.0; 3]; EYE_BINS], [0.0; 3]);
    for i in 0..n {
        let nm = SPECTRUM_MIN_NM + (i as f64 + 0.5) * step;
        let b = (1..EYE_BINS).take_while(|&b| nm >= q[b * QUANTILE_STEPS / EYE_BINS]).count();
        let k = spectrum_rgb(nm);
        for c in 0..3 {
            share[b][c] += k[c];
            total[c] += k[c];
        }
    }
    share.map(|s| std::array::from_fn(|c| s[c] / total[c]))
}

/// An integer hash (Wellons' lowbias32), as glsl/common/spectrum.glsl's `spectrum_hash`.
pub fn spectrum_hash(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

/// Where in its eye bins pixel (x, y) draws its wavelengths, in [0, 1) (glsl/glass.comp `eye_jitter`): the R2
/// lattice over pixels, shifted by a hash of the pixel's 4×4 block.
pub fn eye_jitter(x: u32, y: u32) -> f64 {
    let h = spectrum_hash((x >> 2) ^ spectrum_hash(y >> 2));
    let v = (x & 3) as f32 * 0.754_877_7 + (y & 3) as f32 * 0.569_840_3 + (h >> 8) as f32 * (-24f32).exp2();
    v.fract() as f64
}

/// Eye bin `b`'s wavelength at `u` (glsl/common/spectrum.glsl `eye_wavelength`): the response mass's quantile
/// (b + u) / EYE_BINS, linear between the table's steps.
pub fn eye_wavelength(b: usize, u: f64) -> f64 {
    let q = spectrum_quantiles();
    let x = (b as f64 + u) * (QUANTILE_STEPS / EYE_BINS) as f64;
    let i = (x as usize).min(QUANTILE_STEPS - 1);
    q[i] + (q[i + 1] - q[i]) * (x - i as f64)
}

/// Cauchy's n(λ) = A + B/λ² through a dielectric's IORs at the Fraunhofer C, d and F lines (red to blue,
/// `Material::ior_rgb`), at `nm`.
pub fn cauchy_ior(n_cdf: [f64; 3], nm: f64) -> f64 {
    let (c2, f2) = (1.0 / (656.3f64 * 656.3), 1.0 / (486.1f64 * 486.1));
    let b = (n_cdf[2] - n_cdf[0]) / (f2 - c2);
    n_cdf[0] + b * (1.0 / (nm * nm) - c2)
}

/// The smooth spectrum of an RGB color (Jakob and Hanika 2019, "A Low-Dimensional Function Space for Efficient
/// Spectral Upsampling"): s(λ) = scale · S(c₀x² + c₁x + c₂), x = (λ − 380 nm) / 400 nm, S(y) = ½ + y / (2√(1 + y²)),
/// a sigmoid of a quadratic. As pbrt's `RGBUnboundedSpectrum`, scale = 2·max(rgb) and the coefficients are fitted
/// to rgb / scale, so that any non-negative color (an absorption coefficient in 1/m, a light's color) has one.
/// Its color, under D65 and the observer (`spectrum_rgb`), is `rgb`: within 1e-4 for colors inside sRGB's
/// gamut, nearest in CIELAB for those at its edge (a channel of 0 is approached, never reached).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RgbSpectrum {
    /// 2·max(rgb).
    pub scale: f64,
    /// c₀, c₁, c₂.
    pub coeffs: [f64; 3],
}

/// The sigmoid of a quadratic in the normalized wavelength (`RgbSpectrum`), without its scale.
pub fn sigmoid_quadratic(c: [f64; 3], nm: f64) -> f64 {
    let x = (nm - SPECTRUM_MIN_NM) / (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM);
    let y = (c[0] * x + c[1]) * x + c[2];
    if y.is_infinite() {
        return if y > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + 0.5 * y / (1.0 + y * y).sqrt()
}

/// The wavelengths (1 nm midpoints) and their `spectrum_rgb` the fit integrates over.
fn fit_table() -> &'static [(f64, [f64; 3])] {
    static TABLE: std::sync::OnceLock<Vec<(f64, [f64; 3])>> = std::sync::OnceLock::new();
    TABLE.get_or_init(|| {
        let n = (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) as usize;
        (0..n).map(|i| SPECTRUM_MIN_NM + i as f64 + 0.5).map(|nm| (nm, spectrum_rgb(nm))).collect()
    })
}

/// CIELAB of a linear sRGB color (white: (1, 1, 1), D65), the space the fit's residual is measured in.
fn lab(rgb: [f64; 3]) -> [f64; 3] {
    // sRGB → XYZ (the inverse of XYZ_TO_SRGB), relative to white's XYZ.
    const TO_XYZ: [[f64; 3]; 3] =
        [[0.4124564, 0.3575761, 0.1804375], [0.2126729, 0.7151522, 0.0721750], [0.0193339, 0.1191920, 0.9503041]];
    let f = |t: f64| {
        const D: f64 = 6.0 / 29.0;
        if t > D * D * D {
            t.cbrt()
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    };
    let v: [f64; 3] = std::array::from_fn(|r| {
        let white: f64 = TO_XYZ[r].iter().sum();
        f((0..3).map(|c| TO_XYZ[r][c] * rgb[c]).sum::<f64>() / white)
    });
    [116.0 * v[1] - 16.0, 500.0 * (v[0] - v[1]), 200.0 * (v[1] - v[2])]
}

impl RgbSpectrum {
    /// The spectrum of `rgb` (negative channels taken as 0). Gauss–Newton on the CIELAB residual, as Jakob and
    /// Hanika's table builder, walking from gray (all coefficients 0) to the color in 16 steps, each starting
    /// from the last (their continuation).
    pub fn fit(rgb: [f64; 3]) -> RgbSpectrum {
        let rgb = rgb.map(|c| c.max(0.0));
        let m = rgb.iter().copied().fold(0.0, f64::max);
        if m == 0.0 || rgb.iter().all(|&c| c == m) {
            return RgbSpectrum { scale: 2.0 * m, coeffs: [0.0; 3] };
        }
        let target = rgb.map(|c| c / (2.0 * m));
        let mut c = [0.0; 3];
        const STEPS: usize = 16;
        for step in 1..=STEPS {
            let t = step as f64 / STEPS as f64;
            let goal = lab(target.map(|x| 0.5 + (x - 0.5) * t));
            let residual = |c: [f64; 3]| {
                let got = lab(RgbSpectrum { scale: 1.0, coeffs: c }.rgb());
                std::array::from_fn::<f64, 3, _>(|k| got[k] - goal[k])
            };
            let norm = |r: [f64; 3]| r.iter().map(|x| x * x).sum::<f64>();
            for _ in 0..20 {
                let r = residual(c);
                if norm(r) < 1e-12 {
                    break;
                }
                // The Jacobian by forward differences, column by column.
                let mut j = [[0.0; 3]; 3];
                for k in 0..3 {
                    let mut d = c;
                    d[k] += 1e-5;
                    let rk = residual(d);
                    (0..3).for_each(|row| j[row][k] = (rk[row] - r[row]) / 1e-5);
                }
                let Some(delta) = solve3(j, r) else { break };
                // Halve the step until the residual falls (or give up on this step's color).
                let mut scale = 1.0;
                let mut next = None;
                for _ in 0..12 {
                    let mut trial: [f64; 3] = std::array::from_fn(|k| c[k] - scale * delta[k]);
                    let big = trial.iter().fold(0.0f64, |a, x| a.max(x.abs()));
                    if big > 1000.0 {
                        trial = trial.map(|x| x * 1000.0 / big);
                    }
                    if norm(residual(trial)) < norm(r) {
                        next = Some(trial);
                        break;
                    }
                    scale *= 0.5;
                }
                match next {
                    Some(n) => c = n,
                    None => break,
                }
            }
        }
        RgbSpectrum { scale: 2.0 * m, coeffs: c }
    }

    /// `fit` of a color given in f32 (a material's, a light's), remembered: scenes name few colors, and a light's
    /// is asked for every frame.
    pub fn fit_f32(rgb: [f32; 3]) -> RgbSpectrum {
        type Fits = std::collections::HashMap<[u32; 3], RgbSpectrum>;
        static FITS: std::sync::Mutex<Option<Fits>> = std::sync::Mutex::new(None);
        let key = rgb.map(f32::to_bits);
        // A poisoned lock only means another thread panicked mid-insert: the map is still a cache.
        let mut fits = FITS.lock().unwrap_or_else(|e| e.into_inner());
        *fits.get_or_insert_with(Fits::new).entry(key).or_insert_with(|| RgbSpectrum::fit(rgb.map(f64::from)))
    }

    /// Its value at `nm`.
    pub fn at(&self, nm: f64) -> f64 {
        if self.scale == 0.0 {
            return 0.0;
        }
        self.scale * sigmoid_quadratic(self.coeffs, nm)
    }

    /// Its color: the mean over the range of its value times `spectrum_rgb` (1 nm midpoints).
    pub fn rgb(&self) -> [f64; 3] {
        let table = fit_table();
        let mut sum = [0.0; 3];
        for &(nm, k) in table {
            let s = self.at(nm);
            (0..3).for_each(|c| sum[c] += s * k[c]);
        }
        sum.map(|x| x / table.len() as f64)
    }

    /// Its coefficients as the GPU takes them.
    pub fn coeffs_f32(&self) -> [f32; 3] {
        self.coeffs.map(|c| c as f32)
    }
}

/// x with a x = b (Gaussian elimination with partial pivoting), None when a is singular.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    for col in 0..3 {
        let p = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[p][col].abs() < 1e-300 {
            return None;
        }
        a.swap(col, p);
        b.swap(col, p);
        for row in col + 1..3 {
            let f = a[row][col] / a[col][col];
            let pivot = a[col];
            for (x, p) in a[row].iter_mut().zip(pivot).skip(col) {
                *x -= f * p;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let s: f64 = (row + 1..3).map(|k| a[row][k] * x[k]).sum();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
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
        assert_eq!(glsl_numbers("SPECTRUM_D65"), SPECTRUM_D65);
        // GLSL's mat3 takes columns.
        let columns: Vec<f64> = (0..3).flat_map(|c| (0..3).map(move |r| XYZ_TO_SRGB[r][c])).collect();
        assert_eq!(glsl_numbers("XYZ_TO_SRGB"), columns);
    }

    /// White light (D65) deposits (1, 1, 1): each channel's mean over the range is 1 (midpoint rule, 0.01 nm).
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
        // Red, green and blue (the observer through the sRGB matrix, times D65) peak where they should.
        let argmax =
            |c: usize| (380..=780).max_by(|&a, &b| spectrum_rgb(a as f64)[c].total_cmp(&spectrum_rgb(b as f64)[c]));
        assert!((595..=615).contains(&argmax(0).unwrap()), "red peaks at {:?}", argmax(0));
        assert!((525..=555).contains(&argmax(1).unwrap()), "green peaks at {:?}", argmax(1));
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
    }

    /// Colors come back from their spectra: every color of a grid over sRGB's cube (and unbounded ones, an
    /// absorption coefficient's), inside the gamut within 1e-4 of the largest channel; gray is flat.
    #[test]
    fn upsampled_colors_come_back() {
        let mut worst: f64 = 0.0;
        let steps = [0.05, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95];
        for r in steps {
            for g in steps {
                for b in steps {
                    let rgb = [r, g, b];
                    let got = RgbSpectrum::fit(rgb).rgb();
                    let err = (0..3).map(|c| (got[c] - rgb[c]).abs()).fold(0.0, f64::max);
                    worst = worst.max(err);
                }
            }
        }
        assert!(worst < 1e-4, "worst channel error {worst}");
        // Amber glass's absorption (1/m) and a saturated orange light.
        for rgb in [[0.3, 1.2, 3.0], [1.0, 0.4, 0.05], [12.0, 0.5, 0.8]] {
            let s = RgbSpectrum::fit(rgb);
            let got = s.rgb();
            let m = rgb.iter().copied().fold(0.0, f64::max);
            for c in 0..3 {
                assert!((got[c] - rgb[c]).abs() < 1e-4 * m, "{rgb:?}: {got:?}");
            }
            assert!((380..=780).all(|nm| s.at(nm as f64) >= 0.0));
        }
        let gray = RgbSpectrum::fit([0.7; 3]);
        assert_eq!(gray.coeffs, [0.0; 3]);
        assert!((gray.at(400.0) - 0.7).abs() < 1e-12 && (gray.at(700.0) - 0.7).abs() < 1e-12);
        assert_eq!(RgbSpectrum::fit([0.0; 3]).at(550.0), 0.0);
        // A primary lies on the gamut's edge: its other channels are approached, the nearest a smooth spectrum gets.
        let red = RgbSpectrum::fit([1.0, 0.0, 0.0]).rgb();
        assert!(red[0] > 0.9 && red[1].abs() < 0.1 && red[2].abs() < 0.1, "{red:?}");
        // Amber absorbs blue most: its spectrum falls from blue to red.
        let amber = RgbSpectrum::fit([0.3, 1.2, 3.0]);
        assert!(amber.at(450.0) > amber.at(550.0) && amber.at(550.0) > amber.at(650.0));
    }

    /// The same spectra as an independent implementation's: colour-science 0.4's `find_coefficients_Jakob2019`
    /// (the tabulated CIE 1931 observer and D65, colors as XYZ of rgb / scale, to ΔE 1e-6), at 400 to 700 nm.
    /// Ours uses the observer's fit: they agree within 0.5% of the scale (the test allows 1%).
    #[test]
    fn upsampling_agrees_with_colour_science() {
        let cases: [([f64; 3], [f64; 7]); 4] = [
            ([0.2, 0.5, 0.8], [0.8642, 0.7746, 0.638, 0.4752, 0.3222, 0.2062, 0.13]),
            ([0.8, 0.6, 0.1], [0.0518, 0.1356, 0.3511, 0.6424, 0.7517, 0.601, 0.3043]),
            ([0.1, 0.4, 1.0], [1.2608, 0.9565, 0.6278, 0.3743, 0.2199, 0.1336, 0.085]),
            ([0.3, 1.2, 3.0], [3.7825, 2.8694, 1.8834, 1.1229, 0.6596, 0.4007, 0.2551]),
        ];
        for (rgb, theirs) in cases {
            let s = RgbSpectrum::fit(rgb);
            let ours: Vec<f64> = (0..7).map(|k| s.at(400.0 + 50.0 * k as f64)).collect();
            let worst = (0..7).map(|k| (ours[k] - theirs[k]).abs() / s.scale).fold(0.0, f64::max);
            assert!(worst < 0.01, "{rgb:?}: ours {ours:.4?}, colour-science's {theirs:?}");
        }
    }

    /// The shaders' eye bins are these: the quantiles to 0.01 nm, the shares to 1e-5, each channel's shares summing
    /// to 1.
    #[test]
    fn the_eye_bins_are_the_shaders() {
        let q = spectrum_quantiles();
        let got = glsl_numbers("SPECTRUM_QUANTILES");
        assert_eq!(got.len(), q.len());
        for (a, b) in got.iter().zip(q) {
            assert!((a - b).abs() < 0.01, "quantile {a} vs {b}");
        }
        assert!(q.windows(2).all(|w| w[1] > w[0]));
        let shares = eye_bin_shares();
        let got = glsl_numbers("EYE_BIN_SHARES");
        assert_eq!(got.len(), 3 * EYE_BINS);
        for (a, b) in got.iter().zip(shares.concat()) {
            assert!((a - b).abs() < 1e-5, "share {a} vs {b}");
        }
        for c in 0..3 {
            let sum: f64 = (0..EYE_BINS).map(|b| got[3 * b + c]).sum();
            assert!((sum - 1.0).abs() < 2e-5, "channel {c}: shares sum to {sum}");
        }
    }
}
