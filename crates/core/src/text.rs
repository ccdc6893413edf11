//! Text that reaches a terminal: strings a user or a file controls (names,
//! paths, shader messages) made safe to print, and capped in length.
//!
//! A terminal acts on control characters (ESC starts a command that can
//! retitle the window, clear the screen or move the cursor; CR and newlines
//! forge lines), and bidirectional overrides reorder what is shown. Printed
//! text therefore shows them as escapes (`\e`, `\n`, `\u{202e}`), and a
//! message longer than [`MAX_SHOWN`] characters is cut, saying how much is
//! left out.

use std::borrow::Cow;
use std::fmt::Write;

/// The most characters of one message [`shown`] prints.
pub const MAX_SHOWN: usize = 2000;

/// Whether `c` must not reach a terminal as itself: C0 and C1 controls,
/// DEL, and the Unicode format characters that reorder or hide text.
pub fn is_unsafe(c: char) -> bool {
    c.is_control()
        || matches!(c,
            '\u{200b}'..='\u{200f}' // zero widths, LRM/RLM
            | '\u{2028}'..='\u{202e}' // line/paragraph separators, embeddings, overrides
            | '\u{2060}'..='\u{206f}' // word joiner, isolates, deprecated format controls
            | '\u{feff}')
}

/// `s` with every unsafe character written as an escape; borrowed when
/// there is none. Tabs are kept only where `keep_newlines` asks for whole
/// lines (a multi-line message), as are `\n`.
pub fn printable(s: &str, keep_newlines: bool) -> Cow<'_, str> {
    let kept = |c: char| keep_newlines && (c == '\n' || c == '\t');
    if !s.chars().any(|c| is_unsafe(c) && !kept(c)) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if kept(c) || !is_unsafe(c) {
            out.push(c);
            continue;
        }
        match c {
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            '\u{1b}' => out.push_str("\\e"),
            c => {
                let _ = write!(out, "\\u{{{:x}}}", u32::from(c));
            }
        }
    }
    Cow::Owned(out)
}

/// `s` made [`printable`] and cut to [`MAX_SHOWN`] characters: what the
/// command line prints for an error, a warning or a name.
pub fn shown(s: &str, keep_newlines: bool) -> Cow<'_, str> {
    cap(printable(s, keep_newlines), MAX_SHOWN)
}

/// `s` cut to `max` characters, with a note of how many were left out.
pub fn cap(s: Cow<'_, str>, max: usize) -> Cow<'_, str> {
    match s.char_indices().nth(max) {
        None => s,
        Some((at, _)) => {
            let left = s[at..].chars().count();
            Cow::Owned(format!("{} … ({left} more characters)", &s[..at]))
        }
    }
}

/// A token of a file for an error message: quoted when it looks like a word
/// or a number (`"Kd"`, `"0,3"`), otherwise only its length, so an error about
/// a file that is not what it should be (`mtllib /etc/passwd`, a private key
/// named as a shader) never shows what the file holds.
pub fn shown_token(tok: &str) -> String {
    let wordlike = |c: char| c.is_ascii_alphanumeric() || "_.+-,".contains(c);
    if !tok.is_empty() && tok.len() <= 24 && tok.chars().all(wordlike) {
        format!("\"{tok}\"")
    } else {
        format!("a token of {} characters", tok.chars().count())
    }
}

/// Whether `name` may name a file luster writes (a relative path whose
/// folders are `/`-separated): not empty, no control or format characters
/// (a newline in a file name forges lines in every listing and script that
/// shows it), no backslash, and no part longer than 255 bytes. A reason
/// when it may not.
pub fn file_name_problem(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("is empty")
    } else if name.chars().any(is_unsafe) {
        Some("holds a control character")
    } else if name.contains('\\') {
        Some("holds a backslash")
    } else if name.split('/').any(|part| part.len() > 255) {
        Some("has a part longer than 255 bytes")
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_and_reordering_characters_are_escaped() {
        assert_eq!(printable("plain name.png", false), "plain name.png");
        assert!(matches!(printable("plain", false), Cow::Borrowed(_)));
        assert_eq!(printable("a\u{1b}]0;pwned\u{7}b", false), "a\\e]0;pwned\\u{7}b");
        assert_eq!(printable("x\r\ny", false), "x\\r\\ny");
        assert_eq!(printable("x\ny\tz", true), "x\ny\tz");
        assert_eq!(printable("x\ry", true), "x\\ry");
        assert_eq!(printable("evil\u{202e}gnp.exe", false), "evil\\u{202e}gnp.exe");
        assert_eq!(printable("\u{9b}31m", false), "\\u{9b}31m");
        assert_eq!(printable("grüße", false), "grüße");
    }

    #[test]
    fn tokens_that_could_be_secrets_are_not_quoted() {
        assert_eq!(shown_token("0,3"), "\"0,3\"");
        assert_eq!(shown_token("map_Kd"), "\"map_Kd\"");
        assert_eq!(shown_token("root:x:0:0:root:/root:/bin/bash"), "a token of 31 characters");
        assert_eq!(shown_token("b3BlbnNzaC1rZXktdjEAAAAABG5vbmUAAAAEbm9uZQ"), "a token of 42 characters");
    }

    #[test]
    fn long_messages_are_cut_with_a_count() {
        let long = "é".repeat(MAX_SHOWN + 5);
        let s = shown(&long, false);
        assert!(s.starts_with(&"é".repeat(MAX_SHOWN)));
        assert!(s.ends_with("(5 more characters)"), "{s}");
        assert_eq!(shown("short", false), "short");
    }

    #[test]
    fn output_names_refuse_what_a_shell_or_terminal_would_act_on() {
        assert_eq!(file_name_problem("bunny.png"), None);
        assert_eq!(file_name_problem("café – final.exr"), None);
        assert!(file_name_problem("").is_some());
        assert!(file_name_problem("a\nb.png").is_some());
        assert!(file_name_problem("a\u{1b}[2J.png").is_some());
        assert_eq!(file_name_problem("renders/bunny.png"), None);
        assert!(file_name_problem("a\\b.png").is_some());
        assert!(file_name_problem(&"a".repeat(256)).is_some());
    }
}
