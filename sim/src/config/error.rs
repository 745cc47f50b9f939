//! Errors in data files that point at the file, the line, the column and the field.

use serde::de::DeserializeOwned;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A data file that cannot be used, and where the problem is.
///
/// Displays as `path:line:column: field: message`, followed by the offending line:
///
/// ```text
/// worlds/lab.toml:14:10: wall[2].points: a wall needs at least 2 points, found 1
///    14 | points = [[1.0, 2.0]]
/// ```
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub struct ConfigError {
    /// The file.
    pub path: PathBuf,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// 1-based column, when known.
    pub column: Option<usize>,
    /// The field, as a dotted path (`wall[2].points`), when known.
    pub field: Option<String>,
    /// What is wrong and what was expected.
    pub message: String,
    /// The text of the offending line.
    pub excerpt: Option<String>,
}

impl fmt::Display for ConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
            if let Some(column) = self.column {
                write!(f, ":{column}")?;
            }
        }
        write!(f, ": ")?;
        if let Some(field) = &self.field {
            write!(f, "{field}: ")?;
        }
        write!(f, "{}", self.message)?;
        if let (Some(line), Some(excerpt)) = (self.line, &self.excerpt) {
            write!(f, "\n{line:>6} | {excerpt}")?;
        }
        Ok(())
    }
}

/// The text of one data file, kept to turn byte offsets into lines in error messages.
pub(crate) struct Source {
    pub path: PathBuf,
    pub text: String,
}

impl Source {
    /// Reads a file; a missing or unreadable file is an error naming it.
    pub fn read(path: &Path) -> Result<Source, ConfigError> {
        let text = std::fs::read_to_string(path).map_err(|e| ConfigError {
            path: path.to_path_buf(),
            line: None,
            column: None,
            field: None,
            message: format!("cannot read the file: {e}"),
            excerpt: None,
        })?;
        Ok(Source {
            path: path.to_path_buf(),
            text,
        })
    }

    /// Text already in memory; `path` only names it in errors.
    pub fn text(text: &str, path: &Path) -> Source {
        Source {
            path: path.to_path_buf(),
            text: text.to_string(),
        }
    }

    /// Deserializes the whole file, turning TOML and type errors into located errors.
    pub fn parse<T: DeserializeOwned>(&self) -> Result<T, ConfigError> {
        toml::from_str(&self.text).map_err(|e| {
            let span = e.span().unwrap_or(0..0);
            let message = e.message().trim().to_string();
            let field = field_in_message(&message).or_else(|| self.key_at(span.start));
            self.error(span, field, message)
        })
    }

    /// An error at a byte span of this file.
    pub fn error(
        &self,
        span: Range<usize>,
        field: Option<String>,
        message: impl Into<String>,
    ) -> ConfigError {
        let start = span.start.min(self.text.len());
        let before = &self.text[..start];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = self.text[line_start..start].chars().count() + 1;
        let excerpt = self.text[line_start..]
            .lines()
            .next()
            .unwrap_or("")
            .trim_end()
            .to_string();
        ConfigError {
            path: self.path.clone(),
            line: Some(line),
            column: Some(column),
            field,
            message: message.into(),
            excerpt: Some(excerpt),
        }
    }

    /// An error about the file as a whole (no position).
    pub fn error_in_file(&self, field: Option<String>, message: impl Into<String>) -> ConfigError {
        ConfigError {
            path: self.path.clone(),
            line: None,
            column: None,
            field,
            message: message.into(),
            excerpt: None,
        }
    }

    /// Where the value of `key` is written in the table starting at `span` (a table's span, or
    /// only its `[[header]]`'s): the span of the value on the line `key = value` before the
    /// next table's header, if there is one.
    pub fn key_in(&self, span: Range<usize>, key: &str) -> Option<Range<usize>> {
        let start = span.start.min(self.text.len());
        let mut offset = start;
        for (k, line) in self.text.get(start..)?.split_inclusive('\n').enumerate() {
            let trimmed = line.trim_start();
            if k > 0 && trimmed.starts_with('[') && offset >= span.end {
                return None;
            }
            if let Some(rest) = trimmed.strip_prefix(key)
                && let Some(value) = rest.trim_start().strip_prefix('=')
            {
                let at = offset + (line.len() - value.trim_start().len());
                let length = value.trim().len();
                return Some(at..at + length);
            }
            offset += line.len();
        }
        None
    }

    /// The key assigned on the line containing `offset`, as a dotted path with the table it is
    /// in (`x = 1.0` under `[start]` gives `start.x`; under the third `[[check]]`,
    /// `check[2].x`).
    fn key_at(&self, offset: usize) -> Option<String> {
        let before = &self.text[..offset.min(self.text.len())];
        let start = before.rfind('\n').map_or(0, |i| i + 1);
        let line = self.text[start..].lines().next()?;
        let (key, _) = line.split_once('=')?;
        let key = key.trim();
        if key.is_empty() || key.starts_with('[') {
            return None;
        }
        let header = before[..start]
            .lines()
            .rev()
            .map(str::trim)
            .find(|l| l.starts_with('['));
        let name = |h: &str| {
            h.trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
                .to_string()
        };
        Some(match header {
            Some(h) if h.starts_with("[[") => {
                let name = name(h);
                let header = format!("[[{name}]]");
                let index = before[..start]
                    .lines()
                    .filter(|l| l.trim().starts_with(&header))
                    .count()
                    .saturating_sub(1);
                format!("{name}[{index}].{key}")
            }
            Some(h) => format!("{}.{key}", name(h)),
            None => key.to_string(),
        })
    }
}

/// The field named in a serde message such as "missing field `x`".
fn field_in_message(message: &str) -> Option<String> {
    let rest = message.strip_prefix("missing field `")?;
    Some(rest.split('`').next()?.to_string())
}

/// Resolves `relative` against the folder of the file that names it.
pub(crate) fn resolve(from_file: &Path, relative: &str) -> PathBuf {
    let relative = Path::new(relative);
    if relative.is_absolute() {
        relative.to_path_buf()
    } else {
        from_file
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .join(relative)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(serde::Deserialize, Debug)]
    #[serde(deny_unknown_fields)]
    #[allow(dead_code)]
    struct Demo {
        name: String,
        size: f64,
    }

    fn source(text: &str) -> Source {
        Source {
            path: PathBuf::from("demo.toml"),
            text: text.to_string(),
        }
    }

    #[test]
    fn type_errors_name_line_and_field() {
        let err = source("name = \"a\"\nsize = \"big\"\n")
            .parse::<Demo>()
            .unwrap_err();
        assert_eq!(err.line, Some(2));
        assert_eq!(err.field.as_deref(), Some("size"));
        let text = err.to_string();
        assert!(text.starts_with("demo.toml:2:"), "{text}");
        assert!(text.contains("size = \"big\""), "{text}");
    }

    #[test]
    fn missing_fields_are_named() {
        let err = source("name = \"a\"\n").parse::<Demo>().unwrap_err();
        assert_eq!(err.field.as_deref(), Some("size"), "{err}");
    }

    #[test]
    fn unknown_fields_are_located() {
        let err = source("name = \"a\"\nsize = 1\ncolour = 3\n")
            .parse::<Demo>()
            .unwrap_err();
        assert_eq!(err.line, Some(3), "{err}");
        assert!(err.message.contains("unknown field `colour`"), "{err}");
    }

    #[test]
    fn syntax_errors_are_located() {
        let err = source("name = \"a\"\nsize = [1, \n")
            .parse::<Demo>()
            .unwrap_err();
        assert!(err.line.is_some(), "{err}");
    }
}
