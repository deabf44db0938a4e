//! Turns byte offsets in a TOML file into `line:column` and the dotted
//! path of the field there, so errors can point at what to fix.

use crate::data::toml_syntax::{floor_boundary, line_column};

pub(crate) struct Location {
    pub line: usize,
    pub column: usize,
    /// e.g. `walls[2].ll`, `viewer.ipd`; empty at the top of the file.
    pub path: String,
}

pub(crate) fn locate(text: &str, offset: usize) -> Location {
    // Parsers report byte offsets, which may fall inside a character.
    let offset = floor_boundary(text, offset);
    let (line, column) = line_column(text, offset);
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let this_line = text[line_start..].lines().next().unwrap_or("");

    // The table the error is in; an error on a header line concerns that
    // table itself (serde reports missing fields there).
    let mut table = String::new();
    let mut seen: Vec<(String, usize)> = Vec::new();
    for l in text[..line_start].lines().chain(std::iter::once(this_line)) {
        let t = l.trim();
        if let Some(name) = t.strip_prefix("[[").and_then(|r| r.split("]]").next()) {
            let name = name.trim().to_string();
            let index = match seen.iter_mut().find(|(n, _)| *n == name) {
                Some((_, count)) => {
                    *count += 1;
                    *count - 1
                }
                None => {
                    seen.push((name.clone(), 1));
                    0
                }
            };
            table = format!("{name}[{index}]");
        } else if let Some(name) = t.strip_prefix('[').and_then(|r| r.split(']').next()) {
            table = name.trim().to_string();
        }
    }
    let on_header = this_line.trim_start().starts_with('[');
    let key = if on_header {
        String::new()
    } else {
        key_at(this_line, (offset - line_start).min(this_line.len()))
    };
    let path = match (table.is_empty(), key.is_empty()) {
        (true, _) => key,
        (false, true) => table,
        (false, false) => format!("{table}.{key}"),
    };
    Location { line, column, path }
}

/// The key of the last `key =` before byte `column` of `line`, which also
/// finds keys inside inline tables; the line's own key if the error is on it.
fn key_at(line: &str, column: usize) -> String {
    let trimmed = line.trim_start();
    if trimmed.is_empty() || trimmed.starts_with('#') {
        // A comment or blank line (where errors about the whole file
        // land) names no field.
        return String::new();
    }
    let prefix = &line[..floor_boundary(line, column)];
    let Some(eq) = prefix.rfind('=') else {
        return line.split('=').next().unwrap_or("").trim().to_string();
    };
    let head = prefix[..eq].trim_end();
    let is_key = |c: char| c.is_alphanumeric() || c == '_' || c == '-' || c == '.';
    let start = head
        .char_indices()
        .rev()
        .find(|&(_, c)| !is_key(c))
        .map_or(0, |(i, c)| i + c.len_utf8());
    head[start..].to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offsets_inside_characters_and_keys_after_them_are_found() {
        let text = "[viewer]\nhead = { « = 1, héad_ÿ = [0, 0] }\n";
        for offset in 0..=text.len() + 3 {
            let loc = locate(text, offset);
            assert!(loc.line >= 1 && loc.column >= 1, "{offset}");
        }
        let at = text.find("[0").unwrap();
        assert_eq!(locate(text, at).path, "viewer.héad_ÿ");
    }

    #[test]
    fn a_comment_line_names_no_field() {
        let text = "# a rig = with an equals sign\nunits = \"m\"\n";
        assert_eq!(locate(text, 0).path, "");
        assert_eq!(locate(text, 3).path, "");
    }
}
