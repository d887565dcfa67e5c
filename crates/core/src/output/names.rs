//! The one mapping from a name found in data (an estimate's name, a topic) to a part of a file name,
//! and the check that two names never map to one file: `a.b` and `a_b`, or `/odom/filtered` and
//! `/odom_filtered`, would otherwise overwrite each other's figures and exports without a word.
//!
//! The mapping keeps ASCII letters, digits, `-` and `_`, writes every other character as `_` and trims
//! `_` at both ends; a name with nothing left is `unnamed`. Two names collide when their file names are
//! equal ignoring case (a results folder copied to a case-insensitive file system must stay whole).

use crate::error::{Error, Result};

/// The file-name part of `name`.
///
/// ```
/// use trajdrift_core::output::names::file_stem;
/// assert_eq!(file_stem("estimate/odom"), "estimate_odom");
/// assert_eq!(file_stem("a.b"), "a_b");
/// assert_eq!(file_stem("../../etc/passwd"), "etc_passwd");
/// assert_eq!(file_stem("///"), "unnamed");
/// ```
pub fn file_stem(name: &str) -> String {
    let mapped: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    let trimmed = mapped.trim_matches('_');
    if trimmed.is_empty() {
        "unnamed".into()
    } else {
        trimmed.to_string()
    }
}

/// [`file_stem`] of each of `names`, refused (a usage error) when two of them map to the same file
/// name; `what` names them in the message (`estimates`), `fix` says how to rename one.
///
/// ```
/// use trajdrift_core::output::names::file_stems;
/// assert!(file_stems("estimates", ["lio", "odom"], "").is_ok());
/// let e = file_stems("estimates", ["odom/filtered", "odom_filtered"], "").unwrap_err();
/// assert!(e.to_string().contains("`odom/filtered` and `odom_filtered`"));
/// ```
pub fn file_stems<'a>(
    what: &str,
    names: impl IntoIterator<Item = &'a str>,
    fix: &str,
) -> Result<Vec<String>> {
    let names: Vec<&str> = names.into_iter().collect();
    let stems: Vec<String> = names.iter().map(|n| file_stem(n)).collect();
    for i in 0..stems.len() {
        for j in 0..i {
            if stems[i].eq_ignore_ascii_case(&stems[j]) && names[i] != names[j] {
                return Err(Error::InvalidArgument(format!(
                    "{what} `{}` and `{}` both map to the file name `{}` and would overwrite each other's files; rename one{}",
                    crate::report::escape::escape(names[j]),
                    crate::report::escape::escape(names[i]),
                    stems[j],
                    if fix.is_empty() { String::new() } else { format!(" ({fix})") }
                )));
            }
        }
    }
    Ok(stems)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn stems_are_safe_file_names(name in "\\PC{0,40}") {
            let s = file_stem(&name);
            prop_assert!(!s.is_empty());
            prop_assert!(s.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_'));
        }
    }

    #[test]
    fn collisions_are_refused_case_insensitively() {
        assert!(file_stems("estimates", ["a.b", "a_b"], "").is_err());
        assert!(file_stems("estimates", ["LIO", "lio"], "").is_err());
        assert!(file_stems("estimates", ["//", "__"], "").is_err());
        assert_eq!(
            file_stems("estimates", ["x", "y/z"], "").unwrap(),
            ["x", "y_z"]
        );
    }
}
