//! Source instrumentation: inserts a deadline check into every loop body and
//! function of a user script, so that the per-call timeout holds even inside
//! JIT-compiled code.
//!
//! # Why rewrite the source
//!
//! LuaJIT does not run debug hooks inside compiled traces (a count hook stops
//! `while true do end` only until the loop is compiled, a few dozen iterations
//! later), unless LuaJIT is rebuilt with `LUAJIT_ENABLE_CHECKHOOK`, which the
//! vendored build offers no switch for. Turning the JIT off would cost most of
//! the speed the shaders are written for. So the script itself is made to
//! check: a small tokenizer that knows Lua's strings, long brackets, comments
//! and numbers finds every place a script can spin and inserts
//! `__luster_tick();` there:
//!
//! * after every `do` (the bodies of `while` and both `for` forms, and plain
//!   blocks);
//! * after every `repeat`;
//! * before every `goto` (every `goto` loop has one; a tick after the label
//!   instead would break the common `goto continue` idiom, whose label must
//!   end its block when locals are declared before it);
//! * after the parameter list of every `function` (recursion, including tail
//!   calls, which grow no stack).
//!
//! Every unbounded computation in Lua code passes one of these points, so a
//! script cannot run long without ticking. The tick is a local of the chunk
//! (`local __luster_tick = ...;` on the first line), bound to the trusted
//! prelude's `tick`; it decrements a counter and reads the clock only every
//! few thousand ticks, which the JIT compiles to a few instructions. Nothing is
//! inserted on a new line, so line numbers in messages are the user's. Names
//! starting with `__luster` are refused, so a script cannot shadow or replace
//! the tick.
//!
//! Malformed input (an unterminated string or comment) is passed through
//! unchanged from that point: Lua's own parser then reports it with its line.

/// The name the inserted checks call.
pub(crate) const TICK: &str = "__luster_tick";

/// Names with this prefix are reserved for the runtime.
const RESERVED: &str = "__luster";

/// A script used a reserved name.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ReservedName {
    /// 1-based line of the name.
    pub line: usize,
    /// The name itself.
    pub name: String,
}

/// Returns `code` with deadline checks inserted (see the module doc).
pub(crate) fn instrument(code: &str) -> Result<String, ReservedName> {
    let b = code.as_bytes();
    let mut out = String::with_capacity(code.len() + code.len() / 8 + 64);
    let insert = format!(" {TICK}(); ");
    out.push_str(&format!("local {TICK} = ...; "));
    // A `#!` first line is skipped by Lua; comment it out after our prefix.
    if b.first() == Some(&b'#') {
        out.push_str("--");
    }

    let mut copied = 0; // bytes of `code` already copied to `out`
    let mut i = 0;
    let mut line = 1;
    let mut in_params = false; // between `function` and the `)` closing its parameters
    let flush = |out: &mut String, upto: usize, copied: &mut usize| {
        out.push_str(&code[*copied..upto]);
        *copied = upto;
    };

    while i < b.len() {
        let c = b[i];
        match c {
            b'\n' => {
                line += 1;
                i += 1;
            }
            b' ' | b'\t' | b'\r' | 0x0b | 0x0c => i += 1,
            b'-' if b.get(i + 1) == Some(&b'-') => {
                i += 2;
                if let Some(level) = long_bracket_level(b, i) {
                    match skip_long(b, i, level, &mut line) {
                        Some(end) => i = end,
                        None => break,
                    }
                } else {
                    while i < b.len() && b[i] != b'\n' {
                        i += 1;
                    }
                }
            }
            b'[' if long_bracket_level(b, i).is_some() => {
                let level = long_bracket_level(b, i).unwrap_or(0);
                match skip_long(b, i, level, &mut line) {
                    Some(end) => i = end,
                    None => break,
                }
            }
            b'"' | b'\'' => match skip_short_string(b, i, &mut line) {
                Some(end) => i = end,
                None => break,
            },
            b'0'..=b'9' => {
                i = skip_number(b, i);
            }
            b'.' if b.get(i + 1).is_some_and(u8::is_ascii_digit) => {
                i = skip_number(b, i);
            }
            c if c == b'_' || c.is_ascii_alphabetic() => {
                let start = i;
                while i < b.len() && (b[i] == b'_' || b[i].is_ascii_alphanumeric()) {
                    i += 1;
                }
                let word = &code[start..i];
                if word.starts_with(RESERVED) {
                    return Err(ReservedName { line, name: word.to_string() });
                }
                match word {
                    "do" | "repeat" => {
                        flush(&mut out, i, &mut copied);
                        out.push_str(&insert);
                    }
                    "goto" => {
                        flush(&mut out, start, &mut copied);
                        out.push_str(&insert);
                    }
                    "function" => in_params = true,
                    _ => {}
                }
            }
            b')' => {
                i += 1;
                if in_params {
                    in_params = false;
                    flush(&mut out, i, &mut copied);
                    out.push_str(&insert);
                }
            }
            _ => {
                // Any other byte is an operator or punctuation (or, in invalid
                // code, something Lua will report); none of them matters here.
                // Multi-byte UTF-8 is stepped over whole to keep slicing valid.
                i += utf8_len(c);
            }
        }
    }
    out.push_str(&code[copied..]);
    Ok(out)
}

