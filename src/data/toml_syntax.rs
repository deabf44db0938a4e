//! TOML syntax errors placed at their cause and said in plain words, for
//! every TOML file a user writes (rigs, displays, head paths, manifests).
//! The toml parser reports where it gave up: an unclosed `[` on the line
//! after it (as a missing comma), an unclosed string at the end of its
//! line, a bad number at its last digit. A syntax error names no field:
//! the text there is not yet any field.

use std::ops::Range;

/// A syntax error: 1-based line and column (in characters) and what is
/// wrong there.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SyntaxError {
    pub line: usize,
    pub column: usize,
    pub message: String,
}

/// The first syntax error of `text`, if it is not a TOML document.
pub fn syntax_error(text: &str) -> Option<SyntaxError> {
    let e = toml::from_str::<toml::Table>(text).err()?;
    let span = e.span().unwrap_or(0..0);
    let (offset, message) = explain(text, span, e.message());
    let (line, column) = line_column(text, offset);
    Some(SyntaxError {
        line,
        column,
        message,
    })
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
pub fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let offset = floor_boundary(text, offset);
    let before = &text[..offset];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (
        before.matches('\n').count() + 1,
        before[line_start..].chars().count() + 1,
    )
}

/// The largest character boundary of `text` at or before `offset`.
pub fn floor_boundary(text: &str, offset: usize) -> usize {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    offset
}

/// Where a syntax error that toml reports at `span` with `message` is
/// caused, and what to say about it.
fn explain(text: &str, span: Range<usize>, message: &str) -> (usize, String) {
    let start = floor_boundary(text, span.start);
    let end = floor_boundary(text, span.end.max(start));
    let at = Scan::until(text, start);
    let (line_start, line_end) = line_bounds(text, start);
    let (row, _) = line_column(text, start);
    // toml's own words, less a clause that only confuses.
    let said = message.trim_end_matches(", expected nothing");

    if message.starts_with("unclosed array table") {
        return (start, "unclosed table header, expected `]]`".into());
    }
    if message.starts_with("missing comma between")
        || message.starts_with("unclosed array")
        || message.starts_with("unclosed inline table")
    {
        if let Some(open) = at.open.last().filter(|o| o.kind != Kind::Header) {
            let (what, close) = match open.kind {
                Kind::Array => ("array", ']'),
                _ => ("inline table", '}'),
            };
            let opener = if close == ']' { '[' } else { '{' };
            let eof = text[start..].trim().is_empty();
            let opened_before = open.offset < line_start;
            if eof {
                return (
                    open.offset,
                    format!("unclosed '{opener}': the {what} opened here is never closed (expected `{close}`)"),
                );
            }
            // An array cannot hold `key =` or a table header, so the line
            // that starts with one comes after an array left open.
            if opened_before && starts_statement(&text[start..line_end]) {
                let also = if close == '}' {
                    ", or `,` between its keys"
                } else {
                    ""
                };
                return (
                    open.offset,
                    format!(
                        "unclosed '{opener}': the {what} opened here is not closed before line {row} (expected `{close}`{also})"
                    ),
                );
            }
            if opened_before {
                let (l, c) = line_column(text, open.offset);
                return (start, format!("{said} (in the {what} opened at {l}:{c})"));
            }
        }
        return (start, said.to_string());
    }

    if message.starts_with("invalid basic string")
        || message.starts_with("invalid literal string")
        || message.starts_with("invalid multi-line")
    {
        if let Some(string) = at.string {
            let quote = &text[string.offset..string.offset + string.quote.len()];
            let message = if string.multi_line {
                format!("unclosed multi-line string: the {quote} here is never closed")
            } else {
                format!("unclosed string: the {quote} here is not closed on its line")
            };
            return (string.offset, message);
        }
        return (start, said.to_string());
    }

    if message.starts_with("unclosed table") {
        return (start, "unclosed table header, expected `]`".into());
    }
    if message == "duplicate key" {
        return duplicate(text, start, end, line_start, line_end);
    }

    if message.starts_with("key with no value") {
        let line = &text[line_start..line_end];
        if line.trim().ends_with(']') && !line.trim().starts_with('[') {
            let indent = line.len() - line.trim_start().len();
            return (
                line_start + indent,
                "a table header needs `[` before its name".into(),
            );
        }
        let key = text[line_start..start].trim();
        return (
            start,
            format!("`{key}` has no value: expected `=` and a value after it"),
        );
    }

    if message.starts_with("string values must be quoted") {
        let value = text[start..end].trim();
        if value.is_empty() || value.starts_with('#') {
            return (start, "missing value after `=`".into());
        }
        return (
            start,
            format!(
                "`{value}` is not a value: a number is written without units or spaces, a list as [a, b, c], text in quotes"
            ),
        );
    }

    if message.starts_with("unexpected key or value") {
        let rest = text[start..line_end].trim();
        let decimal_comma = rest.starts_with(',')
            && text[..start].ends_with(|c: char| c.is_ascii_digit())
            && rest[1..].starts_with(|c: char| c.is_ascii_digit());
        let hint = if decimal_comma {
            " (a decimal point is `.`)"
        } else {
            ""
        };
        return (
            start,
            format!("unexpected `{rest}`: expected the end of the line or a `#` comment{hint}"),
        );
    }

    if let Some(digits) = message
        .strip_prefix("invalid type: integer `")
        .and_then(|r| r.split('`').next())
    {
        return (
            start,
            format!("`{digits}` is too large for an integer (at most {}); write it as a float, e.g. `{digits}.0`", i64::MAX),
        );
    }

    let token = token_at(text, start, line_start, line_end);
    let numeric = token
        .1
        .starts_with(|c: char| c.is_ascii_digit() || "+-.".contains(c));
    if numeric && NUMBER_ERRORS.iter().any(|p| message.starts_with(p)) {
        return (token.0, format!("`{}` is not a number ({said})", token.1));
    }
    (start, said.to_string())
}

