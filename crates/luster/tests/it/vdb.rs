//! OpenVDB volumes end to end: the example plume loads and renders, and
//! every bad `<VdbFile>` (a missing, truncated, foreign or oversized file; a
//! grid that is absent, not a float grid, empty, too large, turned, or holds
//! NaN) and bad medium coefficient stops `luster render` with exit code 2 and
//! one line naming the scene, the element and the VDB file, never a panic.
//!
//! The grids come from `crates/render/tests-data/grids.vdb`, written by
//! `tools/make_vdb.py`, which says what each holds.

use crate::common;
use common::{run_limited, Run};
use luster::render::{try_render_with, RenderOptions, Scene};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

/// Text that means a crash rather than an error message.
const CRASH_TEXT: &[&str] =
    &["panicked", "RUST_BACKTRACE", "stack overflow", "fatal runtime error", "memory allocation"];

fn grids() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../render/tests-data/grids.vdb")
}

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A 4×4 scene with one medium whose children are `volume`.
fn scene(volume: &str) -> String {
    format!(
        r#"<Scene>
  <Cameras><Camera id="1"><Position>2 4 20</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>4</NearDistance>
    <ImageResolution>4 4</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>20 20 20</AmbientLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
  <Volumes>
    {volume}
  </Volumes>
</Scene>"#
    )
}

/// Runs `luster render -q` on `xml` in a fresh folder that also holds
/// `grids.vdb` and the files of `extra` (name, bytes).
fn render(xml: &str, extra: &[(&str, Vec<u8>)]) -> (Run, tempfile::TempDir) {
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join("s.xml"), xml).expect("the scene");
    std::fs::copy(grids(), dir.path().join("grids.vdb")).expect("the test grids");
    for (name, bytes) in extra {
        std::fs::write(dir.path().join(name), bytes).expect("a test file");
    }
    let out = dir.path().join("out");
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(["render", "-q", "--threads", "2", "-o"]).arg(&out).arg(dir.path().join("s.xml"));
    (run_limited(cmd, Duration::from_secs(60)), dir)
}

/// What is wrong with how `luster` refused `volume`, or `None` when it
/// refused it as it should: exit code 2, one line naming the scene and
/// holding `words`, no crash.
fn check_refused(volume: &str, extra: &[(&str, Vec<u8>)], words: &[&str]) -> Option<String> {
    let (run, _dir) = render(&scene(volume), extra);
    let err = run.stderr.trim_end();
    let mut problems = Vec::new();
    if run.code != Some(2) {
        problems.push(format!("exit code {:?}, expected 2", run.code));
    }
    if err.lines().count() != 1 || !err.starts_with("error: ") {
        problems.push("stderr is not one \"error: \" line".to_string());
    }
    for w in std::iter::once(&"s.xml").chain(words) {
        if !err.contains(w) {
            problems.push(format!("stderr lacks {w:?}"));
        }
    }
    for crash in CRASH_TEXT {
        if err.contains(crash) {
            problems.push(format!("stderr contains {crash:?}"));
        }
    }
    (!problems.is_empty()).then(|| format!("{volume}: {}\n    stderr: {err}", problems.join("; ")))
}

/// A volume's children, the files it needs beside `grids.vdb`, and the
/// words its error must hold.
type Case<'a> = (String, Vec<(&'a str, Vec<u8>)>, Vec<&'a str>);

/// Bytes that are not a VDB file: a fixed pseudo-random sequence.
fn noise(n: usize) -> Vec<u8> {
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 32) as u8
        })
        .collect()
}

