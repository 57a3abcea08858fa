//! The crate's one error type. Every fallible library call returns [`Result`]; `main` prints the
//! error on one line and exits with code 2. Scene and mesh errors carry their position and render
//! as `path:line:col: expected ..., found ...`.

use std::fmt;
use std::path::{Path, PathBuf};

/// Everything that can go wrong between a command line and a written image.
#[derive(Debug)]
pub enum Error {
    /// A scene or OBJ file is malformed (or asks for something unsupported) at a known position.
    Parse {
        path: PathBuf,
        line: usize,
        col: usize,
        msg: String,
    },
    /// A file could not be read or written.
    Io {
        path: PathBuf,
        action: &'static str,
        source: std::io::Error,
    },
    /// The command line is malformed.
    Usage(String),
    /// The command line of subcommand `command` is malformed: the hint names that command's
    /// own `--help` ([`Error::in_command`] makes it from a [`Error::Usage`]).
    CommandUsage { command: &'static str, msg: String },
    /// A request exceeds a resource limit (image size, bounce count, memory).
    Limit(String),
    /// Anything else that stops a render, with a readable message.
    Other(String),
}

/// The crate's result type.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// A positioned parse error.
    pub fn parse(path: &Path, line: usize, col: usize, msg: impl Into<String>) -> Error {
        Error::Parse {
            path: path.to_path_buf(),
            line,
            col,
            msg: msg.into(),
        }
    }

    /// A usage error raised under subcommand `command` points at `whitted COMMAND --help`;
    /// every other error is returned as it is.
    pub fn in_command(self, command: &'static str) -> Error {
        match self {
            Error::Usage(msg) => Error::CommandUsage { command, msg },
            e => e,
        }
    }

    /// An I/O error on `path` while doing `action` ("read", "write", ...).
    pub fn io(path: &Path, action: &'static str, source: std::io::Error) -> Error {
        Error::Io {
            path: path.to_path_buf(),
            action,
            source,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Parse {
                path,
                line,
                col,
                msg,
            } => write!(f, "{}:{line}:{col}: {msg}", path.display()),
            Error::Io {
                path,
                action,
                source,
            } => write!(f, "{}: cannot {action}: {source}", path.display()),
            Error::Usage(msg) => write!(f, "{msg} (see `whitted --help`)"),
            Error::CommandUsage { command, msg } => {
                write!(f, "{msg} (see `whitted {command} --help`)")
            }
            Error::Limit(msg) | Error::Other(msg) => f.write_str(msg),
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}
