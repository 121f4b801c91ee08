//! The exact CPU photon tracer (`caustics reference`). Placeholder: being written.

use crate::error::{AppError, AppResult};
use std::path::PathBuf;

/// `caustics reference` arguments.
#[derive(clap::Args, Debug, Clone)]
pub struct ReferenceArgs {
    /// Scene file (default: the default scene in assets/scenes/).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Camera name (must be orthographic).
    #[arg(long)]
    pub camera: Option<String>,
    /// AOV to write: caustics or direct.
    #[arg(long, default_value = "caustics")]
    pub aov: String,
    /// Number of photons.
    #[arg(long, default_value_t = 4_000_000)]
    pub photons: u64,
    /// Output size WxH.
    #[arg(long, default_value = "512x512")]
    pub size: String,
    #[arg(long)]
    pub out: PathBuf,
}

pub fn run(_args: &ReferenceArgs) -> AppResult<()> {
    Err(AppError::Failed("reference: not implemented yet".into()))
}
