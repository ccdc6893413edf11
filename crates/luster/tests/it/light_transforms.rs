//! Every emitter under every transform, checked without a reference image:
//! in one scene, light samples (next-event estimation, and MIS) must agree
//! with plain BSDF bounces, and the recursive ray tracer's direct light with
//! the path tracer's direct-only estimate, block by block within their
//! noise (a z-test with each block's variance measured from a second seed).
//!
//! The scene is a diffuse floor and back wall (normalized Phong, `ρ/π`) lit
//! by one emitter that the camera does not see: object lights (`LightSphere`,
//! `LightMesh`, objects whose shader emits, instances of them) under
//! identity, rotation, uniform and non-uniform scale, shear and motion blur,
//! and the lights the format places without a transform (point, spot,
//! directional, square area, environment).

use crate::common::two_seed_mean;
use luster::scene::Description;
use std::path::Path;

/// Image side in pixels; the blocks are `BLOCK`² pixels.
const RES: usize = 16;
const BLOCK: usize = 4;

/// The transforms an object emitter is tried under (the light's placement,
/// `t1`, comes last).
const TRANSFORMS: [(&str, &str, &str); 6] = [
    ("identity", "t1", ""),
    ("rotation", "r1 t1", ""),
    ("uniform scale", "s2 r1 t1", ""),
    ("non-uniform scale", "s1 r1 t1", ""),
    ("shear", "c1 s3 t1", ""),
    ("motion blur", "r1 t1", "<MotionBlur>0 0.6 0.8</MotionBlur>"),
];

/// The box of side 0.5 at the origin, as vertices 3–10 and its faces.
const BOX_FACES: &str =
    "3 5 4  3 6 5  7 8 9  7 9 10  3 4 8  3 8 7  5 6 10  5 10 9  4 5 9  4 9 8  3 7 10  3 10 6";

/// The scene with `emitter` (objects, with `extra` elements beside
/// `<Objects>`) and the camera's `renderer`, at recursion depth `depth`.
fn scene(emitter: &str, extra: &str, renderer: &str, depth: u32) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>{depth}</MaxRecursionDepth>
  <BackgroundColor>0 0 0</BackgroundColor>
  <Cameras><Camera id="1" type="lookAt"><Position>0 7 2</Position><GazePoint>0 0 -0.5</GazePoint><Up>0 1 0</Up>
    <FovY>40</FovY><NearDistance>1</NearDistance><ImageResolution>{RES} {RES}</ImageResolution>
    <ImageName>a.exr</ImageName>{renderer}</Camera></Cameras>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <Textures><Images><Image id="1">sky.exr</Image></Images>
    <TextureMap id="1" type="shader"><Shader>glow.lua</Shader><DecalMode>material</DecalMode></TextureMap></Textures>
  <Transformations>
    <Translation id="1">3.6 1.4 -0.8</Translation>
    <Translation id="2">-3.6 1.4 -0.8</Translation>
    <Rotation id="1">35 0.3 1 0.6</Rotation>
    <Scaling id="1">3 0.5 1.4</Scaling>
    <Scaling id="2">1.6 1.6 1.6</Scaling>
    <Scaling id="3">1 1.6 0.7</Scaling>
    <Composite id="1">1 0.5 0 0  0 1 0 0  0.4 0 1 0  0 0 0 1</Composite>
  </Transformations>
  <VertexData>0 0 0  0 0 0
    -0.25 -0.25 -0.25  0.25 -0.25 -0.25  0.25 0.25 -0.25  -0.25 0.25 -0.25
    -0.25 -0.25 0.25  0.25 -0.25 0.25  0.25 0.25 0.25  -0.25 0.25 0.25
    0 0 -2.5</VertexData>
  {extra}
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <Plane id="2"><Material>1</Material><Point>11</Point><Normal>0 0 1</Normal></Plane>
    {emitter}
  </Objects>
</Scene>"#
    )
}

const GLOW: &str = "function emission(s) return 20, 16, 12 end";

fn path_tracer(params: &str) -> String {
    format!("<Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams>")
}

fn load(dir: &Path, text: &str) -> Description {
    crate::common::load_with(dir, text, &[("glow.lua", GLOW)])
}

use crate::common::render_spp as render;

/// Each block's mean luminance and its standard error, from two seeds.
fn blocks(desc: &Description, spp: u32) -> Vec<(f64, f64)> {
    let (a, b) = (render(desc, spp, 1), render(desc, spp, 2));
    let lum = |p: luster::math::Vec3| f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z);
    let side = RES / BLOCK;
    (0..side * side)
        .map(|k| {
            let (bx, by) = (k % side, k / side);
            let (la, lb): (Vec<f64>, Vec<f64>) = (0..BLOCK * BLOCK)
                .map(|j| (by * BLOCK + j / BLOCK) * RES + bx * BLOCK + j % BLOCK)
                .map(|i| (lum(a.pixels[i]), lum(b.pixels[i])))
                .unzip();
            two_seed_mean(&la, &lb)
        })
        .collect()
}

/// The largest |z| between two estimates' blocks, and their overall means.
fn worst_z(a: &[(f64, f64)], b: &[(f64, f64)]) -> (f64, f64, f64) {
    let z = a
        .iter()
        .zip(b)
        .map(|(x, y)| ((x.0 - y.0) / (x.1 * x.1 + y.1 * y.1).sqrt().max(1e-12)).abs())
        .fold(0.0, f64::max);
    let mean = |v: &[(f64, f64)]| v.iter().map(|x| x.0).sum::<f64>() / v.len() as f64;
    (z, mean(a), mean(b))
}

