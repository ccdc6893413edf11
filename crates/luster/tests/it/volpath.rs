//! Media in the path tracer, judged without reference images: white
//! furnaces (a medium that only scatters, of any density and colour, alone,
//! overlapping another or inside glass, looks exactly as bright as the
//! uniform sky around it; single scattering fails this), transmittance
//! through homogeneous and graded slabs against exp(−∫σt), emission against
//! its integral, and light samples from inside a medium against plain
//! phase-function bounces.

use crate::common::{two_seed_mean, white_sky};
use luster::render::RenderedImage;
use luster::scene::Description;

use crate::common::{load_with as load, render_spp as render};

const MIS: &str = "<Renderer>PathTracing</Renderer><RendererParams>MIS RussianRoulette</RendererParams>";

/// Media (and objects) around the origin, seen from +z under the white sky.
fn under_sky(objects: &str, volumes: &str, res: u32) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>8</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>{res} {res}</ImageResolution>
    <ImageName>a.exr</ImageName>{MIS}</Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials><Material id="1" type="dielectric"><DiffuseReflectance>0 0 0</DiffuseReflectance>
    <MirrorReflectance>1 1 1</MirrorReflectance><RefractionIndex>1.5</RefractionIndex><AbsorptionCoefficient>0 0 0</AbsorptionCoefficient></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects>{objects}</Objects>
  <Volumes>{volumes}</Volumes>
</Scene>"#
    )
}

fn medium(
    id: &str,
    center: &str,
    radius: f32,
    density: f32,
    scattering: &str,
    g: f32,
    extra: &str,
) -> String {
    format!(
        r#"<Volume id="{id}"><Sphere><Center>{center}</Center><Radius>{radius}</Radius></Sphere>
   <Density>{density}</Density><Absorption>0 0 0</Absorption><Scattering>{scattering}</Scattering>
   <Anisotropy>{g}</Anisotropy>{extra}</Volume>"#
    )
}

/// Per-channel mean over the pixels whose centre ray passes within
/// `within` of the image centre (in units of the half-width), of two seeds'
/// renders, with its standard error from the two seeds' differences.
fn mean_two_seeds(desc: &Description, spp: u32, within: f32) -> ([f64; 3], [f64; 3]) {
    let (a, b) = (render(desc, spp, 1), render(desc, spp, 2));
    let w = a.width as usize;
    let px: Vec<usize> = (0..a.pixels.len())
        .filter(|&i| {
            let x = ((i % w) as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let y = ((i / w) as f32 + 0.5) / a.height as f32 * 2.0 - 1.0;
            (x * x + y * y).sqrt() < within
        })
        .collect();
    let mut mean = [0.0; 3];
    let mut se = [0.0; 3];
    for c in 0..3 {
        let (la, lb): (Vec<f64>, Vec<f64>) =
            px.iter().map(|&i| (f64::from(a.pixels[i][c]), f64::from(b.pixels[i][c]))).unzip();
        (mean[c], se[c]) = two_seed_mean(&la, &lb);
    }
    (mean, se)
}

/// Media that scatter without absorbing keep all the light: under a white
/// sky of radiance 1 they are 1 in every channel, thin or dense, grey or
/// coloured (σs different per channel), forward or backward scattering,
/// overlapping, baked from a script, or inside a glass ball.
#[test]
fn scattering_media_pass_the_furnace() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let blob = "function density(s) local r = s.P:length(); return math.max(0, 1 - r * r) * 2 end";
    let glass = r#"<Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1.2</Radius></Sphere>"#;
    let cases: Vec<(&str, String, &str)> = vec![
        ("thin", medium("m", "0 0 0", 1.0, 0.5, "1 1 1", 0.0, ""), ""),
        ("dense, forward", medium("m", "0 0 0", 1.0, 8.0, "1 1 1", 0.6, ""), ""),
        ("coloured, backward", medium("m", "0 0 0", 1.0, 4.0, "0.3 1 3", -0.4, ""), ""),
        (
            "overlapping",
            medium("a", "-0.4 0 0", 0.8, 3.0, "1 1 1", 0.3, "")
                + &medium("b", "0.4 0 0", 0.8, 2.0, "2 1 0.5", 0.0, ""),
            "",
        ),
        (
            "baked script",
            medium(
                "m",
                "0 0 0",
                1.0,
                3.0,
                "1 1 1",
                0.2,
                "<Shader>blob.lua</Shader><GridResolution>24</GridResolution>",
            ),
            "",
        ),
        ("inside glass", medium("m", "0 0 0", 1.0, 2.0, "1 1 1", 0.0, ""), glass),
    ];
    let interior = r#"<Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius><Interior>w</Interior></Sphere>"#;
    let white = under_sky(interior, "", 16).replace(
        "<VertexData>",
        "<Media><Medium id=\"w\"><Absorption>0 0 0</Absorption><Scattering>3 2 1</Scattering><Anisotropy>0.5</Anisotropy></Medium></Media>\n  <VertexData>",
    );
    let scenes = cases
        .iter()
        .map(|(name, v, o)| (*name, under_sky(o, v, 16)))
        .chain([("glass filled with a medium", white)]);
    for (name, text) in scenes {
        let desc = load(dir.path(), &text, &[("blob.lua", blob)]);
        let (mean, se) = mean_two_seeds(&desc, 128, 0.45);
        println!("{name:<20} {mean:.4?} ± {se:.4?}");
        for c in 0..3 {
            assert!(
                (mean[c] - 1.0).abs() < 4.0 * se[c] + 2e-3,
                "{name}, channel {c}: {:.4} ± {:.4}",
                mean[c],
                se[c]
            );
        }
    }
}

