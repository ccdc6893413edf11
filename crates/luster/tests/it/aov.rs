//! Render passes (`--aov`): each pass checked against the scene's geometry
//! where the answer is known analytically (a floor's distance, a sphere's
//! normal, a material's reflectance, an emitter's radiance, which object a
//! ray meets), and the pass file: one EXR whose layers the `exr` crate reads
//! under the expected channel names, the same bytes on one and two threads,
//! and from a split render merged.

use crate::common::{self, run_limited};
use luster::film::aov::BACKGROUND_DEPTH;
use luster::film::Passes;
use luster::math::Vec3;
use luster::render::{render_with, RenderOptions, Scene};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

const W: u32 = 24;
const H: u32 = 20;
/// The camera: at the origin looking down −z, an image plane at distance 1
/// spanning [−1.2, 1.2] × [−1, 1].
const HALF_W: f32 = 1.2;
const FLOOR_Y: f32 = -1.0;
const SPHERE: (Vec3, f32) = (Vec3::new(0.7, 0.2, -4.0), 1.0);
const LIGHT: (Vec3, f32) = (Vec3::new(-1.2, 0.3, -5.0), 0.8);

/// A floor (diffuse 0.25 0.5 0.75), a sphere (diffuse 0.8 0.1 0.1) and a
/// light sphere of radiance 40 over a black background; `extra` goes in the
/// camera.
fn scene(extra: &str) -> String {
    let (c, r) = SPHERE;
    let (lc, lr) = LIGHT;
    format!(
        r#"<Scene>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 0</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-{HALF_W} {HALF_W} -1 1</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>{W} {H}</ImageResolution><ImageName>a.png</ImageName>{extra}</Camera></Cameras>
  <Lights><PointLight id="1"><Position>0 3 0</Position><Intensity>300 300 300</Intensity></PointLight></Lights>
  <Materials>
    <Material id="1"><DiffuseReflectance>0.25 0.5 0.75</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0.8 0.1 0.1</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="3"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <VertexData>0 {FLOOR_Y} 0  {} {} {}  {} {} {}</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <Sphere id="1"><Material>2</Material><Center>2</Center><Radius>{r}</Radius></Sphere>
    <LightSphere id="1"><Material>3</Material><Center>3</Center><Radius>{lr}</Radius><Radiance>40 40 40</Radiance></LightSphere>
  </Objects>
</Scene>"#,
        c.x, c.y, c.z, lc.x, lc.y, lc.z
    )
}

/// What the centre ray of pixel `(x, y)` meets first: the distance along
/// the unit ray, the point, the unit normal, and which surface (0 the
/// floor, 1 the sphere, 2 the light, 3 nothing).
fn analytic(x: u32, y: u32) -> (f32, Vec3, Vec3, usize) {
    let d = Vec3::new(
        -HALF_W + (x as f32 + 0.5) * 2.0 * HALF_W / W as f32,
        1.0 - (y as f32 + 0.5) * 2.0 / H as f32,
        -1.0,
    )
    .normalize();
    let sphere = |(c, r): (Vec3, f32)| {
        let b = d.dot(c);
        let disc = b * b - (c.length_squared() - r * r);
        (disc >= 0.0).then(|| b - disc.sqrt()).filter(|&t| t > 0.0)
    };
    let floor = (d.y < 0.0).then(|| FLOOR_Y / d.y);
    let mut best = (f32::INFINITY, Vec3::ZERO, Vec3::ZERO, 3);
    for (k, t) in [(0, floor), (1, sphere(SPHERE)), (2, sphere(LIGHT))] {
        if let Some(t) = t.filter(|&t| t < best.0) {
            let p = d * t;
            let n = match k {
                0 => Vec3::Y,
                1 => (p - SPHERE.0) / SPHERE.1,
                _ => (p - LIGHT.0) / LIGHT.1,
            };
            best = (t, p, n, k);
        }
    }
    best
}

fn render(dir: &Path, extra: &str, opts: &RenderOptions) -> luster::render::RenderedImage {
    let desc = common::load_with(dir, &scene(extra), &[]);
    let scene = Scene::build(&desc).expect("scene builds");
    render_with(&scene, 0, opts, &|_| {})
}