fn utf8_len(first: u8) -> usize {
    match first {
        0xf0..=0xff => 4,
        0xe0..=0xef => 3,
        0xc0..=0xdf => 2,
        _ => 1,
    }
}

/// If `b[i..]` opens a long bracket `[`, `=`*, `[`, its level (the number of `=`).
fn long_bracket_level(b: &[u8], i: usize) -> Option<usize> {
    if b.get(i) != Some(&b'[') {
        return None;
    }
    let mut j = i + 1;
    while b.get(j) == Some(&b'=') {
        j += 1;
    }
    (b.get(j) == Some(&b'[')).then_some(j - i - 1)
}

/// Skips a long string or comment opening at `i`; the index after its closing
/// bracket, or `None` if it is unterminated.
fn skip_long(b: &[u8], i: usize, level: usize, line: &mut usize) -> Option<usize> {
    let mut j = i + level + 2;
    while j < b.len() {
        match b[j] {
            b'\n' => *line += 1,
            b']' => {
                let mut k = j + 1;
                while k < b.len() && b[k] == b'=' {
                    k += 1;
                }
                if k - j - 1 == level && b.get(k) == Some(&b']') {
                    return Some(k + 1);
                }
            }
            _ => {}
        }
        j += 1;
    }
    None
}

/// Skips a quoted string opening at `i`; `None` if it is unterminated.
fn skip_short_string(b: &[u8], i: usize, line: &mut usize) -> Option<usize> {
    let quote = b[i];
    let mut j = i + 1;
    while j < b.len() {
        match b[j] {
            c if c == quote => return Some(j + 1),
            // An unescaped newline ends the string in error; let Lua say so.
            b'\n' => return None,
            b'\\' => {
                // The escaped byte may be a newline (a continued string) or,
                // after `\z`, whitespace; either way it is inside the string.
                if b.get(j + 1) == Some(&b'\n') {
                    *line += 1;
                }
                j += 2;
            }
            _ => j += 1,
        }
    }
    None
}

/// Skips a numeral as Lua's lexer reads it: digits, letters, `_`, `.`, and a
/// sign right after an exponent letter (`1e-5`, `0x1p+4`, `1ULL`).
fn skip_number(b: &[u8], mut i: usize) -> usize {
    while i < b.len() {
        let c = b[i];
        let exponent_sign =
            (c == b'+' || c == b'-') && i > 0 && matches!(b[i - 1], b'e' | b'E' | b'p' | b'P');
        if c.is_ascii_alphanumeric() || c == b'_' || c == b'.' || exponent_sign {
            i += 1;
        } else {
            break;
        }
    }
    i
}

#[cfg(test)]
mod tests {
    use super::*;

    fn body(code: &str) -> String {
        let out = instrument(code).unwrap();
        out.strip_prefix(&format!("local {TICK} = ...; ")).unwrap().to_string()
    }

    #[test]
    fn loops_functions_and_gotos_get_ticks() {
        let t = format!(" {TICK}(); ");
        assert_eq!(body("while true do end"), format!("while true do{t} end"));
        assert_eq!(body("repeat x() until y"), format!("repeat{t} x() until y"));
        assert_eq!(body("for i=1,3 do end"), format!("for i=1,3 do{t} end"));
        assert_eq!(
            body("local function f(a, b) return a end"),
            format!("local function f(a, b){t} return a end")
        );
        assert_eq!(body("f = function(...) end"), format!("f = function(...){t} end"));
        assert_eq!(body("::top:: goto top"), format!("::top:: {t}goto top"));
    }

    #[test]
    fn strings_comments_and_numbers_are_left_alone() {
        for code in [
            "x = 'do repeat' .. \"function() ::a::\"",
            "x = [[ do ]] .. [==[ repeat ]] ]==]",
            "-- do repeat\n--[[ while true do end ]]\n--[=[ ]] do ]=]",
            "x = 'a\\'do' y = \"\\\"do\"",
            "x = 1e-5 + 0x1p+4 + 3ULL + .5",
            "t = {[1]=2, [ [[a]] ]=3}",
        ] {
            assert_eq!(body(code), code, "{code}");
        }
    }

    #[test]
    fn line_numbers_are_preserved() {
        let code = "local a = 1\nwhile a do\n  a = nil\nend\nlocal s = [[\n\n]]\nfunction f()\nend\n";
        assert_eq!(instrument(code).unwrap().lines().count(), code.lines().count());
    }

    #[test]
    fn reserved_names_are_refused_with_their_line() {
        let e = instrument("x = 1\n__luster_tick = function() end").unwrap_err();
        assert_eq!(e, ReservedName { line: 2, name: "__luster_tick".into() });
        assert!(instrument("local s = '__luster_tick'").is_ok());
    }

    #[test]
    fn unterminated_input_is_passed_through() {
        assert!(body("x = 'abc\nwhile true do end").ends_with("while true do end"));
        assert!(body("x = [[ abc").ends_with("[[ abc"));
    }

    #[test]
    fn shebang_is_commented_out() {
        assert!(instrument("#!/usr/bin/lua\nx = 1").unwrap().contains("; --#!/usr/bin/lua\n"));
    }
}