/// A furnace that fails is seen to fail: a medium of albedo 0.5 under the
/// white sky is visibly darker than the sky.
#[test]
fn an_absorbing_medium_fails_the_furnace() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let v = r#"<Volume id="m"><Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere>
       <Density>4</Density><Absorption>1 1 1</Absorption><Scattering>1 1 1</Scattering></Volume>"#;
    let desc = load(dir.path(), &under_sky("", v, 16), &[]);
    let (mean, se) = mean_two_seeds(&desc, 32, 0.45);
    assert!(mean[1] < 0.8 && se[1] < 0.05, "{mean:?} ± {se:?}");
}

/// A camera on +z looking down −z through a 2-unit window at distance 4,
/// at a slab between z = −0.4 and 0.4 with the background (radiance given
/// in `bg`) behind it.
fn slab_scene(volume: &str, extra: &str) -> String {
    format!(
        r#"<Scene>
  <BackgroundColor>1 1 1</BackgroundColor>
  <Cameras><Camera id="1"><Position>0 0 10</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>4</NearDistance>
    <ImageResolution>8 8</ImageResolution><ImageName>a.exr</ImageName>{MIS}</Camera></Cameras>
  <Lights></Lights>
  <Materials></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects></Objects>
  <Volumes><Volume id="slab"><Box><Min>-5 -5 -0.4</Min><Max>5 5 0.4</Max></Box>{volume}</Volume></Volumes>
  {extra}
</Scene>"#
    )
}

/// Each pixel's path length through the slab over its thickness: 1 / |d.z|
/// of its centre ray (the camera jitters within the pixel; the pixels are
/// small enough that the mean of exp over a pixel is within 1e-4 of this).
fn slant(img: &RenderedImage, i: usize) -> f64 {
    let w = img.width as usize;
    let x = ((i % w) as f64 + 0.5) / w as f64 * 2.0 - 1.0;
    let y = 1.0 - ((i / w) as f64 + 0.5) / img.height as f64 * 2.0;
    (x * x + y * y + 16.0).sqrt() / 4.0
}

/// Absorption only: what comes through a homogeneous slab, and through a
/// slab whose density grows linearly across it (a baked grid, tracked
/// against its majorants), is exp(−σt ∫ρ) per channel within 0.5%.
#[test]
fn transmittance_matches_beer_lambert() {
    let dir = tempfile::tempdir().expect("temp dir");
    let sigma = [0.5f64, 1.0, 2.0];
    let cases = [
        ("homogeneous", "<Absorption>0.5 1 2</Absorption><Scattering>0 0 0</Scattering>".to_string(), 1.0),
        (
            "graded grid",
            // ρ = 1 + z/0.4 · 0.75 on z ∈ [−0.4, 0.4]: its mean across the slab is 1.
            "<Absorption>0.5 1 2</Absorption><Scattering>0 0 0</Scattering><Shader>ramp.lua</Shader><GridResolution>9</GridResolution>"
                .to_string(),
            1.0,
        ),
    ];
    let ramp = "function density(s) return 1 + s.P.z / 0.4 * 0.75 end";
    for (name, v, mean_rho) in cases {
        let desc = load(dir.path(), &slab_scene(&v, ""), &[("ramp.lua", ramp)]);
        let img = render(&desc, 4096, 1);
        let mut ratio = [0.0f64; 3];
        for i in 0..img.pixels.len() {
            for c in 0..3 {
                let want = (-sigma[c] * 0.8 * mean_rho * slant(&img, i)).exp();
                ratio[c] += f64::from(img.pixels[i][c]) / want / img.pixels.len() as f64;
            }
        }
        println!("{name:<12} got / exp(−σt·d): {ratio:.5?}");
        for (c, r) in ratio.iter().enumerate() {
            assert!((r - 1.0).abs() < 0.005, "{name}, channel {c}: {r:.5}");
        }
    }
}

