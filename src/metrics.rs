//! The error metric used everywhere (`caustics compare`, the bench, the tests), docs/design.md "Ground truth and
//! error":
//!
//! 1. Both images are reduced to one plane of irradiance, the **mean of the R, G and B channels** (under white
//!    light and glass that neither tints nor disperses, this equals any single channel; under colored light,
//!    tinted or dispersive glass the mean weighs the channels equally).
//! 2. Both planes are box-filtered to the comparison resolution `res` × `res·H/W` (rounded, at least 1):
//!    area-weighted, so a source pixel that straddles two target pixels is split between them by overlap area.
//!    Sizes need not be multiples of one another, and the filter preserves Σ E · pixel area exactly.
//! 3. On the filtered planes (E under test, E_ref the reference): rel-L1 = Σ|E − E_ref| / Σ E_ref,
//!    flux ratio = Σ E / Σ E_ref, and the peak offset: the distance in meters between the two planes' peak
//!    centroids (the E-weighted centroid of the pixels at or above half the plane's maximum), given the physical
//!    width `extent_m` of the image (2.0 m for the canonical `top` camera; square pixels assumed).
//! 4. `caustics compare` refuses (exit 2) a reference that is all zero or holds a non-finite value, an image
//!    under test with a non-finite value, and a pair whose EXR metadata names different cameras, camera kinds or
//!    AOVs; it warns about other metadata differences (the scene file's hash, the units, the paths).

use crate::error::{Error, Result};
use crate::image_io::{self, RgbImage};
use serde::{Deserialize, Serialize};

/// Comparison results at one resolution.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Comparison width in pixels (height follows the reference's aspect).
    pub res: u32,
    /// Σ|E − E_ref| / Σ E_ref (0 when both are empty, infinite when only the reference is).
    pub rel_l1: f64,
    /// Σ E / Σ E_ref (1 when both are empty, infinite when only the reference is).
    pub flux_ratio: f64,
    /// Distance between the peak centroids ([`peak_centroid`]) of the filtered images, meters (0 when both are
    /// empty, NaN when only one is).
    pub peak_offset_m: f64,
    /// Σ E and Σ E_ref over the filtered planes.
    pub sum: f64,
    /// Σ of the reference's plane.
    pub sum_ref: f64,
}

/// One plane per image: the mean of the three channels, in f64.
pub fn luminance_plane(img: &RgbImage) -> Vec<f64> {
    img.data.iter().map(|p| (p[0] as f64 + p[1] as f64 + p[2] as f64) / 3.0).collect()
}

/// For each target cell j of `dst` cells, the (source index, weight) pairs: the overlap of source pixel i, mapped
/// onto [0, dst), with [j, j + 1), in target-pixel units. The weights of one target cell sum to 1.
fn overlap_weights(src: usize, dst: usize) -> Vec<Vec<(usize, f64)>> {
    let scale = dst as f64 / src as f64;
    let mut cells = vec![Vec::new(); dst];
    for i in 0..src {
        let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
        let mut j = a.floor() as usize;
        while j < dst && (j as f64) < b {
            let w = b.min(j as f64 + 1.0) - a.max(j as f64);
            if w > 0.0 {
                cells[j].push((i, w));
            }
            j += 1;
        }
    }
    cells
}

/// Area-weighted box filter of a `w`×`h` plane to `ow`×`oh`: each output is the mean of E over its footprint.
pub fn box_filter(plane: &[f64], w: usize, h: usize, ow: usize, oh: usize) -> Vec<f64> {
    assert_eq!(plane.len(), w * h, "plane size");
    let wx = overlap_weights(w, ow);
    let wy = overlap_weights(h, oh);
    // Rows first (w → ow), then columns (h → oh).
    let mut tmp = vec![0.0; ow * h];
    for y in 0..h {
        let row = &plane[y * w..(y + 1) * w];
        for (j, cell) in wx.iter().enumerate() {
            tmp[y * ow + j] = cell.iter().map(|&(i, wt)| row[i] * wt).sum();
        }
    }
    let mut out = vec![0.0; ow * oh];
    for (j, cell) in wy.iter().enumerate() {
        for x in 0..ow {
            out[j * ow + x] = cell.iter().map(|&(i, wt)| tmp[i * ow + x] * wt).sum();
        }
    }
    out
}

/// The peak centroid of a `w`-wide plane, in pixels (x, y of pixel centers): the E-weighted centroid of the
/// pixels at or above half the maximum. `None` when no pixel is positive. Unlike the argmax, it is exactly the
/// same for identical planes and moves continuously as the caustic's core moves, instead of jumping between
/// near-equal pixels.
pub fn peak_centroid(v: &[f64], w: usize) -> Option<(f64, f64)> {
    let max = v.iter().copied().filter(|x| x.is_finite()).fold(0.0f64, f64::max);
    if max <= 0.0 {
        return None;
    }
    let (mut sx, mut sy, mut sw) = (0.0, 0.0, 0.0);
    for (i, &x) in v.iter().enumerate() {
        if x.is_finite() && x >= 0.5 * max {
            sx += x * ((i % w) as f64 + 0.5);
            sy += x * ((i / w) as f64 + 0.5);
            sw += x;
        }
    }
    Some((sx / sw, sy / sw))
}

