//! Hostile part files and checkpoints of split renders: files named like a
//! part or a checkpoint that are FIFOs or links to `/dev/zero`, sparse files
//! of gigabytes (alone or behind a valid header), checksum-valid headers
//! that claim 2^32-1 images, tiles or a 4 GiB name, and truncated files.
//!
//! `luster merge` and `luster render --part K/N --resume` must refuse each
//! within [`TIMEOUT`]: exit code 2, one error line naming the file, and no
//! image or part file written. `luster slurm status`, a report, must say in
//! a line what is wrong with the file and end just as quickly.

use super::kit::{xml, Case, Content};
use super::{CRASH_TEXT, TIMEOUT};
use luster::cluster::partfile::PartFile;
use luster::math::Vec3;
use luster::tonemap::Display;

use crate::common::{run_limited, Run};
use std::path::Path;
use std::process::Command;

const GIB: u64 = 1 << 30;

/// Runs `luster ARGS` in `dir`, killing it after [`TIMEOUT`].
fn run(args: &[&str], dir: &Path) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(args).current_dir(dir);
    run_limited(cmd, TIMEOUT)
}

/// A valid finished part 1 of 1 of an 8×8 image `out.png` (one tile), one
/// of `images` images.
fn part(images: u32) -> PartFile {
    PartFile {
        finished: true,
        job: [7; 32],
        n: 1,
        k: 1,
        images,
        image: 0,
        width: 8,
        height: 8,
        image_name: "out.png".into(),
        tonemaps: Vec::new(),
        display: Display::Course,
        tiles: vec![0],
        pixels: vec![Vec3::new(0.5, 0.25, 1.0); 64],
        passes: Default::default(),
        aov: Vec::new(),
    }
}

/// Where the header's fields are.
const N_AT: usize = 8 + 4 + 4 + 32;
const IMAGES_AT: usize = N_AT + 8;
const NAME_AT: usize = N_AT + 7 * 4;
/// The tile count of [`part`]'s encoding (its name is 7 bytes, no tone mapping).
const TILES_AT: usize = NAME_AT + 4 + 7 + 4 + 1;

/// `bytes` with the u32 at `at` set to `v` and the checksum made to match.
fn forged(bytes: &[u8], at: usize, v: u32) -> Vec<u8> {
    let mut b = bytes[..bytes.len() - 4].to_vec();
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
    let crc = crc32fast::hash(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// One case: the files, a command, and what must come of it.
struct Hostile {
    case: Case,
    /// Files written with these bytes and then made this long (sparse).
    padded: Vec<(&'static str, Vec<u8>, u64)>,
    /// The exit code expected: 2, or 0 for the progress report.
    code: i32,
    /// Words stdout must hold (the progress report's lines).
    stdout: Vec<&'static str>,
    /// A file that must not exist afterwards (the part a refused render would write).
    unwritten: Option<&'static str>,
}

fn with(name: &'static str, args: &[&str], expect: &[&'static str]) -> Hostile {
    Hostile {
        case: Case {
            name,
            files: Vec::new(),
            args: args.iter().map(|a| a.to_string()).collect(),
            expect: expect.to_vec(),
            absent: Vec::new(),
            multiline: false,
        },
        padded: Vec::new(),
        code: 2,
        stdout: Vec::new(),
        unwritten: None,
    }
}

/// `luster merge out`.
fn merge(name: &'static str, expect: &[&'static str]) -> Hostile {
    with(name, &["merge", "out"], expect)
}

/// `luster render --part 1/2 --resume` of an 8×8 scene into `out`.
fn resume(name: &'static str, expect: &[&'static str]) -> Hostile {
    let mut h = with(
        name,
        &["render", "-q", "--threads", "2", "-o", "out", "--part", "1/2", "--resume", "s.xml"],
        expect,
    );
    h.case.files.push(("s.xml", Content::Bytes(xml("", "").into_bytes())));
    h.unwritten = Some("out/out.png.part-1-of-2");
    h
}

/// `luster slurm status out`, which reports rather than fails.
fn status(name: &'static str, stdout: &[&'static str]) -> Hostile {
    let mut h = with(name, &["slurm", "status", "out"], &[]);
    h.code = 0;
    h.stdout = stdout.to_vec();
    h
}

