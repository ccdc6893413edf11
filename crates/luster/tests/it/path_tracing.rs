//! Path tracing and object lights in whole renders: a scene with a known
//! answer rendered by every integrator variant, light not counted twice
//! under next-event estimation, an environment light inside the MIS path
//! tracer, and the progressive passes (thread- and pass-independent bytes; a
//! time limit that stops between passes).

use luster::render::{render_with, RenderOptions, RenderedImage, Scene};
use luster::scene::Description;
use std::path::Path;
use std::time::Duration;

fn load(dir: &Path, text: &str) -> Description {
    let p = dir.join("s.xml");
    std::fs::write(&p, text).expect("temp file");
    luster::scene::load(&p).expect("scene loads")
}

fn render(desc: &Description, opts: &RenderOptions) -> RenderedImage {
    let scene = Scene::build(desc).expect("scene builds");
    render_with(&scene, 0, opts, &|_| {})
}

/// A diffuse floor (albedo 0.5, normalized Phong without specular) under a
/// `LightSphere` of radius 0.5 and radiance 10 centred 2 above the origin; a
/// narrow camera looks at the origin. The radiance leaving the floor there
/// is `ρ/π · π L sin²θmax = ρ L R²/d² = 0.5 · 10 · 0.25 / 4 = 0.3125`, and
/// nothing else reaches the camera (one bounce: the light is black).
fn floor_scene(renderer: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>1</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 1 3</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>1</FovY><NearDistance>1</NearDistance><ImageResolution>16 16</ImageResolution>
    <ImageName>a.exr</ImageName>{renderer}</Camera></Cameras>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <VertexData>0 0 0  0 2 0</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <LightSphere id="1"><Material>2</Material><Center>2</Center><Radius>0.5</Radius><Radiance>10 10 10</Radiance></LightSphere>
  </Objects>
</Scene>"#
    )
}

