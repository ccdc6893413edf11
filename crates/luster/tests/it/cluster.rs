//! Split renders from the command line: `luster render --part K/N` then
//! `luster merge` must write exactly the bytes of a single `luster render`
//! (PNG, EXR and the EXR's tone-mapped PNGs); a part killed mid-way and run
//! again with `--resume` continues from its checkpoint to the same bytes;
//! bad parts and bad `--part` values are one sentence and exit code 2, with
//! no image written.
//!
//! One split runs under `--display srgb`, and one scene has a `<Display>`: the
//! display transform travels with the parts.
//!
//! The scenes are multi-sample with a lens, so every pixel takes random
//! samples: only a render that is truly deterministic per pixel can merge to
//! the same bytes.

use crate::common;

use common::run_limited;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const LIMIT: Duration = Duration::from_secs(120);

fn scene(name: &str, size: (u32, u32), samples: u32, light: f32) -> String {
    scene_shown(name, size, samples, light, "")
}

fn scene_shown(name: &str, size: (u32, u32), samples: u32, light: f32, display: &str) -> String {
    let (w, h) = size;
    format!(
        r#"<Scene>
  {display}
  <BackgroundColor>10 20 30</BackgroundColor>
  <Cameras>
    <Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
      <NearPlane>-1 1 -0.75 0.75</NearPlane><NearDistance>2</NearDistance>
      <ImageResolution>{w} {h}</ImageResolution><NumSamples>{samples}</NumSamples>
      <ApertureSize>0.2</ApertureSize><FocusDistance>4</FocusDistance>
      <ImageName>{name}.png</ImageName></Camera>
    <Camera id="2"><Position>1 0 5</Position><Gaze>-0.2 0 -1</Gaze><Up>0 1 0</Up>
      <NearPlane>-1 1 -1 1</NearPlane><NearDistance>2</NearDistance>
      <ImageResolution>{h} {h}</ImageResolution><NumSamples>{samples}</NumSamples>
      <ImageName>{name}_hdr.exr</ImageName>
      <Tonemap><TMO>Photographic</TMO><TMOOptions>0.18 1</TMOOptions><Saturation>1.0</Saturation><Gamma>2.2</Gamma></Tonemap>
      <Tonemap><TMO>ACES</TMO><TMOOptions>0.3 0</TMOOptions><Saturation>0.8</Saturation><Gamma>sRGB</Gamma></Tonemap>
    </Camera>
  </Cameras>
  <Lights><AmbientLight>20 20 20</AmbientLight>
    <PointLight id="1"><Position>3 3 5</Position><Intensity>{light} {light} {light}</Intensity></PointLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance>
    <DiffuseReflectance>0.8 0.5 0.3</DiffuseReflectance><SpecularReflectance>0.5 0.5 0.5</SpecularReflectance>
    <PhongExponent>20</PhongExponent></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1.5</Radius></Sphere></Objects>
</Scene>"#
    )
}

fn luster() -> Command {
    Command::new(env!("CARGO_BIN_EXE_luster"))
}

fn ok(cmd: Command) {
    let what = format!("{cmd:?}");
    let run = run_limited(cmd, LIMIT);
    assert_eq!(run.code, Some(0), "{what} failed: {}", run.stderr);
}

fn render(scenes: &[PathBuf], out: &Path, extra: &[&str]) -> Command {
    let mut c = luster();
    c.arg("render").arg("-q").arg("-o").arg(out).args(extra).args(scenes);
    c
}

fn merge(out: &Path) -> common::Run {
    let mut c = luster();
    c.arg("merge").arg(out);
    run_limited(c, LIMIT)
}

/// The image files (not part files) under `dir`, by name.
fn images(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "png" || e == "exr"))
        .map(|p| (p.file_name().unwrap().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()))
        .collect();
    v.sort();
    v
}

