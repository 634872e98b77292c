//! Scene errors: every message names the file, and where the problem has a
//! place in the text, its `line:column` (1-based), so editors can jump to it.

use std::ops::Range;
use std::path::PathBuf;

/// Why a scene could not be loaded or queried.
#[derive(thiserror::Error, Debug)]
pub enum SceneError {
    /// The scene file (or a file it references without a location) could not be read.
    #[error("{}: cannot read file: {source}", path.display())]
    Io {
        /// The file that could not be read.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// TOML syntax error, wrong type, unknown key, or a semantic problem at a known place.
    #[error("{file}:{line}:{column}: {message}")]
    At {
        /// The file the text came from.
        file: String,
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// A problem without a place in the text.
    #[error("{file}: {message}")]
    Invalid {
        /// The file at fault, or what stands in for it (e.g. the memory-budget variable).
        file: String,
        /// What is wrong.
        message: String,
    },
    /// `Scene::camera` was asked for a name the scene does not have.
    #[error("{file}: unknown camera \"{name}\" (known: {known})")]
    UnknownCamera {
        /// The file (or `<scene>` for a scene not read from a file).
        file: String,
        /// The camera name asked for.
        name: String,
        /// The scene's camera names, comma separated.
        known: String,
    },
}

/// Maps byte offsets of one scene text to `line:column` positions.
pub(crate) struct SourceMap<'a> {
    pub origin: &'a str,
    pub text: &'a str,
}

impl SourceMap<'_> {
    /// 1-based line and column (in characters) of byte offset `offset`.
    pub fn line_column(&self, offset: usize) -> (usize, usize) {
        let mut offset = offset.min(self.text.len());
        while !self.text.is_char_boundary(offset) {
            offset -= 1;
        }
        let before = &self.text[..offset];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = before[line_start..].chars().count() + 1;
        (line, column)
    }

    /// An error at the start of `span`.
    pub fn error(&self, span: &Range<usize>, message: impl Into<String>) -> SceneError {
        let (line, column) = self.line_column(span.start);
        SceneError::At {
            file: self.origin.to_string(),
            line,
            column,
            message: message.into(),
        }
    }

    /// An error without a place in the text.
    pub fn invalid(&self, message: impl Into<String>) -> SceneError {
        SceneError::Invalid {
            file: self.origin.to_string(),
            message: message.into(),
        }
    }

    /// Converts a TOML parse or deserialisation error, keeping its span.
    pub fn toml_error(&self, err: &toml::de::Error) -> SceneError {
        let message = err.message().trim().to_string();
        match err.span() {
            Some(span) => self.error(&span, message),
            None => self.invalid(message),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_lines_and_characters() {
        let map = SourceMap {
            origin: "x.toml",
            text: "a = 1\nbé = 2\n",
        };
        assert_eq!(map.line_column(0), (1, 1));
        assert_eq!(map.line_column(6), (2, 1));
        // 'é' is two bytes: byte 9 is the space after it, the third character.
        assert_eq!(map.line_column(9), (2, 3));
        assert_eq!(map.line_column(1000), (3, 1));
    }
}
