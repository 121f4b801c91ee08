//! Application-level errors and their exit codes: 2 for bad input, 1 for everything else.

use crate::scene::SceneError;
use crate::vk::VkError;

#[derive(Debug, thiserror::Error)]
pub enum AppError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A bad argument or input file; the message names it.
    #[error("{0}")]
    BadInput(String),
    #[error(transparent)]
    Vk(#[from] VkError),
    #[error("{0}")]
    Io(String),
    /// The command ran but its check failed (for example `compare` above a threshold).
    #[error("{0}")]
    Failed(String),
}

impl AppError {
    pub fn exit_code(&self) -> i32 {
        match self {
            AppError::Scene(_) | AppError::BadInput(_) => 2,
            _ => 1,
        }
    }
}

pub type AppResult<T> = Result<T, AppError>;
