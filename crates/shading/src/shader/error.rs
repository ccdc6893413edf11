//! Shader errors: one type for load-time and call-time failures, naming the
//! shader and, where Lua knows it, the script's `file:line`.
//!
//! A message may hold text the script or its file controls (a script's own
//! `error(...)`, the token a syntax error stopped at), and it reaches a
//! terminal: every message is escaped and capped
//! ([`luster_core::text::shown`]), and a syntax error names the token it
//! stopped at only when that looks like a word, a number or Lua punctuation
//! ([`near_token`]), so pointing a shader at a file that is not one (a
//! private key) never shows what the file holds.

use std::fmt;

use luster_core::text::{shown, shown_token};
use std::time::Duration;

/// What went wrong, for callers that react differently (the renderer may stop
/// on a syntax error but keep a count of runtime ones).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShaderErrorKind {
    /// The script does not parse, or uses a reserved name; found at load.
    Syntax,
    /// The script defines none of `color`, `height`, `reflect`.
    NoEntryPoint,
    /// An error raised while the script ran (including at load, when its
    /// top level runs), by Lua or by the script's own `error`.
    Runtime,
    /// An entry point returned something other than numbers, or NaN.
    BadResult,
    /// A scene parameter the script does not declare or read, or one of the
    /// wrong type.
    Parameter,
    /// A call ran past the per-call time limit and was stopped.
    Timeout,
    /// A Lua state ran out of its memory allowance.
    Memory,
    /// The caller asked for a shader id or entry point that does not exist.
    Usage,
    /// The runtime itself failed (creating a Lua state, the prelude).
    Internal,
}

/// A shader failure. Its message already carries the `file:line` Lua
/// reported; [`ShaderError::with_object`] lets the renderer add the object
/// being shaded.
#[derive(Debug, Clone, PartialEq)]
pub struct ShaderError {
    /// The kind of failure.
    pub kind: ShaderErrorKind,
    /// The shader's name, as the scene gave it.
    pub shader: String,
    /// What happened, normally starting with `file:line:`.
    pub message: String,
    /// The object being shaded, when the caller knows it.
    pub object: Option<String>,
    /// The index, in the list the set was built from, of the script at
    /// fault, when the error came from compiling or loading it.
    pub source: Option<usize>,
}

impl ShaderError {
    /// An error of `kind` in `shader`, without a location. The message and
    /// the name are escaped and capped for a terminal.
    pub fn new(kind: ShaderErrorKind, shader: &str, message: impl Into<String>) -> ShaderError {
        let message = message.into();
        ShaderError {
            kind,
            shader: shown(shader, false).into_owned(),
            message: shown(&message, false).into_owned(),
            object: None,
            source: None,
        }
    }

    /// The same error, naming the script at fault by its index.
    pub(crate) fn with_source(mut self, index: usize) -> ShaderError {
        self.source = Some(index);
        self
    }

    /// The same error, naming the object being shaded (e.g. `Mesh[id=3]`).
    pub fn with_object(mut self, object: impl Into<String>) -> ShaderError {
        self.object = Some(object.into());
        self
    }

    /// Turns an mlua error from loading or calling `shader` into a shader error.
    /// `timed_out` and `bad_result` come from the records the prelude shares
    /// with Rust, which say why a call failed more reliably than its message.
    pub(crate) fn from_lua(
        shader: &str,
        err: &mlua::Error,
        timed_out: bool,
        bad_result: bool,
        timeout: Duration,
    ) -> ShaderError {
        let err = root_cause(err);
        let text = match err {
            mlua::Error::RuntimeError(m) => in_script(m),
            other => in_script(&other.to_string()),
        };
        let (kind, message) = match err {
            mlua::Error::SyntaxError { message, .. } => {
                (ShaderErrorKind::Syntax, near_token(&first_part(message)))
            }
            mlua::Error::MemoryError(m) => {
                (ShaderErrorKind::Memory, format!("ran out of memory ({})", first_part(m)))
            }
            _ if timed_out => (
                ShaderErrorKind::Timeout,
                format!(
                    "{text} ({:.3} s per call; the limit is set with --shader-timeout)",
                    timeout.as_secs_f64()
                ),
            ),
            _ if bad_result => {
                // The wrapper's message already names the shader; keep the rest.
                let prefix = format!("shader '{shader}': ");
                (ShaderErrorKind::BadResult, text.strip_prefix(&prefix).unwrap_or(&text).to_string())
            }
            _ => (ShaderErrorKind::Runtime, without_prelude_location(text)),
        };
        ShaderError::new(kind, shader, message)
    }
}

/// Looks through mlua's wrappers (callback errors, contexts) to what Lua said.
fn root_cause(err: &mlua::Error) -> &mlua::Error {
    match err {
        mlua::Error::CallbackError { cause, .. } => root_cause(cause),
        mlua::Error::WithContext { cause, .. } => root_cause(cause),
        other => other,
    }
}

/// A built-in's error names its caller's line, but a built-in called as
/// `return f(...)` is a tail call, whose caller frame Lua has already
/// dropped: the location is then the runtime's own entry wrapper, which would
/// only mislead. Say that the line is unknown, and why.
fn without_prelude_location(text: String) -> String {
    const PRELUDE: &str = "luster/prelude.lua:";
    let Some(rest) = text.strip_prefix(PRELUDE) else { return text };
    match rest.split_once(": ") {
        Some((line, msg)) if line.bytes().all(|b| b.is_ascii_digit()) => format!(
            "{msg} (in a built-in called as `return f(...)`, a tail call, after which Lua keeps no line number)"
        ),
        _ => text,
    }
}

