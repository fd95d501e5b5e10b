//! The library's error type: one enum that callers can match on.

use std::path::PathBuf;

/// Every failure the library reports. Messages are lowercase, without a full stop.
#[derive(Debug)]
#[non_exhaustive]
pub enum Error {
    /// Embree reported an error through its device callback, or returned a null handle.
    Embree {
        /// Embree's `RTCError` code (0 when the failure was a null handle).
        code: u32,
        /// What Embree said, or what call returned null.
        message: String,
    },
    /// A scene file could not be read or parsed.
    Load {
        /// The file.
        path: PathBuf,
        /// What went wrong.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A scene that loaded but cannot be traced (no light, bad values, ...).
    InvalidScene(String),
    /// A parameter outside its domain (NaN, negative, out of range).
    InvalidParameter {
        /// The parameter's name as the user knows it.
        name: &'static str,
        /// Why it was rejected, with the value.
        reason: String,
    },
    /// A run would store more photons than the memory budget allows
    /// (`TraceConfig::memory_budget`, by default a share of the machine's memory).
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
    OutOfMemory {
        /// What the memory was for.
        what: &'static str,
        /// Bytes asked for.
        bytes: u64,
        /// The run's memory budget.
        budget_bytes: u64,
    },
    /// Reading or writing a file failed.
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        source: std::io::Error,
    },
}

// Written out rather than derived: `thiserror` cost two crates of the
// forty a library user compiles (`scripts/count-deps.sh`).
impl std::fmt::Display for Error {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Error::Embree { code, message } => write!(f, "embree error {code}: {message}"),
            Error::Load { path, .. } => write!(f, "cannot load {}", path.display()),
            Error::InvalidScene(what) => write!(f, "invalid scene: {what}"),
            Error::InvalidParameter { name, reason } => {
                write!(f, "invalid parameter `{name}`: {reason}")
            }
            Error::Budget {
                photons,
                needed_bytes,
                budget_bytes,
            } => write!(
                f,
                "photon budget exceeded: {photons} photons would need {needed_bytes} bytes \
                 but the memory budget is {budget_bytes} bytes (raise the budget or lower the \
                 quality)"
            ),
            Error::OutOfMemory {
                what,
                bytes,
                budget_bytes,
            } => write!(
                f,
                "the system refused {bytes} bytes for {what}, although the memory budget \
                 allows {budget_bytes} bytes"
            ),
            Error::Io { path, .. } => write!(f, "cannot access {}", path.display()),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Load { source, .. } => Some(source.as_ref()),
            Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::error::Error as _;

    #[test]
    fn messages_and_sources() {
        let budget = Error::Budget {
            photons: 3,
            needed_bytes: 48,
            budget_bytes: 16,
        };
        assert_eq!(
            budget.to_string(),
            "photon budget exceeded: 3 photons would need 48 bytes but the memory budget is \
             16 bytes (raise the budget or lower the quality)"
        );
        let oom = Error::OutOfMemory {
            what: "the photon map",
            bytes: 64,
            budget_bytes: 128,
        };
        assert_eq!(
            oom.to_string(),
            "the system refused 64 bytes for the photon map, although the memory budget allows \
             128 bytes"
        );
        assert_eq!(
            Error::param("k", "must be at least 1, got 0").to_string(),
            "invalid parameter `k`: must be at least 1, got 0"
        );
        assert_eq!(
            Error::Embree {
                code: 2,
                message: "x".into()
            }
            .to_string(),
            "embree error 2: x"
        );
        assert!(budget.source().is_none());
        let io = Error::Io {
            path: "/no/such".into(),
            source: std::io::Error::new(std::io::ErrorKind::NotFound, "gone"),
        };
        assert_eq!(io.to_string(), "cannot access /no/such");
        assert_eq!(io.source().unwrap().to_string(), "gone");
        let load = Error::Load {
            path: "a.gltf".into(),
            source: "bad json".into(),
        };
        assert_eq!(load.to_string(), "cannot load a.gltf");
        assert_eq!(load.source().unwrap().to_string(), "bad json");
        assert_eq!(
            Error::InvalidScene("no light".into()).to_string(),
            "invalid scene: no light"
        );
    }
}
