//! Golden-image tests of hw7 (object lights and path tracing), at a few
//! samples per pixel so that CI can afford them.
//!
//! Metric: the course's images are Monte Carlo estimates at 100 samples per
//! pixel, so they are judged by their means, not pixel by pixel, with the
//! suite's own judgement (`luster::conformance::noise`, in linear space):
//! each image is rendered twice (seeds 0 and 1) at the count below and
//! compared with the course's `.exr` per 16×16 block and channel,
//! `z = (m_ours − m_course) / σ`, where `σ²` is the variance of our block
//! mean measured by the two seeds (`Σ (a − a')² / 2n²`), grown by the
//! course's own share (4 × spp / 100 of ours) and floored at 10⁻³ of the
//! mean luminance. Blocks that show a light itself (a reference pixel above
//! 10× the image's mean luminance) are left out. Threshold (the suite's
//! noise-aware bar): mean z² ≤ 2 (pure noise gives one), |z| > 5 in at most
//! 0.1% of blocks, and the image's mean luminance within 4 of its own
//! standard errors. A bias — a light of the wrong size, a wrong pdf, light
//! counted twice — shows at any count.
//!
//! The course's Russian-roulette images are left out: they are brighter than
//! any unbiased estimate of their scene (see docs/path-tracing.md).

mod common;
use common::course_root;
use luster::conformance::noise::{block_z, NoiseModel};
use luster::conformance::{Space, STOCHASTIC};
use luster::image::Rgb32Image;
use luster::render::{render_with, RenderOptions, Scene};
use std::path::Path;

/// (scene under hw7/xml, camera index, expected image under expected/2022,
/// samples per pixel, what it tests).
const CASES: &[(&str, usize, &str, u32, &str)] = &[
    ("cornellbox_jaroslav_diffuse_area.xml", 0, "cornellbox_jaroslav_diffuse_area", 4, "mesh light, direct"),
    (
        "cornellbox_jaroslav_glossy_area_sphere.xml",
        0,
        "cornellbox_jaroslav_glossy_area_sphere",
        4,
        "sphere light",
    ),
    ("cornellbox_jaroslav_path_diffuse.xml", 0, "diffuse_next", 8, "NEE, point light; heavy-tailed: 8 spp"),
    ("cornellbox_jaroslav_path_glass.xml", 6, "glass_importance", 4, "cosine bounces, glass and mirror"),
];

fn render(scene: &Scene, cam: usize, spp: u32, seed: u32) -> Rgb32Image {
    let img = render_with(scene, cam, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {});
    let pixels = img.film.pixels.iter().map(|p| p.to_array()).collect();
    Rgb32Image { width: img.width, height: img.height, pixels, encoding: luster::image::Encoding::Linear }
}

#[test]
fn hw7_images_match_the_course_within_their_noise() {
    let Some(root) = course_root("hw7") else { return };
    let hw7 = root.join("hw7");
    let mut failures = Vec::new();
    println!("{:<48} {:>4} {:>8} {:>7} {:>9}", "image", "spp", "mean z²", "|z|>5", "lum σ");
    for &(file, cam, expected, spp, what) in CASES {
        let desc = luster::scene::load(&hw7.join("xml").join(file)).expect("the course scene loads");
        let scene = Scene::build(&desc).expect("the course scene builds");
        let reference = Rgb32Image::load(Path::new(&hw7).join(format!("expected/2022/{expected}.exr")))
            .expect("the course's image reads");
        let a = render(&scene, cam, spp, 0);
        let b = render(&scene, cam, spp, 1);
        let z = block_z(&a, &b, &reference, &NoiseModel::linear(spp, 100, &reference))
            .expect("the renders and the course's image have one size");
        let bar = STOCHASTIC.bar_in(Space::Linear);
        println!(
            "{:<48} {spp:>4} {:>8.2} {:>6.2}% {:>9.2}",
            format!("{expected} ({what})"),
            z.mean_z2,
            z.outliers * 100.0,
            z.luminance_z
        );
        assert!(
            z.left_out < z.count / 3 / 10,
            "{expected}: more than a tenth of the blocks left out as lights: {z:?}"
        );
        if !bar.z_ok(Some(&z)) {
            failures.push(format!(
                "{expected}: mean z² {:.2} (≤ {}), |z|>5 in {:.2}% (≤ {:.1}%), mean luminance {:.2} standard \
                 errors off (≤ {})",
                z.mean_z2,
                bar.max_mean_z2,
                z.outliers * 100.0,
                bar.max_outliers * 100.0,
                z.luminance_z,
                bar.max_luminance_z
            ));
        }
    }
    assert!(failures.is_empty(), "hw7 images differ from the course's:\n{}", failures.join("\n"));
}
