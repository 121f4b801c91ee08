//! Receivers' albedo textures (docs/design.md "Textures"): decoded 8-bit sRGB images (PNG, JPEG) and the
//! procedural checker, and the affine uv transform a material applies to its mesh's texture coordinates.
//!
//! Texture coordinates follow glTF: (0, 0) is the image's top-left corner, u runs right and v down, and the
//! texture repeats outside [0, 1]. OBJ's `vt` (v up) is flipped on load.

use glam::{Vec2, Vec3};

/// An albedo image: RGBA8 texels, sRGB-encoded, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Where it came from (messages name it).
    pub name: String,
    /// Its width in texels.
    pub width: u32,
    /// Its height in texels.
    pub height: u32,
    /// Its texels, sRGB-encoded (alpha is ignored).
    pub texels: Vec<[u8; 4]>,
}

/// A diffuse material's texture: which of the scene's textures ([`super::Scene::textures`]) and the affine map
/// from the mesh's uv to the texture's: `uv' = [m[0]; m[1]] · (u, v, 1)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AlbedoMap {
    /// Index into the scene's textures.
    pub texture: usize,
    /// The uv transform's two rows.
    pub uv_transform: [[f32; 3]; 2],
}

impl AlbedoMap {
    /// The identity transform on texture `texture`.
    pub fn new(texture: usize) -> AlbedoMap {
        AlbedoMap { texture, uv_transform: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] }
    }

    /// Scale uv by `s` (the texture repeats `s` times across the mesh's [0, 1]).
    pub fn scaled(mut self, s: Vec2) -> AlbedoMap {
        for k in 0..3 {
            self.uv_transform[0][k] *= s.x;
            self.uv_transform[1][k] *= s.y;
        }
        self
    }

    /// The transformed coordinates of `uv`.
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let [a, b] = self.uv_transform;
        Vec2::new(a[0] * uv.x + a[1] * uv.y + a[2], b[0] * uv.x + b[1] * uv.y + b[2])
    }
}