/// How toml starts its messages about a malformed number.
const NUMBER_ERRORS: &[&str] = &[
    "invalid float",
    "invalid fraction",
    "invalid mantissa",
    "invalid exponent",
    "invalid integer",
    "invalid binary",
    "invalid octal",
    "invalid hexadecimal",
    "unexpected leading zero",
    "integer number overflowed",
    "`_` may only go between digits",
];

/// A duplicate key or table at `start..end`, with where it was first set
/// when that is easy to tell.
fn duplicate(
    text: &str,
    start: usize,
    end: usize,
    line_start: usize,
    line_end: usize,
) -> (usize, String) {
    let line = text[line_start..line_end].trim();
    if line.starts_with('[') {
        let header = line.split('#').next().unwrap_or(line).trim();
        let first = text[..line_start]
            .lines()
            .position(|l| l.split('#').next().unwrap_or(l).trim() == header);
        let first = first.map_or(String::new(), |n| format!(" (first at line {})", n + 1));
        return (start, format!("table {header} is defined twice{first}"));
    }
    let key = |l: &str| l.split_once('=').map(|(k, _)| normal_key(k));
    let this = key(&text[line_start..line_end]).unwrap_or_default();
    // Where this line's table begins: its header, or the top of the file.
    let lines: Vec<&str> = text[..line_start].lines().collect();
    let table_start = lines
        .iter()
        .rposition(|l| l.trim_start().starts_with('['))
        .map_or(0, |i| i + 1);
    let first = lines[table_start..]
        .iter()
        .position(|l| !this.is_empty() && key(l).as_deref() == Some(this.as_str()))
        .map_or(String::new(), |i| {
            format!(" (first set on line {})", table_start + i + 1)
        });
    let name = if this.is_empty() {
        text[start..end].trim().to_string()
    } else {
        this
    };
    (start, format!("duplicate key `{name}`{first}"))
}

/// A key as written, without the spaces TOML allows around its dots.
fn normal_key(key: &str) -> String {
    key.split('.').map(str::trim).collect::<Vec<_>>().join(".")
}

/// Whether a line begins something that only stands at the top level: a
/// `key =` or a table header.
fn starts_statement(line: &str) -> bool {
    let line = line.trim();
    if let Some(header) = line.strip_prefix('[') {
        let name = header.trim_start_matches('[');
        let name = name.split(']').next().unwrap_or("");
        return name.contains(|c: char| c.is_alphabetic() || c == '_' || c == '"')
            && !name.contains(',');
    }
    let Some((key, _)) = line.split_once('=') else {
        return false;
    };
    let key = key.trim();
    !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_alphanumeric() || "_-. \"'".contains(c))
}

/// The bytes of `text` from the start to the end of the line at `offset`
/// (without its newline).
fn line_bounds(text: &str, offset: usize) -> (usize, usize) {
    let start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    (start, end)
}

/// The value token around `offset` (which may sit just after it).
fn token_at(text: &str, offset: usize, line_start: usize, line_end: usize) -> (usize, &str) {
    let delimiter = |c: char| c.is_whitespace() || ",[]{}=#\"'".contains(c);
    let start = text[line_start..offset]
        .rfind(delimiter)
        .map_or(line_start, |i| line_start + i + 1);
    let end = text[offset..line_end]
        .find(delimiter)
        .map_or(line_end, |i| offset + i);
    (start, &text[start..end])
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Header,
    Array,
    InlineTable,
}

#[derive(Clone, Copy, Debug)]
struct Open {
    offset: usize,
    kind: Kind,
}

#[derive(Clone, Copy, Debug)]
struct InString {
    offset: usize,
    quote: &'static str,
    multi_line: bool,
}