/// An emitting, non-absorbing slab sends `ε · d` along a ray of length `d`
/// through it (emission per unit length, gathered at tentative collisions).
#[test]
fn emission_integrates_along_the_ray() {
    let dir = tempfile::tempdir().expect("temp dir");
    let v = "<Absorption>0.2 0.2 0.2</Absorption><Scattering>0 0 0</Scattering><Emission>1 2 3</Emission>";
    let text = slab_scene(v, "")
        .replace("<BackgroundColor>1 1 1</BackgroundColor>", "<BackgroundColor>0 0 0</BackgroundColor>");
    let desc = load(dir.path(), &text, &[]);
    let img = render(&desc, 2048, 1);
    let mut ratio = [0.0f64; 3];
    for i in 0..img.pixels.len() {
        let d = 0.8 * slant(&img, i);
        // ∫₀^d ε e^{−σ s} ds with ε = Emission · ρ, σ = 0.2.
        let base = (1.0 - (-0.2 * d).exp()) / 0.2;
        for (c, r) in ratio.iter_mut().enumerate() {
            *r += f64::from(img.pixels[i][c]) / (base * (c + 1) as f64) / img.pixels.len() as f64;
        }
    }
    println!("emission got / analytic: {ratio:.5?}");
    for (c, r) in ratio.iter().enumerate() {
        assert!((r - 1.0).abs() < 0.01, "channel {c}: {r:.5}");
    }
}

/// A scattering cloud over a floor, lit by a sphere lamp: light samples
/// from inside the medium (alone, and weighed with phase-function bounces
/// by MIS) and plain bounces must agree, block by block.
#[test]
fn light_samples_in_a_medium_agree_with_bounces() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = |params: &str| {
        format!(
            r#"<Scene>
  <MaxRecursionDepth>5</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 1 5</Position><GazePoint>0 0.6 0</GazePoint><Up>0 1 0</Up>
    <FovY>35</FovY><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams></Camera></Cameras>
  <Materials>
    <Material id="1"><DiffuseReflectance>0.6 0.6 0.6</DiffuseReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance></Material>
  </Materials>
  <VertexData>0 0 0  0 2.6 0</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <LightSphere id="2"><Material>2</Material><Center>2</Center><Radius>0.5</Radius><Radiance>6 6 6</Radiance></LightSphere>
  </Objects>
  <Volumes><Volume id="m"><Box><Min>-1 0.2 -1</Min><Max>1 1.6 1</Max></Box><Density>1.5</Density>
    <Absorption>0.2 0.2 0.2</Absorption><Scattering>0.8 0.7 0.6</Scattering><Anisotropy>0.5</Anisotropy></Volume></Volumes>
</Scene>"#
        )
    };
    let mut runs = Vec::new();
    for params in ["MIS", "NextEventEstimation", ""] {
        let desc = load(dir.path(), &scene(params), &[]);
        runs.push((params, render(&desc, 512, 1), render(&desc, 512, 2)));
    }
    // 4×4 blocks of 4×4 pixels: each block's mean luminance and its error.
    let blocks = |a: &RenderedImage, b: &RenderedImage| -> Vec<(f64, f64)> {
        let lum = |p: luster::math::Vec3| f64::from(0.2126 * p.x + 0.7152 * p.y + 0.0722 * p.z);
        (0..16)
            .map(|k| {
                let (bx, by) = (k % 4, k / 4);
                let px: Vec<usize> = (0..16).map(|j| (by * 4 + j / 4) * 16 + bx * 4 + j % 4).collect();
                let (la, lb): (Vec<f64>, Vec<f64>) =
                    px.iter().map(|&i| (lum(a.pixels[i]), lum(b.pixels[i]))).unzip();
                two_seed_mean(&la, &lb)
            })
            .collect()
    };
    let reference = blocks(&runs[2].1, &runs[2].2);
    let total: f64 = reference.iter().map(|b| b.0).sum::<f64>() / 16.0;
    assert!(total > 0.05, "the lamp lights the scene: {total}");
    for (params, a, b) in &runs[..2] {
        let got = blocks(a, b);
        let mut worst = 0.0f64;
        for (g, r) in got.iter().zip(&reference) {
            let z = (g.0 - r.0) / (g.1 * g.1 + r.1 * r.1).sqrt().max(1e-9);
            worst = worst.max(z.abs());
        }
        let mean: f64 = got.iter().map(|b| b.0).sum::<f64>() / 16.0;
        println!("{params:<20} mean {mean:.4} vs bounces {total:.4}, worst block |z| {worst:.2}");
        assert!(worst < 4.5, "{params}: a block differs from plain bounces by {worst:.2} standard errors");
    }
}

