//! Shaders that drive the BSDF (`DecalMode material`, `docs/shaders.md`
//! "Material outputs") in whole renders: an emissive shader lights a floor
//! with the analytic irradiance in the path tracer, shows as itself in the
//! recursive ray tracer, and a roughness output widens a highlight.

use luster::render::{RenderedImage, Scene};
use luster::scene::Description;

use crate::common::{load_with as load, render_spp as render};

/// A diffuse floor (albedo 0.5, normalized Phong: `ρ/π`) under a sphere of
/// radius 0.5 centred 2 above the origin whose only light is a shader's
/// `emission(s)` of 10; a narrow camera looks at the origin. The sphere is
/// a light of the scene (a `Light::Shaded`, sampled by its cone under NEE
/// and MIS); the radiance leaving the floor there is
/// `ρ/π · π L R²/d² = 0.5 · 10 · 0.25 / 4 = 0.3125`.
fn glowing_sphere(renderer: &str, position: &str, gaze: &str) -> String {
    glowing(
        renderer,
        position,
        gaze,
        r#"<Sphere id="2"><Material>2</Material><Textures>1</Textures><Center>2</Center><Radius>0.5</Radius></Sphere>"#,
    )
}

/// The floor scene of [`glowing_sphere`] with `emitter` (using vertex 2,
/// `0 2 0`, and vertices 3–6, a unit square at height 2) above it.
fn glowing(renderer: &str, position: &str, gaze: &str, emitter: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>1</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>{position}</Position><GazePoint>{gaze}</GazePoint><Up>0 1 0</Up>
    <FovY>1</FovY><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
    <ImageName>a.exr</ImageName>{renderer}</Camera></Cameras>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <Textures><TextureMap id="1" type="shader"><Shader>glow.lua</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <VertexData>0 0 0  0 2 0  -0.5 2 -0.5  0.5 2 -0.5  0.5 2 0.5  -0.5 2 0.5</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    {emitter}
  </Objects>
</Scene>"#
    )
}

const GLOW: &str = "function emission(s) return 10, 10, 10 end";

fn green(img: &RenderedImage) -> Vec<f64> {
    img.pixels.iter().map(|p| f64::from(p.y)).collect()
}

/// Mean of two seeds' renders of `desc` at 64 spp, its standard error, and
/// the variance of one pixel's estimate. The two seeds' pixel-by-pixel
/// differences give that variance (var(a - b) = 2σ²) without assuming the
/// pixels share one true value; the mean of both renders then has standard
/// error σ / sqrt(2n).
fn two_seeds(desc: &Description) -> (f64, f64, f64) {
    let (a, b) = (green(&render(desc, 64, 1)), green(&render(desc, 64, 2)));
    let n = a.len() as f64;
    let var = a.iter().zip(&b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / (2.0 * n);
    let mean = (a.iter().sum::<f64>() + b.iter().sum::<f64>()) / (2.0 * n);
    (mean, (var / (2.0 * n)).sqrt(), var)
}

fn path_tracer(params: &str) -> String {
    format!("<Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams>")
}

/// The mean over the 16×16 pixel centres of the radiance the floor sends
/// to the camera at `0 1 3` looking at the origin (FovY 1°) under the
/// sphere of [`glowing_sphere`]: at a floor point at distance `D` from the
/// sphere's centre `(0, 2, 0)`, `ρ/π · π L (R/D)² cos α = ρ L R² · 2 / D³`
/// (the sphere lies wholly above the floor's horizon).
fn floor_mean_under_the_sphere() -> f64 {
    let (eye, up) = ([0.0, 1.0, 3.0f64], [0.0, 1.0, 0.0f64]);
    let len = |v: [f64; 3]| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    let unit = |v: [f64; 3]| v.map(|c| c / len(v));
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    };
    let fwd = unit(eye.map(|c| -c));
    let right = unit(cross(fwd, up));
    let true_up = cross(right, fwd);
    let half = 0.5f64.to_radians().tan();
    let mut sum = 0.0;
    for j in 0..16 {
        for i in 0..16 {
            let (sx, sy) =
                ((2.0 * (i as f64 + 0.5) / 16.0 - 1.0) * half, (1.0 - 2.0 * (j as f64 + 0.5) / 16.0) * half);
            let d: [f64; 3] = std::array::from_fn(|k| fwd[k] + sx * right[k] + sy * true_up[k]);
            let t = -eye[1] / d[1];
            let (x, z) = (eye[0] + t * d[0], eye[2] + t * d[2]);
            let dist = (x * x + 4.0 + z * z).sqrt();
            sum += 0.5 * 10.0 * 0.25 * 2.0 / dist.powi(3);
        }
    }
    sum / 256.0
}