/// Where the runtime's own code reports errors from: the prelude, and the
/// trampolines that call the entry wrappers.
const RUNTIME_SOURCES: [&str; 2] = ["luster/prelude.lua", "luster"];

/// The message of an error, without the stack traceback the message handler
/// appended, and located in the script: an error raised inside the runtime's
/// own Lua (a library function that recursed too deeply, a comparison
/// inside `table.sort`), or a stack overflow raised where no line is known,
/// takes the line of the script's innermost frame in the traceback.
fn in_script(text: &str) -> String {
    let (msg, trace) = match text.split_once("\nstack traceback:") {
        Some((m, t)) => (m.trim_end(), Some(t)),
        None => (text.trim_end(), None),
    };
    // Messages that LuaJIT or the runtime raise with no line (a coroutine's
    // error travels out of it as it was raised).
    const UNLOCATED: [&str; 3] = ["stack overflow", "error in error handling", "coroutines nested too deep"];
    let bare = runtime_location(msg)
        .map(|(_, rest)| rest)
        .or_else(|| UNLOCATED.iter().any(|w| msg.starts_with(w)).then_some(msg));
    let located = match (bare, trace.and_then(script_frame)) {
        (Some(rest), Some(at)) => format!("{at}: {rest}"),
        _ => msg.to_string(),
    };
    in_words(located)
}

/// What a recursion that filled Lua's stack reads as.
pub(crate) const RECURSION: &str = "recursion too deep: Lua's stack is full";

/// LuaJIT's "stack overflow" in the author's terms: a script recursed too
/// deeply (Lua's stack, not the process's, is full; nothing crashed).
fn in_words(message: String) -> String {
    const LUAJIT: &str = "stack overflow";
    let at = match runtime_location(&message) {
        Some((loc, _)) => loc.len() + 2,
        None => message.find(": ").filter(|&i| message[i + 2..].starts_with(LUAJIT)).map_or(0, |i| i + 2),
    };
    if !message[at..].starts_with(LUAJIT) {
        return message;
    }
    format!("{}{RECURSION}{}", &message[..at], &message[at + LUAJIT.len()..])
}

/// `(location, rest)` when `msg` starts with a location in the runtime's
/// own code (`luster/prelude.lua:120: rest`).
fn runtime_location(msg: &str) -> Option<(&str, &str)> {
    RUNTIME_SOURCES.iter().find_map(|src| {
        let after = msg.strip_prefix(src)?.strip_prefix(':')?;
        let (line, rest) = after.split_once(": ")?;
        (!line.is_empty() && line.bytes().all(|b| b.is_ascii_digit()))
            .then_some((&msg[..src.len() + 1 + line.len()], rest))
    })
}

/// The innermost frame of a traceback that is a line of a script
/// (`\tx.lua:3: in function 'f'` gives `x.lua:3`), skipping C functions and
/// the runtime's own frames.
fn script_frame(trace: &str) -> Option<&str> {
    trace.lines().map(str::trim_start).find_map(|line| {
        let (at, _) = line.split_once(": in ")?;
        let (src, number) = at.rsplit_once(':')?;
        let script = !number.is_empty()
            && number.bytes().all(|b| b.is_ascii_digit())
            && src != "[C]"
            && !RUNTIME_SOURCES.contains(&src);
        script.then_some(at)
    })
}

/// The message without the stack traceback mlua appends (the caller caps
/// it: [`ShaderError::new`]).
fn first_part(s: &str) -> String {
    let s = s.split("\nstack traceback:").next().unwrap_or(s);
    s.trim_end().to_string()
}

/// LuaJIT's syntax errors end with `near 'TOKEN'`, the text it stopped at:
/// for a file that is not Lua, a piece of that file (an unfinished string
/// holds the rest of its line). The token is kept when it is one a script
/// would show anyway: a word or number of at most 24 characters
/// ([`luster_core::text::shown_token`]'s rule), Lua punctuation, `<eof>`, or
/// LuaJIT's escape of one control byte (`<\27>`); otherwise only its length.
pub(crate) fn near_token(message: &str) -> String {
    const NEAR: &str = " near '";
    let Some(at) = message.find(NEAR) else { return message.to_string() };
    let Some(token) = message[at + NEAR.len()..].strip_suffix('\'') else { return message.to_string() };
    let punctuation = |t: &str| t.len() <= 3 && t.chars().all(|c| "+-*/%^#=~<>(){}[];:,.".contains(c));
    let escaped_byte = |t: &str| {
        t.strip_prefix("<\\")
            .and_then(|r| r.strip_suffix('>'))
            .is_some_and(|d| !d.is_empty() && d.len() <= 3 && d.bytes().all(|b| b.is_ascii_digit()))
    };
    let word = shown_token(token);
    let shown = if word.starts_with('"') || punctuation(token) || token == "<eof>" || escaped_byte(token) {
        format!("near '{token}'")
    } else {
        format!("near {word}")
    };
    format!("{}{}", &message[..at + 1], shown)
}

impl fmt::Display for ShaderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "shader '{}'", self.shader)?;
        if let Some(object) = &self.object {
            write!(f, " (shading {object})")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for ShaderError {}
