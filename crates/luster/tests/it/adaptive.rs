//! Adaptive sampling (`--noise-threshold`, `<NoiseThreshold>`): a region
//! without noise stops at the minimum while a noisy one goes on; the
//! adaptive image of a scene with a known answer is unbiased, judged by a
//! z-test with the variance measured from a second seed; the stopping
//! decisions do not depend on the threads (the split-render case is in
//! `aov.rs`, with the passes).

use crate::common::{self, two_seed_mean};
use luster::film::adaptive::Adaptive;
use luster::film::aov::BACKGROUND_DEPTH;
use luster::film::Passes;
use luster::render::{render_with, RenderOptions, RenderedImage, Scene};

/// A diffuse floor (albedo 0.5) under a light sphere of radius 0.5 and
/// radiance `radiance` centred 2 above the origin, path-traced with
/// next-event estimation (one bounce), over a flat `background`, seen from
/// `(0, 1, 3)` with a vertical field of view of `fov` degrees.
fn scene(fov: f32, size: u32, radiance: f32, background: &str, camera_extra: &str) -> String {
    format!(
        r#"<Scene>
  <MaxRecursionDepth>1</MaxRecursionDepth>
  <BackgroundColor>{background}</BackgroundColor>
  <Cameras><Camera id="1" type="lookAt"><Position>0 1 3</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
    <FovY>{fov}</FovY><NearDistance>1</NearDistance><ImageResolution>{size} {size}</ImageResolution>
    <ImageName>a.exr</ImageName><Renderer>PathTracing</Renderer>
    <RendererParams>NextEventEstimation</RendererParams>{camera_extra}</Camera></Cameras>
  <BRDFs><ModifiedPhong id="1" normalized="true"><Exponent>1</Exponent></ModifiedPhong></BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><DiffuseReflectance>0.5 0.5 0.5</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
    <Material id="2"><DiffuseReflectance>0 0 0</DiffuseReflectance><SpecularReflectance>0 0 0</SpecularReflectance></Material>
  </Materials>
  <VertexData>0 0 0  0 2 0</VertexData>
  <Objects>
    <Plane id="1"><Material>1</Material><Point>1</Point><Normal>0 1 0</Normal></Plane>
    <LightSphere id="1"><Material>2</Material><Center>2</Center><Radius>0.5</Radius><Radiance>{radiance} {radiance} {radiance}</Radiance></LightSphere>
  </Objects>
</Scene>"#
    )
}

fn render(text: &str, opts: &RenderOptions) -> RenderedImage {
    let dir = tempfile::tempdir().unwrap();
    let desc = common::load_with(dir.path(), text, &[]);
    let scene = Scene::build(&desc).expect("scene builds");
    render_with(&scene, 0, opts, &|_| {})
}

#[test]
fn a_noise_free_region_stops_at_the_minimum_and_a_noisy_one_goes_on() {
    let size = 48;
    // The top rows are the flat background; the floor below is noisy.
    let extra = "<NumSamples>256</NumSamples><NoiseThreshold>0.01</NoiseThreshold>";
    // The light sphere, whose edge is noisy, is just out of view.
    let text = scene(50.0, size, 3000.0, "60 90 120", extra);
    let passes = Passes::parse("depth,samples").unwrap();
    let adaptive = Adaptive { threshold: None, min_spp: Some(16) };
    let img = render(&text, &RenderOptions { passes, adaptive, ..Default::default() });
    let a = img.aovs.as_ref().unwrap();
    let (depth, samples) = (a.depth().unwrap(), a.samples().unwrap());
    let at = |x: u32, y: u32| (y * size + x) as usize;
    let (mut flat, mut floor, mut floor_samples) = (0, 0, 0.0);
    for y in 0..size {
        for x in 0..size {
            // The stopping rule looks at the 3×3 window around the pixel;
            // those pixels are wholly background when the centre samples of
            // the 5×5 window are (the horizon is a straight line).
            let window = (y.saturating_sub(2)..=(y + 2).min(size - 1))
                .flat_map(|yy| (x.saturating_sub(2)..=(x + 2).min(size - 1)).map(move |xx| (xx, yy)));
            if window.into_iter().all(|(xx, yy)| depth[at(xx, yy)] == BACKGROUND_DEPTH) {
                assert_eq!(samples[at(x, y)], 16.0, "background pixel ({x}, {y})");
                flat += 1;
            } else if depth[at(x, y)] < 10.0 {
                floor += 1;
                floor_samples += f64::from(samples[at(x, y)]);
            }
        }
    }
    assert!(flat > 100 && floor > 1000, "{flat} flat and {floor} floor pixels");
    let mean = floor_samples / f64::from(floor);
    assert!(mean > 64.0, "the noisy floor took {mean:.1} samples a pixel on average");
    assert!(img.mean_spp < 256.0 && img.spp == 256, "{} mean, {} most", img.mean_spp, img.spp);
}

