//! Shader texture maps end to end: Lua reimplementations of the built-in
//! textures render the same images, and a failing or endless shader stops
//! `luster render` with one error naming the shader, the script line and the
//! object, exit code 2 and no image.

use crate::common;
use common::folder;
use luster::render::{render, try_render_with, RenderOptions, Scene};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A small scene: a sphere at the origin and a floor plane, lit by one light,
/// each carrying texture map 1 (whatever `maps` defines).
fn scene_xml(maps: &str, width: u32) -> String {
    format!(
        r#"<Scene>
    <BackgroundColor>10 10 10</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 1.5 4</Position>
            <GazePoint>0 0 0</GazePoint>
            <Up>0 1 0</Up>
            <FovY>45</FovY>
            <NearDistance>1</NearDistance>
            <ImageResolution>{width} {width}</ImageResolution>
            <ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>40 40 40</AmbientLight>
        <PointLight id="1">
            <Position>3 5 4</Position>
            <Intensity>6000 6000 6000</Intensity>
        </PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance>
            <DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance>
            <SpecularReflectance>0.2 0.2 0.2</SpecularReflectance>
            <PhongExponent>20</PhongExponent>
        </Material>
    </Materials>
    <Textures>
{maps}
    </Textures>
    <VertexData>0 0 0
        0 -1 0</VertexData>
    <Objects>
        <Plane id="1">
            <Material>1</Material>
            <Textures>1</Textures>
            <Point>2</Point>
            <Normal>0 1 0</Normal>
        </Plane>
        <Sphere id="2">
            <Material>1</Material>
            <Textures>1</Textures>
            <Center>1</Center>
            <Radius>1</Radius>
        </Sphere>
    </Objects>
</Scene>"#
    )
}

fn render_rgb(scene: &Path) -> Vec<u8> {
    let desc = luster::scene::load(scene).expect("the scene loads");
    let s = Scene::build(&desc).expect("the scene builds");
    try_render_with(&s, 0, &RenderOptions::default(), &|_| {}).expect("no shader fails").to_rgb8()
}

/// (pixels whose 8-bit channels differ at all, largest channel difference).
fn diff(a: &[u8], b: &[u8]) -> (usize, u8) {
    assert_eq!(a.len(), b.len());
    let differing = a.chunks(3).zip(b.chunks(3)).filter(|(p, q)| p != q).count();
    let max = a.iter().zip(b).map(|(x, y)| x.abs_diff(*y)).max().unwrap_or(0);
    (differing, max)
}

const CHECKER_LUA: &str = r#"
-- The hw4 checkerboard: C's truncating cast, then "odd" (C's remainder and
-- Lua's floored one agree on whether an integer is odd).
local floor, ceil = math.floor, math.ceil
local function odd(c)
  local v = (c + param.offset) * param.scale
  local i = v >= 0 and floor(v) or ceil(v)
  return i % 2 ~= 0
end
function color(s)
  local xy = odd(s.P.x) ~= odd(s.P.y)
  if xy ~= odd(s.P.z) then return param.black end
  return param.white
end
"#;

/// The Lua checkerboard and the built-in give the same image: at most 0.1% of
/// the pixels may differ, and only on square edges, where the built-in's
/// single-precision `(c + offset) * scale` and Lua's double precision can
/// round a point to opposite sides.
#[test]
fn lua_checkerboard_matches_the_built_in() {
    let builtin = r#"<TextureMap id="1" type="checkerboard">
            <DecalMode>replace_kd</DecalMode>
            <Scale>2.5</Scale><Offset>0.3</Offset>
            <BlackColor>0.1 0.2 0.6</BlackColor><WhiteColor>0.9 0.8 0.3</WhiteColor>
        </TextureMap>"#;
    let lua = r#"<TextureMap id="1" type="shader">
            <Shader>checker.lua</Shader>
            <DecalMode>replace_kd</DecalMode>
            <Parameter name="scale">2.5</Parameter><Parameter name="offset">0.3</Parameter>
            <Parameter name="black">0.1 0.2 0.6</Parameter><Parameter name="white">0.9 0.8 0.3</Parameter>
        </TextureMap>"#;
    let dir = folder(&[
        ("builtin.xml", &scene_xml(builtin, 160)),
        ("lua.xml", &scene_xml(lua, 160)),
        ("checker.lua", CHECKER_LUA),
    ]);
    let a = render_rgb(&dir.path().join("builtin.xml"));
    let b = render_rgb(&dir.path().join("lua.xml"));
    let (differing, _) = diff(&a, &b);
    assert!(differing * 1000 <= a.len() / 3, "{differing} of {} pixels differ", a.len() / 3);
}

