//! Library error type: every variant names the file (and the line or field) at fault.

use std::path::{Path, PathBuf};

/// Errors raised by the pradar library. The `Display` text is one line naming the file and
/// the field or line, so the command line can print it as is.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read or written.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A file was read but its content is wrong (malformed, truncated, inconsistent).
    #[error("{}: {msg}", file.display())]
    Input {
        /// The file.
        file: PathBuf,
        /// What is wrong, naming the line or field.
        msg: String,
    },
    /// A parameter failed validation.
    #[error("invalid parameter `{field}`: {msg}")]
    Param {
        /// The parameter (dotted path).
        field: String,
        /// Why it is invalid.
        msg: String,
    },
    /// A Parquet/CSV table operation failed.
    #[error("{}: table error: {msg}", file.display())]
    Table {
        /// The file.
        file: PathBuf,
        /// The polars message.
        msg: String,
    },
    /// A figure could not be drawn.
    #[error("{}: plot error: {msg}", file.display())]
    Plot {
        /// The output file.
        file: PathBuf,
        /// The plotting backend message.
        msg: String,
    },
}

/// Result alias for the library.
pub type Result<T, E = Error> = std::result::Result<T, E>;

impl Error {
    /// An input error for `file` with message `msg`.
    pub fn input(file: impl AsRef<Path>, msg: impl Into<String>) -> Self {
        Error::Input {
            file: file.as_ref().to_path_buf(),
            msg: msg.into(),
        }
    }
    /// An I/O error for `file`.
    pub fn io(file: impl AsRef<Path>, source: std::io::Error) -> Self {
        Error::Io {
            file: file.as_ref().to_path_buf(),
            source,
        }
    }
    /// A parameter error for `field`.
    pub fn param(field: impl Into<String>, msg: impl Into<String>) -> Self {
        Error::Param {
            field: field.into(),
            msg: msg.into(),
        }
    }
    /// A table error for `file`.
    pub fn table(file: impl AsRef<Path>, msg: impl std::fmt::Display) -> Self {
        Error::Table {
            file: file.as_ref().to_path_buf(),
            msg: msg.to_string(),
        }
    }
}

/// A number as a message prints it: as Rust writes it (the shortest text that reads back
/// the same) for magnitudes in [1e-3, 1e7) and 0, in exponent form otherwise (`1e300`,
/// not 301 digits; `2.5e-9`), so one line stays one short line whatever a file holds.
pub fn short(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-3..1e7).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_in_messages_are_short() {
        assert_eq!(short(1e300), "1e300");
        assert_eq!(short(-1e308), "-1e308");
        assert_eq!(short(2.5e-9), "2.5e-9");
        assert_eq!(short(0.5), "0.5");
        assert_eq!(short(20000.0), "20000");
        assert_eq!(short(1e7), "1e7");
        assert_eq!(short(0.0), "0");
        assert_eq!(short(f64::NAN), "NaN");
        assert_eq!(short(f64::INFINITY), "inf");
        // a value read back from its text
        let v = 1e297f64.sqrt();
        assert_eq!(short(v).parse::<f64>().unwrap(), v);
    }
}
