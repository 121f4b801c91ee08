//! An on-disk cache of reference images for the bench and the tests.
//!
//! Entries live in `$CAUSTICS_CACHE_DIR`, else `$CARGO_TARGET_DIR/reference-cache`, else the crate's
//! `target/reference-cache`. The key hashes everything the image depends on: the scene file's bytes, the bytes of
//! every mesh file it names, the camera, AOV, paths, photon count, size and seed, plus the tracer's own source
//! (every file of src/reference but this one), so that any change to the tracer traces its references again. The
//! thread count is not part of it (the image does not depend on it).

use super::{trace, RefParams};
use crate::error::{Error, Result};
use crate::image_io::{self, RgbImage};
use crate::scene::Scene;
use std::path::{Path, PathBuf};

/// The tracer's source: src/reference's files but this cache (a test checks that none is missing).
const TRACER_SOURCE: [(&str, &str); 5] = [
    ("geometry.rs", include_str!("geometry.rs")),
    ("mod.rs", include_str!("mod.rs")),
    ("optics.rs", include_str!("optics.rs")),
    ("sampling.rs", include_str!("sampling.rs")),
    ("tracer.rs", include_str!("tracer.rs")),
];

/// 64-bit FNV-1a, stable across Rust versions and platforms (std's hashers are not).
struct Fnv(u64);

impl Fnv {
    fn new(basis: u64) -> Self {
        Fnv(basis)
    }
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    /// Length-prefixed, so that consecutive fields cannot run into each other.
    fn field(&mut self, b: &[u8]) {
        self.bytes(&(b.len() as u64).to_le_bytes());
        self.bytes(b);
    }
}

/// The cache directory the environment names: `CAUSTICS_CACHE_DIR`, else `$CARGO_TARGET_DIR/reference-cache`, else
/// the crate's `target/reference-cache` (the library reads the environment only through this helper).
pub fn cache_dir_from_env() -> PathBuf {
    if let Some(d) = std::env::var_os("CAUSTICS_CACHE_DIR") {
        return PathBuf::from(d);
    }
    if let Some(d) = std::env::var_os("CARGO_TARGET_DIR") {
        return PathBuf::from(d).join("reference-cache");
    }
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target").join("reference-cache")
}

/// Files the scene reads besides itself, resolved like the scene loader does: the mesh files of a TOML scene
/// (`path = ...` of its objects), the external buffers of a glTF scene (`buffers[].uri` that are not data URIs).
fn mesh_files(scene_path: &Path, text: &str) -> Vec<PathBuf> {
    let dir = scene_path.parent().map(Path::to_path_buf).unwrap_or_default();
    if let Ok(doc) = serde_json::from_str::<serde_json::Value>(text) {
        let buffers = doc.get("buffers").and_then(|b| b.as_array()).cloned().unwrap_or_default();
        return buffers
            .iter()
            .filter_map(|b| b.get("uri").and_then(|u| u.as_str()))
            .filter(|u| !u.starts_with("data:"))
            .map(|u| dir.join(u))
            .collect();
    }
    let Ok(table) = text.parse::<toml::Table>() else {
        return Vec::new();
    };
    let Some(objects) = table.get("object").and_then(|o| o.as_array()) else {
        return Vec::new();
    };
    objects.iter().filter_map(|o| o.get("path").and_then(|p| p.as_str()).map(|p| dir.join(p))).collect()
}

/// The cache key (32 hex digits) of a reference run.
pub fn cache_key(scene_path: &Path, p: &RefParams) -> Result<String> {
    let read =
        |path: &Path| std::fs::read(path).map_err(|e| Error::BadInput(format!("{}: cannot read: {e}", path.display())));
    let text = read(scene_path)?;
    let mut parts: Vec<Vec<u8>> = TRACER_SOURCE.iter().map(|(_, source)| source.as_bytes().to_vec()).collect();
    parts.push(text.clone());
    for mesh in mesh_files(scene_path, &String::from_utf8_lossy(&text)) {
        parts.push(read(&mesh)?);
    }
    let params = format!(
        "camera={:?} aov={} paths={} photons={} size={}x{} seed={} time={}",
        p.camera, p.aov, p.paths, p.photons, p.width, p.height, p.seed, p.time
    );
    parts.push(params.into_bytes());
    let mut key = String::new();
    for basis in [0xcbf2_9ce4_8422_2325u64, 0x84222325cbf29ce4] {
        let mut h = Fnv::new(basis);
        for part in &parts {
            h.field(part);
        }
        key.push_str(&format!("{:016x}", h.0));
    }
    Ok(key)
}

/// The reference for `scene_path` and `p` from the cache in `dir` (created if missing), traced and stored there
/// the first time.
pub fn cached_in(dir: &Path, scene_path: &Path, p: &RefParams) -> Result<RgbImage> {
    let key = cache_key(scene_path, p)?;
    let exr = dir.join(format!("{key}.exr"));
    if exr.is_file() {
        if let Ok(img) = image_io::read_exr(&exr) {
            if img.width == p.width && img.height == p.height {
                return Ok(img);
            }
        }
    }
    let scene = Scene::load(scene_path)?;
    let out = trace(&scene, p)?;
    std::fs::create_dir_all(dir).map_err(|e| Error::Io(format!("{}: cannot create: {e}", dir.display())))?;
    let json = serde_json::to_string_pretty(&out.stats).map_err(|e| Error::Failed(e.to_string()))?;
    image_io::write_text(&dir.join(format!("{key}.json")), &json)?;
    image_io::write_exr(&exr, &out.image)?;
    Ok(out.image)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The key covers every file of the tracer: a file added to src/reference must join `TRACER_SOURCE`.
    #[test]
    fn the_key_holds_every_file_of_the_tracer() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/reference");
        let mut files: Vec<String> = std::fs::read_dir(&dir)
            .expect("src/reference")
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| n.ends_with(".rs") && n != "cache.rs")
            .collect();
        files.sort();
        let listed: Vec<&str> = TRACER_SOURCE.iter().map(|(name, _)| *name).collect();
        assert_eq!(files, listed, "src/reference's files against TRACER_SOURCE");
    }
}
