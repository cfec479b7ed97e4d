//! The one error type of `tessera-core`.

use std::path::PathBuf;

/// Everything that can go wrong in the core: bad input files, I/O, invalid parameters.
///
/// Every variant renders as a single line naming the file, the line (where there is one)
/// and the problem, so that the CLI can print it as is.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A syntax or content error in an input file, at a 1-based line.
    #[error("{}:{line}: {msg}", file.display())]
    Parse {
        /// The input file.
        file: PathBuf,
        /// 1-based line of the problem.
        line: usize,
        /// What is wrong, one line.
        msg: String,
    },
    /// A problem with an input file as a whole (empty, binary, inconsistent topology).
    #[error("{}: {msg}", file.display())]
    Input {
        /// The input file.
        file: PathBuf,
        /// What is wrong, one line.
        msg: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file read or written.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A parameter out of its valid range (threshold, depth, segments, ...).
    #[error("invalid parameter: {0}")]
    Param(String),
}

impl Error {
    pub(crate) fn parse(file: &std::path::Path, line: usize, msg: impl Into<String>) -> Self {
        Error::Parse {
            file: file.to_path_buf(),
            line,
            msg: one_line(msg.into()),
        }
    }

    pub(crate) fn input(file: &std::path::Path, msg: impl Into<String>) -> Self {
        Error::Input {
            file: file.to_path_buf(),
            msg: one_line(msg.into()),
        }
    }
}

/// Control characters escaped (`\n`, `\u{1b}`): a message may quote the file or a
/// dependency, and must still be one line.
fn one_line(msg: String) -> String {
    if !msg.chars().any(char::is_control) {
        return msg;
    }
    let mut out = String::with_capacity(msg.len() + 8);
    for c in msg.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}

/// `std::result::Result` with [`Error`] as the default error.
pub type Result<T, E = Error> = std::result::Result<T, E>;
