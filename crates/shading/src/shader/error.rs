//! Shader errors: one type for load-time and call-time failures, naming the
//! shader and, where Lua knows it, the script's `file:line`.

use std::fmt;
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
}

impl ShaderError {
    /// An error of `kind` in `shader`, without a location.
    pub fn new(kind: ShaderErrorKind, shader: &str, message: impl Into<String>) -> ShaderError {
        ShaderError { kind, shader: shader.to_string(), message: message.into(), object: None }
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
            mlua::Error::RuntimeError(m) => first_part(m),
            other => first_part(&other.to_string()),
        };
        let (kind, message) = match err {
            mlua::Error::SyntaxError { message, .. } => (ShaderErrorKind::Syntax, first_part(message)),
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

/// The message without the stack traceback mlua appends.
fn first_part(s: &str) -> String {
    let s = s.split("\nstack traceback:").next().unwrap_or(s);
    s.trim_end().to_string()
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
