//! The library's errors, and the exit codes the CLI gives them: 2 for bad input, 1 for everything else.

use crate::scene::SceneError;
use crate::vk::VkError;

/// The library's errors. [`Error::exit_code`] maps them to the CLI's exit codes.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A scene that cannot be read (bad input).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// A bad argument or input file; the message names it.
    #[error("{0}")]
    BadInput(String),
    /// A setting outside its range, or one the scene cannot be rendered with (bad input). `field` names it as the
    /// library's types do (`Quality::level`); the CLI names its flag instead.
    #[error("{field} = {value}: {rule}")]
    Setting {
        /// The field, as `Type::field`.
        field: &'static str,
        /// Its value, as given.
        value: String,
        /// What it must be.
        rule: String,
    },
    /// A Vulkan call or requirement failed.
    #[error(transparent)]
    Vk(#[from] VkError),
    /// A file could not be read or written.
    #[error("{0}")]
    Io(String),
    /// An image file could not be read or written.
    #[error(transparent)]
    Image(#[from] crate::image_io::ImageError),
    /// The command ran but its check failed (for example `compare` above a threshold).
    #[error("{0}")]
    Failed(String),
}

impl Error {
    /// 2 for bad input (an argument, a scene, an image), 1 for anything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Scene(_) | Error::BadInput(_) | Error::Setting { .. } => 2,
            Error::Image(e) => match e {
                crate::image_io::ImageError::Write { .. } => 1,
                _ => 2,
            },
            _ => 1,
        }
    }

    /// A [`Error::Setting`].
    pub fn setting(field: &'static str, value: impl std::fmt::Display, rule: impl Into<String>) -> Error {
        Error::Setting { field, value: value.to_string(), rule: rule.into() }
    }
}

/// The result of a library operation (a second parameter names another error type, as `std::result::Result`).
pub type Result<T, E = Error> = std::result::Result<T, E>;