/// The comparison size for `res` columns: (res, round(res · h / w)), both at least 1.
pub fn comparison_size(res: u32, width: u32, height: u32) -> (usize, usize) {
    let ow = res.max(1) as usize;
    let oh = ((res as f64 * height as f64 / width.max(1) as f64).round() as usize).max(1);
    (ow, oh)
}

/// The finest comparison width two images both carry: the narrower one's width (the comparison grid keeps the
/// aspect ratio, so its height follows).
pub fn max_comparison_res(a: &RgbImage, b: &RgbImage) -> u32 {
    a.width.min(b.width)
}

/// Compare `a` (under test) against `reference` at comparison width `res`, for an image `extent_m` meters wide.
pub fn compare(a: &RgbImage, reference: &RgbImage, res: u32, extent_m: f32) -> Metrics {
    let (ow, oh) = comparison_size(res, reference.width, reference.height);
    let fa = box_filter(&luminance_plane(a), a.width as usize, a.height as usize, ow, oh);
    let fb = box_filter(&luminance_plane(reference), reference.width as usize, reference.height as usize, ow, oh);
    let sum: f64 = fa.iter().sum();
    let sum_ref: f64 = fb.iter().sum();
    let l1: f64 = fa.iter().zip(&fb).map(|(x, y)| (x - y).abs()).sum();
    // Against an empty reference: equal (also empty) is a perfect match, anything else infinitely wrong.
    let ratio = |num: f64, if_zero: f64| {
        if sum_ref != 0.0 {
            num / sum_ref
        } else if num == 0.0 {
            if_zero
        } else {
            f64::INFINITY
        }
    };
    let pixel_m = extent_m as f64 / ow as f64;
    let peak_offset_m = match (peak_centroid(&fa, ow), peak_centroid(&fb, ow)) {
        (Some((ax, ay)), Some((bx, by))) => ((ax - bx).powi(2) + (ay - by).powi(2)).sqrt() * pixel_m,
        (None, None) => 0.0,
        _ => f64::NAN,
    };
    Metrics { res: ow as u32, rel_l1: ratio(l1, 0.0), flux_ratio: ratio(sum, 1.0), peak_offset_m, sum, sum_ref }
}

/// The side of the tiles [`periodic_share`] takes the spectrum of, pixels of the comparison grid.
pub const PERIODIC_TILE: usize = 32;

/// How periodic the residual E − E_ref is at `res`² (a power of two, at least [`PERIODIC_TILE`]), docs/design.md
/// "Ground truth and error". The residual is cut into [`PERIODIC_TILE`]² tiles; each is windowed (Hann) and
/// Fourier transformed, and its periodic share is the part of its power above the lowest frequencies (two cycles
/// per tile and up) that lies in its strongest 2% of frequency bins. The result is the mean of the tiles' shares
/// weighted by their residual power. Within a tile a fringe pattern (the moiré of splats narrower than their
/// photons' spacing, whose period drifts slowly across the image) is nearly one frequency, so its power sits in a
/// few bins; noise spreads it over all of them (white noise: about 0.13).
pub fn periodic_share(a: &RgbImage, reference: &RgbImage, res: u32) -> f64 {
    assert!(res.is_power_of_two() && res as usize >= PERIODIC_TILE, "periodic_share needs a power-of-two res");
    let n = res as usize;
    let fa = box_filter(&luminance_plane(a), a.width as usize, a.height as usize, n, n);
    let fb = box_filter(&luminance_plane(reference), reference.width as usize, reference.height as usize, n, n);
    let t = PERIODIC_TILE;
    let hann: Vec<f64> =
        (0..t).map(|i| 0.5 - 0.5 * (std::f64::consts::TAU * (i as f64 + 0.5) / t as f64).cos()).collect();
    let freq = |k: usize| if k <= t / 2 { k as f64 } else { k as f64 - t as f64 };
    let (mut weighted, mut total) = (0.0, 0.0);
    let (mut r, mut c) = (vec![0.0; t], vec![0.0; t]);
    for ty in 0..n / t {
        for tx in 0..n / t {
            let mut re: Vec<f64> = (0..t * t)
                .map(|i| {
                    let (x, y) = (tx * t + i % t, ty * t + i / t);
                    (fa[y * n + x] - fb[y * n + x]) * hann[i % t] * hann[i / t]
                })
                .collect();
            let mut im = vec![0.0; t * t];
            for pass in 0..2 {
                for line in 0..t {
                    let at = |k: usize| if pass == 0 { line * t + k } else { k * t + line };
                    for k in 0..t {
                        r[k] = re[at(k)];
                        c[k] = im[at(k)];
                    }
                    fft(&mut r, &mut c);
                    for k in 0..t {
                        re[at(k)] = r[k];
                        im[at(k)] = c[k];
                    }
                }
            }
            let mut power: Vec<f64> = (0..t * t)
                .filter(|&i| freq(i % t).hypot(freq(i / t)) >= 2.0)
                .map(|i| re[i] * re[i] + im[i] * im[i])
                .collect();
            let sum: f64 = power.iter().sum();
            if sum.is_nan() || sum <= 0.0 {
                continue;
            }
            power.sort_by(|x, y| y.total_cmp(x));
            let top = (power.len() * 2).div_ceil(100);
            weighted += power[..top].iter().sum::<f64>();
            total += sum;
        }
    }
    if total > 0.0 {
        weighted / total
    } else {
        0.0
    }
}

