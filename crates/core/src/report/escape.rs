//! Names are data. A topic, frame, type, file, estimate or mission name read from a recording, a
//! manifest or a JSON result can hold anything — newlines, ANSI escapes, bidi controls, markup,
//! spreadsheet formulas, `../` — and reaches a person through one of a few sinks. Each sink has one
//! function here, and every output that shows a name goes through the function of its sink:
//!
//! | sink | function | what it guarantees |
//! |---|---|---|
//! | terminal and messages | [`escape`], [`escape_line`] | control, bidi and invisible format characters shown as `\n`, `\x1b`, `\u{202e}` |
//! | Markdown | [`markdown`] | the above, and Markdown's punctuation backslash-escaped: no link, no HTML, no table break |
//! | CSV | [`csv_field`] | the above, quoted when needed, and a leading `=`, `+`, `-`, `@` neutralised (`'=…`): no formula |
//! | HTML text and attribute values | [`html`] | the above, and `& < > " '` as entities (attributes are always quoted) |
//! | SVG / XML documents | [`xml`] | no character XML 1.0 forbids, no bidi control |
//! | file names | [`crate::output::names::file_stem`] | ASCII letters, digits, `-`, `_`; collisions refused |

use std::borrow::Cow;

/// Characters that change how the text around them is shown without being visible themselves:
/// bidirectional controls (a right-to-left override makes `exe.txt` read `txt.exe`), zero-width
/// characters and the byte-order mark.
fn is_invisible_format(c: char) -> bool {
    matches!(c,
        '\u{061c}' | '\u{200b}'..='\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2060}'..='\u{2069}'
        | '\u{feff}')
}

fn needs_escape(c: char) -> bool {
    c.is_control() || is_invisible_format(c)
}

fn push_visible(out: &mut String, c: char) {
    match c {
        '\n' => out.push_str("\\n"),
        '\r' => out.push_str("\\r"),
        '\t' => out.push_str("\\t"),
        c if (c as u32) < 0x80 => out.push_str(&format!("\\x{:02x}", c as u32)),
        c => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
    }
}

/// The terminal's sink: `s` with every control, bidi and invisible format character written visibly;
/// borrowed when there is none.
///
/// ```
/// use trajdrift_core::report::escape::escape;
/// assert_eq!(escape("/odom"), "/odom");
/// assert_eq!(escape("a\nerror: b\x1b[31m"), "a\\nerror: b\\x1b[31m");
/// assert_eq!(escape("evil\u{202e}fdp.exe"), "evil\\u{202e}fdp.exe");
/// ```
pub fn escape(s: &str) -> Cow<'_, str> {
    if !s.chars().any(needs_escape) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if needs_escape(c) {
            push_visible(&mut out, c);
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

/// A whole message (one line by construction) with control characters escaped.
pub fn escape_line(s: &str) -> String {
    escape(s).into_owned()
}

/// The Markdown sink: [`escape`], then every character Markdown gives a meaning (links, emphasis,
/// code, inline HTML, table cells, headings) backslash-escaped, so a name is shown as written.
///
/// ```
/// use trajdrift_core::report::escape::markdown;
/// assert_eq!(markdown("lever_arm"), "lever\\_arm");
/// assert_eq!(markdown("[x](javascript:alert(1))"), "\\[x\\]\\(javascript:alert\\(1\\)\\)");
/// assert_eq!(markdown("<b>|"), "\\<b\\>\\|");
/// ```
pub fn markdown(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 8);
    for c in escape(s).chars() {
        if matches!(
            c,
            '\\' | '`'
                | '*'
                | '_'
                | '['
                | ']'
                | '('
                | ')'
                | '<'
                | '>'
                | '|'
                | '#'
                | '~'
                | '&'
                | '!'
        ) {
            out.push('\\');
        }
        out.push(c);
    }
    out
}

/// The CSV sink for a text cell: [`escape`] (one line), a leading `=`, `+`, `-`, `@` (a spreadsheet
/// formula) prefixed with `'`, and quoted (quotes doubled) when it holds `,`, `"` or `;`, or starts
/// or ends with a space.
///
/// ```
/// use trajdrift_core::report::escape::csv_field;
/// assert_eq!(csv_field("lever_arm"), "lever_arm");
/// assert_eq!(csv_field("=HYPERLINK(\"http://x\")"), "\"'=HYPERLINK(\"\"http://x\"\")\"");
/// assert_eq!(csv_field("@SUM(A1)"), "'@SUM(A1)");
/// assert_eq!(csv_field("a\nb,c"), "\"a\\nb,c\"");
/// ```
pub fn csv_field(s: &str) -> String {
    let mut v = escape(s).into_owned();
    if v.starts_with([
        '=', '+', '-', '@', '\u{ff1d}', '\u{ff0b}', '\u{ff0d}', '\u{ff20}',
    ]) {
        v.insert(0, '\'');
    }
    if v.contains([',', '"', ';']) || v.starts_with(' ') || v.ends_with(' ') {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v
    }
}

/// The HTML sink, for text and for (double-quoted) attribute values alike: [`escape`], then
/// `& < > " '` as entities.
///
/// ```
/// use trajdrift_core::report::escape::html;
/// assert_eq!(html("<script>\"x\" & 'y'"), "&lt;script&gt;&quot;x&quot; &amp; &#39;y&#39;");
/// ```
pub fn html(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in escape(s).chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&#39;"),
            _ => o.push(c),
        }
    }
    o
}

/// The XML sink, over a whole document whose markup is already escaped (an SVG from the plotting
/// library): every character XML 1.0 forbids (C0 controls but tab and newlines, U+FFFE, U+FFFF) and
/// every bidi or invisible format character written visibly, so the document always parses and
/// shows the names as written.
///
/// ```
/// use trajdrift_core::report::escape::xml;
/// assert_eq!(xml("<text>a\u{1}b</text>"), "<text>a\\x01b</text>");
/// assert_eq!(xml("<svg>\n</svg>"), "<svg>\n</svg>");
/// ```
pub fn xml(s: &str) -> Cow<'_, str> {
    let bad = |c: char| {
        (c.is_control() && !matches!(c, '\t' | '\n' | '\r'))
            || is_invisible_format(c)
            || matches!(c, '\u{fffe}' | '\u{ffff}')
    };
    if !s.chars().any(bad) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if bad(c) {
            push_visible(&mut out, c);
        } else {
            out.push(c);
        }
    }
    Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn no_sink_lets_a_control_or_bidi_character_through(s in "\\PC{0,20}[\\x00-\\x1f\\x7f\u{202a}-\u{202e}]\\PC{0,20}") {
            for out in [escape(&s).into_owned(), markdown(&s), csv_field(&s), html(&s)] {
                prop_assert!(!out.chars().any(needs_escape), "{out:?}");
            }
            prop_assert!(!markdown(&s).contains("\n"));
            let h = html(&s);
            prop_assert!(!h.contains('<') && !h.contains('"'));
        }

        #[test]
        fn csv_cells_never_start_a_formula(s in "[=+@-]\\PC{0,20}") {
            let c = csv_field(&s);
            let body = c.trim_start_matches('"');
            prop_assert!(body.starts_with('\''), "{c}");
        }
    }
}
