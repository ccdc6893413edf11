//! The hostile-input corpus (issue #15): inputs built to hang, exhaust
//! memory, overflow the stack, panic, defeat the shader time limit or leak
//! another file's contents. Each case is written into a fresh folder (FIFOs,
//! links to `/dev/zero` and sparse files of absurd size are made at run time)
//! and `luster` runs once on it. Every case must end within [`TIMEOUT`] with
//! exit code 2, one error line that names the file at fault and says what is
//! wrong, no crash text, and nothing in the output folder.
//!
//! The cases are grouped by the class of the issue they cover; the inputs
//! that are legitimate (huge but finite coordinates) render instead, in
//! [`huge_but_finite_coordinates_render`].

mod cases;
mod cluster;
use crate::common;
mod kit;
mod shaders2;
mod terminal;

use cases::all_cases;
use common::{run_limited, Run};
use kit::{xml, Case};

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Longest a case may take; anything slower is a hang.
const TIMEOUT: Duration = Duration::from_secs(30);

/// Text that means a crash rather than an error message.
const CRASH_TEXT: &[&str] =
    &["panicked", "RUST_BACKTRACE", "stack overflow", "fatal runtime error", "memory allocation", "SIGSEGV"];

/// Runs `luster ARGS` in `dir`, killing it after [`TIMEOUT`].
fn luster(args: &[String], dir: &Path) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(args).current_dir(dir);
    run_limited(cmd, TIMEOUT)
}

/// Every file under `dir`, relative to it.
fn entries(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| rd.flatten().map(|e| PathBuf::from(e.file_name())).collect())
        .unwrap_or_default();
    out.sort();
    out
}

/// What is wrong with one case, or `None` when it behaved.
fn check(case: &Case) -> Option<String> {
    let root = tempfile::tempdir().expect("a temporary folder");
    case.materialize(root.path());
    let out = root.path().join("out");
    std::fs::create_dir(&out).expect("the output folder");
    let args: Vec<String> = case.args.iter().map(|a| a.replace("{out}", "out")).collect();
    let run = luster(&args, root.path());
    let err = run.stderr.trim_end();
    let mut problems = Vec::new();
    match run.code {
        Some(2) => {}
        None => problems.push(format!("did not finish within {TIMEOUT:?} (or was killed by a signal)")),
        Some(c) => problems.push(format!("exit code {c}, expected 2")),
    }
    if !case.multiline && err.lines().count() != 1 {
        problems.push(format!("stderr has {} lines, expected one error line", err.lines().count()));
    }
    if !err.starts_with("error: ") {
        problems.push("stderr does not start with \"error: \"".to_string());
    }
    for word in &case.expect {
        if !err.contains(word) {
            problems.push(format!("stderr lacks {word:?}"));
        }
    }
    for word in case.absent.iter().chain(CRASH_TEXT) {
        if err.contains(word) {
            problems.push(format!("stderr contains {word:?}"));
        }
    }
    let left = entries(&out);
    if !left.is_empty() {
        problems.push(format!("files left in the output folder: {left:?}"));
    }
    let shown: String = err.chars().take(400).collect();
    (!problems.is_empty()).then(|| format!("{}: {}\n    stderr: {shown}", case.name, problems.join("; ")))
}

