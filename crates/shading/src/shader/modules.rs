//! `require "name"`: Lua modules shared between shaders, loaded from the
//! scene's folder and the library folders the scene (`<ShaderLibrary>`) or
//! the command line (`--shader-lib DIR`) names.
//!
//! A module name is one or more identifiers separated by `.` or `/`
//! (`"wood"`, `"lib.wood"`, `"lib/wood"`), which maps to `lib/wood.lua`
//! under each folder in turn; the first that has the file wins. The name
//! cannot spell an absolute path, a `..` or another extension, and the file
//! found must resolve (after symlinks) inside the folder it was found in, so
//! a link cannot lead out. It is read through the scene reader's regular-file
//! and size checks. The prelude caches each module per Lua state, runs it in
//! its own sandboxed environment under the calling shader's time limit, and
//! refuses cycles (`prelude.lua`, `require`). A name no folder has may be
//! one of the modules built into luster (`builtin_modules.rs`).

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::Mutex;

use super::builtin_modules;
use super::instrument::{instrument, ScanError};

/// Largest module accepted, as for scripts.
pub const MAX_MODULE_BYTES: u64 = 4 << 20;

/// The library folders `--shader-lib` named (process-wide: a command-line
/// setting, like `--debug-pixel`).
static LIBRARY_DIRS: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Sets the library folders of `--shader-lib`, searched after the scene's
/// own folders.
pub fn set_library_dirs(dirs: Vec<PathBuf>) {
    if let Ok(mut d) = LIBRARY_DIRS.lock() {
        *d = dirs;
    }
}

/// Where a set's scripts find their modules, in search order: `scene_dirs`
/// (the scene's folder and its `<ShaderLibrary>` folders), then the
/// command line's. Folders that do not exist are kept: a module looked up
/// there is simply not found.
pub fn search_path(scene_dirs: &[PathBuf]) -> Vec<PathBuf> {
    let cli = LIBRARY_DIRS.lock().map(|d| d.clone()).unwrap_or_default();
    let mut all: Vec<PathBuf> = Vec::new();
    for d in scene_dirs.iter().chain(&cli) {
        // A scene named without a folder ("s.xml") has an empty base folder,
        // which cannot be canonicalized: it is the working directory.
        let d = if d.as_os_str().is_empty() { PathBuf::from(".") } else { d.clone() };
        if !all.contains(&d) {
            all.push(d);
        }
    }
    all
}

/// A set's module search path and the files its scripts required.
#[derive(Debug, Default)]
pub(crate) struct Modules {
    roots: Vec<PathBuf>,
    required: Mutex<BTreeSet<PathBuf>>,
}

/// The module file `name` names, relative to a folder, or why the name is
/// refused.
fn relative_path(name: &str) -> Result<PathBuf, String> {
    let ident = |s: &str| {
        !s.is_empty()
            && s.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
            && !s.as_bytes()[0].is_ascii_digit()
    };
    if name.ends_with(".lua") {
        return Err(format!(
            "require: '{}' is not a module name: leave out the .lua (require \"{}\")",
            name.escape_debug(),
            name.trim_end_matches(".lua").escape_debug()
        ));
    }
    let parts: Vec<&str> = name.split(['.', '/']).collect();
    if name.len() > 200 || !parts.iter().all(|p| ident(p)) {
        return Err(format!(
            "require: '{}' is not a module name (identifiers separated by '.' or '/', such as \"lib.wood\": \
             no absolute paths, '..', or file extensions)",
            name.escape_debug()
        ));
    }
    let mut path: PathBuf = parts.iter().collect();
    path.set_extension("lua");
    Ok(path)
}

/// A module's code with the time-limit checks inserted, or why it cannot be.
fn instrumented(shown: &str, code: &str) -> Result<String, String> {
    match instrument(code) {
        Ok(code) => Ok(code),
        Err(ScanError::Reserved { line, name: word }) => {
            Err(format!("{shown}:{line}: the name '{word}' is reserved for the shader runtime"))
        }
        Err(ScanError::Unterminated { line }) => {
            Err(format!("{shown}:{line}: a string or comment opened here does not close"))
        }
    }
}

impl Modules {
    pub(crate) fn new(roots: Vec<PathBuf>) -> Modules {
        Modules { roots, required: Mutex::new(BTreeSet::new()) }
    }

    /// The files required so far (canonical paths), for a watcher.
    pub(crate) fn required(&self) -> Vec<PathBuf> {
        self.required.lock().map(|r| r.iter().cloned().collect()).unwrap_or_default()
    }

    /// Finds and reads module `name`: its file as messages show it, its
    /// instrumented code and its canonical path (which identifies it
    /// whatever the name's spelling), or a one-sentence reason.
    pub(crate) fn load(&self, name: &str) -> Result<(String, String, String), String> {
        let rel = relative_path(name)?;
        for root in &self.roots {
            let candidate = root.join(&rel);
            // symlink_metadata: a dangling link is "found" and then refused
            // below, rather than silently skipped.
            if std::fs::symlink_metadata(&candidate).is_err() {
                continue;
            }
            let shown = candidate.display().to_string();
            let escape =
                || format!("require: {shown} leads outside the folder {} it was found in", root.display());
            let (Ok(real), Ok(real_root)) = (candidate.canonicalize(), root.canonicalize()) else {
                return Err(escape());
            };
            if !real.starts_with(&real_root) {
                return Err(escape());
            }
            let code = luster_core::file::read_text(&real, MAX_MODULE_BYTES)
                .map_err(|why| format!("require: cannot read module {shown}: {why}"))?;
            let code = instrumented(&shown, &code)?;
            let key = real.display().to_string();
            if let Ok(mut r) = self.required.lock() {
                r.insert(real);
            }
            return Ok((shown, code, key));
        }
        // No folder has it: a built-in module of that name, not watched (it
        // is no file), identified by a key no canonical path can spell.
        if let Some(code) = builtin_modules::source(name) {
            let shown = builtin_modules::shown(name);
            let code = instrumented(&shown, code)?;
            return Ok((shown, code, format!("built-in:{name}")));
        }
        let looked: Vec<String> = self.roots.iter().map(|r| r.display().to_string()).collect();
        Err(format!(
            "require: no module '{name}' ({} not found in {})",
            rel.display(),
            if looked.is_empty() { "any folder: no folders are set".to_string() } else { looked.join(", ") }
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_map_to_lua_files_and_nothing_else() {
        assert_eq!(relative_path("wood").unwrap(), PathBuf::from("wood.lua"));
        assert_eq!(relative_path("lib.wood").unwrap(), PathBuf::from("lib/wood.lua"));
        assert_eq!(relative_path("lib/wood").unwrap(), PathBuf::from("lib/wood.lua"));
        for bad in ["", "/etc/passwd", "../x", "lib..x", "a/../b", "wood.lua", "a\\b", "1x", "a b", "lib/"] {
            let e = relative_path(bad).unwrap_err();
            assert!(e.starts_with("require: '") && e.contains("is not a module name"), "{bad}: {e}");
        }
    }
}