/// Mean and standard error of the pixels' green channel.
fn mean_and_se(img: &RenderedImage) -> (f64, f64) {
    let v: Vec<f64> = img.pixels.iter().map(|p| f64::from(p.y)).collect();
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

#[test]
fn every_variant_finds_the_known_radiance_under_a_sphere_light() {
    let dir = tempfile::tempdir().expect("temp dir");
    let expected = 0.3125;
    let variants = [
        ("", 16),
        ("<Renderer>PathTracing</Renderer><RendererParams>NextEventEstimation</RendererParams>", 16),
        ("<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>", 64),
        ("<Renderer>PathTracing</Renderer><RendererParams>ImportanceSampling</RendererParams>", 256),
        ("<Renderer>PathTracing</Renderer>", 256),
        ("<Renderer>PathTracing</Renderer><RendererParams>ImportanceSampling RussianRoulette</RendererParams>", 256),
    ];
    for (renderer, spp) in variants {
        let img = render(
            &load(dir.path(), &floor_scene(renderer)),
            &RenderOptions { spp: Some(spp), ..Default::default() },
        );
        let (m, se) = mean_and_se(&img);
        // The pixels see points up to 0.03 from the origin, where the
        // radiance is lower by less than 0.1%: well inside 1%.
        println!("{renderer:<100} {spp:>4} spp: {m:.4} ± {se:.4} (expected {expected})");
        assert!(
            (m - expected).abs() <= 4.0 * se + 0.01 * expected,
            "{renderer}: mean {m:.4} ± {se:.4}, expected {expected}"
        );
    }
}

/// `floor_scene` with a point light of intensity 4 at (2, 2, 0) beside its
/// sphere light, and the radiance the floor then sends to the camera.
fn two_light_scene(params: &str) -> (String, f64) {
    let text = floor_scene(&format!("<Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams>"))
        .replace(
            "  <VertexData>",
            "  <Lights><PointLight id=\"1\"><Position>2 2 0</Position><Intensity>4 4 4</Intensity></PointLight></Lights>\n  <VertexData>",
        );
    // The point light adds ρ/π · I cos/d² = 0.5/π · 4 · (2/√8)/8 at the
    // origin; the sphere does not shade it (the line passes 1.41 from its
    // centre).
    (text, 0.3125 + 0.5 / std::f64::consts::PI * 4.0 * (2.0 / 8f64.sqrt()) / 8.0)
}

#[test]
fn mis_keeps_the_known_radiance_choosing_one_light_or_sampling_all() {
    // The sphere light (power π·10·4π·0.25 ≈ 98.7) and the point light
    // (power 4π·4 ≈ 50.3): under `OneLight` MIS chooses them 2:1, not
    // evenly; `AllLights`, and `MIS` alone with so few lights, sample both
    // at every hit. A light weighed with another chance than it was drawn
    // with would miss.
    let dir = tempfile::tempdir().expect("temp dir");
    for params in ["MIS OneLight", "MIS AllLights", "MIS"] {
        let (text, expected) = two_light_scene(params);
        let img = render(&load(dir.path(), &text), &RenderOptions { spp: Some(64), ..Default::default() });
        let (m, se) = mean_and_se(&img);
        println!("two lights under {params}: {m:.4} ± {se:.4} (expected {expected:.4})");
        assert!(
            (m - expected).abs() <= 4.0 * se + 0.01 * expected,
            "{params}: mean {m:.4} ± {se:.4}, expected {expected:.4}"
        );
    }
}

#[test]
fn mis_sampling_both_of_two_lights_is_less_noisy_than_choosing_one() {
    // One sample of a light chosen by power carries the choice's noise
    // (each light's estimate divided by its chance) on top of the sample's
    // own; sampling both has only the latter, and the point light's has
    // none. By default a scene with so few lights samples them all.
    let dir = tempfile::tempdir().expect("temp dir");
    let scene =
        |params: &str| Scene::build(&load(dir.path(), &two_light_scene(params).0)).expect("scene builds");
    let (one, all, auto) = (scene("MIS OneLight"), scene("MIS AllLights"), scene("MIS"));
    let (v1, va, vd) = (two_seed_variance(&one, 4), two_seed_variance(&all, 4), two_seed_variance(&auto, 4));
    println!("per-pixel variance with two lights: OneLight {v1:.6}, AllLights {va:.6}, MIS alone {vd:.6}");
    assert!(v1 > 0.0, "choosing one light shows no noise to compare with");
    assert!(va < 0.5 * v1, "AllLights variance {va:.6} is not below half of OneLight's {v1:.6}");
    assert_eq!(va, vd, "MIS alone does not sample both of two lights");
}

#[test]
fn mis_keeps_the_last_bounces_share_of_the_light() {
    // At the depth limit MIS still weighs each light sample against a
    // bounce, so that bounce must be traced (for the light it hits, nothing
    // more) or its share is lost. A sphere of radius 1.5 at height 2 fills
    // so wide a cone (1 − cos θmax = 0.34) that its density, 0.47, is near
    // the cosine bounce's: the power heuristic gives the bounce about a
    // quarter of the weight. The floor must get ρ L R²/d² = 0.5 · 10 · 2.25 / 4.
    let dir = tempfile::tempdir().expect("temp dir");
    let text = floor_scene("<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>")
        .replace("<MaxRecursionDepth>1</MaxRecursionDepth>", "<MaxRecursionDepth>0</MaxRecursionDepth>")
        .replace("<Radius>0.5</Radius>", "<Radius>1.5</Radius>");
    let expected = 0.5 * 10.0 * 2.25 / 4.0;
    let img = render(&load(dir.path(), &text), &RenderOptions { spp: Some(64), ..Default::default() });
    let (m, se) = mean_and_se(&img);
    println!("MIS at the depth limit: {m:.4} ± {se:.4} (expected {expected:.4})");
    assert!(
        (m - expected).abs() <= 4.0 * se + 0.01 * expected,
        "mean {m:.4} ± {se:.4}, expected {expected:.4}"
    );
}

/// Per-pixel variance of the green channel, from two seeds' differences.
fn two_seed_variance(scene: &Scene, spp: u32) -> f64 {
    let img =
        |seed| render_with(scene, 0, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {});
    let (a, b) = (img(1), img(2));
    let d2: f64 = a.pixels.iter().zip(&b.pixels).map(|(x, y)| f64::from(x.y - y.y).powi(2)).sum();
    d2 / 2.0 / a.pixels.len() as f64
}

#[test]
fn mis_at_the_depth_limit_is_less_noisy_than_light_samples_alone() {
    // The floor beside a wall-like 1×1 `LightMesh` standing 0.05 from the
    // point the camera sees, at depth 0. Area samples of the light near its
    // foot carry cos·cos/d² terms that make next-event estimation noisy;
    // MIS weighs them against the bounce, which finds those directions with
    // a bounded weight. If MIS counted its light samples in full at the last
    // vertex (no bounce traced there), its noise would be next-event
    // estimation's.
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = |params: &str| {
        let text = floor_scene(&format!("<Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams>"))
            .replace("<MaxRecursionDepth>1</MaxRecursionDepth>", "<MaxRecursionDepth>0</MaxRecursionDepth>")
            .replace(
                "<VertexData>0 0 0  0 2 0</VertexData>",
                "<VertexData>0 0 0  0.05 0 -0.5  0.05 1 -0.5  0.05 1 0.5  0.05 0 0.5</VertexData>",
            )
            .replace(
                r#"<LightSphere id="1"><Material>2</Material><Center>2</Center><Radius>0.5</Radius><Radiance>10 10 10</Radiance></LightSphere>"#,
                r#"<LightMesh id="1"><Material>2</Material><Faces>2 3 4  2 4 5</Faces><Radiance>10 10 10</Radiance></LightMesh>"#,
            );
        Scene::build(&load(dir.path(), &text)).expect("scene builds")
    };
    let (mis, nee) = (scene("MIS"), scene("NextEventEstimation"));
    let (vm, vn) = (two_seed_variance(&mis, 16), two_seed_variance(&nee, 16));
    println!("per-pixel variance at depth 0: MIS {vm:.5}, next-event estimation {vn:.5}");
    assert!(vn > 0.0, "next-event estimation shows no noise to compare with");
    assert!(vm < 0.5 * vn, "MIS variance {vm:.5} is not below half of next-event estimation's {vn:.5}");
    let all: Vec<usize> = (0..16 * 16).collect();
    let ((a, sa), (b, sb)) = (two_seed_mean(&mis, 16, &all), two_seed_mean(&nee, 16, &all));
    let z = (a - b) / (sa * sa + sb * sb).sqrt();
    assert!(z.abs() <= 4.0, "MIS {a:.4} ± {sa:.4} and next-event estimation {b:.4} ± {sb:.4} disagree");
}

#[test]
fn next_event_estimation_does_not_count_an_emitter_twice() {
    // Two bounces: an emitter seen by the bounce ray would add the direct
    // light a second time (a 100% excess) if next-event estimation did not
    // discard it.
    let dir = tempfile::tempdir().expect("temp dir");
    let text = floor_scene(
        "<Renderer>PathTracing</Renderer><RendererParams>NextEventEstimation ImportanceSampling</RendererParams>",
    )
    .replace("<MaxRecursionDepth>1</MaxRecursionDepth>", "<MaxRecursionDepth>2</MaxRecursionDepth>");
    let img = render(&load(dir.path(), &text), &RenderOptions { spp: Some(32), ..Default::default() });
    let (m, se) = mean_and_se(&img);
    assert!((m - 0.3125).abs() <= 4.0 * se + 0.003, "mean {m:.4} ± {se:.4}, expected 0.3125");
}

#[test]
fn passes_threads_and_time_limits_keep_the_image_exact() {
    let dir = tempfile::tempdir().expect("temp dir");
    let desc = load(
        dir.path(),
        &floor_scene("<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>"),
    );
    let scene = Scene::build(&desc).expect("builds");
    let opts = RenderOptions { spp: Some(24), ..Default::default() };
    let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).build().expect("pool");
    let one = pool(1).install(|| render_with(&scene, 0, &opts, &|_| {}));
    let two = pool(2).install(|| render_with(&scene, 0, &opts, &|_| {}));
    assert_eq!(one.film, two.film, "thread count changed the image");
    assert_eq!(one.spp, 24);
    // A generous limit takes every sample, in passes, and changes no byte.
    let limited = RenderOptions { time_limit: Some(Duration::from_secs(3600)), ..opts };
    let long = render_with(&scene, 0, &limited, &|_| {});
    assert_eq!(long.film, one.film, "a time limit that is not reached changed the image");
    // A limit already past stops after the first pass: one sample per pixel,
    // every pixel finite, the same as a one-sample render would be at that pass.
    let short = RenderOptions { time_limit: Some(Duration::from_nanos(1)), spp: Some(1 << 20), ..opts };
    let cut = render_with(&scene, 0, &short, &|_| {});
    assert_eq!(cut.spp, 1, "a time limit in the past still takes the first pass only");
    assert!(cut.pixels.iter().all(|p| p.is_finite()));
    // Progress adds up to the work announced.
    let total = std::sync::atomic::AtomicU64::new(0);
    render_with(&scene, 0, &opts, &|n| {
        total.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
    });
    assert_eq!(total.into_inner(), luster::render::work(&scene, 0, &opts));
}

