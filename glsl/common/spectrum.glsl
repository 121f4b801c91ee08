// Spectral photons (docs/design.md "Color"): a photon of dispersive glass carries one wavelength, drawn
// uniformly over [SPECTRUM_MIN_NM, SPECTRUM_MAX_NM] and stratified over the photons' cells, and deposits its flux
// as the linear sRGB of that wavelength. src/spectrum.rs holds the same numbers (its tests read this file).
#ifndef SPECTRUM_GLSL
#define SPECTRUM_GLSL

const float SPECTRUM_MIN_NM = 380.0;
const float SPECTRUM_MAX_NM = 780.0;
// The CIE 1931 2° colour matching functions as Wyman, Sloan and Shirley's multi-lobe fit (JCGT 2013): lobes of
// (weight, mean nm, sigma below the mean, sigma above it), x̄ from three, ȳ and z̄ from two each.
const vec4 CIE_LOBES[7] = vec4[7](
    vec4(1.056, 599.8, 37.9, 31.0), vec4(0.362, 442.0, 16.0, 26.7), vec4(-0.065, 501.1, 20.4, 26.2),
    vec4(0.821, 568.8, 46.9, 40.5), vec4(0.286, 530.9, 16.3, 31.1),
    vec4(1.217, 437.0, 11.8, 36.0), vec4(0.681, 459.0, 26.0, 13.8));
// XYZ to linear sRGB (its D65 primaries), rows as GLSL reads a matrix's columns.
const mat3 XYZ_TO_SRGB = mat3(3.2404542, -0.9692660, 0.0556434, -1.5371385, 1.8760108, -0.2040259, -0.4985314,
                              0.0415560, 1.0572252);
// CIE standard illuminant D65, relative power at 5 nm steps from 380 to 780 nm (linear between them): white light.
const float SPECTRUM_D65[81] = float[81](
    49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.486, 92.4589, 93.4318, 90.057, 86.6823, 95.7736,
    104.865, 110.936, 117.008, 117.41, 117.812, 116.336, 114.861, 115.392, 115.923, 112.367, 108.811, 109.082,
    109.354, 108.578, 107.802, 106.296, 104.79, 106.239, 107.689, 106.047, 104.405, 104.225, 104.046, 102.023,
    100.0, 98.1671, 96.3342, 96.0611, 95.788, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991, 88.6489,
    87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.863, 80.0268, 80.1207, 80.2146, 81.2462, 82.2778, 80.281,
    78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.979, 74.349, 67.9765, 61.604, 65.7448, 69.8856, 72.4863, 75.087,
    69.3398, 63.5927, 55.0054, 46.4182, 56.6118, 66.8054, 65.0941, 63.3828);
// Each channel's scale: one over the mean of its response times D65 over the range, so that D65, sampled
// uniformly, deposits (1, 1, 1) per watt.
const vec3 SPECTRUM_WHITE = vec3(0.037859876, 0.037839598, 0.037864591);

float d65(float nm) {
    float u = clamp((nm - SPECTRUM_MIN_NM) / 5.0, 0.0, 80.0);
    uint i = min(uint(u), 79u);
    return mix(SPECTRUM_D65[i], SPECTRUM_D65[i + 1u], u - float(i));
}

float cie_lobe(float nm, vec4 l) {
    float t = (nm - l.y) / (nm < l.y ? l.z : l.w);
    return l.x * exp(-0.5 * t * t);
}

vec3 cie_xyz(float nm) {
    return vec3(cie_lobe(nm, CIE_LOBES[0]) + cie_lobe(nm, CIE_LOBES[1]) + cie_lobe(nm, CIE_LOBES[2]),
                cie_lobe(nm, CIE_LOBES[3]) + cie_lobe(nm, CIE_LOBES[4]),
                cie_lobe(nm, CIE_LOBES[5]) + cie_lobe(nm, CIE_LOBES[6]));
}

// The RGB a photon of wavelength nm deposits per watt of white light (D65; some channels negative: spectral
// colours lie outside sRGB's gamut); the mean over the range is (1, 1, 1).
vec3 spectrum_rgb(float nm) { return SPECTRUM_WHITE * d65(nm) * (XYZ_TO_SRGB * cie_xyz(nm)); }

