//! The display transform (`<Display>`, `--display`) in whole renders: a
//! Lambertian reflectance of 0.18 under an irradiance of 255 (the film's
//! white) is linear 45.9, which the course's clamp writes as 45 and the sRGB
//! transform as 118; an OBJ model gets the sRGB transform by default and its
//! 8-bit `map_Kd` is sRGB-decoded; `--display` overrides the scene; an unknown
//! mode is one sentence with exit code 2.

use crate::common;

use luster::film::rgb8;
use luster::image::outputs::plan_outputs;
use luster::math::Vec3;
use luster::render::{render_with, RenderOptions, Scene};
use luster::scene::description::PointLightDesc;
use luster::scene::obj::ModelView;
use luster::scene::Description;
use luster::tonemap::Display;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// A triangle in z = 0 seen head-on from z = 4, lit by a point light at the
/// eye whose irradiance at the image's centre is 255; 9×9 pixels, so the
/// centre pixel's ray meets the triangle at the origin.
fn head_on(display: &str) -> String {
    format!(
        r#"<Scene>
  {display}
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 4</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>2</NearDistance><ImageResolution>9 9</ImageResolution>
    <ImageName>grey.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0 0 0</AmbientLight>
    <PointLight id="1"><Position>0 0 4</Position><Intensity>4080 4080 4080</Intensity></PointLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>0 0 0</AmbientReflectance>
    <DiffuseReflectance>0.18 0.18 0.18</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance>
    <PhongExponent>1</PhongExponent></Material></Materials>
  <VertexData>-10 -10 0 10 -10 0 0 10 0</VertexData>
  <Objects><Mesh id="1"><Material>1</Material><Faces>1 2 3</Faces></Mesh></Objects>
</Scene>"#
    )
}

/// The 8-bit centre pixel of the first image `desc` writes.
fn centre(desc: &Description) -> [u8; 3] {
    let scene = Scene::build(desc).expect("scene builds");
    let img = render_with(&scene, 0, &RenderOptions { spp: Some(1), ..Default::default() }, &|_| {});
    let cam = &scene.cameras[0];
    let plan = plan_outputs(&cam.image_name, &cam.tonemaps, cam.display).expect("a plan");
    let rgb = rgb8(&img.film, &plan[0].kind).expect("an 8-bit image");
    let i = 3 * (img.width as usize * (img.height as usize / 2) + img.width as usize / 2);
    [rgb[i], rgb[i + 1], rgb[i + 2]]
}

fn load_xml(dir: &Path, text: &str) -> Description {
    let p = dir.join("grey.xml");
    std::fs::write(&p, text).expect("scene written");
    luster::scene::load(&p).expect("scene loads")
}

#[test]
fn course_scenes_keep_the_clamp_and_display_srgb_encodes() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let course = load_xml(dir.path(), &head_on(""));
    assert_eq!(course.display, Display::Course);
    assert_eq!(centre(&course), [45; 3], "linear 45.9, clamped and truncated");
    let srgb = load_xml(dir.path(), &head_on("<Display>sRGB</Display>"));
    assert_eq!(centre(&srgb), [118; 3], "sRGB mid-grey");
    let filmic = load_xml(dir.path(), &head_on("<Display>filmic</Display>"));
    let f = centre(&filmic)[0];
    assert!(f != 45 && f != 118 && (90..=125).contains(&f), "filmic mid-grey at {f}");
}

/// A square in z = 0 facing +z (the model view's front), with `mtl`.
fn quad_model(dir: &Path, mtl: &str) -> std::path::PathBuf {
    let obj = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\nf 1/1 3/3 4/4\n";
    std::fs::write(dir.join("quad.obj"), obj).expect("OBJ written");
    std::fs::write(dir.join("quad.mtl"), mtl).expect("MTL written");
    dir.join("quad.obj")
}