#[test]
fn each_pass_holds_the_first_hits_analytic_values() {
    let dir = tempfile::tempdir().unwrap();
    let passes = Passes::parse("all").unwrap();
    // One sample a pixel goes through its centre: the analytic ray.
    let img = render(dir.path(), "", &RenderOptions { passes, ..Default::default() });
    let a = img.aovs.as_ref().expect("passes were asked for");
    let (depth, normal, albedo) = (a.depth().unwrap(), a.normal().unwrap(), a.albedo().unwrap());
    let (ids, emission, position) = (a.object_id().unwrap(), a.emission().unwrap(), a.position().unwrap());
    let mut id_of = [None; 4];
    let mut seen = [0; 4];
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let (t, p, n, k) = analytic(x, y);
            seen[k] += 1;
            let at = format!("pixel ({x}, {y}), surface {k}");
            if k == 3 {
                assert_eq!(depth[i], BACKGROUND_DEPTH, "{at}");
                assert_eq!(
                    (normal[i], albedo[i], emission[i], ids[i]),
                    (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, 0.0)
                );
                continue;
            }
            assert!((depth[i] - t).abs() < 1e-4 * t, "{at}: depth {} against {t}", depth[i]);
            assert!((position[i] - p).length() < 1e-4 * t, "{at}: position {} against {p}", position[i]);
            assert!((normal[i] - n).length() < 1e-3, "{at}: normal {} against {n}", normal[i]);
            let want_albedo = [Vec3::new(0.25, 0.5, 0.75), Vec3::new(0.8, 0.1, 0.1), Vec3::ZERO][k];
            assert!((albedo[i] - want_albedo).length() < 1e-6, "{at}: albedo {}", albedo[i]);
            let want_emission = if k == 2 { Vec3::splat(40.0) } else { Vec3::ZERO };
            assert_eq!(emission[i], want_emission, "{at}");
            // One id per object, the same at every pixel, and no two alike.
            assert!(ids[i] >= 1.0, "{at}: id {}", ids[i]);
            assert_eq!(*id_of[k].get_or_insert(ids[i]), ids[i], "{at}");
        }
    }
    assert!(seen.iter().all(|&s| s > 5), "every surface and the background are in view: {seen:?}");
    let [floor, sphere, light, _] = id_of.map(|id| id.unwrap_or(0.0));
    assert!(floor != sphere && sphere != light && floor != light, "{id_of:?}");
    assert!(a.samples().unwrap().iter().all(|&s| s == 1.0));
}

#[test]
fn filtered_passes_average_the_samples_and_the_beauty_is_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let opts = RenderOptions { spp: Some(16), ..Default::default() };
    let plain = render(dir.path(), "", &opts);
    let passes = Passes::parse("albedo,normal,depth,samples").unwrap();
    let with = render(dir.path(), "", &RenderOptions { passes, ..opts });
    assert!(plain.aovs.is_none());
    assert!(plain.film.pixels == with.film.pixels, "passes change no beauty pixel");
    let a = with.aovs.unwrap();
    let (albedo, depth) = (a.albedo().unwrap(), a.depth().unwrap());
    let floor = Vec3::new(0.25, 0.5, 0.75);
    for y in 0..H {
        for x in 0..W {
            let i = (y * W + x) as usize;
            let (.., k) = analytic(x, y);
            // A pixel wholly on the floor: its samples all see the floor.
            let all_floor = (0..3).all(|dy| {
                (0..3).all(|dx| {
                    let (xx, yy) =
                        ((x + dx).saturating_sub(1).min(W - 1), (y + dy).saturating_sub(1).min(H - 1));
                    analytic(xx, yy).3 == 0
                })
            });
            if all_floor {
                assert!((albedo[i] - floor).length() < 1e-5, "({x}, {y}): {}", albedo[i]);
                assert!(depth[i] < 1e3, "({x}, {y})");
            }
            // Depth is one sample's, never a blend: a floor or sphere
            // distance within the pixel's spread, or the background.
            if k == 3 && depth[i] != BACKGROUND_DEPTH {
                assert!(depth[i] > 2.0 && depth[i] < 20.0, "({x}, {y}): {}", depth[i]);
            }
        }
    }
    assert!(a.samples().unwrap().iter().all(|&s| s == 16.0));
}

