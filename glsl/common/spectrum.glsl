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
// Each channel's scale: (SPECTRUM_MAX_NM - SPECTRUM_MIN_NM) over the integral of its response over the range, so
// that an equal-energy spectrum, sampled uniformly, deposits (1, 1, 1) per watt (white balanced to illuminant E).
const vec3 SPECTRUM_WHITE = vec3(3.116211, 3.939409, 4.120958);

float cie_lobe(float nm, vec4 l) {
    float t = (nm - l.y) / (nm < l.y ? l.z : l.w);
    return l.x * exp(-0.5 * t * t);
}

vec3 cie_xyz(float nm) {
    return vec3(cie_lobe(nm, CIE_LOBES[0]) + cie_lobe(nm, CIE_LOBES[1]) + cie_lobe(nm, CIE_LOBES[2]),
                cie_lobe(nm, CIE_LOBES[3]) + cie_lobe(nm, CIE_LOBES[4]),
                cie_lobe(nm, CIE_LOBES[5]) + cie_lobe(nm, CIE_LOBES[6]));
}

// The RGB a photon of wavelength nm deposits per watt of its flux (some channels negative: spectral colours lie
// outside sRGB's gamut); the mean over the range is (1, 1, 1).
vec3 spectrum_rgb(float nm) { return SPECTRUM_WHITE * (XYZ_TO_SRGB * cie_xyz(nm)); }

// An integer hash (Wellons' lowbias32).
uint spectrum_hash(uint x) {
    x ^= x >> 16;
    x *= 0x7feb352du;
    x ^= x >> 15;
    x *= 0x846ca68bu;
    x ^= x >> 16;
    return x;
}

// The wavelength of the photon of cell (x, y) of its level, stratified so that any few neighbours spread over the
// range: the R2 lattice (Roberts 2018), frac(x·a1 + y·a2), whose every small patch of cells spreads evenly, shifted
// by a hash of the cell's 4×4 block (a Cranley–Patterson rotation per block). The lattice alone is a fixed pattern,
// which shows as diagonal moiré where the glass maps the cells onto the receivers.
float photon_wavelength(uvec2 xy, uint level) {
    uint h = spectrum_hash((xy.x >> 2) ^ spectrum_hash((xy.y >> 2) ^ spectrum_hash(level)));
    float u = fract(float(xy.x & 3u) * 0.7548776662 + float(xy.y & 3u) * 0.5698402910 + float(h >> 8) * exp2(-24.0));
    return mix(SPECTRUM_MIN_NM, SPECTRUM_MAX_NM, u);
}

// Cauchy's n(λ) = A + B/λ² through a dielectric's IORs at the Fraunhofer C, d and F lines (ior_rgb, red to blue):
// the curve they were made from (src/scene/mod.rs, Material::ior_rgb).
float cauchy_ior(vec3 n_cdf, float nm) {
    const float C2 = 1.0 / (656.3 * 656.3), F2 = 1.0 / (486.1 * 486.1);
    float b = (n_cdf.z - n_cdf.x) / (F2 - C2);
    return n_cdf.x + b * (1.0 / (nm * nm) - C2);
}

// An absorption coefficient given per channel as at the C, d and F lines (red, green, blue), at wavelength nm:
// linear between them, constant beyond.
float sigma_at(vec3 s_rgb, float nm) {
    if (nm >= 587.6) return mix(s_rgb.g, s_rgb.r, clamp((nm - 587.6) / (656.3 - 587.6), 0.0, 1.0));
    return mix(s_rgb.b, s_rgb.g, clamp((nm - 486.1) / (587.6 - 486.1), 0.0, 1.0));
}

#endif