#[test]
fn json_scenes_name_object_lights_and_renderers_alike() {
    // The 2025 JSON encoding of the floor scene: attributes with `_`, every
    // value a string, `_data` for text beside attributes.
    let json = r#"{"Scene": {
  "MaxRecursionDepth": "1",
  "Cameras": {"Camera": {"_id": "1", "_type": "lookAt", "Position": "0 1 3", "GazePoint": "0 0 0", "Up": "0 1 0",
    "FovY": "1", "NearDistance": "1", "ImageResolution": "16 16", "ImageName": "a.exr",
    "Renderer": "PathTracing", "RendererParams": "NextEventEstimation ImportanceSampling"}},
  "BRDFs": {"ModifiedPhong": {"_id": "1", "_normalized": "true", "Exponent": "1"}},
  "Materials": {"Material": [
    {"_id": "1", "_BRDF": "1", "DiffuseReflectance": "0.5 0.5 0.5", "SpecularReflectance": "0 0 0"},
    {"_id": "2", "DiffuseReflectance": "0 0 0", "SpecularReflectance": "0 0 0"}]},
  "VertexData": {"_data": "0 0 0  0 2 0"},
  "Objects": {
    "Plane": {"_id": "1", "Material": "1", "Point": "1", "Normal": "0 1 0"},
    "LightSphere": {"_id": "1", "Material": "2", "Center": "2", "Radius": "0.5", "Radiance": "10 10 10"}}
}}"#;
    let dir = tempfile::tempdir().expect("temp dir");
    let p = dir.path().join("s.json");
    std::fs::write(&p, json).expect("temp file");
    let desc = luster::scene::load(&p).expect("the JSON scene loads");
    assert_eq!(desc.emitters.len(), 1);
    let img = render(&desc, &RenderOptions { spp: Some(4), ..Default::default() });
    let (m, _) = mean_and_se(&img);
    assert!((m - 0.3125).abs() < 0.01 * 0.3125, "mean {m:.4}, expected 0.3125");
}

