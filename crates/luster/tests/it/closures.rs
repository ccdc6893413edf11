//! Shader closures (`docs/closures.md`) in whole renders, judged without
//! reference images: white furnaces (a closure that loses no energy, under
//! a uniform white sky, looks exactly as bright as the sky), light samples
//! against plain bounces through a transmitting closure, the recursive ray
//! tracer's approximation, and bad closures as one-sentence errors.

use crate::common::{two_seed_mean, white_sky};
use luster::render::RenderedImage;
use luster::scene::Description;
use std::path::Path;

fn load(dir: &Path, text: &str, shader: &str) -> Description {
    crate::common::load_with(dir, text, &[("m.lua", shader)])
}

use crate::common::render_spp as render;

/// A unit sphere at the origin, its material the closure of `m.lua`, seen
/// from +z under the white sky, by `renderer`.
fn sphere_under_sky(renderer: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>48</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName>{renderer}</Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images>
    <TextureMap id="1" type="shader"><Shader>m.lua</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#
    )
}

/// Pixels whose centre ray hits the sphere inside 0.9 of its radius.
fn inner(img: &RenderedImage) -> Vec<usize> {
    let half = 15f32.to_radians().tan() * 5.0;
    (0..img.pixels.len())
        .filter(|&i| {
            let x = ((i % img.width as usize) as f32 + 0.5) / img.width as f32 * 2.0 - 1.0;
            let y = ((i / img.width as usize) as f32 + 0.5) / img.height as f32 * 2.0 - 1.0;
            (x * x + y * y).sqrt() * half < 0.9
        })
        .collect()
}

fn luminance(p: luster::math::Vec3) -> f64 {
    f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z)
}

/// The mean luminance over `pixels` of two seeds' renders, its standard
/// error from the two seeds' pixel differences (var(a − b) = 2σ²), and the
/// smallest and largest pixel of the mean image.
fn two_seeds(desc: &Description, spp: u32) -> (f64, f64, f64, f64) {
    let (a, b) = (render(desc, spp, 1), render(desc, spp, 2));
    let px = inner(&a);
    let (la, lb): (Vec<f64>, Vec<f64>) =
        px.iter().map(|&i| (luminance(a.pixels[i]), luminance(b.pixels[i]))).unzip();
    let (mean, se) = two_seed_mean(&la, &lb);
    let both: Vec<f64> = la.iter().zip(&lb).map(|(x, y)| 0.5 * (x + y)).collect();
    let lo = both.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = both.iter().copied().fold(0.0, f64::max);
    (mean, se, lo, hi)
}

const MIS: &str = "<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>";

/// Closures that keep all the light: under a white sky of radiance 1 every
/// pixel of the sphere is 1, whatever the lobe's roughness; a closure that
/// lost the light between microfacets (single scattering) would be visibly
/// darker at high roughness.
#[test]
fn white_closures_pass_the_furnace() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let cases = [
        ("diffuse", "diffuse{albedo = 1}"),
        ("rough diffuse", "diffuse{albedo = 1, roughness = 0.7}"),
        ("conductor 0.2", "conductor{f0 = 1, roughness = 0.2}"),
        ("conductor 0.6", "conductor{f0 = 1, roughness = 0.6}"),
        ("conductor 1.0", "conductor{f0 = 1, roughness = 1}"),
        ("anisotropic conductor", "conductor{f0 = 1, roughness = 0.5, anisotropy = 0.8}"),
        (
            "coat over white",
            "layer{top = dielectric{ior = 1.5, roughness = 0.2}, base = diffuse{albedo = 1}}",
        ),
        ("glass", "dielectric{ior = 1.5, roughness = 0.3}"),
        ("thin glass", "dielectric{ior = 1.5, roughness = 0.3, thin = true}"),
        ("openpbr white", "openpbr{base_color = 1}"),
        ("openpbr white metal", "openpbr{base_color = 1, base_metalness = 1, specular_roughness = 0.7}"),
        ("openpbr coated", "openpbr{base_color = 1, coat_weight = 1, coat_roughness = 0.3}"),
    ];
    for (name, closure) in cases {
        let shader = format!("function material(s)\n  local c = {closure}\n  return c\nend\n");
        let desc = load(dir.path(), &sphere_under_sky(MIS), &shader);
        let (mean, se, lo, hi) = two_seeds(&desc, 64);
        println!("{name:<24} mean {mean:.4} ± {se:.4}, pixels {lo:.3}–{hi:.3}");
        assert!(mean > 0.99 - 4.0 * se && mean < 1.01 + 4.0 * se, "{name}: {mean:.4} ± {se:.4}");
    }
}

/// A furnace that fails is seen to fail: a grey closure is as grey as its
/// albedo.
#[test]
fn a_grey_closure_is_as_bright_as_its_albedo() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let desc = load(
        dir.path(),
        &sphere_under_sky(MIS),
        "function material(s) return 0.5 * diffuse{albedo = 0.8} end",
    );
    let (mean, se, _, _) = two_seeds(&desc, 16);
    assert!((mean - 0.4).abs() < 4.0 * se + 1e-3, "{mean} ± {se}");
}

