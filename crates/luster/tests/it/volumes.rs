//! Volumes end to end: transmittance through a homogeneous slab (and an
//! ellipsoid) is exp(−σt·d) for camera and shadow rays, marched or closed-form; a
//! constant-density hypertexture renders the analytic sphere's silhouette;
//! media cast shadows and are shadowed; a baked grid renders like the script;
//! a failing density script stops the render naming the volume.

use crate::common;
use common::folder;
use luster::render::{try_render_with, RenderOptions, RenderedImage, Scene};
use std::path::Path;

/// A scene seen by a camera on +z looking down −z through a 2-unit-wide
/// window (pixel (w/2, h/2) looks straight along −z), lit by one point light,
/// with `objects` and `volumes` added.
fn scene(res: u32, objects: &str, volumes: &str, light: &str) -> String {
    format!(
        r#"<Scene>
  <BackgroundColor>200 100 50</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>4</NearDistance>
    <ImageResolution>{res} {res}</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><AmbientLight>0 0 0</AmbientLight>
    <PointLight id="1"><Position>{light}</Position><Intensity>10000 10000 10000</Intensity></PointLight></Lights>
  <Materials>
    <Material id="1"><AmbientReflectance>0 0 0</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
      <SpecularReflectance>0 0 0</SpecularReflectance><PhongExponent>1</PhongExponent></Material>
  </Materials>
  <VertexData>0 0 0  0 0 -3</VertexData>
  <Objects>{objects}</Objects>
  <Volumes>{volumes}</Volumes>
</Scene>"#
    )
}

fn render_file(path: &Path, spp: u32) -> Result<RenderedImage, String> {
    let desc = luster::scene::load(path).map_err(|e| e.to_string())?;
    let s = Scene::build(&desc).map_err(|e| e.to_string())?;
    let opts = RenderOptions { spp: Some(spp), ..RenderOptions::default() };
    try_render_with(&s, 0, &opts, &|_| {}).map_err(|e| e.to_string())
}

fn render(xml: &str, extra: &[(&str, &str)]) -> RenderedImage {
    let mut files = vec![("s.xml", xml)];
    files.extend_from_slice(extra);
    let dir = folder(&files);
    render_file(&dir.path().join("s.xml"), 1).expect("the scene renders")
}

fn centre(img: &RenderedImage) -> [f32; 3] {
    img.pixels[((img.height / 2) * img.width + img.width / 2) as usize].to_array()
}

/// An absorbing slab 0.8 thick (z from −0.4 to 0.4) with σa = (0.5, 1, 2).
fn slab(extra: &str) -> String {
    format!(
        r#"<Volume id="slab"><Box><Min>-5 -5 -0.4</Min><Max>5 5 0.4</Max></Box>
        <Absorption>0.5 1 2</Absorption><Scattering>0 0 0</Scattering>{extra}</Volume>"#
    )
}

fn assert_within_1_percent(got: [f32; 3], want: [f32; 3]) {
    for c in 0..3 {
        assert!(
            (got[c] - want[c]).abs() <= 0.01 * want[c],
            "channel {c}: {} vs {} ({got:?})",
            got[c],
            want[c]
        );
    }
}

/// Camera rays: the background through the slab is scaled by exp(−σa·0.8),
/// by the closed form (constant density) and by marching a script's
/// constant density with a step that does not divide the thickness.
#[test]
fn transmittance_through_a_homogeneous_slab() {
    let want = [200.0 * (-0.5f32 * 0.8).exp(), 100.0 * (-0.8f32).exp(), 50.0 * (-1.6f32).exp()];
    let constant = render(&scene(9, "", &slab(""), "0 0 20"), &[]);
    assert_within_1_percent(centre(&constant), want);
    let scripted = scene(9, "", &slab("<Shader>one.lua</Shader><StepSize>0.07</StepSize>"), "0 0 20");
    let marched = render(&scripted, &[("one.lua", "function density(s) return 1 end")]);
    assert_within_1_percent(centre(&marched), want);
    // Twice the density, twice the optical depth.
    let doubled = render(&scene(9, "", &slab("<Density>2</Density>"), "0 0 20"), &[]);
    let want2 = [200.0 * (-0.8f32).exp(), 100.0 * (-1.6f32).exp(), 50.0 * (-3.2f32).exp()];
    assert_within_1_percent(centre(&doubled), want2);
}