/// A constant-radiance lat-long sky `sky.exr` in `dir`.
fn constant_sky(dir: &Path, l: f32) {
    let img = image::Rgb32FImage::from_pixel(16, 8, image::Rgb([l, l, l]));
    image::DynamicImage::ImageRgb32F(img).save(dir.join("sky.exr")).expect("EXR written");
}

/// Mean of the pixels' green channel over two renders with different seeds,
/// and its standard error from the seeds' per-pixel differences:
/// `Var(a_i) ≈ (a_i − b_i)² / 2`, so `Var(mean) = Σ (a_i − b_i)² / 4 / n²`.
fn two_seed_mean(scene: &Scene, spp: u32, pixels: &[usize]) -> (f64, f64) {
    let img =
        |seed| render_with(scene, 0, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {});
    let (a, b) = (img(1), img(2));
    let n = pixels.len() as f64;
    let (mut sum, mut d2) = (0.0, 0.0);
    for &i in pixels {
        let (x, y) = (f64::from(a.pixels[i].y), f64::from(b.pixels[i].y));
        sum += (x + y) / 2.0;
        d2 += (x - y).powi(2);
    }
    (sum / n, (d2 / 4.0).sqrt() / n)
}

/// The pixels of a 24×24 image, seen by a camera 5 from the origin with a
/// vertical field of view of `2 · half_fov` degrees, whose centre ray passes
/// within `r` of the origin (measured in the plane through it).
fn pixels_within(half_fov: f32, r: f32) -> Vec<usize> {
    let half = half_fov.to_radians().tan() * 5.0;
    (0..24 * 24)
        .filter(|&i| {
            let x = ((i % 24) as f32 + 0.5) / 12.0 - 1.0;
            let y = ((i / 24) as f32 + 0.5) / 12.0 - 1.0;
            (x * x + y * y).sqrt() * half < r
        })
        .collect()
}