/// sRGB-encoded 8-bit value → linear reflectance.
pub fn srgb_to_linear(c: u8) -> f32 {
    let x = c as f32 / 255.0;
    if x <= 0.04045 {
        x / 12.92
    } else {
        ((x + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear reflectance → sRGB-encoded 8-bit value.
pub fn linear_to_srgb(y: f32) -> u8 {
    let y = y.clamp(0.0, 1.0);
    let x = if y <= 0.0031308 { 12.92 * y } else { 1.055 * y.powf(1.0 / 2.4) - 0.055 };
    (x * 255.0).round() as u8
}

/// Textures larger than this per side are downsampled when uploaded (their mips would be all a view sees).
pub const MAX_TEXTURE_SIZE: u32 = 2048;

impl Texture {
    /// Decode an image file's bytes (PNG, JPEG or WebP; 8- or 16-bit, gray or color, with or without alpha;
    /// WebP lossy or lossless).
    pub fn decode(name: &str, bytes: &[u8]) -> Result<Texture, String> {
        let img = image::load_from_memory(bytes).map_err(|e| format!("not a PNG, JPEG or WebP image ({e})"))?;
        let rgba = img.to_rgba8();
        let (width, height) = rgba.dimensions();
        if width == 0 || height == 0 {
            return Err("the image is empty".into());
        }
        let texels = rgba.pixels().map(|p| p.0).collect();
        Ok(Texture { name: name.to_string(), width, height, texels })
    }

    /// Read and decode an image file; errors start with its path.
    pub fn load(path: &std::path::Path) -> Result<Texture, String> {
        let file = path.display();
        let bytes = std::fs::read(path).map_err(|e| format!("{file}: cannot read: {e}"))?;
        Texture::decode(&file.to_string(), &bytes).map_err(|e| format!("{file}: {e}"))
    }

    /// A checkerboard of `squares` × `squares` squares over uv [0, 1]², alternating linear albedos `a` (the
    /// top-left square) and `b`, 16 texels per square.
    pub fn checker(a: Vec3, b: Vec3, squares: u32) -> Texture {
        let per = 16u32;
        let n = (squares.max(1) * per).min(MAX_TEXTURE_SIZE);
        let enc = |c: Vec3| [linear_to_srgb(c.x), linear_to_srgb(c.y), linear_to_srgb(c.z), 255];
        let (ea, eb) = (enc(a), enc(b));
        let texels = (0..n * n)
            .map(|i| {
                let (x, y) = (i % n, i / n);
                if ((x * squares / n) + (y * squares / n)).is_multiple_of(2) {
                    ea
                } else {
                    eb
                }
            })
            .collect();
        Texture { name: format!("checker {squares}x{squares}"), width: n, height: n, texels }
    }

    /// The linear albedo of the texel that holds `uv` (repeating), unfiltered: what a test expects well inside a
    /// region of constant color.
    pub fn texel_at(&self, uv: Vec2) -> Vec3 {
        let f = uv - uv.floor();
        let x = ((f.x * self.width as f32) as u32).min(self.width - 1);
        let y = ((f.y * self.height as f32) as u32).min(self.height - 1);
        let t = self.texels[(y * self.width + x) as usize];
        Vec3::new(srgb_to_linear(t[0]), srgb_to_linear(t[1]), srgb_to_linear(t[2]))
    }

    /// The mean linear albedo over the image (what a path without uv, such as the light's view, uses).
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self
            .texels
            .iter()
            .map(|t| Vec3::new(srgb_to_linear(t[0]), srgb_to_linear(t[1]), srgb_to_linear(t[2])).as_dvec3())
            .sum();
        (sum / self.texels.len().max(1) as f64).as_vec3()
    }

    /// The mip chain of the texture resized to `size` × `size`, filtered in linear space, as 16-bit linear
    /// reflectance (decoded from sRGB here, exactly, rather than by a driver's sampler, whose sRGB decode may be
    /// approximate: lavapipe's was seen 0.7% off at dark values): level 0 is `size`, each next level half the last
    /// (down to 1).
    pub fn mip_chain(&self, size: u32) -> Vec<Vec<[u16; 4]>> {
        let lin: Vec<[f32; 4]> = self
            .texels
            .iter()
            .map(|t| [srgb_to_linear(t[0]), srgb_to_linear(t[1]), srgb_to_linear(t[2]), t[3] as f32 / 255.0])
            .collect();
        let mut level = resample(&lin, self.width, self.height, size, size);
        let mut out = Vec::new();
        let mut s = size;
        loop {
            let q = |x: f32| (x.clamp(0.0, 1.0) * 65535.0).round() as u16;
            out.push(level.iter().map(|p| [q(p[0]), q(p[1]), q(p[2]), u16::MAX]).collect());
            if s == 1 {
                return out;
            }
            let n = (s / 2).max(1);
            level = resample(&level, s, s, n, n);
            s = n;
        }
    }
}

/// Box-resample a linear RGBA image (w × h) to (nw × nh): each output texel averages the source area it covers
/// (exactly, with fractional coverage at its edges), so that minification keeps the mean albedo.
fn resample(src: &[[f32; 4]], w: u32, h: u32, nw: u32, nh: u32) -> Vec<[f32; 4]> {
    if (w, h) == (nw, nh) {
        return src.to_vec();
    }
    // Per axis: for each output index, the source indices and weights it covers.
    let spans = |n: u32, old: u32| -> Vec<Vec<(u32, f32)>> {
        let scale = old as f64 / n as f64;
        (0..n)
            .map(|i| {
                let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
                let mut v = Vec::new();
                let mut j = a.floor() as u32;
                while (j as f64) < b && j < old {
                    let cover = (b.min(j as f64 + 1.0) - a.max(j as f64)).max(0.0);
                    if cover > 0.0 {
                        v.push((j, (cover / scale) as f32));
                    }
                    j += 1;
                }
                v
            })
            .collect()
    };
    let (sx, sy) = (spans(nw, w), spans(nh, h));
    let mut out = vec![[0.0f32; 4]; (nw * nh) as usize];
    for (y, ys) in sy.iter().enumerate() {
        for (x, xs) in sx.iter().enumerate() {
            let mut acc = [0.0f32; 4];
            for &(j, wy) in ys {
                for &(i, wx) in xs {
                    let p = src[(j * w + i) as usize];
                    for k in 0..4 {
                        acc[k] += p[k] * wx * wy;
                    }
                }
            }
            out[y * nw as usize + x] = acc;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_code() {
        for c in 0..=255u8 {
            assert_eq!(linear_to_srgb(srgb_to_linear(c)), c);
        }
    }

    #[test]
    fn checker_alternates_from_the_top_left() {
        let t = Texture::checker(Vec3::ONE, Vec3::ZERO, 4);
        assert_eq!(t.texel_at(Vec2::new(0.1, 0.1)), Vec3::ONE);
        assert_eq!(t.texel_at(Vec2::new(0.3, 0.1)), Vec3::ZERO);
        assert_eq!(t.texel_at(Vec2::new(0.3, 0.3)), Vec3::ONE);
        // It repeats outside [0, 1].
        assert_eq!(t.texel_at(Vec2::new(1.1, -0.9)), Vec3::ONE);
    }

    #[test]
    fn mips_keep_the_mean_albedo() {
        let t = Texture::checker(Vec3::new(0.9, 0.5, 0.1), Vec3::new(0.1, 0.2, 0.3), 3);
        let chain = t.mip_chain(64);
        assert_eq!(chain.len(), 7);
        assert_eq!(chain[6].len(), 1);
        let last = chain[6][0];
        let mean = t.mean();
        // The box filter keeps the mean; 16 bits hold it to 8e-6.
        for k in 0..3 {
            let got = last[k] as f32 / 65535.0;
            assert!((got - mean[k]).abs() <= 1e-5 + 1e-5 * mean[k], "channel {k}: {got} vs {}", mean[k]);
        }
        // Level 0 at the texture's own size is its texels, decoded.
        assert_eq!(chain[0][5][0], (srgb_to_linear(t.texels[5][0]) * 65535.0).round() as u16);
    }

    #[test]
    fn a_non_image_is_refused() {
        let e = Texture::decode("x", b"not an image").unwrap_err();
        assert!(e.contains("not a PNG, JPEG or WebP"), "{e}");
    }
}
