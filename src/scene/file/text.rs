//! A scene file's bytes as text, and toml's messages told without anything they quote of the
//! file.

use crate::scene::SceneError;

/// A scene file's bytes as text, without a leading UTF-8 byte-order mark. Bytes that are not
/// UTF-8 are an error naming the first one's byte offset, line and column (never the text).
pub fn decode_utf8<'a>(bytes: &'a [u8], label: &str) -> Result<&'a str, SceneError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    std::str::from_utf8(bytes).map_err(|e| {
        let offset = e.valid_up_to();
        let before = &bytes[..offset];
        let line_start = before
            .iter()
            .rposition(|&b| b == b'\n')
            .map_or(0, |i| i + 1);
        // The part of the line before the bad byte is valid UTF-8: count its characters.
        let column = 1 + String::from_utf8_lossy(&before[line_start..])
            .chars()
            .count();
        SceneError::NotUtf8 {
            file: label.to_string(),
            line: 1 + before.iter().filter(|&&b| b == b'\n').count(),
            column,
            offset,
        }
    })
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        1 + before.matches('\n').count(),
        1 + before[line_start..].chars().count(),
    )
}

/// Words toml and serde quote in their messages that come from our schema or the TOML
/// grammar, not from the file: they are kept; anything else quoted is left out of the message.
const SCHEMA_WORDS: &[&str] = &[
    "camera",
    "light",
    "object",
    "eye",
    "target",
    "fov_y_deg",
    "center",
    "normal",
    "radius",
    "intensity",
    "name",
    "mesh",
    "translate",
    "rotate_deg",
    "scale",
    "casts_shadow",
    "gltf_scene",
    "kind",
    "disk",
    "line",
    "a",
    "b",
    "true",
    "false",
    "inf",
    "nan",
];

/// toml's message without anything it quotes from the file, one line ("; " between lines).
///
/// serde and toml quote the file in a few known shapes: `unknown field `X``, `duplicate key
/// `X``, `invalid type: string "X"` (a Debug string), `character `X``. Those parts are
/// dropped by shape; what follows the last ", expected " is the schema's or the grammar's
/// (field lists, types). Elsewhere a `` `word` `` or `"word"` is kept only if it is a schema
/// key path or TOML punctuation, and anything after a quote left unmatched is cut.
pub(super) fn sanitize_toml_message(message: &str) -> String {
    let lines: Vec<String> = message
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .map(sanitize_toml_line)
        .collect();
    let mut text = lines.join("; ");
    if text.len() > 400 {
        let mut cut = 400;
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        text.truncate(cut);
        text.push('…');
    }
    text
}

fn sanitize_toml_line(line: &str) -> String {
    // Without the input, toml ends with the key path: `in `light.radius``.
    if let Some(path) = line.strip_prefix("in `").and_then(|r| r.strip_suffix('`')) {
        return if is_schema_path(path) {
            line.to_string()
        } else {
            "in a key of the file".into()
        };
    }
    for prefix in ["duplicate key", "unknown field", "unknown variant"] {
        if line.starts_with(prefix) {
            // The quoted name comes first; the list of what is expected (ours) after it.
            let tail = line.rfind(", expected").map_or("", |i| &line[i..]);
            return format!("{prefix}{}", strip_quoted(tail));
        }
    }
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some(rest) = line.strip_prefix(prefix) {
            // `string "..."`, `integer `5``, `character `x``...: the kind, not the value.
            let kind: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphabetic() || *c == ' ')
                .collect();
            let kind = match kind.trim() {
                "" => "value",
                k => k,
            };
            let tail = rest.rfind(", expected").map_or("", |i| &rest[i..]);
            return format!("{prefix}{kind}{}", strip_quoted(tail));
        }
    }
    strip_quoted(line)
}

/// `text` without its quoted words, but for schema key paths and TOML punctuation; after a
/// quote left unmatched nothing is kept. Double-quoted words may hold `\"` escapes.
fn strip_quoted(text: &str) -> String {
    let keep = |quoted: &str| {
        is_schema_path(quoted)
            || (!quoted.is_empty()
                && quoted.len() <= 3
                && quoted.chars().all(|c| c.is_ascii_punctuation() || c == ' '))
            || (quoted.len() == 2 && quoted.starts_with('\\'))
    };
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(open) = rest.find(['`', '"']) {
        let quote = rest.as_bytes()[open];
        let after = &rest[open + 1..];
        // The closing quote: the next one, skipping `\x` escapes inside double quotes.
        let mut close = None;
        let mut escaped = false;
        for (k, b) in after.bytes().enumerate() {
            if escaped {
                escaped = false;
            } else if b == b'\\' && quote == b'"' {
                escaped = true;
            } else if b == quote {
                close = Some(k);
                break;
            }
        }
        let Some(len) = close else {
            out.push_str(rest[..open].trim_end_matches(' '));
            return out;
        };
        let quoted = &after[..len];
        if keep(quoted) {
            out.push_str(&rest[..open + 1 + len + 1]);
        } else {
            out.push_str(rest[..open].trim_end_matches(' '));
        }
        rest = &after[len + 1..];
    }
    out.push_str(rest);
    out
}

/// A key path such as `object.1.scale` of schema words and indices.
fn is_schema_path(path: &str) -> bool {
    path.split('.').all(|k| {
        SCHEMA_WORDS.contains(&k) || (!k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
    })
}
