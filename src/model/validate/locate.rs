//! Where in the file a message points, and how it quotes the file: every stage reports its
//! errors through these, so a message reads the same whichever check wrote it.

use crate::model::ModelError;

/// Builds a [`ModelError`] at byte `offset` of `text`.
pub(in crate::model) fn error_at(file: &str, text: &str, offset: usize, msg: &str) -> ModelError {
    let (line, column, snippet) = locate(text, offset);
    ModelError {
        file: file.to_string(),
        line: Some(line),
        column: Some(column),
        message: msg.to_string(),
        snippet: Some(snippet),
    }
}

/// 1-based line and column (in characters) of byte `offset`, and that line's text.
pub(super) fn locate(text: &str, offset: usize) -> (usize, usize, String) {
    let mut off = offset.min(text.len());
    while !text.is_char_boundary(off) {
        off -= 1;
    }
    let before = &text[..off];
    let line = before.matches('\n').count() + 1;
    let start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = text[start..off].chars().count() + 1;
    let end = text[off..].find('\n').map_or(text.len(), |i| off + i);
    (
        line,
        column,
        text[start..end].trim_end_matches('\r').to_string(),
    )
}

/// Byte offset of the start of each line of `text`.
pub(super) fn line_starts(text: &str) -> Vec<usize> {
    std::iter::once(0)
        .chain(text.match_indices('\n').map(|(i, _)| i + 1))
        .collect()
}

pub(super) fn locate_line(text: &str, line: usize) -> String {
    text.lines().nth(line - 1).unwrap_or("").to_string()
}

/// An expression shortened for messages (hostile input can be kilobytes long).
pub(super) fn abbreviate(s: &str) -> String {
    const MAX: usize = 60;
    if s.chars().count() <= MAX {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(MAX).collect::<String>())
    }
}