#[test]
fn hostile_inputs_are_refused_cleanly() {
    let cases = all_cases();
    assert!(cases.len() >= 100, "the corpus has only {} cases", cases.len());
    let failures = kit::check_two_at_a_time(&cases, check);
    assert!(
        failures.is_empty(),
        "{} of {} hostile cases misbehaved:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// Huge but finite coordinates are legitimate: they render (and must not
/// push the BVH builder's leaf indices out of range).
#[test]
fn huge_but_finite_coordinates_render() {
    let far_mesh = xml("<Mesh id=\"1\"><Material>1</Material><Faces>1 2 3 1 2 4</Faces></Mesh>", "")
        .replace("0 1 -3</VertexData>", "0 1 -3 1e30 1e30 -1e30</VertexData>");
    let cases = [
        ("m.obj", "v 0 0 -3\nv 1e9 0 -3\nv 0 1e9 -3\nv 1 1 -3\nf 1 2 3\nf 1 3 4\nf 2 3 4\n".to_string()),
        ("s.xml", far_mesh),
        ("t.obj", "v -1.7e38 0 -3\nv 1.7e38 0 -3\nv 0 1 -3\nv 0 -1.7e38 -4\nv 0 1.7e38 -4\nv 1 0 -4\nf 1 2 3\nf 4 5 6\nf 1 5 6\n".to_string()),
    ];
    for (name, text) in cases {
        let root = tempfile::tempdir().expect("a temporary folder");
        std::fs::write(root.path().join(name), text).expect("the scene");
        let args: Vec<String> =
            ["render", "-q", "--threads", "2", "-o", "out", name].iter().map(|a| a.to_string()).collect();
        let run = luster(&args, root.path());
        assert_eq!(run.code, Some(0), "{name} should render; stderr: {}", run.stderr);
        assert_eq!(entries(&root.path().join("out")).len(), 1, "{name}: one image expected");
    }
}

/// A symbolic link loop under `luster suite` ends (each folder is walked once).
#[test]
fn suite_survives_a_symlink_loop() {
    let root = tempfile::tempdir().expect("a temporary folder");
    let xml_dir = root.path().join("hw1").join("xml");
    std::fs::create_dir_all(&xml_dir).expect("folders");
    std::fs::write(xml_dir.join("s.xml"), xml("", "")).expect("a scene");
    let expected = root.path().join("hw1").join("expected");
    std::fs::create_dir_all(&expected).expect("folders");
    image::RgbImage::new(8, 8).save(expected.join("out.png")).expect("an expected image");
    // A FIFO among the scenes must not block the suite either.
    let fifo = xml_dir.join("pipe.xml");
    assert!(Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
    std::os::unix::fs::symlink("..", xml_dir.join("loop")).expect("a link");
    std::os::unix::fs::symlink("../xml", xml_dir.join("loop2")).expect("a link");
    let args: Vec<String> =
        ["suite", "--threads", "1", "-o", "out", "."].iter().map(|a| a.to_string()).collect();
    let run = luster(&args, root.path());
    assert!(run.code.is_some(), "suite did not finish within {TIMEOUT:?}");
    for crash in CRASH_TEXT {
        assert!(!run.stderr.contains(crash), "suite crashed: {}", run.stderr);
    }
    let rendered = std::fs::read_dir(root.path().join("out")).map(|rd| rd.count()).unwrap_or(0);
    assert!(rendered >= 1, "the one scene should be rendered once; stderr: {}", run.stderr);
}

/// A legal film too large for the memory the process may use (`ulimit -v`)
/// is refused up front with a sentence, not by an allocation abort midway.
#[test]
fn a_film_beyond_the_memory_limit_is_refused_up_front() {
    use std::os::unix::process::CommandExt;
    let root = tempfile::tempdir().expect("a temporary folder");
    let scene = xml("", "").replace("<ImageResolution>8 8", "<ImageResolution>32768 4096");
    std::fs::write(root.path().join("s.xml"), scene).expect("the scene");
    std::fs::create_dir(root.path().join("out")).expect("the output folder");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(["render", "-q", "--threads", "2", "-o", "out", "s.xml"]).current_dir(root.path());
    // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            let limit = libc::rlimit { rlim_cur: 2 << 30, rlim_max: 2 << 30 };
            if libc::setrlimit(libc::RLIMIT_AS, &limit) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
    let run = run_limited(cmd, TIMEOUT);
    let err = run.stderr.trim_end();
    assert_eq!(run.code, Some(2), "stderr: {err}");
    assert_eq!(err.lines().count(), 1, "one error line expected: {err}");
    for word in ["error: ", "s.xml", "32768x4096", "memory"] {
        assert!(err.contains(word), "the error lacks {word:?}: {err}");
    }
    for crash in CRASH_TEXT {
        assert!(!err.contains(crash), "crashed: {err}");
    }
    assert!(entries(&root.path().join("out")).is_empty());
}

/// A model whose file name holds control characters renders to an image
/// named without them.
#[test]
fn a_model_named_with_control_characters_gets_a_clean_image_name() {
    let root = tempfile::tempdir().expect("a temporary folder");
    let name = "m\nx\u{1b}[2J.obj";
    std::fs::write(root.path().join(name), "v 0 0 -3\nv 1 0 -3\nv 0 1 -3\nf 1 2 3\n").expect("the model");
    let args: Vec<String> = ["render", "-q", "--threads", "2", "--size", "8x8", "-o", "out", name]
        .iter()
        .map(|a| a.to_string())
        .collect();
    let run = luster(&args, root.path());
    assert_eq!(run.code, Some(0), "stderr: {}", run.stderr);
    assert_eq!(entries(&root.path().join("out")), vec![PathBuf::from("m_x_[2J.png")]);
}