/// A sphere of ior 1 (a boundary that neither reflects nor bends light)
/// around `inside`, or nothing, with `volumes`, under the white sky and a
/// point light.
fn null_sphere(interior: &str, volumes: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>8</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
    <ImageName>a.exr</ImageName>{MIS}</Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1" type="latlong"><ImageId>1</ImageId></SphericalDirectionalLight>
    <PointLight id="2"><Position>3 3 3</Position><Intensity>20 20 20</Intensity></PointLight></Lights>
  <Materials><Material id="1" type="dielectric"><DiffuseReflectance>0 0 0</DiffuseReflectance>
    <MirrorReflectance>1 1 1</MirrorReflectance><RefractionIndex>1</RefractionIndex><AbsorptionCoefficient>0 0 0</AbsorptionCoefficient></Material></Materials>
  <Media><Medium id="milk"><Absorption>0.3 0.3 0.6</Absorption><Scattering>1.5 1.2 0.9</Scattering><Anisotropy>0.3</Anisotropy></Medium></Media>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius>{interior}</Sphere></Objects>
  <Volumes>{volumes}</Volumes>
</Scene>"#
    )
}

/// A medium filling an object (`<Interior>`), entered through its surface,
/// looks as the same medium in a bound of the same shape does: per channel,
/// within the two renders' combined noise.
#[test]
fn an_interior_medium_matches_a_bounded_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    white_sky(dir.path());
    let inside = load(dir.path(), &null_sphere("<Interior>milk</Interior>", ""), &[]);
    let (a, sa) = mean_two_seeds(&inside, 256, 0.45);
    let bounded = r#"<Volume id="m"><Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere>
        <Absorption>0.3 0.3 0.6</Absorption><Scattering>1.5 1.2 0.9</Scattering><Anisotropy>0.3</Anisotropy></Volume>"#;
    let volume = load(dir.path(), &null_sphere("", bounded), &[]);
    let (b, sb) = mean_two_seeds(&volume, 256, 0.45);
    println!("interior {a:.4?} ± {sa:.4?}, bounded {b:.4?} ± {sb:.4?}");
    for c in 0..3 {
        let z = (a[c] - b[c]) / (sa[c] * sa[c] + sb[c] * sb[c]).sqrt();
        assert!(z.abs() < 4.0, "channel {c}: interior {:.4} vs bounded {:.4}, z = {z:.2}", a[c], b[c]);
        assert!(a[c] < 0.95, "channel {c}: the medium dims the sky behind it: {:.4}", a[c]);
    }
}

/// An `<Interior>` naming no medium of `<Media>`, and a medium with a
/// negative coefficient or an anisotropy outside (−1, 1), are one
/// sentence naming the element.
#[test]
fn bad_media_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let cases = [
        (null_sphere("<Interior>cream</Interior>", ""), "cream"),
        (
            null_sphere("", "")
                .replace("<Absorption>0.3 0.3 0.6</Absorption>", "<Absorption>0.3 -1 0.6</Absorption>"),
            "Absorption",
        ),
        (
            null_sphere("", "").replace("<Anisotropy>0.3</Anisotropy>", "<Anisotropy>1.5</Anisotropy>"),
            "Anisotropy",
        ),
    ];
    for (text, word) in cases {
        let p = dir.path().join("s.xml");
        std::fs::write(&p, text).expect("temp file");
        let e = luster::scene::load(&p).expect_err("a bad medium is refused").to_string();
        assert!(e.contains(word) && e.contains("s.xml") && !e.contains('\n'), "{e}");
    }
}