#[test]
fn an_emissive_shader_lights_a_floor_with_the_analytic_irradiance() {
    let dir = tempfile::tempdir().expect("temp dir");
    let expected = floor_mean_under_the_sphere();
    // The slanted view spreads the pixels along z, where the radiance falls.
    assert!(expected < 0.3125 * (1.0 - 5e-4) && expected > 0.3125 * 0.995, "{expected}");
    let mut variance = Vec::new();
    for params in ["MIS", "NextEventEstimation ImportanceSampling", "ImportanceSampling"] {
        let desc =
            load(dir.path(), &glowing_sphere(&path_tracer(params), "0 1 3", "0 0 0"), &[("glow.lua", GLOW)]);
        let (mean, se, var) = two_seeds(&desc);
        let z = (mean - expected) / se;
        println!("{params:<40} mean {mean:.5} ± {se:.5} (expected {expected:.5}), z = {z:.2}, pixel variance {var:.3e}");
        // A sampled cone that the sphere fills has next to no variance; the
        // bar's floor, 1e-4 of the value, covers taking each pixel's centre
        // for its footprint.
        assert!(
            (mean - expected).abs() < 4.0 * se + 1e-4 * expected,
            "{params}: mean {mean:.5} ± {se:.5}, expected {expected:.5}"
        );
        variance.push(var);
    }
    // Bounces alone find the sphere with probability (R/d)² = 1/16, so a
    // pixel's estimate is mostly 0 or 16 times the mean; sampled as a light
    // (MIS, NEE) the glowing sphere lights the floor almost without noise.
    let [mis, nee, bounces] = variance[..] else { unreachable!() };
    println!("pixel variance, bounces only / MIS: {:.0}, / NEE: {:.0}", bounces / mis, bounces / nee);
    assert!(
        mis * 100.0 < bounces && nee * 100.0 < bounces,
        "variance MIS {mis}, NEE {nee}, bounces {bounces}"
    );
}

#[test]
fn an_emissive_shader_on_a_mesh_is_sampled_like_a_light_mesh() {
    // A unit square at height 2 over the floor, glowing by a shader or as a
    // LightMesh of the same radiance: both give the analytic
    // `ρ L · 4 F`, F the form factor from the origin to a quarter of the
    // square (a corner-aligned 0.5 × 0.5 rectangle at height 2).
    let dir = tempfile::tempdir().expect("temp dir");
    let (a, b) = (0.25f64, 0.25f64);
    let corner = |a: f64, b: f64| a / (1.0 + a * a).sqrt() * (b / (1.0 + a * a).sqrt()).atan();
    let form = (corner(a, b) + corner(b, a)) / (2.0 * std::f64::consts::PI);
    let expected = 0.5 * 10.0 * 4.0 * form;
    let shaded =
        r#"<Mesh id="2"><Material>2</Material><Textures>1</Textures><Faces>3 4 5 5 6 3</Faces></Mesh>"#;
    let light = r#"<LightMesh id="2"><Material>2</Material><Faces>3 4 5 5 6 3</Faces><Radiance>10 10 10</Radiance></LightMesh>"#;
    for params in ["MIS", "NextEventEstimation ImportanceSampling"] {
        let mut means = Vec::new();
        for emitter in [shaded, light] {
            let text = glowing(&path_tracer(params), "0 1 3", "0 0 0", emitter);
            let (mean, se, _) = two_seeds(&load(dir.path(), &text, &[("glow.lua", GLOW)]));
            println!(
                "{params:<40} {:<9} mean {mean:.5} ± {se:.5} (at the origin {expected:.5})",
                &emitter[1..10]
            );
            // The slanted view spreads the pixels over ±0.09 of the floor
            // along z, where the irradiance falls by up to 0.4%: the mean
            // lies about 0.15% below the value at the origin.
            let rel = mean / expected - 1.0;
            assert!(
                (-0.005..0.001).contains(&rel),
                "{params}, {emitter}: mean {mean:.5} ± {se:.5}, {expected:.5}"
            );
            means.push((mean, se));
        }
        // The same pixels under the same density: equal within the noise.
        let ((m1, s1), (m2, s2)) = (means[0], means[1]);
        let bar = 4.0 * (s1 * s1 + s2 * s2).sqrt() + 1e-4 * m2;
        assert!(
            (m1 - m2).abs() < bar,
            "{params}: shader {m1:.5} ± {s1:.5} against LightMesh {m2:.5} ± {s2:.5}"
        );
    }
}

