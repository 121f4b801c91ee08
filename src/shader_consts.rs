// Constants shared by Rust and GLSL. build.rs `include!`s this file and passes every constant to shaderc as a
// macro definition, so the two sides cannot drift. Keep it to plain `pub const NAME: u32 = value;` lines.

/// Side of the traversal work group (Piao's 8x8). The bench sweeps TRAVERSE_WG_SWEEP.
pub const TRAVERSE_WG: u32 = 8;
/// Side of the level-0 photon grid (Wyman's 64x64).
pub const LEVEL0_RES: u32 = 64;
/// Traversal levels 0..MAX_LEVELS (level 16 is a 4,194,304² grid). Cell x and y are packed in 24 bits.
pub const MAX_LEVELS: u32 = 17;
/// Work-group size of 1D compute passes.
pub const LINEAR_WG: u32 = 64;
/// Side of the work group of 2D image passes.
pub const TILE_WG: u32 = 8;
/// Largest splat radius in caustic-map texels (point size 2r must stay within lavapipe's 255).
pub const MAX_SPLAT_RADIUS: u32 = 64;
/// Side of the shared-memory window in which the tiled compute splat gathers a work group's taps.
pub const SPLAT_TILE: u32 = 32;
/// Mip levels kept in the coverage pyramid (covers refractor g-buffers up to 64·2^(MAX_PYRAMID_MIPS-1)).
pub const MAX_PYRAMID_MIPS: u32 = 12;
/// Largest number of photon batches recorded per frame.
pub const MAX_BATCHES: u32 = 4096;
/// Capacity of the GPU tile stack used by batching (depth-first: at most 3 per level, plus one).
pub const TILE_STACK: u32 = 96;
/// Exact transport: the most specular interactions a path may have before it is cut (the CPU reference's cap).
pub const MAX_INTERACTIONS: u32 = 32;
/// Exact transport: energy-account terms are fixed point with 2^ACCOUNT_SHIFT units per sr (or m²).
pub const ACCOUNT_SHIFT: u32 = 44;