const PERLIN_LUA: &str = r#"
-- The course's perlin texture, absval conversion, NumOctaves octaves.
local abs = math.abs
function color(s)
  local sum, w, total, f = 0, 1, 0, param.scale
  for _ = 1, param.octaves do
    sum = sum + w * abs(course_noise(s.P.x * f, s.P.y * f, s.P.z * f))
    total = total + w
    w, f = w * 0.5, f * 2
  end
  local v = sum / total
  return v, v, v
end
"#;

/// The Lua Perlin texture (on the `course_noise` built-in) and the built-in
/// one: every channel within one 8-bit step, and at most 1% of the pixels
/// differing at all (the positions are scaled in double precision in Lua,
/// single in Rust).
#[test]
fn lua_perlin_matches_the_built_in() {
    let builtin = r#"<TextureMap id="1" type="perlin">
            <DecalMode>replace_kd</DecalMode>
            <NoiseScale>3</NoiseScale><NoiseConversion>absval</NoiseConversion><NumOctaves>4</NumOctaves>
        </TextureMap>"#;
    let lua = r#"<TextureMap id="1" type="shader">
            <Shader>perlin.lua</Shader>
            <DecalMode>replace_kd</DecalMode>
            <Parameter name="scale">3</Parameter><Parameter name="octaves">4</Parameter>
        </TextureMap>"#;
    let dir = folder(&[
        ("builtin.xml", &scene_xml(builtin, 160)),
        ("lua.xml", &scene_xml(lua, 160)),
        ("perlin.lua", PERLIN_LUA),
    ]);
    let a = render_rgb(&dir.path().join("builtin.xml"));
    let b = render_rgb(&dir.path().join("lua.xml"));
    let (differing, max) = diff(&a, &b);
    assert!(max <= 1, "a channel differs by {max}");
    assert!(differing * 100 <= a.len() / 3, "{differing} of {} pixels differ", a.len() / 3);
}

/// The same shader scene in the JSON encoding renders the same image.
#[test]
fn json_encoding_of_a_shader_map() {
    let xml_map = r#"<TextureMap id="1" type="shader">
            <Shader>checker.lua</Shader>
            <DecalMode>replace_kd</DecalMode>
            <Parameter name="scale">2</Parameter><Parameter name="offset">0</Parameter>
            <Parameter name="black">0 0 0</Parameter><Parameter name="white">1 1 1</Parameter>
        </TextureMap>"#;
    let json = r#"{"Scene": {
      "BackgroundColor": "10 10 10",
      "Cameras": {"Camera": {"_id": "1", "_type": "lookAt", "Position": "0 1.5 4", "GazePoint": "0 0 0",
        "Up": "0 1 0", "FovY": "45", "NearDistance": "1", "ImageResolution": "64 64", "ImageName": "out.png"}},
      "Lights": {"AmbientLight": "40 40 40",
        "PointLight": {"_id": "1", "Position": "3 5 4", "Intensity": "6000 6000 6000"}},
      "Materials": {"Material": {"_id": "1", "AmbientReflectance": "1 1 1", "DiffuseReflectance": "0.5 0.5 0.5",
        "SpecularReflectance": "0.2 0.2 0.2", "PhongExponent": "20"}},
      "Textures": {"TextureMap": {"_id": "1", "_type": "shader", "Shader": "checker.lua",
        "DecalMode": "replace_kd",
        "Parameter": [{"_name": "scale", "_data": "2"}, {"_name": "offset", "_data": "0"},
                      {"_name": "black", "_data": "0 0 0"}, {"_name": "white", "_data": "1 1 1"}]}},
      "VertexData": {"_data": "0 0 0 0 -1 0"},
      "Objects": {
        "Plane": {"_id": "1", "Material": "1", "Textures": "1", "Point": "2", "Normal": "0 1 0"},
        "Sphere": {"_id": "2", "Material": "1", "Textures": "1", "Center": "1", "Radius": "1"}}}}"#;
    let dir = folder(&[("a.xml", &scene_xml(xml_map, 64)), ("a.json", json), ("checker.lua", CHECKER_LUA)]);
    let a = render_rgb(&dir.path().join("a.xml"));
    let b = render_rgb(&dir.path().join("a.json"));
    assert_eq!(diff(&a, &b), (0, 0));
}