fn luster() -> Command {
    Command::new(env!("CARGO_BIN_EXE_luster"))
}

fn run(args: &[&str]) -> common::Run {
    let mut cmd = luster();
    cmd.args(args);
    let r = run_limited(cmd, Duration::from_secs(120));
    assert_eq!(r.code, Some(0), "luster {args:?}: {}", r.stderr);
    r
}

/// The layers of the pass file, by channel name.
fn layers(path: &Path) -> Vec<(String, Vec<f32>)> {
    use exr::prelude::*;
    let image = read_all_flat_layers_from_file(path).expect("the pass file reads");
    assert_eq!(image.layer_data.len(), 1, "one part");
    image.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

#[test]
fn the_pass_file_has_the_expected_layers_and_the_same_bytes_on_any_threads_and_split() {
    let dir = tempfile::tempdir().unwrap();
    // Several samples with a lens and adaptive sampling: every pixel's
    // values are random, and its sample count too.
    let extra = "<NumSamples>24</NumSamples><ApertureSize>0.1</ApertureSize><FocusDistance>4</FocusDistance>";
    let text = scene(extra).replace(
        "<ImageName>a.png</ImageName>",
        "<ImageName>a.png</ImageName><Renderer>PathTracing</Renderer><RendererParams>NextEventEstimation</RendererParams>",
    );
    let scene_path = dir.path().join("s.xml");
    std::fs::write(&scene_path, text).unwrap();
    let s = scene_path.to_str().unwrap();
    let out = |name: &str| dir.path().join(name);
    let common = ["--aov", "all", "--noise-threshold", "0.05", "--min-spp", "8", "-q"];
    for (threads, folder) in [("1", "one"), ("2", "two")] {
        let o = out(folder);
        run(&[&["render", s, "-o", o.to_str().unwrap(), "--threads", threads], &common[..]].concat());
    }
    let split = out("split");
    for k in 1..=3 {
        let part = format!("{k}/3");
        run(&[&["render", s, "-o", split.to_str().unwrap(), "--part", &part], &common[..]].concat());
    }
    run(&["merge", split.to_str().unwrap()]);
    for name in ["a.png", "a.aov.exr"] {
        let one = std::fs::read(out("one").join(name)).unwrap();
        assert!(one == std::fs::read(out("two").join(name)).unwrap(), "{name}: one thread against two");
        assert!(one == std::fs::read(split.join(name)).unwrap(), "{name}: whole against split and merged");
    }
    let layers = layers(&out("one").join("a.aov.exr"));
    let mut names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    names.sort_unstable();
    let want = [
        "B",
        "G",
        "R",
        "albedo.B",
        "albedo.G",
        "albedo.R",
        "depth.Z",
        "emission.B",
        "emission.G",
        "emission.R",
        "normal.X",
        "normal.Y",
        "normal.Z",
        "object_id.X",
        "position.X",
        "position.Y",
        "position.Z",
        "samples.X",
    ];
    assert_eq!(names, want);
    let samples = &layers.iter().find(|(n, _)| n == "samples.X").unwrap().1;
    assert_eq!(samples.len(), (W * H) as usize);
    assert!(samples.iter().all(|&s| (8.0..=24.0).contains(&s)), "between --min-spp and NumSamples");
    assert!(samples.contains(&8.0) && samples.contains(&24.0), "the heat map varies");
    // The beauty layer is the image the render wrote, in linear values.
    let png = image::open(out("one").join("a.png")).unwrap().to_rgb8();
    let r = &layers.iter().find(|(n, _)| n == "R").unwrap().1;
    for (i, p) in png.pixels().enumerate() {
        assert_eq!(p.0[0], r[i].clamp(0.0, 255.0) as u8, "pixel {i}");
    }
}

#[test]
fn a_bad_pass_name_is_one_sentence_and_exit_code_2() {
    let mut cmd = luster();
    cmd.args(["render", "nothing.xml", "--aov", "albedo,zdepth"]);
    let r = run_limited(cmd, Duration::from_secs(30));
    assert_eq!(r.code, Some(2));
    assert!(r.stderr.contains("\"zdepth\" is not a render pass"), "{}", r.stderr);
}
