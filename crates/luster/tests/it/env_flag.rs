//! `--env FILE [--env-rotate DEG] [--env-strength S]`: an HDRI lighting any
//! scene (`luster::scene::hdri`), judged without reference images. A white
//! diffuse sphere under a constant HDRI of value `c` is `c × 255` (the film's
//! white is 255) on the sphere and exactly so around it; the strength scales
//! the image; a turned map lights the sphere as a map whose pixels were
//! turned by the test does; a course scene's own environment is replaced
//! with a warning; a model scene loses its studio lights; split renders and
//! thread counts give the same bytes; bad input is one sentence and exit
//! code 2; `luster watch` keeps the HDRI over reloads and re-renders when it
//! is saved.

use crate::common::{folder, run_limited, two_seed_mean, Run};
use luster::render::RenderedImage;
use luster::scene::hdri::Hdri;
use luster::scene::Description;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// Writes a `w × h` lat-long EXR whose texel `(x, y)` is `f(x, y)`.
fn write_exr(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) {
    let img = image::Rgb32FImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    image::DynamicImage::ImageRgb32F(img).save(path).expect("EXR written");
}

/// A unit sphere at the origin seen from +z (24×24, 30° field of view),
/// its material a white diffuse closure, path-traced with MIS; its own
/// `SphericalDirectionalLight` reads `old.exr`.
const SPHERE: &str = r#"<Scene>
  <MaxRecursionDepth>16</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams></Camera></Cameras>
  <Textures><Images><Image id="1">old.exr</Image></Images>
    <TextureMap id="1" type="shader"><Shader>m.lua</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#;

const WHITE_DIFFUSE: &str = "function material(s) return diffuse{albedo = 1} end\n";

/// A folder with the sphere scene (`s.xml`), its shader and a bright `old.exr`.
fn sphere_folder() -> tempfile::TempDir {
    let dir = folder(&[("s.xml", SPHERE), ("m.lua", WHITE_DIFFUSE)]);
    write_exr(&dir.path().join("old.exr"), 8, 4, |_, _| [7.0, 0.0, 0.0]);
    dir
}

/// `desc` lit by `map` (in the scene's folder) turned by `rotation`, scaled by `strength`.
fn with_env(desc: &Description, map: &Path, rotation: f32, strength: f32) -> Description {
    let mut d = desc.clone();
    Hdri::new(map, rotation, strength).expect("a valid HDRI").apply(&mut d);
    d
}

use crate::common::render_spp as render;

/// Pixel `i`'s centre, in [-1, 1]² (y up), of a `w`-wide square image.
fn centre(i: usize, w: usize) -> (f32, f32) {
    let x = ((i % w) as f32 + 0.5) / w as f32 * 2.0 - 1.0;
    let y = 1.0 - ((i / w) as f32 + 0.5) / w as f32 * 2.0;
    (x, y)
}

/// Where the sphere's silhouette lies, in the units of [`centre`]: the
/// camera at distance 5 sees a unit sphere at `tan(asin(1/5)) / tan(15°)`.
fn silhouette() -> f32 {
    (1.0f32 / 5.0).asin().tan() / 15f32.to_radians().tan()
}

fn luminance(p: luster::math::Vec3) -> f64 {
    f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z)
}

/// Mean luminance over `pixels` of two seeds' renders and its standard error.
fn two_seeds(a: &RenderedImage, b: &RenderedImage, pixels: &[usize]) -> (f64, f64) {
    let (la, lb): (Vec<f64>, Vec<f64>) =
        pixels.iter().map(|&i| (luminance(a.pixels[i]), luminance(b.pixels[i]))).unzip();
    two_seed_mean(&la, &lb)
}