impl Hostile {
    /// Puts `content` at `path`, in place of what the case had there.
    fn file(mut self, path: &'static str, content: Content) -> Hostile {
        self.case.files.retain(|(p, _)| *p != path);
        self.case.files.push((path, content));
        self
    }
    fn bytes(self, path: &'static str, bytes: Vec<u8>) -> Hostile {
        self.file(path, Content::Bytes(bytes))
    }
    /// For a case whose own file is where the part would go.
    fn keeps_part_path(mut self) -> Hostile {
        self.unwritten = None;
        self
    }
    fn padded(mut self, path: &'static str, bytes: Vec<u8>, len: u64) -> Hostile {
        self.padded.push((path, bytes, len));
        self
    }

    /// What is wrong with the run, or `None` when it behaved.
    fn check(&self) -> Option<String> {
        let root = tempfile::tempdir().expect("a temporary folder");
        let dir = root.path();
        std::fs::create_dir(dir.join("out")).expect("the output folder");
        self.case.materialize(dir);
        for (path, bytes, len) in &self.padded {
            std::fs::write(dir.join(path), bytes).expect("a case file");
            std::fs::OpenOptions::new()
                .write(true)
                .open(dir.join(path))
                .and_then(|f| f.set_len(*len))
                .expect("a sparse file");
        }
        let args: Vec<&str> = self.case.args.iter().map(String::as_str).collect();
        let ran = run(&args, dir);
        let err = ran.stderr.trim_end();
        let mut problems = Vec::new();
        match ran.code {
            Some(c) if c == self.code => {}
            None => problems.push(format!("did not finish within {TIMEOUT:?} (or was killed by a signal)")),
            Some(c) => problems.push(format!("exit code {c}, expected {}", self.code)),
        }
        if self.code == 2 {
            if err.lines().count() != 1 || !err.starts_with("error: ") {
                problems.push("stderr is not one line starting with \"error: \"".to_string());
            }
            for word in &self.case.expect {
                if !err.contains(word) {
                    problems.push(format!("stderr lacks {word:?}"));
                }
            }
        }
        for word in &self.stdout {
            if !ran.stdout.contains(word) {
                problems.push(format!("stdout lacks {word:?}"));
            }
        }
        for word in CRASH_TEXT {
            if err.contains(word) {
                problems.push(format!("stderr contains {word:?}"));
            }
        }
        if ran.stdout.contains('\u{1b}') || err.contains('\u{1b}') {
            problems.push("an escape character reached the terminal".to_string());
        }
        let images: Vec<String> = std::fs::read_dir(dir.join("out"))
            .map(|rd| rd.flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect())
            .unwrap_or_default();
        if images.iter().any(|n| n.ends_with(".png") || n.ends_with(".exr")) {
            problems.push(format!("an image was written: {images:?}"));
        }
        if let Some(p) = self.unwritten {
            if dir.join(p).exists() {
                problems.push(format!("{p} was written"));
            }
        }
        let shown: String = ran.stdout.chars().chain(err.chars()).take(400).collect();
        (!problems.is_empty())
            .then(|| format!("{}: {}\n    output: {shown:?}", self.case.name, problems.join("; ")))
    }
}

