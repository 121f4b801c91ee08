//! The error metric used everywhere (`caustics compare`, bench, tests). Placeholder: being written.

use crate::error::{AppError, AppResult};
use std::path::PathBuf;

#[derive(clap::Args, Debug, Clone)]
pub struct CompareArgs {
    pub a: PathBuf,
    pub b: PathBuf,
}

pub fn run_compare(_args: &CompareArgs) -> AppResult<()> {
    Err(AppError::Failed("compare: not implemented yet".into()))
}