// An integer hash (Wellons' lowbias32).
uint spectrum_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// A point in [0, 1) for cell (x, y) of a grid, so that any few neighbours spread evenly: the R2 lattice (Roberts
// 2018), frac(x·a1 + y·a2), whose every small patch of cells spreads evenly, shifted by `block`, a hash of the
// cell's 4×4 block (a Cranley–Patterson rotation per block). The lattice alone is a fixed pattern, which shows as
// diagonal moiré where the glass maps the cells onto the receivers.
float r2_spread(uvec2 xy, uint block) {
    return fract(float(xy.x & 3u) * 0.7548776662 + float(xy.y & 3u) * 0.5698402910 + float(block >> 8) * exp2(-24.0));
}

// The wavelength of the photon of cell (x, y) of its level, stratified so that any few neighbours spread over the
// range (r2_spread, its block hash salted by the level).
float photon_wavelength(uvec2 xy, uint level) {
    uint h = spectrum_hash((xy.x >> 2) ^ spectrum_hash((xy.y >> 2) ^ spectrum_hash(level)));
    return mix(SPECTRUM_MIN_NM, SPECTRUM_MAX_NM, r2_spread(xy, h));
}

// The eye view's dispersive glass (src/spectrum.rs EYE_BINS): a pixel traces one wavelength in each of EYE_BINS
// bins of equal response mass (the sum of |spectrum_rgb|), drawn within its bin by that mass: the wavelengths below
// which lie 0, 1/60, ..., 1 of it (linear between), and each bin's share of each channel's response.
const uint EYE_BINS = 6u;
const float SPECTRUM_QUANTILES[61] = float[61](
    380.00, 420.73, 427.45, 432.31, 436.16, 439.53, 442.65, 445.67, 448.64, 451.61, 454.69, 457.96, 461.48,
    465.23, 469.36, 473.85, 478.71, 483.94, 489.45, 494.90, 499.97, 504.66, 508.98, 512.99, 516.75, 520.23,
    523.49, 526.58, 529.60, 532.61, 535.70, 538.91, 542.32, 545.97, 550.02, 554.65, 559.08, 563.20, 567.09,
    570.79, 574.32, 577.71, 580.99, 584.25, 587.51, 590.80, 594.07, 597.32, 600.56, 603.84, 607.20, 610.63,
    614.11, 617.70, 621.49, 625.62, 630.31, 635.79, 642.64, 652.99, 780.00);
const vec3 EYE_BIN_SHARES[6] = vec3[6](
    vec3(0.074250, -0.072079, 0.595198), vec3(-0.127421, 0.083241, 0.502888), vec3(-0.293567, 0.414970, -0.002117),
    vec3(0.066023, 0.489737, -0.059420), vec3(0.589547, 0.125233, -0.027645), vec3(0.691168, -0.041102, -0.008904));

// Where in its eye bins pixel p draws its wavelengths, in [0, 1) (src/spectrum.rs eye_jitter): r2_spread over the
// pixels, so that neighbouring pixels spread over each bin.
float eye_jitter(ivec2 p) {
    uvec2 xy = uvec2(p);
    return r2_spread(xy, spectrum_hash((xy.x >> 2) ^ spectrum_hash(xy.y >> 2)));
}

// Eye bin b's wavelength at u in [0, 1): the response mass's quantile (b + u) / EYE_BINS.
float eye_wavelength(uint b, float u) {
    float x = (float(b) + u) * (60.0 / float(EYE_BINS));
    uint i = min(uint(x), 59u);
    return mix(SPECTRUM_QUANTILES[i], SPECTRUM_QUANTILES[i + 1u], x - float(i));
}

// Cauchy's n(λ) = A + B/λ² through a dielectric's IORs at the Fraunhofer C, d and F lines (ior_rgb, red to blue):
// the curve they were made from (src/scene/mod.rs, Material::ior_rgb).
float cauchy_ior(vec3 n_cdf, float nm) {
    const float C2 = 1.0 / (656.3 * 656.3), F2 = 1.0 / (486.1 * 486.1);
    float b = (n_cdf.z - n_cdf.x) / (F2 - C2);
    return n_cdf.x + b * (1.0 / (nm * nm) - C2);
}

// The smooth spectrum of a non-negative RGB color (src/spectrum.rs RgbSpectrum: Jakob and Hanika 2019), at
// wavelength nm: 2·max(rgb) times the sigmoid of the quadratic with coefficients c in the normalized wavelength.
float rgb_spectrum(vec3 rgb, vec3 c, float nm) {
    float x = (nm - SPECTRUM_MIN_NM) / (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM);
    float y = (c.x * x + c.y) * x + c.z;
    float s = isinf(y) ? step(0.0, y) : 0.5 + 0.5 * y * inversesqrt(1.0 + y * y);
    return 2.0 * max(rgb.r, max(rgb.g, rgb.b)) * s;
}

#endif