/// The white furnace: under a constant HDRI of value 0.5 a white diffuse
/// sphere is 0.5 × 255 (within 4 standard errors measured from two seeds),
/// and every pixel that misses it is exactly that; the scene's own bright
/// red environment is gone, with a warning.
#[test]
fn a_white_sphere_under_a_constant_hdri_is_the_hdri_times_255() {
    let dir = sphere_folder();
    write_exr(&dir.path().join("grey.exr"), 16, 8, |_, _| [0.5, 0.5, 0.5]);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("loads");
    let desc = with_env(&desc, &dir.path().join("grey.exr"), 0.0, 1.0);
    assert!(desc
        .warnings
        .iter()
        .any(|w| w.message.contains("replaces the scene's SphericalDirectionalLight")));
    let (a, b) = (render(&desc, 16, 1), render(&desc, 16, 2));
    let r = silhouette();
    let on: Vec<usize> = (0..a.pixels.len())
        .filter(|&i| {
            let (x, y) = centre(i, 24);
            (x * x + y * y).sqrt() < 0.9 * r
        })
        .collect();
    let off: Vec<usize> = (0..a.pixels.len())
        .filter(|&i| {
            let (x, y) = centre(i, 24);
            (x * x + y * y).sqrt() > 1.15 * r
        })
        .collect();
    assert!(on.len() > 100 && off.len() > 100, "{} and {} pixels", on.len(), off.len());
    for &i in &off {
        assert_eq!(a.pixels[i], luster::math::Vec3::splat(127.5), "background pixel {i}");
    }
    let (mean, se) = two_seeds(&a, &b, &on);
    assert!(se < 0.01 * 127.5, "the test resolves 1%: ± {se}");
    assert!((mean - 127.5).abs() < 4.0 * se, "the sphere: {mean} ± {se}, expected 127.5");
}

/// A map with one bright region near the horizon at the image's centre
/// (Blender's +x), a dim sky elsewhere; `shift` turns its columns by that
/// many texels (what `--env-rotate` does, done to the pixels).
fn sun_map(path: &Path, shift: u32) {
    let (w, h) = (64, 32);
    write_exr(path, w, h, |x, y| {
        let x = (x + shift) % w;
        if (28..36).contains(&x) && (12..18).contains(&y) {
            [30.0, 28.0, 24.0]
        } else {
            [0.05, 0.06, 0.08]
        }
    });
}

/// Mean luminance of the left and right halves of the sphere.
fn halves(img: &RenderedImage) -> (f64, f64) {
    let r = silhouette();
    let (mut left, mut right, mut n) = (0.0, 0.0, 0.0);
    for (i, p) in img.pixels.iter().enumerate() {
        let (x, y) = centre(i, 24);
        if (x * x + y * y).sqrt() < 0.9 * r && x.abs() > 0.2 * r {
            if x < 0.0 {
                left += luminance(*p);
                n += 1.0;
            } else {
                right += luminance(*p);
            }
        }
    }
    (left / n, right / n)
}

/// `--env-rotate 0` puts the map's centre at +x (the camera's right), 180
/// at -x; a map turned 90° by `--env-rotate` lights the sphere as the map
/// whose columns the test moved a quarter turn does: the block means of
/// the two renders agree within noise (|z| < 4.5 over 16 blocks, the
/// variance from a second seed), while the unturned map differs by far.
#[test]
fn rotation_turns_the_light_counter_clockwise_seen_from_above() {
    let dir = sphere_folder();
    sun_map(&dir.path().join("sun.exr"), 0);
    sun_map(&dir.path().join("sun_turned.exr"), 16);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("loads");
    let (sun, turned) = (dir.path().join("sun.exr"), dir.path().join("sun_turned.exr"));

    let (l0, r0) = halves(&render(&with_env(&desc, &sun, 0.0, 1.0), 16, 1));
    assert!(r0 > 3.0 * l0, "rotation 0 lights the right (+x) side: left {l0}, right {r0}");
    let (l180, r180) = halves(&render(&with_env(&desc, &sun, 180.0, 1.0), 16, 1));
    assert!(l180 > 3.0 * r180, "rotation 180 lights the left (-x) side: left {l180}, right {r180}");

    let by_flag = with_env(&desc, &sun, 90.0, 1.0);
    let by_pixels = with_env(&desc, &turned, 0.0, 1.0);
    let unturned = with_env(&desc, &sun, 0.0, 1.0);
    let pair = |d: &Description| (render(d, 16, 1), render(d, 16, 2));
    let (fa, fb) = pair(&by_flag);
    let (pa, pb) = pair(&by_pixels);
    let (ua, ub) = pair(&unturned);
    let blocks: Vec<Vec<usize>> =
        (0..16).map(|k| (0..576).filter(|i| (i % 24) / 6 + 4 * ((i / 24) / 6) == k).collect()).collect();
    let z = |a: (&RenderedImage, &RenderedImage), b: (&RenderedImage, &RenderedImage)| {
        blocks
            .iter()
            .map(|px| {
                let ((m1, s1), (m2, s2)) = (two_seeds(a.0, a.1, px), two_seeds(b.0, b.1, px));
                (m1 - m2).abs() / (s1 * s1 + s2 * s2).sqrt().max(1e-9)
            })
            .fold(0.0, f64::max)
    };
    let same = z((&fa, &fb), (&pa, &pb));
    assert!(same < 4.5, "--env-rotate 90 against the turned pixels: max |z| = {same}");
    let differ = z((&ua, &ub), (&pa, &pb));
    assert!(differ > 10.0, "the test can tell the maps apart: max |z| = {differ}");
}