/// Above this many standard errors a block fails. Hundreds of blocks are
/// tested; a true difference of zero passes all of them with probability
/// above 99%.
const Z_MAX: f64 = 4.5;

/// An emitter to try: its objects, elements beside `<Objects>`, whether a
/// bounce can hit it, and whether the recursive ray tracer lights by it.
struct Case {
    name: String,
    objects: String,
    extra: String,
    hittable: bool,
    whitted: bool,
}

fn object_cases() -> Vec<Case> {
    let mut cases = Vec::new();
    for (tname, xf, motion) in TRANSFORMS {
        let tr = format!("<Transformations>{xf}</Transformations>{motion}");
        let sphere = |el: &str, inner: &str| {
            format!(
                r#"<{el} id="9"><Material>2</Material>{inner}<Center>2</Center><Radius>0.3</Radius>{tr}</{el}>"#
            )
        };
        let mesh = |el: &str, inner: &str| {
            format!(r#"<{el} id="9"><Material>2</Material>{inner}<Faces>{BOX_FACES}</Faces>{tr}</{el}>"#)
        };
        let case = |kind: &str, objects: String, whitted: bool| Case {
            name: format!("{kind}, {tname}"),
            objects,
            extra: String::new(),
            hittable: true,
            whitted,
        };
        cases.push(case("LightSphere", sphere("LightSphere", "<Radiance>40 32 24</Radiance>"), true));
        cases.push(case("LightMesh", mesh("LightMesh", "<Radiance>20 16 12</Radiance>"), true));
        cases.push(case("emissive sphere", sphere("Sphere", "<Textures>1</Textures>"), false));
        cases.push(case("emissive mesh", mesh("Mesh", "<Textures>1</Textures>"), false));
        // The base mesh glows on the far side of the room, out of view.
        let base = format!(
            r#"<Mesh id="8"><Material>2</Material><Textures>1</Textures><Faces>{BOX_FACES}</Faces><Transformations>t2</Transformations></Mesh>
    <MeshInstance id="9" baseMeshId="8" resetTransform="true"><Material>2</Material>{tr}</MeshInstance>"#
        );
        cases.push(case("emissive instance", base, false));
    }
    cases
}

fn placed_light_cases() -> Vec<Case> {
    let lights = |l: &str| format!("<Lights>{l}</Lights>");
    let case = |name: &str, extra: String, hittable: bool| Case {
        name: name.to_string(),
        objects: String::new(),
        extra,
        hittable,
        whitted: true,
    };
    vec![
        case(
            "point",
            lights(
                r#"<PointLight id="1"><Position>3 2 0</Position><Intensity>30 30 30</Intensity></PointLight>"#,
            ),
            false,
        ),
        case(
            "spot",
            lights(
                r#"<SpotLight id="1"><Position>2 3 1</Position><Direction>-0.5 -1 -0.5</Direction><Intensity>60 60 60</Intensity><CoverageAngle>70</CoverageAngle><FalloffAngle>40</FalloffAngle></SpotLight>"#,
            ),
            false,
        ),
        case(
            "directional",
            lights(
                r#"<DirectionalLight id="1"><Direction>-0.4 -1 -0.6</Direction><Radiance>2 2 2</Radiance></DirectionalLight>"#,
            ),
            false,
        ),
        case(
            "area",
            lights(
                r#"<AreaLight id="1"><Position>3 1.8 -0.5</Position><Normal>-0.6 -1 0.2</Normal><Size>0.8</Size><Radiance>20 20 20</Radiance></AreaLight>"#,
            ),
            false,
        ),
        case(
            "environment",
            format!(
                r#"<Textures><Images><Image id="1">sky.exr</Image></Images></Textures>{}"#,
                lights(
                    r#"<SphericalDirectionalLight id="1"><ImageId>1</ImageId></SphericalDirectionalLight>"#
                )
            ),
            true,
        ),
    ]
}

/// Light samples, MIS and plain bounces agree, and the recursive ray
/// tracer's direct light is the path tracer's direct-only estimate, for
/// every emitter under every transform.
#[test]
fn every_emitter_under_every_transform_is_estimated_without_bias() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut cases = object_cases();
    cases.extend(placed_light_cases());
    crate::common::white_sky(dir.path());
    let mut failures = Vec::new();
    for c in &cases {
        let run = |renderer: &str, depth: u32, spp: u32| {
            blocks(&load(dir.path(), &scene(&c.objects, &c.extra, renderer, depth)), spp)
        };
        let mis = run(&path_tracer("MIS"), 2, 64);
        let mut checks = vec![("NEE", run(&path_tracer("NextEventEstimation"), 2, 64), mis.clone())];
        // The course's variants without light samples stop at the last
        // vertex, where a light sample still adds that vertex's direct
        // light: they see the same paths one depth further.
        if c.hittable {
            checks.push(("bounces", run(&path_tracer("ImportanceSampling"), 3, 1024), mis.clone()));
        }
        if c.whitted {
            checks.push(("recursive, direct", run("", 0, 64), run(&path_tracer("MIS"), 0, 64)));
        }
        for (what, got, reference) in &checks {
            let (z, a, b) = worst_z(got, reference);
            println!("{:<32} {what:<18} {a:.4} against {b:.4}, worst block |z| {z:.2}", c.name);
            assert!(b > 1e-3, "{}: the light does not reach the room", c.name);
            if z >= Z_MAX {
                failures.push(format!("{}: {what} {a:.4} against {b:.4} (|z| {z:.1})", c.name));
            }
        }
    }
    assert!(failures.is_empty(), "biased estimates:\n{}", failures.join("\n"));
}
