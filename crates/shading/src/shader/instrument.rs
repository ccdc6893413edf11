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
//! prelude's `tick`; it compares the watchdog's clock with the call's start,
//! which the JIT compiles to a few instructions. Nothing is
//! inserted on a new line, so line numbers in messages are the user's. Names
//! starting with `__luster` are refused, so a script cannot shadow or replace
//! the tick.
//!
//! The scanner follows LuaJIT's lexer (`lj_lex.c`) exactly where it matters
//! for finding keywords: a newline is `\n`, `\r`, `\r\n` or `\n\r`; a line
//! comment ends at either `\r` or `\n`; a short string ends at its quote and
//! fails at a bare newline; a backslash escapes the next character, a newline
//! (of any of the four forms), or with `\z` all whitespace that follows,
//! newlines included; long strings and comments close only at a bracket of
//! their own level; a numeral takes a sign only right after its exponent
//! letter (`e` for decimal, `p` for hexadecimal); and bytes from 0x80 up are
//! identifier characters. Where the scanner and Lua could still disagree (an
//! unterminated string or comment), instrumenting fails: the caller reports
//! Lua's own syntax error, or refuses the script if Lua would accept it.

/// The name the inserted checks call.
pub(crate) const TICK: &str = "__luster_tick";

/// Names with this prefix are reserved for the runtime.
const RESERVED: &str = "__luster";

/// Why a script could not be instrumented.
#[derive(Debug, Clone, PartialEq)]
pub enum ScanError {
    /// A script used a reserved name.
    Reserved {
        /// The 1-based line.
        line: usize,
        /// The name.
        name: String,
    },
    /// A string or comment opened on this line never closes.
    Unterminated {
        /// The 1-based line where it opens.
        line: usize,
    },
}

/// Returns `code` with deadline checks inserted (see the module doc).
pub fn instrument(code: &str) -> Result<String, ScanError> {
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
            b'\n' | b'\r' => i = newline(b, i, &mut line),
            b' ' | b'\t' | 0x0b | 0x0c => i += 1,
            b'-' if b.get(i + 1) == Some(&b'-') => {
                let open = line;
                i += 2;
                if let Some(level) = long_bracket_level(b, i) {
                    i = skip_long(b, i, level, &mut line).ok_or(ScanError::Unterminated { line: open })?;
                } else {
                    while i < b.len() && b[i] != b'\n' && b[i] != b'\r' {
                        i += 1;
                    }
                }
            }
            b'[' if long_bracket_level(b, i).is_some() => {
                let level = long_bracket_level(b, i).unwrap_or(0);
                let open = line;
                i = skip_long(b, i, level, &mut line).ok_or(ScanError::Unterminated { line: open })?;
            }
            b'"' | b'\'' => {
                let open = line;
                i = skip_short_string(b, i, &mut line).ok_or(ScanError::Unterminated { line: open })?;
            }
            b'0'..=b'9' => {
                i = skip_number(b, i);
            }
            b'.' if b.get(i + 1).is_some_and(u8::is_ascii_digit) => {
                i = skip_number(b, i);
            }
            c if is_ident(c) => {
                let start = i;
                while i < b.len() && (is_ident(b[i]) || b[i].is_ascii_digit()) {
                    i += 1;
                }
                let word = &code[start..i];
                if word.starts_with(RESERVED) {
                    return Err(ScanError::Reserved { line, name: word.to_string() });
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
            // Any other byte is an operator or punctuation (or, in invalid
            // code, something Lua will report); none of them matters here.
            _ => i += 1,
        }
    }
    out.push_str(&code[copied..]);
    Ok(out)
}

/// A byte that starts or continues a name: LuaJIT takes every byte from 0x80
/// up as a letter, so UTF-8 names are single words.
fn is_ident(c: u8) -> bool {
    c == b'_' || c.is_ascii_alphabetic() || c >= 0x80
}

/// Skips the newline at `i` (`\n`, `\r`, or a `\r\n` / `\n\r` pair, as Lua
/// counts them) and counts it.
fn newline(b: &[u8], i: usize, line: &mut usize) -> usize {
    *line += 1;
    match (b[i], b.get(i + 1)) {
        (b'\n', Some(b'\r')) | (b'\r', Some(b'\n')) => i + 2,
        _ => i + 1,
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
            b'\n' | b'\r' => j = newline(b, j, line),
            b']' => {
                let mut k = j + 1;
                while k < b.len() && b[k] == b'=' {
                    k += 1;
                }
                if k - j - 1 == level && b.get(k) == Some(&b']') {
                    return Some(k + 1);
                }
                // The `]` that ended this run may open the closing bracket.
                j = k;
            }
            _ => j += 1,
        }
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
            // An unescaped newline ends the string in error.
            b'\n' | b'\r' => return None,
            b'\\' => {
                j += 1;
                match b.get(j) {
                    None => return None,
                    // A continued string: the newline (either pair) is inside.
                    Some(b'\n' | b'\r') => j = newline(b, j, line),
                    // `\z` skips all whitespace that follows, newlines included.
                    Some(b'z') => {
                        j += 1;
                        while j < b.len() {
                            match b[j] {
                                b'\n' | b'\r' => j = newline(b, j, line),
                                b' ' | b'\t' | 0x0b | 0x0c => j += 1,
                                _ => break,
                            }
                        }
                    }
                    Some(_) => j += 1,
                }
            }
            _ => j += 1,
        }
    }
    None
}