/// Writes a 12×7 PNG of distinct colours (odd sizes, so rows and columns
/// cannot be confused) as `name` in `dir`.
fn write_test_png(dir: &Path, name: &str) {
    let img = image::RgbImage::from_fn(12, 7, |x, y| {
        image::Rgb([(x * 21) as u8, (y * 36) as u8, ((x * 7 + y * 13) % 256) as u8 ^ 0x5a])
    });
    img.save(dir.join(name)).expect("the test image is written");
}

/// `texture(name, u, v)` in a shader samples the scene's image exactly as an
/// image map does: bilinear like a `bilinear` map, `"nearest"` like a nearest
/// one, by the image's id or its file name. The images must be identical.
#[test]
fn lua_texture_matches_image_maps() {
    let image = r#"<Images><Image id="wall">grid.png</Image></Images>"#;
    let map = |interp: &str| {
        format!(
            r#"{image}<TextureMap id="1" type="image"><ImageId>wall</ImageId>
            <DecalMode>replace_kd</DecalMode><Interpolation>{interp}</Interpolation></TextureMap>"#
        )
    };
    let shader = |file: &str| {
        format!(
            r#"{image}<TextureMap id="1" type="shader"><Shader>{file}</Shader>
            <DecalMode>replace_kd</DecalMode></TextureMap>"#
        )
    };
    let dir = folder(&[
        ("bilinear.xml", &scene_xml(&map("bilinear"), 96)),
        ("nearest.xml", &scene_xml(&map("nearest"), 96)),
        ("lua_bilinear.xml", &scene_xml(&shader("bilinear.lua"), 96)),
        ("lua_nearest.xml", &scene_xml(&shader("nearest.lua"), 96)),
        ("bilinear.lua", "function color(s) return texture('wall', s.uv.u, s.uv.v) end"),
        ("nearest.lua", "function color(s) return texture('grid.png', s.uv.u, s.uv.v, 'nearest') end"),
    ]);
    write_test_png(dir.path(), "grid.png");
    let render = |f: &str| render_rgb(&dir.path().join(f));
    let (bilinear, nearest) = (render("bilinear.xml"), render("nearest.xml"));
    assert_ne!(bilinear, nearest, "the two filters should differ on this image");
    assert_eq!(diff(&render("lua_bilinear.xml"), &bilinear), (0, 0));
    assert_eq!(diff(&render("lua_nearest.xml"), &nearest), (0, 0));
}

/// Sampling an image the scene does not have, or with an unknown filter, is
/// an error naming the shader and line and listing the scene's images.
#[test]
fn lua_texture_errors_are_clear() {
    let image = r#"<Images><Image id="1">grid.png</Image></Images>"#;
    let map = format!(
        r#"{image}<TextureMap id="1" type="shader"><Shader>t.lua</Shader>
        <DecalMode>replace_kd</DecalMode></TextureMap>"#
    );
    for (script, words) in [
        (
            "function color(s)\n  local r, g, b = texture('nope', 0, 0)\n  return r, g, b\nend",
            &["t.lua:2", "no image nope", "\"1\", \"grid.png\""][..],
        ),
        // A tail call leaves Lua no line to report; the message says so.
        ("function color(s)\n  return texture('nope', 0, 0)\nend", &["no image nope", "tail call"][..]),
        (
            "function color(s)\n  local c = {texture(1, 0, 0, 'cubic')}\n  return c[1], c[2], c[3]\nend",
            &["t.lua:2", "unknown filter cubic"][..],
        ),
        (
            "function color(s)\n  local r = texture(1, 'a', 0)\n  return r, r, r\nend",
            &["t.lua:2", "must be numbers"][..],
        ),
    ] {
        let dir = folder(&[("s.xml", &scene_xml(&map, 16)), ("t.lua", script)]);
        write_test_png(dir.path(), "grid.png");
        let desc = luster::scene::load(&dir.path().join("s.xml")).expect("loads");
        let scene = Scene::build(&desc).expect("builds");
        let e = match try_render_with(&scene, 0, &RenderOptions::default(), &|_| {}) {
            Ok(_) => panic!("{script} rendered"),
            Err(e) => e.to_string(),
        };
        for w in words {
            assert!(e.contains(w), "{w:?} missing from {e:?}");
        }
    }
}

