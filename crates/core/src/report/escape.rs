//! Names read from files (topics, frames, types, paths) shown to a person: control characters are
//! escaped (`\n`, `\t`, `\x1b`, `\u{85}`), so a crafted name cannot break a table or fake a line
//! of the tool's own output on a terminal.

use std::borrow::Cow;

/// `s` with every control character escaped; borrowed when there is none.
///
/// ```
/// use trajdrift_core::report::escape::escape;
/// assert_eq!(escape("/odom"), "/odom");
/// assert_eq!(escape("a\nerror: b\x1b[31m"), "a\\nerror: b\\x1b[31m");
/// ```
pub fn escape(s: &str) -> Cow<'_, str> {
    if !s.chars().any(char::is_control) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() && (c as u32) < 0x80 => {
                out.push_str(&format!("\\x{:02x}", c as u32))
            }
            c if c.is_control() => out.push_str(&format!("\\u{{{:x}}}", c as u32)),
            c => out.push(c),
        }
    }
    Cow::Owned(out)
}

/// A whole message (one line by construction) with control characters escaped.
pub fn escape_line(s: &str) -> String {
    escape(s).into_owned()
}