/// Skips a numeral as LuaJIT's lexer reads it: name characters, `.`, and a
/// sign right after the exponent letter (`e` for decimal, `p` once the numeral
/// starts with `0x`), as in `1e-5`, `0x1p+4`, `1ULL`.
fn skip_number(b: &[u8], start: usize) -> usize {
    let hex = b.get(start) == Some(&b'0') && matches!(b.get(start + 1), Some(b'x' | b'X'));
    let exp = if hex { b'p' } else { b'e' };
    let mut i = start;
    while i < b.len() {
        let c = b[i];
        let exponent_sign = (c == b'+' || c == b'-') && i > start && b[i - 1].to_ascii_lowercase() == exp;
        if is_ident(c) || c.is_ascii_digit() || c == b'.' || exponent_sign {
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
        assert_eq!(e, ScanError::Reserved { line: 2, name: "__luster_tick".into() });
        let e = instrument("x = 1\r\ny = '\\z\r\n\r\n  '\r__luster_x = 1").unwrap_err();
        assert_eq!(e, ScanError::Reserved { line: 5, name: "__luster_x".into() });
        assert!(instrument("local s = '__luster_tick'").is_ok());
    }

    #[test]
    fn unterminated_input_is_an_error_with_its_line() {
        assert_eq!(
            instrument("x = 1\nx = 'abc\nwhile true do end"),
            Err(ScanError::Unterminated { line: 2 })
        );
        assert_eq!(instrument("x = [[ abc"), Err(ScanError::Unterminated { line: 1 }));
        assert_eq!(instrument("\n\n--[==[ ]] ]=]"), Err(ScanError::Unterminated { line: 3 }));
        assert_eq!(instrument("x = 'a\\"), Err(ScanError::Unterminated { line: 1 }));
        assert_eq!(instrument("x = 'a\rb'"), Err(ScanError::Unterminated { line: 1 }));
    }

    /// Every string and comment form of Lua, each followed by a loop that
    /// must get its tick: if the scanner lost track anywhere, the loop after
    /// it would run unchecked.
    #[test]
    fn every_string_and_comment_form_is_followed_by_a_checked_loop() {
        let t = format!(" {TICK}(); ");
        let forms = [
            "'plain'",
            "\"plain\"",
            "'it''s'",
            "'esc \\' \\\" \\\\ \\n \\t \\a \\b \\f \\v \\r'",
            "'dec \\65\\066\\0 hex \\x41 utf \\u{48}'",
            "'cont \\\n line'",
            "'cont \\\r\n crlf'",
            "'cont \\\n\r lfcr'",
            "'cont \\\r cr'",
            "'z \\z    \n\n  \r\n  \t done'",
            "\"z \\z\"",
            "'quote inside \"double\"'",
            "\"quote inside 'single'\"",
            "'do end while repeat function goto'",
            "[[long do]]",
            "[[\nmulti\r\nline]]",
            "[==[ ]] ]=] ]===] ]==]",
            "[=[ ]]]=]",
            "[[ ]=] ]]",
            "-- line comment do\n",
            "-- line comment ended by CR do\r",
            "--[[ long comment do ]]",
            "--[==[ long\n comment ]] ]==]",
            "--[= not long, so a line comment do\n",
            "--[ not long either do\n",
            "--\n",
            "0x1e+1",
            "1e+10",
            "0x1p-4",
            "3.14e-2",
            "123ULL",
        ];
        for form in forms {
            let code = format!("x = {form}\nwhile true do end");
            let got = body(&code);
            assert!(got.ends_with(&format!("while true do{t} end")), "{form:?} -> {got:?}");
            assert_eq!(got.matches(TICK).count(), 1, "{form:?} -> {got:?}");
        }
    }

    #[test]
    fn numbers_take_a_sign_only_after_their_own_exponent_letter() {
        let t = format!(" {TICK}(); ");
        // In hex, `e` is a digit: `0x1e+function` is 0x1e plus a function.
        assert_eq!(body("x = 0x1e+function() end"), format!("x = 0x1e+function(){t} end"));
        assert_eq!(body("x = 1e+5"), "x = 1e+5");
    }

    #[test]
    fn utf8_names_are_single_words() {
        assert_eq!(body("local xédo = 1"), "local xédo = 1");
        assert_eq!(body("local é = 1 while é do end"), format!("local é = 1 while é do {TICK}();  end"));
    }

    #[test]
    fn shebang_is_commented_out() {
        assert!(instrument("#!/usr/bin/lua\nx = 1").unwrap().contains("; --#!/usr/bin/lua\n"));
    }
}
