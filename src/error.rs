//! Application-level errors and their exit codes: 2 for bad input, 1 for everything else.

use crate::scene::SceneError;
use crate::vk::VkError;

/// The library's errors. [`AppError::exit_code`] maps them to the CLI's exit codes.
#[derive(Debug, thiserror::Error)]
pub enum AppError {
    /// A scene that cannot be read (bad input).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A bad argument or input file; the message names it.
    #[error("{0}")]
    BadInput(String),
    /// A Vulkan call or requirement failed.
    #[error(transparent)]
    Vk(#[from] VkError),
    /// A file could not be read or written.
    #[error("{0}")]
    Io(String),
    /// The command ran but its check failed (for example `compare` above a threshold).
    #[error("{0}")]
    Failed(String),
}

impl AppError {
    /// 2 for bad input (an argument, a scene, an image), 1 for anything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            AppError::Scene(_) | AppError::BadInput(_) => 2,
            _ => 1,
        }
    }
}

/// The result of a library operation.
pub type AppResult<T> = Result<T, AppError>;