/// A diffuse unit sphere (the course's material: `kd cos θ`, no 1/π) under
/// a constant sky `L` receives `π kd L` everywhere, and a convex object
/// never sees itself, so the MIS path tracer's answer is exactly that
/// whatever the environment light's `Sampler`. MIS weighs a bounce that
/// escapes against the density of the light sampler actually used; weighing
/// it by the importance map's density while the light draws uniform or
/// cosine directions counts the sky 20–40% too much.
#[test]
fn mis_weighs_escaping_rays_by_the_environment_sampler_in_use() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (l, kd) = (2.0, 0.5);
    constant_sky(dir.path(), l);
    let expected = std::f64::consts::PI * kd * f64::from(l);
    for sampler in ["importance", "uniform", "cosine"] {
        let text = format!(
            r#"<Scene>
  <MaxRecursionDepth>2</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>30</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams></Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1"><ImageId>1</ImageId><Sampler>{sampler}</Sampler></SphericalDirectionalLight></Lights>
  <Materials><Material id="1"><DiffuseReflectance>{kd} {kd} {kd}</DiffuseReflectance></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#
        );
        let scene = Scene::build(&load(dir.path(), &text)).expect("scene builds");
        // Pixels whose centre ray meets the sphere well inside its outline.
        let inner = pixels_within(15.0, 0.8);
        assert!(inner.len() > 150, "{} inner pixels", inner.len());
        let (m, se) = two_seed_mean(&scene, 16, &inner);
        println!("{sampler:<10} mean {m:.4} ± {se:.4} (expected {expected:.4})");
        assert!(se < 0.01 * expected, "{sampler}: standard error {se} too large to test");
        assert!(
            (m - expected).abs() <= 4.0 * se + 1e-4 * expected,
            "{sampler}: mean {m:.4} ± {se:.4}, expected π kd L = {expected:.4}"
        );
    }
}

/// A 1×1 `LightMesh` 1 above the floor of [`floor_scene`], moving 3 along x
/// over the shutter. Next-event estimation, bounces alone and MIS estimate
/// the same image only if light samples are drawn where the light is at the
/// ray's time, as bounce rays find it.
#[test]
fn a_moving_light_mesh_is_sampled_where_rays_find_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let scene = |renderer: &str| {
        let text = floor_scene(renderer)
            .replace("<VertexData>0 0 0  0 2 0</VertexData>", "<VertexData>0 0 0  -0.5 1 -0.5  0.5 1 -0.5  0.5 1 0.5  -0.5 1 0.5</VertexData>")
            .replace(
                r#"<LightSphere id="1"><Material>2</Material><Center>2</Center><Radius>0.5</Radius><Radiance>10 10 10</Radiance></LightSphere>"#,
                r#"<LightMesh id="1"><Material>2</Material><Faces>2 3 4  2 4 5</Faces><Radiance>10 10 10</Radiance><MotionBlur>3 0 0</MotionBlur></LightMesh>"#,
            );
        Scene::build(&load(dir.path(), &text)).expect("scene builds")
    };
    let variants = [
        ("<Renderer>PathTracing</Renderer><RendererParams>NextEventEstimation</RendererParams>", 64),
        ("<Renderer>PathTracing</Renderer><RendererParams>ImportanceSampling</RendererParams>", 256),
        ("<Renderer>PathTracing</Renderer><RendererParams>MIS</RendererParams>", 64),
    ];
    let means: Vec<(f64, f64)> = variants
        .iter()
        .map(|(renderer, spp)| {
            let s = scene(renderer);
            let all: Vec<usize> = (0..16 * 16).collect();
            let (m, se) = two_seed_mean(&s, *spp, &all);
            println!("{renderer:<90} {m:.4} ± {se:.4}");
            assert!(m > 0.01, "{renderer}: no light reached the floor ({m})");
            (m, se)
        })
        .collect();
    for i in 0..means.len() {
        for j in i + 1..means.len() {
            let ((a, sa), (b, sb)) = (means[i], means[j]);
            let z = (a - b) / (sa * sa + sb * sb).sqrt();
            assert!(
                z.abs() <= 4.0,
                "{} and {} disagree: {a:.4} vs {b:.4} (z = {z:.1})",
                variants[i].0,
                variants[j].0
            );
        }
    }
}

