//! The error type of the pipeline crates (pedo-io, pedo-track, pedo-output, pedo-study), and
//! the wording of counts in their messages.

use modal_core::ModalError;

/// Everything that can go wrong reading, writing or processing a recording.
///
/// Parse errors always name the file (or the name given to an in-memory parser) and, for text
/// formats, the 1-based line, so a user can open the file at the offending place.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// The operating system refused to read or write the file.
    #[error("{path}: {source}")]
    Io {
        /// The file or folder the operation was on.
        path: String,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// A text file is malformed at a given line.
    #[error("{path}:{line}: {msg}")]
    Parse {
        /// The file, or the name given to an in-memory parser.
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong with that line.
        msg: String,
    },
    /// A file is malformed as a whole (binary header, missing frames, unknown format).
    #[error("{path}: {msg}")]
    Format {
        /// The file, or the name given to an in-memory parser.
        path: String,
        /// What is wrong with it.
        msg: String,
    },
    /// The file is not a recording of any supported format: `recognised` says what the content
    /// looks like (or that nothing was recognised); the message lists the supported formats.
    #[error(
        "{path}: not a supported pressure recording: {recognised}; supported: {}",
        crate::formats::SUPPORTED
    )]
    UnknownFormat {
        /// The file, or the name given to an in-memory parser.
        path: String,
        /// What the content looks like, or that nothing was recognised.
        recognised: String,
    },
    /// A 3-D array looks stored time-last (rows, columns, frames) by the rule of
    /// [`crate::recording::TIME_LAST_RULE`], and no option said which axis is time
    /// (`--time-axis`, Python `time_axis=`): read as stored it would be `shape[0]` frames of
    /// `shape[1] × shape[2]` sensels, transposed `shape[2]` frames of `shape[0] × shape[1]`;
    /// the message names both.
    #[error("{}", time_last_message(path, shape))]
    TimeLast {
        /// The file, or empty for an array handed over (see [`IoError::of_input`]).
        path: String,
        /// The array's shape as stored.
        shape: [usize; 3],
    },
    /// An argument is out of range or inconsistent.
    #[error("invalid input: {0}")]
    InvalidInput(String),
    /// A user-facing option has a value it does not accept.
    #[error(transparent)]
    Option(#[from] modal_core::OptionError),
    /// The input holds no object that can be modelled (a frame with too few non-collinear
    /// samples above the level for a surface).
    #[error("{0}")]
    NoObject(String),
    /// A produced object could not be turned into a modal-core shape.
    #[error(transparent)]
    Shape(#[from] ModalError),
    /// An output folder cannot be written: it is not a usable name, it holds files that are not a
    /// pedomatch output, or the run was interrupted.
    #[error("{path}: {msg}")]
    Output {
        /// The output folder (or file in it).
        path: String,
        /// Why it cannot be written.
        msg: String,
    },
    /// A figure could not be drawn or encoded.
    #[error("figure: {0}")]
    Figure(String),
    /// The run was stopped through its [`crate::cancel::Cancel`] before it finished.
    #[error("cancelled")]
    Cancelled,
}

impl IoError {
    /// A [`IoError::Parse`]: `path` is malformed at 1-based `line`.
    pub fn parse(path: &str, line: usize, msg: impl Into<String>) -> Self {
        IoError::Parse {
            path: path.to_string(),
            line,
            msg: msg.into(),
        }
    }
    /// A [`IoError::Format`]: `path` is malformed as a whole.
    pub fn format(path: &str, msg: impl Into<String>) -> Self {
        IoError::Format {
            path: path.to_string(),
            msg: msg.into(),
        }
    }
    /// An [`IoError::UnknownFormat`]: `path` looks like `recognised`, no supported format.
    pub fn unknown_format(path: &str, recognised: impl Into<String>) -> Self {
        IoError::UnknownFormat {
            path: path.to_string(),
            recognised: recognised.into(),
        }
    }
    /// An [`IoError::InvalidInput`].
    pub fn invalid(msg: impl Into<String>) -> Self {
        IoError::InvalidInput(msg.into())
    }
    /// An [`IoError::NoObject`].
    pub fn no_object(msg: impl Into<String>) -> Self {
        IoError::NoObject(msg.into())
    }

    /// This error as one about the input `name` (a recording's path): a recording without an
    /// object is a fact about the file, named as a read error names it. Other errors are
    /// returned as they are (they name their file already, or are not about it).
    pub fn of_input(self, name: &str) -> Self {
        match self {
            IoError::NoObject(msg) => IoError::NoObject(format!("{name}: {msg}")),
            IoError::TimeLast { path, shape } if path.is_empty() => IoError::TimeLast {
                path: name.to_string(),
                shape,
            },
            e => e,
        }
    }
}

/// The message of [`IoError::TimeLast`]: both readings of the array and the option that
/// chooses.
fn time_last_message(path: &str, shape: &[usize; 3]) -> String {
    let [a, b, c] = *shape;
    let file = if path.is_empty() {
        String::new()
    } else {
        format!("{path}: ")
    };
    format!(
        "{file}a 3-D array of shape ({a}, {b}, {c}) looks stored time-last ({}): read as \
         stored it is {a} frames of {b} x {c} sensels, transposed {c} frames of {a} x {b}. Say \
         which: --time-axis last (Python time_axis=\"last\") reads {c} frames of {a} x {b}, \
         --time-axis first (time_axis=\"first\") {a} frames of {b} x {c}",
        crate::recording::TIME_LAST_RULE
    )
}

/// Result alias of the crate.
pub type Result<T> = std::result::Result<T, IoError>;

/// `n` and a noun, in the singular for one and with a plain `s` otherwise: the counts of the
/// messages and terminal lines.
///
/// ```
/// use pedo_io::counted;
/// assert_eq!(counted(1, "recording"), "1 recording");
/// assert_eq!(counted(0, "isobaric level"), "0 isobaric levels");
/// ```
pub fn counted(n: usize, noun: &str) -> String {
    if n == 1 {
        format!("1 {noun}")
    } else {
        format!("{n} {noun}s")
    }
}
