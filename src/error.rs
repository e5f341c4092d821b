//! The library's error type. Every variant renders as one line that names the file, key
//! or value at fault; the CLI prints it and exits non-zero.

/// Errors of luxtally's library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad user input: `origin` names the file (and key) at fault.
    #[error("{origin}: {message}")]
    Input { origin: String, message: String },
    /// A file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// Embree reported an error through its device error callback.
    #[error("embree: {0}")]
    Embree(String),
    /// A requested feature is not available in this build or on this machine.
    #[error("{0}")]
    Unsupported(String),
}

impl Error {
    /// Bad input at `origin` (a file, or `file: key`).
    pub fn input(origin: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Input {
            origin: origin.into(),
            message: message.into(),
        }
    }

    /// An I/O error on `path`.
    pub fn io(path: impl AsRef<std::path::Path>, source: std::io::Error) -> Self {
        Error::Io {
            path: path.as_ref().display().to_string(),
            source,
        }
    }
}

pub type Result<T> = std::result::Result<T, Error>;