/// The strength scales every pixel: the same seed at strength 2.5 is 2.5
/// times the image at 1 (the density and so the samples do not change).
#[test]
fn strength_scales_the_image() {
    let dir = sphere_folder();
    sun_map(&dir.path().join("sun.exr"), 0);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("loads");
    let sun = dir.path().join("sun.exr");
    let one = render(&with_env(&desc, &sun, 30.0, 1.0), 4, 3);
    let more = render(&with_env(&desc, &sun, 30.0, 2.5), 4, 3);
    for (i, (a, b)) in one.pixels.iter().zip(&more.pixels).enumerate() {
        assert!((*b - *a * 2.5).abs().max_element() <= 1e-5 * b.max_element().max(1.0), "pixel {i}: {a} {b}");
    }
    assert!(one.pixels.iter().any(|p| p.max_element() > 10.0), "a lit image");
}

/// A UV sphere of radius 1 (convex) as OBJ text, with a white MTL material.
fn sphere_obj(dir: &Path) -> std::path::PathBuf {
    let (n, m) = (24, 12);
    let mut obj = String::from("mtllib m.mtl\nusemtl white\n");
    for j in 0..=m {
        let t = std::f32::consts::PI * j as f32 / m as f32;
        for i in 0..n {
            let p = 2.0 * std::f32::consts::PI * i as f32 / n as f32;
            obj += &format!("v {} {} {}\n", t.sin() * p.cos(), t.cos(), t.sin() * p.sin());
        }
    }
    for j in 0..m {
        for i in 0..n {
            let (a, b) = (j * n + i + 1, j * n + (i + 1) % n + 1);
            let (c, d) = (a + n, b + n);
            // Counter-clockwise seen from outside, as OBJ faces are.
            obj += &format!("f {a} {d} {c}\nf {a} {b} {d}\n");
        }
    }
    std::fs::write(dir.join("m.mtl"), "newmtl white\nKd 1 1 1\nKs 0 0 0\n").expect("MTL");
    let p = dir.join("ball.obj");
    std::fs::write(&p, obj).expect("OBJ");
    p
}