/// The model scene of `path` seen head-on, lit only by a point light at the
/// eye giving the square's centre an irradiance of `irradiance`.
fn model_head_on(path: &Path, display: Option<Display>, irradiance: f32) -> Description {
    let view = ModelView {
        width: 9,
        height: 9,
        samples: 1,
        azimuth: 0.0,
        elevation: 0.0,
        ground: false,
        display,
        ..Default::default()
    };
    let mut desc = luster::scene::load_viewed(path, &view).expect("model loads");
    let eye = desc.cameras[0].position;
    let d2 = eye.length_squared();
    desc.point_lights = vec![PointLightDesc {
        position: eye,
        intensity: Vec3::splat(irradiance * d2),
        loc: desc.cameras[0].loc.clone(),
    }];
    desc.ambient_light = Vec3::ZERO;
    desc.background = Vec3::ZERO;
    desc
}

#[test]
fn an_obj_model_is_srgb_encoded_by_default() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let path = quad_model(dir.path(), "newmtl m\nKa 0 0 0\nKd 0.18 0.18 0.18\nKs 0 0 0\n");
    let desc = model_head_on(&path, None, 255.0);
    assert_eq!(desc.display, Display::Srgb);
    assert_eq!(centre(&desc), [118; 3], "Kd 0.18 under the film's white is sRGB mid-grey");
    assert_eq!(centre(&model_head_on(&path, Some(Display::Course), 255.0)), [45; 3]);
}

#[test]
fn an_obj_models_8_bit_map_kd_is_srgb_decoded() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    // 188 is sRGB for linear 0.50; under half the film's white, 0.25 is 137 in sRGB.
    image::RgbImage::from_pixel(4, 4, image::Rgb([188, 188, 188]))
        .save(dir.path().join("grey.png"))
        .expect("PNG");
    let path = quad_model(dir.path(), "newmtl m\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nmap_Kd grey.png\n");
    assert_eq!(centre(&model_head_on(&path, None, 127.5)), [137; 3]);
    // The course's workflow reads the texel as the reflectance 188/255: 94.
    assert_eq!(centre(&model_head_on(&path, Some(Display::Course), 127.5)), [94; 3]);
}

fn luster(args: &[&str]) -> common::Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(args);
    common::run_limited(cmd, Duration::from_secs(60))
}

fn centre_of_png(path: &Path) -> [u8; 3] {
    let img = image::open(path).expect("the PNG").to_rgb8();
    img.get_pixel(img.width() / 2, img.height() / 2).0
}

#[test]
fn the_command_line_overrides_the_scene() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let scene = dir.path().join("grey.xml");
    std::fs::write(&scene, head_on("")).expect("scene written");
    let out = dir.path().join("out");
    let (s, o) = (scene.to_str().unwrap(), out.to_str().unwrap());
    let r = luster(&["render", "-q", s, "-o", o]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(centre_of_png(&out.join("grey.png")), [45; 3]);
    let r = luster(&["render", "-q", "--display", "srgb", s, "-o", o]);
    assert_eq!(r.code, Some(0), "{}", r.stderr);
    assert_eq!(centre_of_png(&out.join("grey.png")), [118; 3]);
    let r = luster(&["render", "-q", "--display", "gamma", s, "-o", o]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    assert!(r.stderr.contains("not a display transform"), "{}", r.stderr);
}

#[test]
fn an_unknown_display_is_one_sentence_naming_file_and_element() {
    let dir = tempfile::tempdir().expect("a temporary folder");
    let scene = dir.path().join("bad.xml");
    std::fs::write(&scene, head_on("<Display>vivid</Display>")).expect("scene written");
    let out = dir.path().join("out");
    let r = luster(&["render", "-q", scene.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert_eq!(r.code, Some(2), "{}", r.stderr);
    let line = r.stderr.trim();
    assert_eq!(line.lines().count(), 1, "{line}");
    assert!(line.contains("bad.xml") && line.contains("<Display>") && line.contains("srgb"), "{line}");
    assert!(!line.contains("vivid"), "the message does not quote the file: {line}");
    assert!(!out.join("grey.png").exists(), "no image");
}