#[test]
fn only_objects_whose_shader_emits_become_lights() {
    let dir = tempfile::tempdir().expect("temp dir");
    let lights = |shader: &str| {
        let desc =
            load(dir.path(), &glowing_sphere(&path_tracer("MIS"), "0 1 3", "0 0 0"), &[("glow.lua", shader)]);
        Scene::build(&desc).expect("scene builds").lights.len()
    };
    assert_eq!(lights(GLOW), 1);
    // Emission defined but zero everywhere: no light, so no light samples.
    assert_eq!(lights("function emission(s) return 0, 0, 0 end"), 0);
    // Emission on part of the surface only (the upper half) is found.
    assert_eq!(lights("function emission(s) if s.P.y > 2.2 then return 5, 5, 5 end return 0, 0, 0 end"), 1);
}

#[test]
fn the_recursive_ray_tracer_shows_an_emissive_shader_as_it_is() {
    // Looking straight at the sphere: its black material reflects nothing,
    // so every pixel is exactly the emission.
    let dir = tempfile::tempdir().expect("temp dir");
    let desc = load(dir.path(), &glowing_sphere("", "0 2 3", "0 2 0"), &[("glow.lua", GLOW)]);
    let img = render(&desc, 1, 0);
    assert!(img.pixels.iter().all(|p| p.to_array() == [10.0; 3]), "{:?}", &img.pixels[..4]);
}

/// A white metal sphere under a point light beside the camera, its
/// roughness from a shader parameter, in the recursive ray tracer.
fn highlight(roughness: f64) -> Vec<f64> {
    let dir = tempfile::tempdir().expect("temp dir");
    let text = format!(
        r#"<Scene>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>128 128</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <Lights><PointLight id="1"><Position>0 0 5</Position><Intensity>1000 1000 1000</Intensity></PointLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance><SpecularReflectance>0.04 0.04 0.04</SpecularReflectance></Material></Materials>
  <Textures><TextureMap id="1" type="shader"><Shader>metal.lua</Shader><DecalMode>material</DecalMode>
    <Parameter name="roughness">{roughness}</Parameter></TextureMap></Textures>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#
    );
    let metal = "params { roughness = 0.3 }\n\
                 function metalness(s) return 1 end\n\
                 function roughness(s) return param.roughness end";
    green(&render(&load(dir.path(), &text, &[("metal.lua", metal)]), 1, 0))
}

#[test]
fn a_roughness_output_widens_the_highlight() {
    // The highlight's area, counted as pixels above half its peak: GGX's
    // half-maximum cone grows about as α² = roughness⁴, so doubling the
    // roughness should grow the area by an order of magnitude.
    let area = |v: &[f64]| {
        let peak = v.iter().copied().fold(0.0, f64::max);
        assert!(peak > 0.0);
        v.iter().filter(|&&x| x > 0.5 * peak).count()
    };
    let (narrow, wide) = (area(&highlight(0.2)), area(&highlight(0.4)));
    println!("pixels above half the peak: roughness 0.2: {narrow}, 0.4: {wide}");
    assert!(narrow >= 1 && wide >= 6 * narrow, "roughness 0.2: {narrow} pixels, 0.4: {wide}");
}

#[test]
fn a_require_escape_is_a_one_sentence_error_with_exit_code_2() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = glowing_sphere("", "0 2 3", "0 2 0");
    std::fs::write(dir.path().join("s.xml"), scene).expect("scene");
    std::fs::write(
        dir.path().join("glow.lua"),
        "local x = require '../secret'\nfunction emission(s) return 1, 1, 1 end",
    )
    .expect("shader");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["render", "-q", "-o"])
        .arg(dir.path().join("out"))
        .arg(dir.path().join("s.xml"))
        .output()
        .expect("luster runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("glow.lua:1") && err.contains("'../secret' is not a module name"), "{err}");
    // A --shader-lib that is not a folder is refused before anything runs.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["render", "-q", "--shader-lib"])
        .arg(dir.path().join("nope"))
        .arg(dir.path().join("s.xml"))
        .output()
        .expect("luster runs");
    assert_eq!(out.status.code(), Some(2));
}