#[test]
fn bad_vdb_files_and_grids_are_refused_in_one_line() {
    let at = "Volume[id=smoke]/VdbFile";
    let with =
        |file: &str, grids: &str| format!("<Volume id=\"smoke\"><VdbFile>{file}</VdbFile>{grids}</Volume>");
    let grid = |name: &str| with("grids.vdb", &format!("<DensityGrid>{name}</DensityGrid>"));
    let truncated = std::fs::read(grids()).expect("the test grids")[..5000].to_vec();
    let cases: Vec<Case> = vec![
        (with("no_such.vdb", ""), vec![], vec![at, "cannot read VDB file", "no_such.vdb", "no such file"]),
        (with("cut.vdb", ""), vec![("cut.vdb", truncated)], vec![at, "cut.vdb", "ends early"]),
        (
            with("noise.vdb", ""),
            vec![("noise.vdb", noise(4096))],
            vec![at, "noise.vdb", "not an OpenVDB file"],
        ),
        (with(".", ""), vec![], vec![at, "cannot read VDB file", "folder"]),
        (grid("smoke"), vec![], vec![at, "grids.vdb", "no grid named \"smoke\""]),
        (
            with("grids.vdb", "<DensityGrid>few</DensityGrid><EmissionGrid>flame</EmissionGrid>"),
            vec![],
            vec![at, "grids.vdb", "no grid named \"flame\""],
        ),
        (grid("velocity"), vec![], vec![at, "grids.vdb", "grid \"velocity\" is not a float grid"]),
        (grid("double"), vec![], vec![at, "grids.vdb", "grid \"double\" is not a float grid"]),
        (grid("empty"), vec![], vec![at, "grids.vdb", "grid \"empty\" has no active voxels"]),
        (grid("huge"), vec![], vec![at, "grids.vdb", "32.1 GB", "more than the 1.1 GB allowed"]),
        (grid("rotated"), vec![], vec![at, "grids.vdb", "transform other than a scale and a translation"]),
        (grid("nan"), vec![], vec![at, "grids.vdb", "not finite"]),
        (grid("half"), vec![], vec![at, "grids.vdb", "half floats"]),
        (
            with("grids.vdb", "<DensityGrid>few</DensityGrid><EmissionGrid>shifted</EmissionGrid>"),
            vec![],
            vec![at, "different transforms"],
        ),
        (
            with("grids.vdb", "<Shader>d.lua</Shader>"),
            vec![("d.lua", b"function density(s) return 1 end".to_vec())],
            vec![at, "not both"],
        ),
        (
            "<Hypertexture id=\"h\"><VdbFile>grids.vdb</VdbFile><Material>1</Material></Hypertexture>".into(),
            vec![],
            vec!["Hypertexture[id=h]/VdbFile", "for media"],
        ),
    ];
    let failures: Vec<String> =
        cases.iter().filter_map(|(volume, extra, words)| check_refused(volume, extra, words)).collect();
    assert!(
        failures.is_empty(),
        "{} of {} cases misbehaved:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
}

#[test]
fn a_vdb_file_larger_than_accepted_is_refused_unread() {
    // A sparse file: its size is past the limit, its blocks are not on disk.
    let dir = tempfile::tempdir().expect("a temporary folder");
    let big = std::fs::File::create(dir.path().join("big.vdb")).expect("a file");
    big.set_len((1 << 30) + 1).expect("a sparse file");
    let volume =
        format!("<Volume id=\"smoke\"><VdbFile>{}</VdbFile></Volume>", dir.path().join("big.vdb").display());
    let failure =
        check_refused(&volume, &[], &["Volume[id=smoke]/VdbFile", "big.vdb", "more than the 1073741824"]);
    assert!(failure.is_none(), "{}", failure.unwrap_or_default());
}

#[test]
fn negative_coefficients_and_anisotropy_out_of_range_are_refused() {
    let ball = "<Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere>";
    let mut failures = Vec::new();
    for (child, words) in [
        ("<Scattering>1 -0.5 1</Scattering>", ["Volume[id=v]/Scattering", "finite and ≥ 0"]),
        ("<Emission>0 0 -2</Emission>", ["Volume[id=v]/Emission", "finite and ≥ 0"]),
        ("<Absorption>-1 0 0</Absorption>", ["Volume[id=v]/Absorption", "finite and ≥ 0"]),
        ("<Anisotropy>1</Anisotropy>", ["Volume[id=v]/Anisotropy", "between -0.99 and 0.99"]),
        ("<Anisotropy>-1.5</Anisotropy>", ["Volume[id=v]/Anisotropy", "between -0.99 and 0.99"]),
    ] {
        failures.extend(check_refused(&format!("<Volume id=\"v\">{ball}{child}</Volume>"), &[], &words));
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn negative_values_are_empty_and_the_scene_renders() {
    // `few` holds a voxel of −3 beside its positive ones.
    let volume = "<Volume id=\"smoke\"><VdbFile>grids.vdb</VdbFile><DensityGrid>few</DensityGrid>\
                  <EmissionGrid>glow</EmissionGrid><Emission>1 0.5 0.2</Emission></Volume>";
    let (run, dir) = render(&scene(volume), &[]);
    assert_eq!(run.code, Some(0), "stderr: {}", run.stderr);
    assert!(dir.path().join("out/a.png").is_file());
}

#[test]
fn the_plume_example_loads_and_renders() {
    let path = repo().join("examples/scenes/smoke_vdb.xml");
    let mut desc = luster::scene::load(&path).expect("the example loads");
    let v = &desc.volumes[0];
    let f = v.vdb.as_ref().expect("a VdbFile");
    assert_eq!((f.density_grid.as_str(), f.emission_grid.as_deref()), ("density", Some("temperature")));
    assert!(v.bound.is_none());
    desc.cameras[0].resolution = (24, 24);
    let scene = Scene::build(&desc).expect("the example builds");
    let m = &scene.volumes.media[0];
    // Active voxels (8, 1, 8)–(39, 63, 37) of 1/32 unit, one more on each side.
    let g = m.density_grid().expect("a density grid");
    assert_eq!(g.dims(), [34, 65, 32]);
    assert!(
        (g.bounds().min.y - 0.0).abs() < 1e-6 && (g.bounds().max.y - 2.0).abs() < 1e-6,
        "{:?}",
        g.bounds()
    );
    assert_eq!(m.step, 1.0 / 32.0);
    let opts = RenderOptions { spp: Some(2), ..RenderOptions::default() };
    let img = try_render_with(&scene, 0, &opts, &|_| {}).expect("the example renders");
    assert!(img.pixels.iter().all(|p| p.is_finite()));
}

#[test]
fn the_watch_server_watches_the_vdb_file() {
    let volume = "<Volume id=\"smoke\"><VdbFile>grids.vdb</VdbFile><DensityGrid>few</DensityGrid></Volume>";
    let dir = tempfile::tempdir().expect("a temporary folder");
    std::fs::write(dir.path().join("s.xml"), scene(volume)).expect("the scene");
    std::fs::copy(grids(), dir.path().join("grids.vdb")).expect("the test grids");
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let files = luster::watch::files::scene_files(&desc);
    let root = dir.path().canonicalize().expect("the folder");
    assert!(files.contains(&root.join("grids.vdb")), "{files:?}");
}
