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
//!
//! The Slurm scripts are run too, by bash, with paths a shell would act on
//! and the luster binary replaced by a stub that records its arguments:
//! nothing but the intended words may reach it, and values that sbatch reads
//! itself are refused when it would misread them.

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

/// `luster render`, with the scenes after `--` as the Slurm script gives them.
fn render(scenes: &[PathBuf], out: &Path, extra: &[&str]) -> Command {
    let mut c = luster();
    c.arg("render").arg("-q").arg("-o").arg(out).args(extra).arg("--").args(scenes);
    c
}

/// `luster merge -- OUT`, as the Slurm script runs it.
fn merge(out: &Path) -> common::Run {
    let mut c = luster();
    c.arg("merge").arg("--").arg(out);
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
    assert!(merge.contains(&format!("merge -- '{}'", d.join("slurm").display())), "{merge}");
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
    // 160×120 is 20×15 tiles of 8 pixels; 16 tiles a chunk on one thread.
    let tiles = luster::render::tile_origins(160, 120).len();
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
            && status.contains(&format!("of {tiles} tiles checkpointed")),
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

/// A file name with everything a shell acts on: substitutions, separators,
/// quotes, globs, white space and a leading `-`.
const SHELLY: &str = "-n x $(touch MARK) `touch MARK`; touch MARK & '\"' * ? [a] |<>";

/// The words each run of `stub` recorded, one run a line.
fn recorded(log: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(log).unwrap_or_default();
    text.lines().map(|l| l.split('\0').filter(|w| !w.is_empty()).map(String::from).collect()).collect()
}

/// Writes an executable shell script that appends its arguments to `$LOG`
/// (NUL-separated, one run a line) and prints `say`.
fn stub(path: &Path, say: &str) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(path, format!("#!/bin/sh\n{{ printf '%s\\0' \"$@\"; echo; }} >> \"$LOG\"\necho {say}\n"))
        .unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

fn bash(script: &str, dir: &Path, log: &Path, path: Option<&Path>) -> std::process::Output {
    let mut c = Command::new("bash");
    c.arg("-c").arg(script).current_dir(dir).env("LOG", log).env("SLURM_ARRAY_TASK_ID", "1");
    if let Some(p) = path {
        c.env("PATH", format!("{}:{}", p.display(), std::env::var("PATH").unwrap_or_default()));
    }
    c.output().unwrap()
}

#[test]
fn generated_scripts_run_exactly_the_intended_words() {
    let root = tempfile::tempdir().unwrap();
    let d = &root.path().canonicalize().unwrap();
    // The binary too: the scripts run the path of the binary that wrote them.
    let bin_dir = d.join(format!("bin {SHELLY}"));
    std::fs::create_dir(&bin_dir).unwrap();
    let bin = bin_dir.join("luster");
    std::fs::copy(env!("CARGO_BIN_EXE_luster"), &bin).unwrap();
    let scenes: Vec<PathBuf> =
        [format!("{SHELLY}.xml"), "$(touch MARK).json".to_string(), "it's.xml".to_string()]
            .iter()
            .map(|n| d.join(n))
            .collect();
    for s in &scenes {
        std::fs::write(s, "<Scene/>").unwrap();
    }
    let lib = d.join(format!("lib {SHELLY}"));
    std::fs::create_dir(&lib).unwrap();
    // No white space, quote, backslash, # or % (sbatch reads the log path itself).
    let out = d.join("out;$(touch${IFS}MARK)`touch${IFS}MARK`*?[a]|&<>-n");
    let made = Command::new(&bin)
        .current_dir(d)
        .arg("slurm")
        .arg("-o")
        .arg(&out)
        .args(["--tasks", "3", "--cpus-per-task", "2", "--partition", "short,long", "--time", "1-00:30"])
        .args(["--spp", "2", "--seed", "5", "--shader-lib"])
        .arg(&lib)
        .args(&scenes)
        .output()
        .unwrap();
    assert!(made.status.success(), "{}", String::from_utf8_lossy(&made.stderr));
    let said = String::from_utf8(made.stdout).unwrap();
    let (array, merge_script) = (out.join("luster.sbatch"), out.join("luster-merge.sbatch"));
    let quote = |p: &Path| luster::cluster::slurm::quote(p.to_str().unwrap());
    assert!(said.contains(&format!("wrote {} and {}\n", quote(&array), quote(&merge_script))), "{said}");

    // The binary becomes a stub, and both scripts run.
    std::fs::remove_file(&bin).unwrap();
    stub(&bin, "rendered");
    let log = d.join("argv");
    for script in [&array, &merge_script] {
        let ran = bash(&format!("bash {}", quote(script)), d, &log, None);
        assert!(ran.status.success(), "{}", String::from_utf8_lossy(&ran.stderr));
    }
    let words = |v: &[&str]| v.iter().map(|w| w.to_string()).collect::<Vec<String>>();
    let path = |p: &Path| p.to_str().unwrap().to_string();
    let mut render = words(&["render", "--part", "1/3", "--resume", "--threads", "2", "-o"]);
    render.push(path(&out));
    render.extend(words(&["--spp", "2", "--seed", "5", "--shader-lib"]));
    render.push(path(&lib));
    render.extend(words(&["--checkpoint", "60", "--"]));
    render.extend(scenes.iter().map(|s| path(s)));
    let merged = vec!["merge".to_string(), "--".to_string(), path(&out)];
    assert_eq!(recorded(&log), vec![render, merged]);
    assert!(!d.join("MARK").exists(), "a script ran a command from a file name");

    // The printed submit command, pasted into a shell, runs sbatch on the two scripts.
    let hint = said.lines().find_map(|l| l.strip_prefix("submit with: ")).expect("a submit command");
    let stubs = d.join("stubs");
    std::fs::create_dir(&stubs).unwrap();
    stub(&stubs.join("sbatch"), "42");
    let sbatch_log = d.join("sbatch-argv");
    let ran = bash(hint, d, &sbatch_log, Some(&stubs));
    assert!(ran.status.success(), "{hint}: {}", String::from_utf8_lossy(&ran.stderr));
    assert_eq!(
        recorded(&sbatch_log),
        vec![
            vec!["--parsable".to_string(), path(&array)],
            vec!["--dependency=afterok:42".to_string(), path(&merge_script)]
        ]
    );
    assert!(!d.join("MARK").exists(), "the submit command ran a command from a file name");
}

#[test]
fn values_sbatch_reads_itself_are_refused() {
    let dir = common::folder(&[("s.xml", "<Scene/>"), ("a\nb.xml", "<Scene/>")]);
    let d = dir.path();
    let cases: [(&[&str], &str, &[&str]); 9] = [
        (&["--partition", "short\ntouch MARK"], "out", &["the partition", "short\\ntouch MARK"]),
        (&["--partition", "short --wrap=id"], "out", &["the partition", "not a Slurm partition name"]),
        (&["--time", "1:00\n#SBATCH --wrap=id"], "out", &["the time limit", "Slurm's formats"]),
        (&["--time", "1h"], "out", &["the time limit"]),
        (&[], "o\ntouch MARK", &["the output folder", "control character"]),
        (&[], "my renders", &["the output folder", "white space"]),
        (&[], "o#1", &["the output folder", "a #"]),
        (&[], "o%j", &["the output folder", "a %"]),
        (&["a\nb.xml"], "out", &["the scene path", "a\\nb.xml", "control character"]),
    ];
    for (extra, out, says) in cases {
        let mut c = luster();
        c.current_dir(d).args(["slurm", "--tasks", "2", "-o", out]).args(extra).arg("s.xml");
        let run = run_limited(c, LIMIT);
        let what = format!("{extra:?} -o {out:?}");
        assert_eq!(run.code, Some(2), "{what}: {}", run.stderr);
        let err = run.stderr.trim_end();
        assert!(err.starts_with("error: ") && err.lines().count() == 1, "{what}: {err}");
        for word in says {
            assert!(err.contains(word), "{what}: {err} lacks {word}");
        }
        assert!(!d.join(out).join("luster.sbatch").exists(), "{what}: a script was written");
    }
}