/// `replace_km` makes a plain material a mirror with the script's reflectance.
#[test]
fn reflect_drives_the_mirror_reflectance() {
    let lua = "function reflect(s) return 1, 1, 1 end";
    let map = r#"<TextureMap id="1" type="shader">
            <Shader>mirror.lua</Shader><DecalMode>replace_km</DecalMode>
        </TextureMap>"#;
    let dir = folder(&[("m.xml", &scene_xml(map, 48)), ("mirror.lua", lua)]);
    let desc = luster::scene::load(&dir.path().join("m.xml")).expect("loads");
    let mut plain = desc.clone();
    plain.texture_maps.clear();
    for o in &mut plain.objects {
        o.textures.clear();
    }
    let mirrored = render(&Scene::build(&desc).expect("builds"), 0, &|_| {});
    let without = render(&Scene::build(&plain).expect("builds"), 0, &|_| {});
    // Mirrors add light; the floor reflects the sphere and vice versa.
    let sum = |img: &luster::render::RenderedImage| img.pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>();
    assert!(sum(&mirrored) > sum(&without) * 1.05, "{} vs {}", sum(&mirrored), sum(&without));
}

struct Run {
    code: Option<i32>,
    stderr: String,
    out: PathBuf,
    _dir: tempfile::TempDir,
}

/// Runs `luster render` on a scene whose map 1 is `shader.lua` = `script`.
fn cli(script: &str, extra: &[&str]) -> Run {
    let map = r#"<TextureMap id="1" type="shader">
            <Shader>boom.lua</Shader><DecalMode>replace_kd</DecalMode>
        </TextureMap>"#;
    // Only the sphere carries the map, so the error must name it.
    let xml = scene_xml(map, 48).replacen("<Textures>1</Textures>", "", 1);
    let dir = folder(&[("s.xml", &xml), ("boom.lua", script)]);
    let out = dir.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["render", "-q", "--threads", "2", "-o"])
        .arg(&out)
        .args(extra)
        .arg(dir.path().join("s.xml"))
        .output()
        .expect("luster runs");
    Run { code: o.status.code(), stderr: String::from_utf8_lossy(&o.stderr).into_owned(), out, _dir: dir }
}

fn no_image(run: &Run) -> bool {
    !run.out.join("out.png").exists() && std::fs::read_dir(&run.out).map_or(true, |mut d| d.next().is_none())
}

#[test]
fn a_runtime_error_stops_the_render_naming_shader_line_and_object() {
    let script = "local k = 2\nfunction color(s)\n  if s.P.y > 0.5 then error('too high') end\n  return 1, 0, 0\nend\n";
    let run = cli(script, &[]);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    let line = run.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    for word in ["error: ", "s.xml", "shader 'boom'", "boom.lua:3", "too high", "Sphere[id=2]"] {
        assert!(line.contains(word), "{word:?} missing from {line:?}");
    }
    assert!(no_image(&run), "an image was written");
}

#[test]
fn a_shader_timeout_is_reported_cleanly() {
    let t = std::time::Instant::now();
    let run = cli("function color(s)\n  while true do end\nend\n", &["--shader-timeout", "0.2"]);
    assert_eq!(run.code, Some(2), "{}", run.stderr);
    let line = run.stderr.trim_end();
    assert_eq!(line.lines().count(), 1, "{line}");
    for word in ["shader 'boom'", "boom.lua:2", "time limit", "0.200 s", "Sphere[id=2]"] {
        assert!(line.contains(word), "{word:?} missing from {line:?}");
    }
    assert!(no_image(&run), "an image was written");
    // Two workers, each stopped at its first call: well under the 10 s default.
    assert!(t.elapsed().as_secs_f64() < 5.0, "took {:?}", t.elapsed());
}

#[test]
fn a_bad_timeout_is_refused() {
    let run = cli("function color(s) return 1, 1, 1 end", &["--shader-timeout", "0"]);
    assert_eq!(run.code, Some(2));
    assert!(run.stderr.contains("not a time limit"), "{}", run.stderr);
}
