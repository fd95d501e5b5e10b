//! The library's error type: one enum that callers can match on.

use std::path::PathBuf;

/// Every failure the library reports. Messages are lowercase, without a full stop.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Embree reported an error through its device callback, or returned a null handle.
    #[error("embree error {code}: {message}")]
    Embree {
        /// Embree's `RTCError` code (0 when the failure was a null handle).
        code: u32,
        /// What Embree said, or what call returned null.
        message: String,
    },
    /// A scene file could not be read or parsed.
    #[error("cannot load {}", path.display())]
    Load {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A scene that loaded but cannot be traced (no light, bad values, ...).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A parameter outside its domain (NaN, negative, out of range).
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter {
        /// The parameter's name as the user knows it.
        name: &'static str,
        /// Why it was rejected, with the value.
        reason: String,
    },
    /// A run would store more photons than the memory budget allows
    /// (`TraceConfig::memory_budget`, by default a share of the machine's memory).
    #[error(
        "photon budget exceeded: {photons} photons would need {needed_bytes} bytes \
         but the memory budget is {budget_bytes} bytes (raise the budget or lower the quality)"
    )]
    Budget {
        /// Photons the run asked for.
        photons: u64,
        /// Bytes they would take.
        needed_bytes: u64,
        /// Bytes allowed.
        budget_bytes: u64,
    },
    /// The system refused memory that the budget allows: a limit on the
    /// process's address space, or memory other processes hold.
    #[error(
        "the system refused {bytes} bytes for {what}, although the memory budget allows \
         {budget_bytes} bytes"
    )]
    OutOfMemory {
        /// What the memory was for.
        what: &'static str,
        /// Bytes asked for.
        bytes: u64,
        /// The run's memory budget.
        budget_bytes: u64,
    },
    /// Reading or writing a file failed.
    #[error("cannot access {}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
}

/// `Result` with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub fn param(name: &'static str, reason: impl Into<String>) -> Self {
        Error::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}

/// Rejects NaN, infinite and negative values of a named parameter.
pub fn check_non_negative(name: &'static str, value: f32) -> Result<f32> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(Error::param(
            name,
            format!("must be a finite number >= 0, got {value}"),
        ))
    }
}