/// In-place radix-2 FFT of (re, im), whose length is a power of two.
fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -std::f64::consts::TAU / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (wr, wi) = ((ang * k as f64).cos(), (ang * k as f64).sin());
                let (a, b) = (start + k, start + k + len / 2);
                let (xr, xi) = (re[b] * wr - im[b] * wi, re[b] * wi + im[b] * wr);
                re[b] = re[a] - xr;
                im[b] = im[a] - xi;
                re[a] += xr;
                im[a] += xi;
            }
        }
        len <<= 1;
    }
}

/// What makes a comparison meaningless is refused (bad input, exit 2): a reference that is all zero or not
/// finite (every image would score perfectly, or every metric be NaN), a non-finite image under test, and a pair
/// whose metadata names different cameras, camera kinds or AOVs. Other metadata differences are warned about.
pub fn check_pair(
    pa: &std::path::Path,
    a: &RgbImage,
    ma: &image_io::ExrMeta,
    pb: &std::path::Path,
    b: &RgbImage,
    mb: &image_io::ExrMeta,
) -> Result<()> {
    let non_finite = |img: &RgbImage| img.data.iter().position(|p| !p.iter().all(|x| x.is_finite()));
    for (path, img, what) in [(pb, b, "reference"), (pa, a, "image under test")] {
        if let Some(i) = non_finite(img) {
            let (x, y) = (i as u32 % img.width, i as u32 / img.width);
            return Err(Error::BadInput(format!(
                "{}: the {what} holds a non-finite value (pixel {x}, {y}: {:?})",
                path.display(),
                img.data[i]
            )));
        }
    }
    if b.data.iter().all(|p| p.iter().all(|&x| x == 0.0)) {
        return Err(Error::BadInput(format!(
            "{}: the reference is all zero: every error metric would be meaningless against it",
            pb.display()
        )));
    }
    for key in ["camera", "camera_kind", "aov"] {
        if let (Some(x), Some(y)) = (ma.get(key), mb.get(key)) {
            if x != y {
                return Err(Error::BadInput(format!(
                    "{} has {key} `{x}` but {} has {key} `{y}`: the images do not show the same thing",
                    pa.display(),
                    pb.display()
                )));
            }
        }
    }
    // A render against a CPU reference differs in transport, level and photons by design.
    let reference_pair = ma.get("transport").map(String::as_str) == Some("reference")
        || mb.get("transport").map(String::as_str) == Some("reference");
    let expected = ["camera", "camera_kind", "aov", "transport", "level", "photons", "method", "paths", "seed"];
    let keys: std::collections::BTreeSet<&String> = ma.keys().chain(mb.keys()).collect();
    for key in keys {
        // The scene's path may be spelled differently for the same file: its hash decides.
        if key == "scene" || (reference_pair && expected.contains(&key.as_str())) {
            continue;
        }
        if let (Some(x), Some(y)) = (ma.get(key), mb.get(key)) {
            if x != y {
                log::warn!("{} has {key} `{x}` but {} has `{y}`", pa.display(), pb.display());
            }
        }
    }
    if ma.is_empty() != mb.is_empty() {
        let none = if ma.is_empty() { pa } else { pb };
        log::warn!("{} has no caustics metadata: its camera and AOV cannot be checked", none.display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_partition_each_source_pixel() {
        for (src, dst) in [(10, 3), (3, 10), (512, 64), (100, 64), (7, 7)] {
            let cells = overlap_weights(src, dst);
            let mut per_src = vec![0.0; src];
            for cell in &cells {
                for &(i, w) in cell {
                    per_src[i] += w;
                }
            }
            let scale = dst as f64 / src as f64;
            for s in per_src {
                assert!((s - scale).abs() < 1e-12, "{src}->{dst}");
            }
            for cell in &cells {
                assert!((cell.iter().map(|c| c.1).sum::<f64>() - 1.0).abs() < 1e-12, "{src}->{dst}");
            }
        }
    }
}
