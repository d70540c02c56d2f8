//! User text echoed in messages: on one line and of bounded length, so an
//! error stays one readable line whatever the input held (a 10 000-character
//! name, a path with a newline in it).
//!
//! [`code`] quotes a name, key or expression (`` `v * cos(theta)` ``), cut
//! after [`SHOWN`] characters with its length stated; [`path`] writes a path
//! whole, its control characters escaped (`a\nb/c.toml`). Both escape
//! control characters the way Rust string literals do (`\n`, `\t`,
//! `\u{1b}`), so nothing a user wrote can start a new line.

use std::fmt::Write as _;
use std::path::Path;

/// Characters of user text a message shows before cutting it.
pub const SHOWN: usize = 60;

/// `s` with its control characters escaped (`\n`, `\r`, `\t`, `\u{..}`).
pub fn escaped(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{{{:x}}}", c as u32);
            }
            c => out.push(c),
        }
    }
    out
}

/// `s` in backticks: escaped, and when longer than [`SHOWN`] characters
/// its start, an ellipsis and its length (`` `qqqq…` (10000 characters) ``).
pub fn code(s: &str) -> String {
    let n = s.chars().count();
    if n <= SHOWN {
        return format!("`{}`", escaped(s));
    }
    let head: String = s.chars().take(SHOWN - 1).collect();
    format!("`{}…` ({n} characters)", escaped(&head))
}

/// `s` as [`code`] shows it, without the backticks (for text already
/// quoted by its message, such as a key in `` key `...` ``).
pub fn bare(s: &str) -> String {
    let n = s.chars().count();
    if n <= SHOWN {
        return escaped(s);
    }
    let head: String = s.chars().take(SHOWN - 1).collect();
    format!("{}… ({n} characters)", escaped(&head))
}

/// A path as a message shows it: whole, on one line (control characters
/// escaped; bytes that are not UTF-8 shown as U+FFFD).
pub fn path(p: &Path) -> String {
    escaped(&p.to_string_lossy())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn echoed_text_is_one_bounded_line() {
        assert_eq!(code("v * cos(theta)"), "`v * cos(theta)`");
        let long = "q".repeat(10_000);
        let c = code(&long);
        assert!(c.len() < 100, "{c}");
        assert!(c.ends_with("…` (10000 characters)"), "{c}");
        assert_eq!(
            bare(&long),
            format!("{}… (10000 characters)", "q".repeat(59))
        );
        assert_eq!(code("a\nb\u{1b}"), "`a\\nb\\u{1b}`");
        assert_eq!(path(Path::new("a\nb/c.toml")), "a\\nb/c.toml");
        assert_eq!(path(Path::new("dir/c.toml")), "dir/c.toml");
        // Multi-byte characters are cut at a character, not a byte.
        let wide = "é".repeat(100);
        assert!(code(&wide).starts_with("`éé"));
    }
}
