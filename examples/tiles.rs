//! Write the pool's tile texture, `assets/textures/pool_tiles.png` (CC0): 8 × 8 square glazed tiles with grout
//! lines between them, 64 texels a tile. Each tile takes a slightly different glaze (a fixed hash of its row and
//! column), as fired tiles do, so the repeats of the texture do not read as a grid of copies. The scenes map it
//! with `uv_scale` so that one tile is 12.5 cm, a common pool tile, with grout about 6 mm wide.
//!
//! ```text
//! cargo run --release --example tiles [-- OUT.png]
//! ```

/// Texels per tile, tiles per side, grout half-width (texels).
const TILE: u32 = 64;
const TILES: u32 = 8;
const GROUT: f32 = 1.6;

/// The glaze (sRGB 8-bit): a pool tile's aqua, and the grout: a light cement grey.
const GLAZE: [f32; 3] = [104.0, 182.0, 210.0];
const GROUT_COLOR: [f32; 3] = [196.0, 200.0, 198.0];

/// A fixed hash of a tile's row and column, in [0, 1).
fn hash(x: u32, y: u32) -> f32 {
    let mut h = x.wrapping_mul(0x9E37_79B9) ^ y.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    (h & 0xFFFF) as f32 / 65536.0
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| "assets/textures/pool_tiles.png".into());
    let side = TILE * TILES;
    let mut img = image::RgbImage::new(side, side);
    for (x, y, px) in img.enumerate_pixels_mut() {
        let (tx, ty) = (x / TILE, y / TILE);
        // Distance to the tile's nearest edge, texel centres: the grout fills GROUT texels on each side of a seam,
        // with one texel of bevel into the glaze.
        let (fx, fy) = ((x % TILE) as f32 + 0.5, (y % TILE) as f32 + 0.5);
        let edge = fx.min(TILE as f32 - fx).min(fy).min(TILE as f32 - fy);
        let glaze_t = ((edge - GROUT) / 1.5).clamp(0.0, 1.0);
        let shade = 0.94 + 0.08 * hash(tx, ty);
        let bevel = 0.92 + 0.08 * glaze_t;
        for c in 0..3 {
            let glaze = (GLAZE[c] * shade * bevel).min(255.0);
            px[c] = (GROUT_COLOR[c] + (glaze - GROUT_COLOR[c]) * glaze_t).round() as u8;
        }
    }
    if let Some(dir) = std::path::Path::new(&out).parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    if let Err(e) = img.save(&out) {
        eprintln!("tiles: {out}: {e}");
        std::process::exit(1);
    }
    println!("wrote {out} ({side}x{side})");
}