/// A model scene under `--env`: no key, fill or ambient light is left (a
/// black HDRI gives a black image), and its MTL white (Kd 1) is an albedo
/// of 1: under a constant HDRI of 0.5 the ball is 0.5 × 255 within noise.
#[test]
fn a_model_scene_is_lit_by_the_hdri_alone() {
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = sphere_obj(dir.path());
    write_exr(&dir.path().join("grey.exr"), 16, 8, |_, _| [0.5, 0.5, 0.5]);
    let view = luster::scene::obj::ModelView { width: 24, height: 24, ground: false, ..Default::default() };
    let desc = luster::scene::load_viewed(&obj, &view).expect("loads");
    let grey = dir.path().join("grey.exr");
    let dark = render(&with_env(&desc, &grey, 0.0, 0.0), 4, 1);
    assert!(dark.pixels.iter().all(|p| *p == luster::math::Vec3::ZERO), "no studio light is left");

    let lit = with_env(&desc, &grey, 0.0, 1.0);
    let (a, b) = (render(&lit, 16, 1), render(&lit, 16, 2));
    // The framing camera fits the ball's bounding sphere into 1/1.1 of the view.
    let on: Vec<usize> = (0..576)
        .filter(|&i| {
            let (x, y) = centre(i, 24);
            (x * x + y * y).sqrt() < 0.6
        })
        .collect();
    let (mean, se) = two_seeds(&a, &b, &on);
    assert!(se < 0.01 * 127.5, "the test resolves 1%: ± {se}");
    assert!((mean - 127.5).abs() < 4.0 * se, "the ball: {mean} ± {se}, expected 127.5");
    let corner = a.pixels[0];
    assert_eq!(corner, luster::math::Vec3::splat(127.5), "the background is the HDRI");
}

fn luster() -> Command {
    Command::new(env!("CARGO_BIN_EXE_luster"))
}

fn run(dir: &Path, args: &[&str]) -> Run {
    let mut c = luster();
    c.args(args).current_dir(dir);
    run_limited(c, Duration::from_secs(120))
}

/// Every file of `dir`, by name, with its bytes.
fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut v: Vec<_> = std::fs::read_dir(dir)
        .expect("a folder")
        .map(|e| {
            let e = e.expect("an entry");
            (e.file_name().to_string_lossy().into_owned(), std::fs::read(e.path()).expect("a file"))
        })
        .collect();
    v.sort();
    v
}

/// The same scene and HDRI give the same bytes on one thread, on two, and
/// split into two parts merged; the replaced environment is a warning.
#[test]
fn renders_with_an_hdri_are_deterministic_and_split_alike() {
    let dir = sphere_folder();
    sun_map(&dir.path().join("sun.exr"), 0);
    let env = ["--env", "sun.exr", "--env-rotate", "-40", "--env-strength", "0.5", "--spp", "4"];
    let one =
        run(dir.path(), &[&["render", "s.xml", "-o", "one", "-q", "--threads", "1"][..], &env].concat());
    assert_eq!(one.code, Some(0), "{}", one.stderr);
    assert!(one.stderr.contains("warning") && one.stderr.contains("--env replaces"), "{}", one.stderr);
    let two =
        run(dir.path(), &[&["render", "s.xml", "-o", "two", "-q", "--threads", "2"][..], &env].concat());
    assert_eq!(two.code, Some(0), "{}", two.stderr);
    for k in ["1/2", "2/2"] {
        let part =
            run(dir.path(), &[&["render", "s.xml", "-o", "split", "-q", "--part", k][..], &env].concat());
        assert_eq!(part.code, Some(0), "{}", part.stderr);
    }
    let merged = run(dir.path(), &["merge", "split"]);
    assert_eq!(merged.code, Some(0), "{}", merged.stderr);
    let reference = files(&dir.path().join("one"));
    assert!(!reference.is_empty());
    assert_eq!(files(&dir.path().join("two")), reference, "two threads");
    let split: Vec<_> =
        files(&dir.path().join("split")).into_iter().filter(|(n, _)| !n.contains(".part-")).collect();
    assert_eq!(split, reference, "two parts merged");
}