/// A clear glass sphere (no absorption) under a constant sky `L`: every
/// path through it leaves it again, reflected or refracted, with the
/// Fresnel weights summing to 1 at each interface, so every pixel sees `L`
/// (paths past the depth limit, after a dozen interfaces, are negligible).
/// Past one sample per pixel the path tracer follows one of a dielectric's
/// two rays, chosen by Fresnel probability, at weight 1: about two
/// secondary rays per camera ray (in and out); at one sample it traces both,
/// the course's deterministic split, a tree of them. Both find `L`.
#[test]
fn glass_paths_follow_one_branch_past_one_sample_and_keep_the_sky() {
    let dir = tempfile::tempdir().expect("temp dir");
    let l = 2.0f32;
    constant_sky(dir.path(), l);
    let text = r#"<Scene>
  <MaxRecursionDepth>12</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 5</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>20</FovY><NearDistance>1</NearDistance><ImageResolution>24 24</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>ImportanceSampling</RendererParams></Camera></Cameras>
  <Textures><Images><Image id="1">sky.exr</Image></Images></Textures>
  <Lights><SphericalDirectionalLight id="1"><ImageId>1</ImageId></SphericalDirectionalLight></Lights>
  <Materials><Material id="1" type="dielectric"><DiffuseReflectance>0 0 0</DiffuseReflectance>
    <SpecularReflectance>0 0 0</SpecularReflectance><AbsorptionCoefficient>0 0 0</AbsorptionCoefficient>
    <RefractionIndex>1.5</RefractionIndex></Material></Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#;
    let scene = Scene::build(&load(dir.path(), text)).expect("scene builds");
    // Pixels whose rays all meet the sphere (half the image spans 0.88).
    let inner = pixels_within(10.0, 0.75);
    assert!(inner.len() > 150, "{} inner pixels", inner.len());
    for (spp, branching) in [(1, true), (16, false)] {
        let img = render_with(&scene, 0, &RenderOptions { spp: Some(spp), ..Default::default() }, &|_| {});
        let worst = inner
            .iter()
            .map(|&i| (f64::from(img.pixels[i].y) / f64::from(l) - 1.0).abs())
            .fold(0.0, f64::max);
        let per_camera_ray = img.stats.secondary as f64 / img.stats.primary as f64;
        println!(
            "{spp:>2} spp: worst pixel off by {:.2e}, {per_camera_ray:.2} secondary rays a camera ray",
            worst
        );
        assert!(worst < 1e-3, "{spp} spp: a pixel through the glass is {worst:.2e} off the sky's radiance");
        if branching {
            assert!(
                per_camera_ray > 3.0,
                "1 spp: {per_camera_ray:.2} secondary rays, expected both rays traced"
            );
        } else {
            assert!(per_camera_ray < 2.5, "{spp} spp: {per_camera_ray:.2} secondary rays, expected one path");
        }
    }
}

