//! Reading a TOML file into its schema, with the position of every error.

use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;

/// Why a task or cell file could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConfigError {
    /// The file could not be read: check the path and its permissions.
    #[error("{}: cannot read the file: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file is not TOML, or a value does not fit the schema: the message
    /// says what was expected at that place.
    #[error("{}:{line}:{column}: {field}: {message}", path.display(), field = if field.is_empty() { "(file)" } else { field })]
    Invalid {
        path: PathBuf,
        line: usize,
        column: usize,
        /// Dotted path of the offending key, e.g. `tolerance.n_mm`.
        field: String,
        message: String,
    },
    /// The file has no `[task]`, `[cell]` or `[campaign]` table, so it is
    /// not known what to check it against.
    #[error("{}: not a task, cell or campaign file: expected a [task], [cell] or [campaign] table", path.display())]
    UnknownKind { path: PathBuf },
}

/// Line and column of the last key of `keys` (a path of tables), or of the
/// file's start if it cannot be found.
fn key_position(text: &str, keys: &[&str]) -> (usize, usize) {
    let offset = toml_edit::Document::parse(text).ok().and_then(|document| {
        let (last, tables) = keys.split_last()?;
        let mut table: &dyn toml_edit::TableLike = document.as_table();
        for key in tables {
            table = table.get(key)?.as_table_like()?;
        }
        table.key(last)?.span().map(|span| span.start)
    });
    line_column(text, offset.unwrap_or(0))
}

/// The error `message` about `field`, at the key `keys` (a path of tables)
/// of the file `path` holding `text`: for checks made after the file was
/// read, which span several keys or files.
pub fn invalid_at_key(
    path: &Path,
    text: &str,
    keys: &[&str],
    field: &str,
    message: String,
) -> ConfigError {
    let (line, column) = key_position(text, keys);
    ConfigError::Invalid {
        path: path.to_owned(),
        line,
        column,
        field: field.to_owned(),
        message,
    }
}

pub fn read(path: &Path) -> Result<String, ConfigError> {
    std::fs::read_to_string(path).map_err(|source| ConfigError::Read {
        path: path.to_owned(),
        source,
    })
}

/// Deserialises `text`; an error carries the key path (serde_path_to_error)
/// and the span (toml) turned into a 1-based line and column.
pub fn parse<T: DeserializeOwned>(path: &Path, text: &str) -> Result<T, ConfigError> {
    let deserializer = match toml::Deserializer::parse(text) {
        Ok(d) => d,
        Err(e) => return Err(invalid(path, text, String::new(), &e)),
    };
    serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let field = e.path().to_string();
        invalid(
            path,
            text,
            if field == "." { String::new() } else { field },
            e.inner(),
        )
    })
}

fn invalid(path: &Path, text: &str, field: String, error: &toml::de::Error) -> ConfigError {
    let offset = error.span().map_or(0, |span| span.start);
    let (line, column) = line_column(text, offset);
    ConfigError::Invalid {
        path: path.to_owned(),
        line,
        column,
        field,
        message: error.message().to_owned(),
    }
}

/// 1-based line and column (in characters) of a byte offset.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_column_counts_from_one() {
        let text = "a = 1\nbb = 2\n";
        assert_eq!(line_column(text, 0), (1, 1));
        assert_eq!(line_column(text, 6), (2, 1));
        assert_eq!(line_column(text, 11), (2, 6));
        assert_eq!(line_column(text, 999), (3, 1));
    }
}
