//! Image files: 32-bit float OpenEXR for the physical AOVs, 8-bit PNG for `beauty`. Every write goes to a
//! temporary file in the same directory and is renamed into place, so a failed run never leaves a half-written
//! file behind.

use std::path::{Path, PathBuf};

/// An image file that cannot be read or written. A leaf of the library: the library's [`crate::Error`] wraps it
/// (a file that cannot be read, or a directory that does not exist, is bad input; a failed write is not).
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// The file cannot be read as the image it should be.
    #[error("{path}: cannot read {format}: {message}")]
    Read {
        /// The file.
        path: PathBuf,
        /// EXR or PNG.
        format: &'static str,
        /// The decoder's message.
        message: String,
    },
    /// The directory a file would be written into does not exist.
    #[error("{0}: output directory does not exist")]
    NoDirectory(PathBuf),
    /// Writing failed (nothing is left behind).
    #[error("{path}: cannot write: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// What failed.
        message: String,
    },
}

type Result<T, E = ImageError> = std::result::Result<T, E>;

/// An RGB float image, row-major, row 0 at the top.
#[derive(Clone, Debug)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Pixels, row-major from the top-left.
    pub data: Vec<[f32; 3]>,
}

impl RgbImage {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Self {
        RgbImage { width, height, data: vec![[0.0; 3]; (width * height) as usize] }
    }

    /// The pixel at column `x`, row `y`.
    pub fn at(&self, x: u32, y: u32) -> [f32; 3] {
        self.data[(y * self.width + x) as usize]
    }

    /// One channel as a plane of floats.
    pub fn channel(&self, c: usize) -> Vec<f32> {
        self.data.iter().map(|p| p[c]).collect()
    }
}

fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    path.with_file_name(format!(".{name}.partial-{}", std::process::id()))
}

/// Bad input unless the directory `path` would be written into exists (checked before any work starts, so
/// that a long render does not fail at its end).
pub fn check_output_dir(path: &Path) -> Result<()> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) if !dir.is_dir() => Err(ImageError::NoDirectory(path.to_path_buf())),
        _ => Ok(()),
    }
}

/// Write through a temporary file and rename it into place.
pub fn write_atomic(path: &Path, write: impl FnOnce(&Path) -> Result<(), String>) -> Result<()> {
    check_output_dir(path)?;
    let tmp = temp_path(path);
    match write(&tmp).and_then(|_| std::fs::rename(&tmp, path).map_err(|e| e.to_string())) {
        Ok(()) => Ok(()),
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            Err(ImageError::Write { path: path.to_path_buf(), message: e })
        }
    }
}

/// Write `img` as a 32-bit float OpenEXR (through a temporary file, renamed: no half-written file).
pub fn write_exr(path: &Path, img: &RgbImage) -> Result<()> {
    write_exr_meta(path, img, &ExrMeta::new())
}

/// Metadata of an EXR this program wrote: `caustics.*` string attributes of its header (without the prefix):
/// `scene_hash`, `camera`, `camera_kind`, `aov`, `units`, `transport`, `level`, ... (docs/design.md).
pub type ExrMeta = std::collections::BTreeMap<String, String>;

/// The prefix of the header attributes that hold [`ExrMeta`].
pub const META_PREFIX: &str = "caustics.";

/// Write an RGB float EXR with `meta` as `caustics.<key>` text attributes in its header.
pub fn write_exr_meta(path: &Path, img: &RgbImage, meta: &ExrMeta) -> Result<()> {
    use exr::meta::attribute::{AttributeValue, Text};
    use exr::prelude::*;
    write_atomic(path, |tmp| {
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let p: [f32; 3] = img.data[y * img.width as usize + x];
            (p[0], p[1], p[2])
        });
        let mut image = Image::from_channels((img.width as usize, img.height as usize), channels);
        for (k, v) in meta {
            let (Some(key), Some(value)) = (Text::new_or_none(format!("{META_PREFIX}{k}")), Text::new_or_none(v))
            else {
                return Err(format!("EXR attribute {k} = {v}: not representable as EXR text"));
            };
            image.layer_data.attributes.other.insert(key, AttributeValue::Text(value));
        }
        image.write().to_file(tmp).map_err(|e| e.to_string())
    })
}

/// Read an OpenEXR's RGB channels.
pub fn read_exr(path: &Path) -> Result<RgbImage> {
    read_exr_meta(path).map(|(img, _)| img)
}

/// Read an EXR's first RGB(A) layer and its `caustics.*` header attributes (empty for other files).
pub fn read_exr_meta(path: &Path) -> Result<(RgbImage, ExrMeta)> {
    use exr::meta::attribute::AttributeValue;
    use exr::prelude::*;
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| RgbImage::new(res.width() as u32, res.height() as u32),
        |img: &mut RgbImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width as usize;
            img.data[pos.y() * w + pos.x()] = [r, g, b];
        },
    )
    .map_err(|e| ImageError::Read { path: path.to_path_buf(), format: "EXR", message: e.to_string() })?;
    let mut meta = ExrMeta::new();
    let layer = &image.layer_data.attributes.other;
    for (k, v) in layer.iter().chain(image.attributes.other.iter()) {
        if let (Some(key), AttributeValue::Text(t)) = (k.to_string().strip_prefix(META_PREFIX), v) {
            meta.insert(key.to_string(), t.to_string());
        }
    }
    Ok((image.layer_data.channel_data.pixels, meta))
}

/// FNV-1a (64 bit) of a file's bytes, as 16 hex digits: the scene hash of [`ExrMeta`].
pub fn file_hash(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap_or_default();
    let mut h: u64 = 0xcbf29ce484222325;
    for b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100000001b3);
    }
    format!("{h:016x}")
}

/// Write 8-bit RGBA (already tone-mapped and sRGB-encoded).
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<()> {
    write_atomic(path, |tmp| {
        image::save_buffer_with_format(tmp, rgba, width, height, image::ColorType::Rgba8, image::ImageFormat::Png)
            .map_err(|e| e.to_string())
    })
}

/// Read a PNG as (width, height, RGBA8 bytes).
pub fn read_png(path: &Path) -> Result<(u32, u32, Vec<u8>)> {
    let img = image::open(path).map_err(|e| ImageError::Read {
        path: path.to_path_buf(),
        format: "PNG",
        message: e.to_string(),
    })?;
    let rgba = img.to_rgba8();
    Ok((rgba.width(), rgba.height(), rgba.into_raw()))
}

/// Write text (JSON, Markdown, SVG) atomically.
pub fn write_text(path: &Path, text: &str) -> Result<()> {
    write_atomic(path, |tmp| std::fs::write(tmp, text).map_err(|e| e.to_string()))
}