/// The GLSL ellipsoid page's case: a homogeneous, semi-opaque ellipsoid
/// whose opacity follows the path length through it. Along the axis the
/// chord is twice the radius in that direction, also after a rotation.
#[test]
fn a_homogeneous_ellipsoid_is_as_opaque_as_its_chord_is_long() {
    let ellipsoid = |rotation: &str| {
        format!(
            r#"<Volume id="e"><Ellipsoid><Center>0 0 0</Center><Radii>1 0.5 2</Radii>{rotation}</Ellipsoid>
            <Absorption>0.3 0.5 0.1</Absorption><Scattering>0 0 0</Scattering></Volume>"#
        )
    };
    let chord =
        |len: f32| [200.0 * (-0.3 * len).exp(), 100.0 * (-0.5 * len).exp(), 50.0 * (-0.1 * len).exp()];
    assert_within_1_percent(centre(&render(&scene(9, "", &ellipsoid(""), "0 0 20"), &[])), chord(4.0));
    let turned = ellipsoid("<Rotation>90 0 1 0</Rotation>");
    assert_within_1_percent(centre(&render(&scene(9, "", &turned, "0 0 20"), &[])), chord(2.0));
}

/// Shadow rays: a plane lit through the slab receives exp(−σa·0.8) of the
/// light it gets without it (closed form and marched).
#[test]
fn media_attenuate_shadow_rays() {
    // The plane at z = −3 faces the camera; the light is behind the camera, so
    // its light crosses the slab once on the way to the plane. The camera ray
    // crosses it too, so compare against the slab alone in front of the camera
    // by putting the slab between light and plane but off the camera's path.
    let plane = r#"<Plane id="1"><Material>1</Material><Point>2</Point><Normal>0 0 1</Normal></Plane>"#;
    // The light sits at x = 40 beside the plane, the slab stands at x = 20 to 21
    // (a box the camera rays never cross): light reaches the plane through 1 unit.
    let wall = |extra: &str| {
        format!(
            r#"<Volume id="wall"><Box><Min>20 -50 -50</Min><Max>21 50 50</Max></Box>
            <Absorption>0.5 1 2</Absorption><Scattering>0 0 0</Scattering>{extra}</Volume>"#
        )
    };
    let light = "40 0 5";
    let lit = render(&scene(9, plane, "", light), &[]);
    let shaded = render(&scene(9, plane, &wall(""), light), &[]);
    let marched = render(
        &scene(9, plane, &wall("<Shader>one.lua</Shader><StepSize>0.03</StepSize>"), light),
        &[("one.lua", "function density(s) return 1 end")],
    );
    let l = centre(&lit);
    assert!(l[0] > 1.0, "the plane is lit: {l:?}");
    // The shadow ray leaves the plane's centre for (40, 0, 5): it crosses the
    // slab's 1-unit x extent over a path longer by |d|/|d.x|.
    let dir = luster::math::Vec3::new(40.0, 0.0, 8.0).normalize();
    let path = 1.0 / dir.x;
    let want = [l[0] * (-0.5 * path).exp(), l[1] * (-path).exp(), l[2] * (-2.0 * path).exp()];
    assert_within_1_percent(centre(&shaded), want);
    assert_within_1_percent(centre(&marched), want);
}