/// A floor under a square lamp, a rough glass pane between them: the
/// floor's light comes through the pane. Light samples through the
/// surface (alone, and weighed with bounces by MIS) and plain bounces (no
/// light samples) must agree.
#[test]
fn light_through_a_rough_pane_agrees_between_light_samples_and_bounces() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = |params: &str| {
        format!(
            r#"<Scene>
  <MaxRecursionDepth>6</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0.9 0.01</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>10</FovY><NearDistance>1</NearDistance><ImageResolution>12 12</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams></Camera></Cameras>
  <Textures><TextureMap id="1" type="shader"><Shader>m.lua</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.8 0.8 0.8</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>
  </Materials>
  <VertexData>0 0 0  -1 1 -1  1 1 -1  1 1 1  -1 1 1  -1 2 -1  1 2 -1  1 2 1  -1 2 1</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <Mesh id="2"><Material>2</Material><Textures>1</Textures><Faces>2 3 4 4 5 2</Faces></Mesh>
    <LightMesh id="3"><Material>2</Material><Faces>6 7 8 8 9 6</Faces><Radiance>5 5 5</Radiance></LightMesh>
  </Objects>
</Scene>"#
        )
    };
    let shader = "function material(s) return dielectric{ior = 1.5, roughness = 0.4, thin = true} end";
    let mut means = Vec::new();
    for params in ["MIS", "ImportanceSampling", "NextEventEstimation ImportanceSampling"] {
        let desc = load(dir.path(), &scene(params), shader);
        let (a, b) = (render(&desc, 256, 1), render(&desc, 256, 2));
        let (la, lb): (Vec<f64>, Vec<f64>) =
            a.pixels.iter().zip(&b.pixels).map(|(x, y)| (luminance(*x), luminance(*y))).unzip();
        let (mean, se) = two_seed_mean(&la, &lb);
        println!("{params:<20} floor {mean:.4} ± {se:.4}");
        means.push((mean, se));
    }
    let [(mis, smis), (b, sb), (nee, snee)] = means[..] else { unreachable!() };
    assert!(b > 0.05, "light reaches the floor through the pane: {b}");
    for (name, a, sa) in [("MIS", mis, smis), ("light samples alone", nee, snee)] {
        let z = (a - b) / (sa * sa + sb * sb).sqrt();
        assert!(z.abs() < 4.0, "{name} {a:.4} ± {sa:.4} vs bounces {b:.4} ± {sb:.4}: z = {z:.2}");
    }
}

/// The recursive ray tracer renders a closure: a smooth metal mirrors the
/// sky, a diffuse closure is lit by a point light.
#[test]
fn the_recursive_tracer_approximates_closures() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let desc = load(dir.path(), &sphere_under_sky(""), "function material(s) return conductor{f0 = 0.9} end");
    let img = render(&desc, 1, 1);
    for &i in &inner(&img) {
        let l = luminance(img.pixels[i]);
        assert!((l - 0.9).abs() < 0.05, "a smooth metal mirrors the white sky: {l}");
    }
}

/// A bad closure stops the render with one sentence naming the shader, the
/// line and the parameter, and exit code 2.
#[test]
fn a_bad_closure_is_one_sentence_and_exit_code_2() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    for (code, want) in [
        (
            "function material(s)\n  local c = diffuse{albdo = 1}\n  return c\nend\n",
            "m.lua:2: diffuse{}: unknown parameter 'albdo'",
        ),
        ("function material(s)\n  local c = conductor{roughness = 1.5}\n  return c\nend\n", "roughness"),
        ("function material(s)\n  return 1\nend\n", "material() returned a number"),
        ("function material(s)\n  local c = diffuse{albedo = 0/0}\n  return c\nend\n", "albedo"),
    ] {
        std::fs::write(dir.path().join("m.lua"), code).expect("shader");
        std::fs::write(dir.path().join("s.xml"), sphere_under_sky(MIS)).expect("scene");
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_luster"))
            .args(["render", "-q", "--spp", "1", "-o"])
            .arg(dir.path().join("out"))
            .arg(dir.path().join("s.xml"))
            .output()
            .expect("luster runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{code}: {err}");
        assert!(err.contains("shader 'm'") && err.contains(want), "{code}: {err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{code}: {err}");
        assert!(!dir.path().join("out/a.exr").exists(), "no half-written image");
    }
}

/// The closures example scene loads, compiles every example shader and
/// renders (at a tenth of its size, one sample per pixel) without an error.
#[test]
fn the_closures_example_renders() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/scenes/closures.xml");
    let mut desc = luster::scene::load(&path).expect("the example loads");
    for cam in &mut desc.cameras {
        cam.resolution = (cam.resolution.0 / 10, cam.resolution.1 / 10);
    }
    let img = render(&desc, 1, 1);
    let mean = img.pixels.iter().map(|p| luminance(*p)).sum::<f64>() / img.pixels.len() as f64;
    assert!(mean > 0.0 && mean.is_finite(), "mean {mean}");
}