/// Bad input: one sentence naming the file (or the flag), exit code 2, no
/// image written, nothing of a file's contents quoted.
#[test]
fn bad_hdris_and_numbers_are_one_sentence() {
    let dir = folder(&[("s.xml", &SPHERE.replace("old.exr", "sun.exr")), ("m.lua", WHITE_DIFFUSE)]);
    sun_map(&dir.path().join("sun.exr"), 0);
    std::fs::write(dir.path().join("text.exr"), "secret words, not an image").expect("file");
    std::fs::write(dir.path().join("flat.png"), "").expect("file");
    write_exr(
        &dir.path().join("nan.exr"),
        8,
        4,
        |x, y| if (x, y) == (5, 2) { [f32::NAN; 3] } else { [1.0; 3] },
    );
    let cases: [(&[&str], &str); 8] = [
        (&["--env", "missing.exr"], "missing.exr"),
        (&["--env", "flat.png"], ".hdr"),
        (&["--env", "text.exr"], "text.exr"),
        (&["--env", "nan.exr"], "(5, 2)"),
        (&["--env", "sun.exr", "--env-strength", "-1"], "--env-strength"),
        (&["--env", "sun.exr", "--env-strength", "inf"], "--env-strength"),
        (&["--env", "sun.exr", "--env-rotate", "nan"], "--env-rotate"),
        (&["--env-rotate", "30"], "--env"),
    ];
    for (args, word) in cases {
        let r = run(dir.path(), &[&["render", "s.xml", "-o", "out", "-q"][..], args].concat());
        assert_eq!(r.code, Some(2), "{args:?}: {}", r.stderr);
        let errors: Vec<&str> = r.stderr.lines().filter(|l| l.starts_with("error")).collect();
        assert_eq!(errors.len(), 1, "{args:?}: {}", r.stderr);
        // clap names a missing flag on the line after its error.
        assert!(r.stderr.contains(word), "{args:?}: {}", r.stderr);
        assert!(!r.stderr.contains("secret") && !r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
        assert!(!dir.path().join("out/a.exr").exists(), "{args:?}: no image");
    }
    // Any aspect is accepted (as Blender does): a square map renders.
    write_exr(&dir.path().join("square.exr"), 8, 8, |_, _| [1.0; 3]);
    let r = run(dir.path(), &["render", "s.xml", "-o", "out", "-q", "--spp", "1", "--env", "square.exr"]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
}

/// `luster watch --env`: the HDRI is the background of every frame, stays
/// over a reload of the scene, and saving the HDRI re-renders.
#[test]
fn watch_keeps_the_hdri_over_reloads_and_follows_its_file() {
    use crate::watch::{events, finished, frame, start_with, until};
    // The sphere lies behind the camera: the frames show the HDRI alone.
    let scene = SPHERE
        .replace("<Center>1</Center>", "<Center>2</Center>")
        .replace("<VertexData>0 0 0</VertexData>", "<VertexData>0 0 0\n0 0 20</VertexData>");
    let scene = scene.replace("a.exr", "a.png");
    let dir = sphere_folder();
    std::fs::write(dir.path().join("s.xml"), &scene).expect("scene");
    write_exr(&dir.path().join("sky.exr"), 8, 4, |_, _| [1.0, 0.0, 0.0]);
    let w = start_with(dir.path(), "s.xml", &["--env", "sky.exr", "--spp", "1"]);
    let rx = events(&w.addr);
    let first = until(&rx, "a first frame", finished);
    assert_eq!(first["error"], serde_json::Value::Null, "{first}");
    let (n1, red, _) = frame(&w.addr);
    assert_eq!(red, [255, 0, 0], "the HDRI, not the scene's own map");

    // A reload of the scene keeps the HDRI.
    let tmp = dir.path().join("s.tmp");
    std::fs::write(&tmp, scene.replace("<FovY>30</FovY>", "<FovY>31</FovY>")).expect("scene");
    std::fs::rename(&tmp, dir.path().join("s.xml")).expect("saved");
    until(&rx, "a reloaded frame", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (n2, still, _) = frame(&w.addr);
    assert_eq!(still, [255, 0, 0], "the HDRI survives the reload");

    // Saving the HDRI is a change of the scene.
    let tmp = dir.path().join("sky.tmp.exr");
    write_exr(&tmp, 8, 4, |_, _| [0.0, 1.0, 0.0]);
    std::fs::rename(&tmp, dir.path().join("sky.exr")).expect("saved");
    until(&rx, "a frame of the new HDRI", |s| finished(s) && s["frame"].as_u64() > Some(n2));
    let (_, green, _) = frame(&w.addr);
    assert_eq!(green, [0, 255, 0], "the saved HDRI");
}