/// Mean and standard error of the green channel over the pixels of
/// `block` (x0, y0, x1, y1) of two seeds' renders ([`two_seed_mean`]).
fn block_mean(a: &RenderedImage, b: &RenderedImage, (x0, y0, x1, y1): (u32, u32, u32, u32)) -> (f64, f64) {
    let pick = |img: &RenderedImage| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (y * img.width + x) as usize))
            .map(|i| f64::from(img.pixels[i].y))
            .collect::<Vec<f64>>()
    };
    two_seed_mean(&pick(a), &pick(b))
}

#[test]
fn the_adaptive_image_is_unbiased() {
    // A narrow view of the lit floor: every pixel noisy, none flat.
    let text = scene(1.0, 32, 4000.0, "0 0 0", "<NumSamples>256</NumSamples>");
    let adaptive = Adaptive { threshold: Some(0.005), min_spp: Some(8) };
    let passes = Passes::parse("samples").unwrap();
    let opts = |seed, adaptive| RenderOptions { adaptive, seed, passes, ..Default::default() };
    let (a1, a2) = (render(&text, &opts(1, adaptive)), render(&text, &opts(2, adaptive)));
    // The reference: every pixel at the most samples, other seeds.
    let (u1, u2) =
        (render(&text, &opts(3, Adaptive::default())), render(&text, &opts(4, Adaptive::default())));
    assert_eq!(u1.mean_spp, 256.0);
    // The test means something only if the pixels stopped at different counts.
    let s = a1.aovs.as_ref().unwrap().samples().unwrap();
    let (lo, hi) = s.iter().fold((f32::MAX, 0f32), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(lo < hi && a1.mean_spp < 128.0, "samples from {lo} to {hi}, mean {}", a1.mean_spp);
    // The whole image, then 16 blocks of 8×8: z-scores of the adaptive
    // mean against the reference's, the variances from the seeds' pairs.
    let mut blocks = vec![(0, 0, 32, 32)];
    blocks.extend((0..16).map(|b| (b % 4 * 8, b / 4 * 8, b % 4 * 8 + 8, b / 4 * 8 + 8)));
    for (k, block) in blocks.into_iter().enumerate() {
        let (ma, sa) = block_mean(&a1, &a2, block);
        let (mu, su) = block_mean(&u1, &u2, block);
        let z = (ma - mu) / sa.hypot(su);
        if k == 0 {
            eprintln!(
                "adaptive: mean {ma:.4} ± {sa:.4} against {mu:.4} ± {su:.4} uniform, z = {z:.2}, {:.1} spp on average",
                a1.mean_spp
            );
        }
        assert!(z.abs() < 4.0, "block {block:?}: adaptive {ma} ± {sa}, uniform {mu} ± {su}: z = {z:.2}");
    }
}

#[test]
fn stopping_decisions_do_not_depend_on_the_threads() {
    let extra = "<NumSamples>64</NumSamples><NoiseThreshold>0.03</NoiseThreshold>";
    let text = scene(50.0, 40, 3000.0, "60 90 120", extra);
    let opts = RenderOptions { passes: Passes::parse("samples").unwrap(), ..Default::default() };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| render(&text, &opts))
    };
    let (one, two) = (on(1), on(2));
    assert!(one.film.pixels == two.film.pixels);
    assert!(one.aovs == two.aovs);
    assert!(one.mean_spp < 64.0, "some pixels stopped early: {}", one.mean_spp);
}

#[test]
fn a_threshold_out_of_range_is_an_error_naming_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene(50.0, 8, 1.0, "0 0 0", "<NoiseThreshold>2</NoiseThreshold>");
    let p = dir.path().join("s.xml");
    std::fs::write(&p, text).unwrap();
    let e = match luster::scene::load(&p) {
        Ok(_) => panic!("a threshold of 2 was accepted"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("line 7") && e.contains("<NoiseThreshold> must be between 0 and 1, found 2"), "{e}");
}
