//! Where the course's Perlin noise lives, per kind of object: meshes carry it
//! in object space (hw4 `cube_perlin`, `cube_perlin_bump`), spheres in world
//! space (hw4 `ellipsoids_texture`). Each case renders an object under a
//! scaling and the same object built without it, and checks which of the two
//! equivalent noise scales reproduces the transformed render.

use luster::render::{render, Scene};
use luster::scene::description::Description;
use std::io::Write;
use std::path::Path;

/// A scene of `objects` with a Perlin map as `mode` (`replace_kd` or
/// `bump_normal`) of `NoiseScale` and `BumpFactor` `map`, a scaling `s1` by
/// 0.5, and a point light.
fn scene(objects: &str, map: (f32, f32), mode: &str) -> String {
    let (scale, bump) = map;
    format!(
        r#"<Scene>
  <Cameras><Camera id="1"><Position>0.25 0.25 3</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-0.12 0.12 -0.12 0.12</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>64 64</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>60 60 60</AmbientLight>
    <PointLight id="1"><Position>1 2 4</Position><Intensity>2000 2000 2000</Intensity></PointLight></Lights>
  <Materials><Material id="1"><AmbientReflectance>1 1 1</AmbientReflectance>
    <DiffuseReflectance>1 1 1</DiffuseReflectance><SpecularReflectance>0.5 0.5 0.5</SpecularReflectance>
    <PhongExponent>20</PhongExponent></Material></Materials>
  <Textures><TextureMap id="1" type="perlin"><NoiseScale>{scale}</NoiseScale>
    <NoiseConversion>absval</NoiseConversion><DecalMode>{mode}</DecalMode><BumpFactor>{bump}</BumpFactor></TextureMap></Textures>
  <Transformations><Scaling id="1">0.5 0.5 0.5</Scaling></Transformations>
  <VertexData>-0.5 -0.5 0  1.5 -0.5 0  1.5 1.5 0  -0.5 1.5 0  -0.25 -0.25 0  0.75 -0.25 0  0.75 0.75 0  -0.25 0.75 0
    0.5 0.5 -1  0.25 0.25 -0.5</VertexData>
  <Objects>{objects}</Objects>
</Scene>"#
    )
}

/// A square facing the camera: vertices 1–4 scaled by `s1`, or 5–8 (the
/// same corners) as they are.
fn square(scaled: bool) -> String {
    let (faces, xf) =
        if scaled { ("1 2 3 1 3 4", "<Transformations>s1</Transformations>") } else { ("5 6 7 5 7 8", "") };
    format!(r#"<Mesh id="1"><Material>1</Material><Textures>1</Textures>{xf}<Faces>{faces}</Faces></Mesh>"#)
}

/// A sphere of radius 1 at (0.5, 0.5, −1) scaled by `s1`, or the same
/// sphere (radius 0.5 at (0.25, 0.25, −0.5)) as it is.
fn sphere(scaled: bool) -> String {
    let (c, r, xf) = if scaled { (9, 1.0, "<Transformations>s1</Transformations>") } else { (10, 0.5, "") };
    format!(
        r#"<Sphere id="1"><Material>1</Material><Textures>1</Textures>{xf}<Center>{c}</Center><Radius>{r}</Radius></Sphere>"#
    )
}

fn rgb(dir: &Path, name: &str, text: &str) -> Vec<u8> {
    let p = dir.join(name);
    std::fs::File::create(&p).unwrap().write_all(text.as_bytes()).unwrap();
    let desc: Description = luster::scene::load(&p).unwrap();
    render(&Scene::build(&desc).unwrap(), 0, &|_| {}).to_rgb8()
}

/// Metric: the mean absolute 8-bit difference over all channels. The
/// transformed and the pre-built object solve the same intersections up to
/// float rounding, so equivalent noise agrees to well under one level,
/// while noise at the wrong scale differs by tens of levels.
fn mean_diff(a: &[u8], b: &[u8]) -> f64 {
    a.iter().zip(b).map(|(&x, &y)| f64::from(x.abs_diff(y))).sum::<f64>() / a.len() as f64
}

/// `make(true)` rendered with noise scale 4 and bump factor 0.05 must match
/// `make(false)` with the map `same` and differ from it with `other`.
fn check(make: fn(bool) -> String, same: (f32, f32), other: (f32, f32), what: &str) {
    let dir = tempfile::tempdir().unwrap();
    for mode in ["replace_kd", "bump_normal"] {
        let t = rgb(dir.path(), "t.xml", &scene(&make(true), (4.0, 0.05), mode));
        let right = rgb(dir.path(), "r.xml", &scene(&make(false), same, mode));
        let wrong = rgb(dir.path(), "w.xml", &scene(&make(false), other, mode));
        let (dr, dw) = (mean_diff(&t, &right), mean_diff(&t, &wrong));
        assert!(dr < 0.5, "{what} ({mode}): differs from its equivalent by {dr:.2} levels on average");
        assert!(dw > 5.0, "{what} ({mode}): the other space gives nearly the same image ({dw:.2} levels)");
    }
}

#[test]
fn noise_on_a_scaled_mesh_is_in_object_space() {
    // Object space: p_object = 2 p_world, so scale 4 there is scale 8 in the
    // world; the bump tilts the object-space normal by the object-space
    // gradient, half the world one, as a halved bump factor does.
    check(square, (8.0, 0.025), (4.0, 0.05), "mesh");
}

#[test]
fn noise_on_a_scaled_sphere_is_in_world_space() {
    check(sphere, (4.0, 0.05), (8.0, 0.025), "sphere");
}