/// A hypertexture whose density is constant in a ball is that ball: its
/// silhouette (and shading, with the bound's normal) matches the analytic
/// sphere's. One whose density falls off from the centre, thresholded at a
/// radius, matches that sphere to within a pixel on the silhouette.
#[test]
fn a_constant_density_isosurface_is_the_sphere() {
    let sphere = r#"<Sphere id="1"><Material>1</Material><Center>1</Center><Radius>0.7</Radius></Sphere>"#;
    let hyper = |bound_r: f32, shader: &str| {
        format!(
            r#"<Hypertexture id="h"><Sphere><Center>0 0 0</Center><Radius>{bound_r}</Radius></Sphere>
            <Material>1</Material><Shader>{shader}</Shader><Threshold>0.5</Threshold></Hypertexture>"#
        )
    };
    let analytic = render(&scene(64, sphere, "", "2 3 10"), &[]);
    let mask = |img: &RenderedImage| -> Vec<bool> {
        img.pixels.iter().map(|p| (p.x - 200.0).abs() > 1e-3 || (p.y - 100.0).abs() > 1e-3).collect()
    };
    let constant = render(
        &scene(64, "", &hyper(0.7, "one.lua"), "2 3 10"),
        &[("one.lua", "function density(s) return 1 end")],
    );
    assert_eq!(mask(&constant), mask(&analytic), "silhouettes differ");
    let worst = analytic
        .pixels
        .iter()
        .zip(&constant.pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0.0, f32::max);
    assert!(worst < 0.05, "shading differs by {worst}");

    // density = 1 − |P| / 1.4 crosses 0.5 at |P| = 0.7, inside a 1.0 bound.
    let falloff = render(
        &scene(64, "", &hyper(1.0, "ball.lua"), "2 3 10"),
        &[("ball.lua", "function density(s) return 1 - length(s.P) / 1.4 end")],
    );
    let (a, b) = (mask(&analytic), mask(&falloff));
    let differing = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    let silhouette = a.iter().filter(|&&x| x).count();
    // The silhouette of a 0.7 sphere is a ~45-pixel-wide disc: ~140 edge pixels.
    assert!(differing <= 12, "{differing} pixels differ (of {silhouette} covered)");
}

/// A dense scattering medium between the light and a plane darkens the
/// plane (volumes cast shadows), and an opaque sphere between the light and
/// a medium darkens the medium (surfaces shadow volumes).
#[test]
fn volumes_cast_and_receive_shadows() {
    let plane = r#"<Plane id="1"><Material>1</Material><Point>2</Point><Normal>0 0 1</Normal></Plane>"#;
    // The cloud sits halfway between the plane's centre (0, 0, −3) and the
    // light (10, 0, 10), away from the camera's rays: light reaching the
    // centre crosses 1 unit of it at σt = 3, keeping e⁻³ ≈ 5%.
    let cloud = r#"<Volume id="c"><Sphere><Center>5 0 3.5</Center><Radius>0.5</Radius></Sphere>
        <Absorption>1 1 1</Absorption><Scattering>2 2 2</Scattering></Volume>"#;
    let without = centre(&render(&scene(9, plane, "", "10 0 10"), &[]));
    let with = centre(&render(&scene(9, plane, cloud, "10 0 10"), &[]));
    let want = without[0] * (-3.0f32).exp();
    assert!((with[0] - want).abs() < 0.01 * want, "{with:?} vs {want} (unshadowed {without:?})");

    // A medium seen against black, lit from the side; then a sphere blocks the light.
    let lit_cloud = r#"<Volume id="c"><Sphere><Center>0 0 0</Center><Radius>0.5</Radius></Sphere>
        <Absorption>0.1 0.1 0.1</Absorption><Scattering>1 1 1</Scattering></Volume>"#;
    let blocker = r#"<Sphere id="1"><Material>1</Material><Center>2</Center><Radius>0.3</Radius></Sphere>"#;
    let black = |xml: String| xml.replace("<BackgroundColor>200 100 50</BackgroundColor>", "");
    let open = centre(&render(&black(scene(9, "", lit_cloud, "10 0 0")), &[]));
    let blocked =
        centre(&render(&black(scene(9, blocker, lit_cloud, "10 0 0").replace("0 0 -3", "5 0 0")), &[]));
    assert!(open[0] > 5.0, "the medium scatters light: {open:?}");
    assert!(blocked[0] < open[0] * 0.05, "the sphere shadows the medium: {blocked:?} vs {open:?}");
}

