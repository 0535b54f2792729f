//! One error type for the library. Every fallible call returns `Result`; the C ABI maps
//! each variant to a status code and keeps `Display` as the readable last-error message.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// A scene file is malformed or refers to something that does not exist.
    #[error("{file}: {field}: {message}")]
    Scene { file: String, field: String, message: String },
    /// A value is outside its documented range (IOR ≤ 0, NaN position, unknown knob …).
    #[error("{what}: {message}")]
    InvalidInput { what: String, message: String },
    /// No Vulkan loader, no suitable device, a missing extension or feature.
    #[error("Vulkan unavailable: {0}")]
    Unsupported(String),
    /// Device or host memory ran out.
    #[error("out of memory: {0}")]
    OutOfMemory(String),
    /// Any other Vulkan failure, with the call that failed.
    #[error("{call}: {result}")]
    Vulkan { call: &'static str, result: ash::vk::Result },
    /// The validation layer reported errors while the frame ran (tests fail on these).
    #[error("Vulkan validation reported {0} error(s)")]
    Validation(u32),
    #[error("{0}")]
    Image(String),
    /// A scene update the renderer cannot take in place: the plan a fresh renderer would make
    /// for the new state has other stages or maps (objects came into each other's view, …).
    /// The update itself is valid; a new renderer (or, through the C ABI, a reconfigure)
    /// renders it.
    #[error("scene update: the plan changes ({0}): make a new renderer")]
    PlanChanged(String),
}

pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    pub fn invalid(what: impl Into<String>, message: impl Into<String>) -> Error {
        Error::InvalidInput { what: what.into(), message: message.into() }
    }
    pub fn scene(file: impl Into<String>, field: impl Into<String>, message: impl Into<String>) -> Error {
        Error::Scene { file: file.into(), field: field.into(), message: message.into() }
    }
    pub fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Error {
        Error::Io { path: path.into(), source }
    }
}

/// Attaches the failing call's name to a `vk::Result`.
pub trait VkCall<T> {
    fn call(self, call: &'static str) -> Result<T>;
}

impl<T> VkCall<T> for std::result::Result<T, ash::vk::Result> {
    fn call(self, call: &'static str) -> Result<T> {
        self.map_err(|result| match result {
            ash::vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | ash::vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
                Error::OutOfMemory(format!("{call}: {result}"))
            }
            _ => Error::Vulkan { call, result },
        })
    }
}

/// A value for an error message: at most 64 characters (a 100 kB value is not echoed back
/// in full), with "…" where it was cut.
pub fn clip(s: &str) -> String {
    const MAX: usize = 64;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        s.chars().take(MAX).collect::<String>() + "…"
    }
}

/// A whole message on one line, at most 300 characters.
pub fn clip_long(s: &str) -> String {
    let one: String = s.split_whitespace().collect::<Vec<_>>().join(" ");
    if one.chars().count() <= 300 {
        one
    } else {
        one.chars().take(300).collect::<String>() + "…"
    }
}