fn cases() -> Vec<Hostile> {
    use Content::{Fifo, Link, Sparse};
    let good = part(1).encode();
    let p = "out/out.png.part-1-of-1";
    let ckpt = "out/out.png.part-1-of-2.checkpoint";
    let mut many = part(luster::cluster::MAX_IMAGES);
    (many.n, many.k) = (luster::cluster::MAX_PARTS, 1);
    let mut truncated = good.clone();
    truncated.truncate(good.len() - 10);
    let mut unfinished = part(1);
    unfinished.finished = false;
    unfinished.tiles.clear();
    unfinished.pixels.clear();
    vec![
        merge("part FIFO", &[p, "FIFO"]).file(p, Fifo),
        merge("part link to /dev/zero", &[p, "a device"]).file(p, Link("/dev/zero")),
        merge("part of 64 GiB", &[p, "bytes, more than"]).file(p, Sparse(64 * GIB)),
        merge("part of 2 GiB behind a valid header", &[p, "header implies", "truncated or corrupt"]).padded(
            p,
            good.clone(),
            2 * GIB,
        ),
        merge("2^32-1 images", &[p, "not a usable part file"]).bytes(p, forged(&good, IMAGES_AT, u32::MAX)),
        merge("2^32-1 parts", &[p, "not a usable part file"]).bytes(p, forged(&good, N_AT, u32::MAX)),
        merge("2^32-1 tiles", &[p, "not a usable part file"]).bytes(p, forged(&good, TILES_AT, u32::MAX)),
        merge("a 4 GiB name", &[p, "not a usable part file"]).bytes(p, forged(&good, NAME_AT, u32::MAX)),
        merge("truncated part", &[p, "truncated or corrupt"]).bytes(p, truncated),
        merge("header only", &[p, "truncated or corrupt"]).bytes(p, good[..TILES_AT + 8].to_vec()),
        merge("empty part", &[p, "does not start with LUSTPART"]).bytes(p, Vec::new()),
        resume("checkpoint FIFO", &[ckpt, "FIFO"]).file(ckpt, Fifo),
        resume("checkpoint link to /dev/zero", &[ckpt, "a device"]).file(ckpt, Link("/dev/zero")),
        resume("checkpoint of 64 GiB", &[ckpt, "bytes, more than"]).file(ckpt, Sparse(64 * GIB)),
        resume("finished part FIFO", &["out/out.png.part-1-of-2", "FIFO"])
            .file("out/out.png.part-1-of-2", Fifo)
            .keeps_part_path(),
        resume("scene FIFO", &["s.xml", "FIFO"]).file("s.xml", Fifo),
        status("status: checkpoint FIFO", &["unreadable", ckpt, "FIFO"]).file(ckpt, Fifo),
        status("status: checkpoint link to /dev/zero", &["unreadable", ckpt, "a device"])
            .file(ckpt, Link("/dev/zero")),
        status("status: 2^32-1 images", &["unreadable", p, "not a usable part file"])
            .bytes(p, forged(&good, IMAGES_AT, u32::MAX)),
        status(
            "status: 2^24 images in 2^20 parts",
            &["1 of 16777216 part files finished", "more unfinished parts"],
        )
        .bytes("out/out.png.part-1-of-1048576", many.encode()),
        status("status: an escape in a name", &["unreadable", "a\\e[2J.png.part-1-of-1"])
            .bytes("out/a\u{1b}[2J.png.part-1-of-1", b"garbage".to_vec()),
        status(
            "status: a 2 GiB checkpoint behind a valid header",
            &["unreadable", "out.png.part-1-of-1.checkpoint", "header implies"],
        )
        .padded("out/out.png.part-1-of-1.checkpoint", unfinished.encode(), 2 * GIB),
    ]
}

#[test]
fn hostile_part_files_and_checkpoints_are_refused_quickly() {
    let cases = cases();
    let failures = super::kit::check_two_at_a_time(&cases, Hostile::check);
    assert!(
        failures.is_empty(),
        "{} of {} hostile part-file cases misbehaved:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

/// A checkpoint that is a regular file but not a usable one (here 2 GiB
/// behind a valid header) is set aside with a warning naming it, and the
/// part renders from the start, without reading the gigabytes.
#[test]
fn an_unusable_checkpoint_is_set_aside_quickly() {
    let root = tempfile::tempdir().expect("a temporary folder");
    let dir = root.path();
    std::fs::write(dir.join("s.xml"), xml("", "")).expect("a scene");
    std::fs::create_dir(dir.join("out")).expect("the output folder");
    let ckpt = dir.join("out/out.png.part-1-of-2.checkpoint");
    let mut stale = part(1);
    (stale.n, stale.finished) = (2, false);
    std::fs::write(&ckpt, stale.encode()).expect("a checkpoint");
    std::fs::OpenOptions::new().write(true).open(&ckpt).and_then(|f| f.set_len(2 * GIB)).expect("sparse");
    let start = std::time::Instant::now();
    let ran =
        run(&["render", "-q", "--threads", "2", "-o", "out", "--part", "1/2", "--resume", "s.xml"], dir);
    assert_eq!(ran.code, Some(0), "{}", ran.stderr);
    assert!(
        ran.stderr.starts_with("warning: ")
            && ran.stderr.contains("out.png.part-1-of-2.checkpoint")
            && ran.stderr.contains("header implies")
            && ran.stderr.contains("starting the part over"),
        "{}",
        ran.stderr
    );
    assert!(dir.join("out/out.png.part-1-of-2").is_file() && !ckpt.exists());
    assert!(start.elapsed() < TIMEOUT / 3, "took {:?}", start.elapsed());
}
