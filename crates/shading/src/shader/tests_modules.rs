//! `require`: modules found in the allowed folders only, loaded once per
//! state, run in the sandbox under the time limit, with errors naming the
//! module's file and line, and cycles refused.

use super::*;
use std::path::Path;

/// A folder holding `files` (path relative to it, text).
fn tree(files: &[(&str, &str)]) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, text) in files {
        let p = dir.path().join(name);
        std::fs::create_dir_all(p.parent().expect("a parent")).expect("folders");
        std::fs::write(p, text).expect("a file");
    }
    dir
}

fn set(dirs: &[&Path], scripts: &[&str], timeout: Duration) -> Result<ShaderSet, ShaderError> {
    let sources = scripts
        .iter()
        .enumerate()
        .map(|(i, code)| ShaderSource::new(format!("s{i}"), format!("s{i}.lua"), *code));
    ShaderSet::with_modules(sources.collect(), timeout, None, dirs.iter().map(|d| d.to_path_buf()).collect())
}

fn color_of(set: &ShaderSet, id: usize) -> [f32; 3] {
    set.color(id, &ShadeInput::default()).expect("the call succeeds")
}

const WOOD: &str = "local M = {}\nfunction M.rings(x) return x * 2 end\nM.loads = 0\nreturn M";

#[test]
fn two_shaders_share_one_module_loaded_once() {
    let scene = tree(&[("lib/wood.lua", WOOD)]);
    let a = "local w = require 'lib.wood'\nw.loads = w.loads + 1\nfunction color(s) return w.rings(0.25), w.loads, 0 end";
    let b = "local w = require 'lib/wood'\nfunction color(s) return w.loads, 0, 0 end";
    let set = set(&[scene.path()], &[a, b], DEFAULT_TIMEOUT).expect("loads");
    // Both scripts saw the same table: the module ran once in this state.
    assert_eq!(color_of(&set, 0), [0.5, 1.0, 0.0]);
    assert_eq!(color_of(&set, 1), [1.0, 0.0, 0.0]);
    let wood = scene.path().join("lib/wood.lua").canonicalize().unwrap();
    assert_eq!(set.required_files(), [wood]);
}

#[test]
fn folders_are_searched_in_order() {
    let (first, second) =
        (tree(&[("m.lua", "return 1")]), tree(&[("m.lua", "return 2"), ("n.lua", "return 3")]));
    let code = "local m, n = require 'm', require 'n'\nfunction color(s) return m, n, 0 end";
    let set = set(&[first.path(), second.path()], &[code], DEFAULT_TIMEOUT).expect("loads");
    assert_eq!(color_of(&set, 0), [1.0, 3.0, 0.0]);
}

fn load_err(dirs: &[&Path], code: &str) -> ShaderError {
    set(dirs, &[code], Duration::from_millis(300)).expect_err("the script must fail to load")
}

#[test]
fn names_cannot_leave_the_folders() {
    let outside = tree(&[("secret.lua", "return 'secret'")]);
    let scene = tree(&[("ok.lua", "return 1")]);
    let abs = outside.path().join("secret").display().to_string();
    for name in [abs.as_str(), "../secret", "..", "ok.lua", "a\\\\b", ""] {
        let e = load_err(
            &[scene.path()],
            &format!("local m = require '{name}'\nfunction color(s) return 1, 1, 1 end"),
        );
        assert!(
            e.message.contains("is not a module name") && e.message.starts_with("s0.lua:1:"),
            "{name}: {e}"
        );
        assert!(!e.message.contains('\n'), "{e}");
    }
    let e = load_err(&[scene.path()], "require(42)");
    assert!(e.message.contains("expected a module name (a string), got a number"), "{e}");
}

#[cfg(unix)]
#[test]
fn a_symlink_cannot_lead_out_of_its_folder() {
    let outside = tree(&[("secret.lua", "return 'secret'")]);
    let scene = tree(&[]);
    std::os::unix::fs::symlink(outside.path().join("secret.lua"), scene.path().join("leak.lua")).unwrap();
    std::os::unix::fs::symlink(outside.path(), scene.path().join("dir")).unwrap();
    for name in ["leak", "dir.secret"] {
        let e = load_err(&[scene.path()], &format!("local m = require '{name}'"));
        assert!(e.message.contains("leads outside the folder"), "{name}: {e}");
    }
    // A link that stays inside is fine.
    let inside = tree(&[("real.lua", "return 7")]);
    std::os::unix::fs::symlink(inside.path().join("real.lua"), inside.path().join("alias.lua")).unwrap();
    let set = set(
        &[inside.path()],
        &["local m = require 'alias'\nfunction color(s) return m, 0, 0 end"],
        DEFAULT_TIMEOUT,
    )
    .expect("loads");
    assert_eq!(color_of(&set, 0), [7.0, 0.0, 0.0]);
}

#[test]
fn missing_and_irregular_modules_are_clear_errors() {
    let scene = tree(&[("folder.lua/x", "")]);
    let e = load_err(&[scene.path()], "require 'nothing'");
    assert!(e.message.contains("no module 'nothing' (nothing.lua not found in"), "{e}");
    let e = load_err(&[scene.path()], "require 'folder'");
    assert!(e.message.contains("cannot read module") && e.message.contains("it is a folder"), "{e}");
    let e = load_err(&[], "require 'x'");
    assert!(e.message.contains("no folders are set"), "{e}");
}

#[test]
fn errors_in_a_module_name_its_file_and_line() {
    let scene = tree(&[("bad.lua", "local x = 1\nlocal y = nil + x\nreturn y"), ("syntax.lua", "return )")]);
    let e = load_err(&[scene.path()], "require 'bad'");
    assert!(e.message.contains("bad.lua:2:") && e.message.contains("arithmetic"), "{e}");
    let e = load_err(&[scene.path()], "require 'syntax'");
    assert!(e.message.contains("syntax.lua:1:"), "{e}");
}

#[test]
fn cycles_are_errors_not_hangs() {
    let scene =
        tree(&[("a.lua", "local b = require 'b'\nreturn b"), ("b.lua", "local a = require 'a'\nreturn a")]);
    let e = load_err(&[scene.path()], "require 'a'");
    assert!(e.message.contains("cycle: 'a' -> 'b' -> 'a'"), "{e}");
    assert!(e.message.contains("b.lua:1:"), "{e}");
}

#[test]
fn modules_run_in_the_sandbox_under_the_time_limit() {
    let scene = tree(&[
        ("spin.lua", "while true do end"),
        ("escape.lua", "return io.open('/etc/passwd')"),
        ("glob.lua", "leaked = 1\nreturn {}"),
    ]);
    let e = load_err(&[scene.path()], "require 'spin'");
    assert_eq!(e.kind, ShaderErrorKind::Timeout, "{e}");
    assert!(e.message.contains("spin.lua:1") && e.message.contains("time limit"), "{e}");
    let e = load_err(&[scene.path()], "require 'escape'");
    assert!(
        e.message.contains("escape.lua:1") && e.message.contains("io") && e.message.contains("removed"),
        "{e}"
    );
    // A module's globals stay in the module.
    let set = set(
        &[scene.path()],
        &["require 'glob'\nfunction color(s) return leaked or 0, 0, 0 end"],
        DEFAULT_TIMEOUT,
    )
    .expect("loads");
    assert_eq!(color_of(&set, 0), [0.0, 0.0, 0.0]);
}

#[test]
fn a_scene_without_a_folder_searches_the_working_directory() {
    let path = crate::shader::search_path(&[std::path::PathBuf::new()]);
    assert_eq!(path.first().map(|p| p.as_path()), Some(std::path::Path::new(".")));
}