fn assert_same_images(single: &Path, merged: &Path) {
    let (a, b) = (images(single), images(merged));
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|(n, _)| n.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    assert!(a.len() >= 3, "the single render wrote {:?}", names(&a));
    for ((n, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{n}: the merged file differs from the single render's");
    }
}

#[test]
fn parts_merge_to_the_bytes_of_a_single_render() {
    let filmic = scene_shown("b", (37, 50), 3, 6e5, "<Display>filmic</Display>");
    let dir = common::folder(&[("a.xml", &scene("a", (70, 45), 4, 4e5)), ("b.xml", &filmic)]);
    let d = dir.path();
    let one = vec![d.join("a.xml")];
    let both = vec![d.join("a.xml"), d.join("b.xml")];
    // 2 images in 3 parts: every image split by tiles. 4 images in 2 parts:
    // whole images per part.
    for (scenes, n, tag, extra) in [(&one, 3, "tiles", &["--display", "srgb"][..]), (&both, 2, "images", &[])]
    {
        let single = d.join(format!("single-{tag}"));
        let parts = d.join(format!("parts-{tag}"));
        ok(render(scenes, &single, extra));
        for k in 1..=n {
            let part = format!("{k}/{n}");
            ok(render(scenes, &parts, &[&["--part", part.as_str()][..], extra].concat()));
        }
        let m = merge(&parts);
        assert_eq!(m.code, Some(0), "{}", m.stderr);
        assert_same_images(&single, &parts);
    }
    // The Slurm scripts of the last split: one array task per part.
    let mut c = luster();
    c.arg("slurm")
        .arg("-o")
        .arg(d.join("slurm"))
        .args(["--tasks", "3", "--spp", "2", "--shader-timeout", "1.5", "--display", "aces"])
        .arg("--shader-lib")
        .arg(d)
        .args(&both);
    ok(c);
    let array = std::fs::read_to_string(d.join("slurm/luster.sbatch")).unwrap();
    for want in [
        "#SBATCH --array=1-3",
        "#SBATCH --requeue",
        "--part \"$SLURM_ARRAY_TASK_ID/3\" --resume",
        "'--spp' '2'",
        "'--shader-timeout' '1.5'",
        "'--display' 'aces'",
    ] {
        assert!(array.contains(want), "{want} missing from\n{array}");
    }
    assert!(array.contains(&format!("'{}'", d.join("b.xml").display())), "{array}");
    let lib = d.canonicalize().unwrap();
    assert!(array.contains(&format!("'--shader-lib' '{}'", lib.display())), "{array}");
    let merge = std::fs::read_to_string(d.join("slurm/luster-merge.sbatch")).unwrap();
    assert!(merge.contains(&format!("merge '{}'", d.join("slurm").display())), "{merge}");
}

fn assert_refused(run: &common::Run, says: &str, out: &Path) {
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    let lines: Vec<&str> = run.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert!(lines.first().is_some_and(|l| l.starts_with("error: ") && l.contains(says)), "{}", run.stderr);
    assert!(!run.stderr.contains("panicked"), "{}", run.stderr);
    assert!(images(out).is_empty(), "an image was written despite: {}", run.stderr);
}

#[test]
fn bad_parts_are_refused_in_one_sentence_and_write_nothing() {
    let dir =
        common::folder(&[("a.xml", &scene("a", (40, 40), 2, 4e5)), ("c.xml", &scene("a", (40, 40), 2, 5e5))]);
    let d = dir.path();
    let (a, c) = (vec![d.join("a.xml")], vec![d.join("c.xml")]);
    let out = d.join("out");
    for bad in ["5/4", "0/0", "0/3", "two/3"] {
        let run = run_limited(render(&a, &out, &["--part", bad]), LIMIT);
        assert_eq!(run.code, Some(2), "--part {bad}: {}", run.stderr);
        assert!(run.stderr.contains(bad) && !out.exists(), "--part {bad}: {}", run.stderr);
    }
    let fresh = |name: &str| {
        let p = d.join(name);
        for k in 1..=3 {
            ok(render(&a, &p, &["--part", &format!("{k}/3")]));
        }
        p
    };
    let part = |dir: &Path, k: u32| dir.join(format!("a.png.part-{k}-of-3"));

    let missing = fresh("missing");
    std::fs::remove_file(part(&missing, 2)).unwrap();
    assert_refused(&merge(&missing), "a.png.part-2-of-3 is missing", &missing);

    let truncated = fresh("truncated");
    let bytes = std::fs::read(part(&truncated, 3)).unwrap();
    std::fs::write(part(&truncated, 3), &bytes[..bytes.len() - 100]).unwrap();
    assert_refused(&merge(&truncated), "truncated or corrupt", &truncated);

    let corrupt = fresh("corrupt");
    let mut bytes = std::fs::read(part(&corrupt, 1)).unwrap();
    let mid = bytes.len() / 2;
    bytes[mid] ^= 1;
    std::fs::write(part(&corrupt, 1), &bytes).unwrap();
    assert_refused(&merge(&corrupt), "truncated or corrupt", &corrupt);

    // Part 1 of another scene that writes the same image name.
    let mixed = fresh("mixed");
    ok(render(&c, &mixed, &["--part", "1/3"]));
    assert_refused(&merge(&mixed), "come from different renders", &mixed);

    // The same scene with other options, or split in another number of parts.
    let options = fresh("options");
    ok(render(&a, &options, &["--part", "2/3", "--seed", "7"]));
    assert_refused(&merge(&options), "come from different renders", &options);
    let other_n = fresh("other-n");
    ok(render(&a, &other_n, &["--part", "1/2"]));
    assert_refused(&merge(&other_n), "come from different renders", &other_n);

    // A part copied under another part's name.
    let duplicated = fresh("duplicated");
    std::fs::copy(part(&duplicated, 1), part(&duplicated, 2)).unwrap();
    assert_refused(&merge(&duplicated), "not what its name says", &duplicated);

    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    assert_refused(&merge(&empty), "no part files", &empty);
}

#[test]
fn a_killed_part_resumes_from_its_checkpoint_to_the_same_bytes() {
    let dir = common::folder(&[("k.xml", &scene("k", (160, 120), 300, 4e5))]);
    let d = dir.path();
    let s = vec![d.join("k.xml")];
    let parts = d.join("parts");
    let args = ["--part", "1/1", "--resume", "--checkpoint", "0", "--threads", "1"];
    let checkpoint = parts.join("k.png.part-1-of-1.checkpoint");
    let mut child = render(&s, &parts, &args).stdout(std::process::Stdio::null()).spawn().unwrap();
    // 160×120 is 10×8 tiles; 16 tiles a chunk on one thread.
    let start = Instant::now();
    while !checkpoint.exists() {
        assert!(child.try_wait().unwrap().is_none(), "the part ended before writing a checkpoint");
        assert!(start.elapsed() < LIMIT, "no checkpoint after {LIMIT:?}");
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        !parts.join("k.png.part-1-of-1").exists(),
        "the first camera's part finished before it was killed: make the test scene heavier"
    );

    let status =
        Command::new(env!("CARGO_BIN_EXE_luster")).arg("slurm").arg("status").arg(&parts).output().unwrap();
    let status = String::from_utf8_lossy(&status.stdout);
    assert!(
        status.contains("0 of 2 part files finished")
            && status.contains("k.png in progress")
            && status.contains("of 80 tiles checkpointed"),
        "{status}"
    );
    // Not quiet, to read how many tiles came from the checkpoint.
    let out = Command::new(env!("CARGO_BIN_EXE_luster"))
        .arg("render")
        .arg("-o")
        .arg(&parts)
        .args(args)
        .args(&s)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(said.contains("resumed from a checkpoint"), "the second run started over:\n{said}");
    assert!(!checkpoint.exists(), "the finished part leaves no checkpoint");

    let single = d.join("single");
    ok(render(&s, &single, &["--threads", "1"]));
    let m = merge(&parts);
    assert_eq!(m.code, Some(0), "{}", m.stderr);
    assert_same_images(&single, &parts);
}