/// What is open at a byte of a TOML text: brackets and a string. Only
/// ASCII delimiters are looked for, so every offset kept is a character
/// boundary.
#[derive(Debug, Default)]
struct Scan {
    open: Vec<Open>,
    string: Option<InString>,
}

impl Scan {
    fn until(text: &str, end: usize) -> Self {
        let bytes = &text.as_bytes()[..end.min(text.len())];
        let mut scan = Scan::default();
        let mut line_blank = true;
        let mut i = 0;
        while i < bytes.len() {
            let b = bytes[i];
            if let Some(s) = scan.string {
                let closes = bytes[i..].starts_with(s.quote.as_bytes());
                if b == b'\\' && s.quote.starts_with('"') {
                    i += 2;
                    continue;
                }
                if closes {
                    scan.string = None;
                    i += s.quote.len();
                    continue;
                }
                if b == b'\n' && !s.multi_line {
                    scan.string = None;
                    line_blank = true;
                }
                i += 1;
                continue;
            }
            match b {
                b'#' => {
                    // A comment runs to the end of its line.
                    i = bytes[i..]
                        .iter()
                        .position(|&c| c == b'\n')
                        .map_or(bytes.len(), |n| i + n);
                    continue;
                }
                b'\n' => {
                    // A header ends with its line, closed or not.
                    if let Some(h) = scan.open.iter().position(|o| o.kind == Kind::Header) {
                        scan.open.truncate(h);
                    }
                    line_blank = true;
                    i += 1;
                    continue;
                }
                b'"' | b'\'' => {
                    let triple = if b == b'"' { "\"\"\"" } else { "'''" };
                    let multi_line = bytes[i..].starts_with(triple.as_bytes());
                    let quote = match (b, multi_line) {
                        (b'"', true) => "\"\"\"",
                        (b'"', false) => "\"",
                        (_, true) => "'''",
                        _ => "'",
                    };
                    scan.string = Some(InString {
                        offset: i,
                        quote,
                        multi_line,
                    });
                    i += quote.len();
                }
                b'[' => {
                    let kind = if line_blank && scan.open.is_empty() {
                        Kind::Header
                    } else {
                        Kind::Array
                    };
                    scan.open.push(Open { offset: i, kind });
                    i += 1;
                }
                b'{' => {
                    scan.open.push(Open {
                        offset: i,
                        kind: Kind::InlineTable,
                    });
                    i += 1;
                }
                b']' | b'}' => {
                    let kind = if b == b'}' {
                        Kind::InlineTable
                    } else {
                        Kind::Array
                    };
                    if scan
                        .open
                        .last()
                        .is_some_and(|o| o.kind == kind || (b == b']' && o.kind == Kind::Header))
                    {
                        scan.open.pop();
                    }
                    i += 1;
                }
                _ => i += 1,
            }
            if !b.is_ascii_whitespace() {
                line_blank = false;
            }
        }
        scan
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `(line, column, message)` of the text's syntax error.
    fn error(text: &str) -> (usize, usize, String) {
        let e = syntax_error(text).unwrap_or_else(|| panic!("parses: {text:?}"));
        (e.line, e.column, e.message)
    }

    fn expect(text: &str, line: usize, column: usize, message: &str) {
        assert_eq!(error(text), (line, column, message.to_string()), "{text:?}");
    }

    #[test]
    fn an_unclosed_bracket_is_reported_where_it_opened() {
        let rig = "name = \"r\"\nunits = \"m\"\n[[walls]]\nll = [-1, 0, -1\nlr = [1, 0, -1]\n";
        expect(
            rig,
            4,
            6,
            "unclosed '[': the array opened here is not closed before line 5 (expected `]`)",
        );
        expect(
            "head = [0, 1.7, 0\n",
            1,
            8,
            "unclosed '[': the array opened here is never closed (expected `]`)",
        );
        // Over several lines, up to a table header.
        expect(
            "[viewer]\nhead = [0,\n  1.7,\n  0\n[[walls]]\n",
            2,
            8,
            "unclosed '[': the array opened here is not closed before line 5 (expected `]`)",
        );
        // Brackets in strings and comments are not brackets.
        expect(
            "name = \"a [ b\"\nhead = [0, # ]\n 1\nipd = 1\n",
            2,
            8,
            "unclosed '[': the array opened here is not closed before line 4 (expected `]`)",
        );
        expect(
            "head = [[0, 1], [2, 3]\nipd = 1\n",
            1,
            8,
            "unclosed '[': the array opened here is not closed before line 2 (expected `]`)",
        );
        expect(
            "head = { x = 1\nipd = 0.06\n",
            1,
            8,
            "unclosed '{': the inline table opened here is not closed before line 2 (expected `}`, or `,` between its keys)",
        );
        // A value on the next line is a missing comma after all.
        expect(
            "ll = [\n  1\n  2\n]\n",
            3,
            3,
            "missing comma between array elements, expected `,` (in the array opened at 1:6)",
        );
    }

    #[test]
    fn unclosed_headers_and_strings_are_placed_and_named() {
        expect(
            "units = \"m\"\n[viewer\nipd = 1\n",
            2,
            8,
            "unclosed table header, expected `]`",
        );
        expect(
            "[[walls]\nname = \"f\"\n",
            1,
            9,
            "unclosed table header, expected `]]`",
        );
        expect(
            "[viewer]\nname = \"abc\nipd = 0.06\n",
            2,
            8,
            "unclosed string: the \" here is not closed on its line",
        );
        expect(
            "[viewer]\nname = 'abc\nipd = 0.06\n",
            2,
            8,
            "unclosed string: the ' here is not closed on its line",
        );
        expect(
            "a = \"\"\"abc\nipd = 1\n",
            1,
            5,
            "unclosed multi-line string: the \"\"\" here is never closed",
        );
        // Columns count characters, not bytes.
        expect(
            "a = \"é\"\nb = \"ü\n",
            2,
            5,
            "unclosed string: the \" here is not closed on its line",
        );
    }

    #[test]
    fn duplicates_say_where_the_first_one_is() {
        expect(
            "[viewer]\nipd = 0.06\nhead = [0, 1, 0]\nipd = 0.07\n",
            4,
            1,
            "duplicate key `ipd` (first set on line 2)",
        );
        expect(
            "[viewer]\nipd = 1\n[viewer]\nipd = 2\n",
            3,
            2,
            "table [viewer] is defined twice (first at line 1)",
        );
        expect(
            "[viewer]\nhead.x = 1\nhead . x = 2\n",
            3,
            8,
            "duplicate key `head.x` (first set on line 2)",
        );
        // The same key in another table is no duplicate.
        expect(
            "[[walls]]\nname = \"a\"\n[[walls]]\nname = \"b\"\nname = \"c\"\n",
            5,
            1,
            "duplicate key `name` (first set on line 4)",
        );
    }

    #[test]
    fn missing_equals_signs_values_and_brackets_are_said() {
        expect(
            "[viewer]\nipd 0.06\n",
            2,
            5,
            "`ipd` has no value: expected `=` and a value after it",
        );
        expect(
            "viewer]\nipd = 1\n",
            1,
            1,
            "a table header needs `[` before its name",
        );
        expect("ipd =\nhead = 1\n", 1, 6, "missing value after `=`");
        expect("ipd = # none\n", 1, 7, "missing value after `=`");
        expect(
            "ipd = 1.5 m\n",
            1,
            7,
            "`1.5 m` is not a value: a number is written without units or spaces, a list as [a, b, c], text in quotes",
        );
        expect(
            "ipd = 1,5\n",
            1,
            8,
            "unexpected `,5`: expected the end of the line or a `#` comment (a decimal point is `.`)",
        );
    }

    #[test]
    fn bad_numbers_are_shown_whole_from_their_first_character() {
        for (line, number, why) in [
            ("ipd = 0.0.6", "0.0.6", "invalid float"),
            ("ipd = 1e", "1e", "invalid exponent, expected digits"),
            ("ipd = 06", "06", "unexpected leading zero"),
            ("ipd = .5", ".5", "invalid mantissa, expected digits"),
            ("ipd = 1__0", "1__0", "`_` may only go between digits"),
            ("ll = [1, 2.5.3, 0]", "2.5.3", "invalid float"),
        ] {
            let column = line.find(number).unwrap() + 1;
            expect(
                &format!("{line}\n"),
                1,
                column,
                &format!("`{number}` is not a number ({why})"),
            );
        }
        expect(
            "far = 99999999999999999999\n",
            1,
            7,
            "`99999999999999999999` is too large for an integer (at most 9223372036854775807); write it as a float, e.g. `99999999999999999999.0`",
        );
    }

    #[test]
    fn good_toml_has_no_syntax_error_and_any_text_is_placed() {
        assert_eq!(syntax_error("a = [1, 2]\n[t]\nb = { c = 'x' }\n"), None);
        // Every prefix of a rig, cut anywhere (inside characters too),
        // gets a place on a line of the text.
        let rig = "name = \"é [ü\"\n[viewer]\nhead = [0, { x = '''\n]''' }, \"\\\"\"]\n";
        for cut in 0..=rig.len() {
            let text = &rig[..floor_boundary(rig, cut)];
            if let Some(e) = syntax_error(text) {
                assert!(
                    e.line >= 1 && e.line <= text.lines().count().max(1) + 1,
                    "{text:?}: {e:?}"
                );
                assert!(e.column >= 1 && !e.message.is_empty(), "{text:?}: {e:?}");
            }
        }
    }
}
