//! The first stage: the text is TOML in the shape of [`FileSchema`] (known keys, TOML types).
//! Its own stage because its errors come from the parser, which sometimes gives no place.

use super::R;
use super::locate::error_at;
use crate::model::schema::FileSchema;

/// Parses the text into the serde mirror of the file, placing the parser's errors.
pub(super) fn parse(text: &str, file: &str) -> R<FileSchema> {
    toml::from_str(text).map_err(|e| {
        let off = e.span().map_or(0, |s| s.start);
        let msg = e.message().trim().to_string();
        match e.span() {
            Some(_) => error_at(file, text, off, &msg),
            // The parser gives no place for some errors (its nesting limit): point at the
            // most deeply nested line, the likely culprit.
            None => error_at(file, text, most_nested_line(text), &msg),
        }
    })
}

/// Byte offset of the start of the line with the most dots and opening brackets (the deepest
/// nesting of keys, tables and arrays), roughly: quotes are not tracked.
fn most_nested_line(text: &str) -> usize {
    let mut best = (0, 0);
    let mut start = 0;
    for line in text.split_inclusive('\n') {
        let depth = line
            .chars()
            .filter(|c| matches!(c, '.' | '[' | '{'))
            .count();
        if depth > best.0 {
            best = (depth, start);
        }
        start += line.len();
    }
    best.1
}