/// A small box lit by a point light and a light mesh, with a glass and a
/// mirror sphere, for paths of every kind of vertex.
fn mixed_box(params: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>4</MaxRecursionDepth>
  <Cameras><Camera id="1" type="lookAt"><Position>0 0 1.8</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>60</FovY><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer><RendererParams>{params}</RendererParams></Camera></Cameras>
  <Lights><PointLight id="1"><Position>0.5 1.5 0.5</Position><Intensity>2 2 2</Intensity></PointLight></Lights>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong>
    <TorranceSparrow id="2"><Exponent>40</Exponent></TorranceSparrow></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.7 0.6 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2" type="dielectric"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance>
      <AbsorptionCoefficient>0 0 0</AbsorptionCoefficient><RefractionIndex>1.5</RefractionIndex></Material>
    <Material id="3" type="mirror"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance>
      <MirrorReflectance>0.9 0.9 0.9</MirrorReflectance></Material>
    <Material id="4" BRDF="2"><DiffuseReflectance>0.3 0.5 0.3</DiffuseReflectance><SpecularReflectance>0.4 0.4 0.4</SpecularReflectance></Material>
    <Material id="5"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <VertexData>-2 -2 -2  2 -2 -2  2 2 -2  -2 2 -2  -2 -2 2  2 -2 2  2 2 2  -2 2 2
    -0.7 -1.4 -0.6  0.7 -1.4 0.4  0 -1.2 -1.2
    -0.3 1.9 -0.3  0.3 1.9 -0.3  0.3 1.9 0.3  -0.3 1.9 0.3</VertexData>
  <Objects>
    <Mesh id="1"><Material>1</Material><Faces>1 2 3 1 3 4  1 5 6 1 6 2  2 6 7 2 7 3  4 3 7 4 7 8  1 4 8 1 8 5</Faces></Mesh>
    <Sphere id="1"><Material>2</Material><Center>9</Center><Radius>0.5</Radius></Sphere>
    <Sphere id="2"><Material>3</Material><Center>10</Center><Radius>0.5</Radius></Sphere>
    <Sphere id="3"><Material>4</Material><Center>11</Center><Radius>0.4</Radius></Sphere>
    <LightMesh id="1"><Material>5</Material><Radiance>6 6 6</Radiance><Faces>12 13 14 12 14 15</Faces></LightMesh>
  </Objects>
</Scene>"#
    )
}

/// The path tracer follows two samples' paths in step
/// (`Integrator::radiance_pair`); each must come out exactly as it does
/// alone, ray counts included, whatever its paths meet: light samples,
/// bounces, roulette, glass, mirrors, a glossy lobe.
#[test]
fn paths_traced_in_pairs_are_the_paths_traced_alone() {
    use luster::integrator::{PathState, RayStats};
    use luster::math::{Ray, Vec3};
    use luster::render::sampler::PixelSampler;
    let dir = tempfile::tempdir().expect("temp dir");
    let variants = [
        "NextEventEstimation",
        "NextEventEstimation ImportanceSampling RussianRoulette",
        "ImportanceSampling",
        "RussianRoulette",
        "MIS",
        "MIS OneLight",
    ];
    let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
    let mut nonzero = 0;
    for params in variants {
        let scene = Scene::build(&load(dir.path(), &mixed_box(params))).expect("scene builds");
        let integrator = luster::integrator::Integrator::from_desc(&scene.cameras[0].renderer);
        for count in [2u32, 3, 16] {
            for pixel in 0..24u32 {
                let (x, y) = (pixel % 6, pixel / 6);
                // Directions from the camera spread over the box.
                let a = pixel as f32 * 0.61;
                let d = Vec3::new(a.cos() * 0.8, a.sin() * 0.8 - 0.2, -1.0).normalize();
                let ray = Ray::new(Vec3::new(0.0, 0.0, 1.8), d);
                let state = |s: u32| {
                    let mut sampler = PixelSampler::new(7, x, y, 0, count);
                    sampler.restart(s);
                    sampler.skip();
                    PathState::new(RayStats::default(), 0.0, sampler)
                };
                for s in (0..count - 1).step_by(2) {
                    let (mut a1, mut b1) = (state(s), state(s + 1));
                    let la = integrator.radiance(&scene, &ray, &mut a1);
                    let lb = integrator.radiance(&scene, &ray, &mut b1);
                    let (mut a2, mut b2) = (state(s), state(s + 1));
                    let [pa, pb] = integrator.radiance_pair(&scene, [&ray, &ray], &mut a2, &mut b2);
                    assert_eq!(bits(la), bits(pa), "{params}, {count} spp, pixel {pixel}, sample {s}");
                    assert_eq!(bits(lb), bits(pb), "{params}, {count} spp, pixel {pixel}, sample {}", s + 1);
                    for (one, two) in [(&a1, &a2), (&b1, &b2)] {
                        let (o, t) = (one.stats, two.stats);
                        assert_eq!((o.primary, o.secondary, o.shadow), (t.primary, t.secondary, t.shadow));
                    }
                    nonzero += usize::from(la != Vec3::ZERO) + usize::from(lb != Vec3::ZERO);
                }
            }
        }
    }
    assert!(nonzero > 500, "only {nonzero} samples found light");
}