/// More scattering octaves brighten a dense, lit medium (light that would
/// scatter more than once), and one octave is plain single scattering.
#[test]
fn scattering_octaves_brighten_a_dense_medium() {
    let cloud = |extra: &str| {
        format!(
            r#"<Volume id="c"><Sphere><Center>0 0 0</Center><Radius>0.5</Radius></Sphere>
            <Absorption>0.05 0.05 0.05</Absorption><Scattering>6 6 6</Scattering>{extra}</Volume>"#
        )
    };
    let black = |xml: String| xml.replace("<BackgroundColor>200 100 50</BackgroundColor>", "");
    let one = centre(&render(&black(scene(9, "", &cloud(""), "10 0 0")), &[]));
    let same = centre(&render(
        &black(scene(9, "", &cloud("<ScatteringOctaves>1</ScatteringOctaves>"), "10 0 0")),
        &[],
    ));
    let three = centre(&render(
        &black(scene(9, "", &cloud("<ScatteringOctaves>3</ScatteringOctaves>"), "10 0 0")),
        &[],
    ));
    assert_eq!(one, same);
    assert!(three[0] > one[0] * 1.2, "{three:?} vs {one:?}");
}

/// A script's density baked on a grid renders close to the script itself.
#[test]
fn a_baked_grid_renders_like_its_script() {
    let script = "function density(s) return 0.5 + 0.5 * fbm(s.P.x * 2, s.P.y * 2, s.P.z * 2, 3) end";
    let vol = |extra: &str| {
        format!(
            r#"<Volume id="v"><Sphere><Center>0 0 0</Center><Radius>0.9</Radius></Sphere><Shader>fog.lua</Shader>
            <Absorption>0.5 0.5 0.5</Absorption><Scattering>1 1 1</Scattering><Density>2</Density>{extra}</Volume>"#
        )
    };
    let exact = render(&scene(32, "", &vol(""), "5 5 10"), &[("fog.lua", script)]);
    let baked =
        render(&scene(32, "", &vol("<GridResolution>64</GridResolution>"), "5 5 10"), &[("fog.lua", script)]);
    let n = exact.pixels.len() as f32;
    let mean_err =
        exact.pixels.iter().zip(&baked.pixels).map(|(a, b)| (*a - *b).abs().max_element()).sum::<f32>() / n;
    assert!(mean_err < 1.5, "mean difference {mean_err} (0–255 scale)");
}

/// A failing density script stops the render with the volume named; a
/// script without density() is refused when the scene is built.
#[test]
fn density_script_errors_name_the_volume() {
    let xml = scene(
        9,
        "",
        r#"<Volume id="smoke"><Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere><Shader>bad.lua</Shader></Volume>"#,
        "0 0 20",
    );
    let dir = folder(&[("s.xml", &xml), ("bad.lua", "function density(s)\n  error('no density here')\nend")]);
    let e = render_file(&dir.path().join("s.xml"), 1).err().expect("the render fails");
    for w in ["bad.lua:2", "no density here", "Volume[id=smoke]"] {
        assert!(e.contains(w), "{w:?} missing from {e:?}");
    }
    let dir = folder(&[("s.xml", &xml), ("bad.lua", "function color(s) return 1, 1, 1 end")]);
    let e = render_file(&dir.path().join("s.xml"), 1).err().expect("the build fails");
    assert!(e.contains("defines no density(s)") && e.contains("Volume"), "{e}");
}
