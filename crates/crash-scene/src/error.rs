//! Scene errors: every one names the file, line and column, the key and what is valid.

use thiserror::Error;

/// What kind of mistake a scene file holds (tests and tools match on it; people read
/// the message).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ErrorKind {
    /// The file (or an imported mesh file) could not be read.
    Read,
    /// Not valid TOML.
    Syntax,
    /// A key this format does not know.
    UnknownKey,
    /// A value of the wrong TOML type.
    WrongType,
    /// A required key is absent.
    Missing,
    /// A value outside its valid range or set.
    Invalid,
    /// A name that refers to nothing (e.g. an undefined material).
    Reference,
    /// An imported mesh file is malformed.
    MeshFile,
    /// The geometry is unusable (degenerate elements, bodies interpenetrating at t = 0).
    Geometry,
    /// Valid input that the solver cannot run yet (e.g. a general load curve on a
    /// prescribed velocity: parsed and checked, but the core has no such program).
    Unsupported,
    /// The scene needs more memory than the machine has available, or a file is larger
    /// than the reader accepts.
    TooLarge,
}

/// A scene error located in its file: `file:line:column: key = value: what is valid`
/// (`file: message` when there is no line, e.g. the scene file itself is unreadable).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{}", self.located())]
pub struct SceneError {
    pub kind: ErrorKind,
    /// The scene file as named by the caller.
    pub file: String,
    /// 1-based line and column (in characters) of the offending key or value; line 0
    /// when the error concerns the whole file, column 0 when only the line is known
    /// (errors located in a keyword deck).
    pub line: usize,
    pub column: usize,
    /// Dotted key path, e.g. `materials.steel.poisson` or `bodies[1].thickness`.
    pub key: String,
    /// The full explanation (starts with the key).
    pub message: String,
}

impl SceneError {
    fn located(&self) -> String {
        if self.line == 0 {
            format!("{}: {}", self.file, self.message)
        } else if self.column == 0 {
            format!("{}:{}: {}", self.file, self.line, self.message)
        } else {
            format!(
                "{}:{}:{}: {}",
                self.file, self.line, self.column, self.message
            )
        }
    }
}

/// 1-based (line, column) of a byte offset; columns count characters.
pub fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_lines_and_characters_from_one() {
        let t = "a = 1\nbé = 2\n";
        assert_eq!(line_col(t, 0), (1, 1));
        assert_eq!(line_col(t, 6), (2, 1));
        // 'é' is two bytes but one column
        assert_eq!(line_col(t, 6 + 3), (2, 3));
        assert_eq!(line_col(t, 1000), (3, 1));
    }
}
