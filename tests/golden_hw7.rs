//! Golden-image tests of hw7 (object lights and path tracing), at a few
//! samples per pixel so that CI can afford them.
//!
//! Metric: the course's images are Monte Carlo estimates at 100 samples per
//! pixel, so they are judged by their means, not pixel by pixel. Each image
//! is rendered twice (seeds 0 and 1) at the count below, in linear radiance,
//! and compared with the course's `.exr` per 16×16 block and channel:
//! `z = (m_ours − m_course) / σ`, where `σ²` is the variance of our block
//! mean measured by the two seeds (`Σ (a − a')² / 2n²`), grown by the
//! course's own share (`spp / 100` of ours) and floored at 10⁻³ (a converged
//! block still differs by rounding). Blocks that show a light itself (a
//! reference pixel above 10; the lights are 16 to 32, lit surfaces below 5)
//! are left out of the z test: a sub-pixel difference in where a light's
//! edge falls outweighs everything else there. Threshold: mean z² ≤ 2 (pure
//! noise gives one) and |z| > 5 in at most 0.5% of blocks; and the image's
//! mean luminance within 4 of its own standard errors (from the same pair). A bias — a light
//! of the wrong size, a wrong pdf, light counted twice — shows at any count.
//!
//! The course's Russian-roulette images are left out: they are brighter than
//! any unbiased estimate of their scene (see docs/path-tracing.md).

mod common;
use common::course_root;
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

const BLOCK: u32 = 16;
const MAX_MEAN_Z2: f64 = 2.0;
const MAX_OUTLIERS: f64 = 0.005;
const MAX_LUMINANCE_SIGMAS: f64 = 4.0;
/// Reference radiance above which a pixel shows a light (see the module doc).
const LIGHT: f32 = 10.0;

fn render(scene: &Scene, cam: usize, spp: u32, seed: u32) -> Rgb32Image {
    let img = render_with(scene, cam, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {});
    let pixels = img.film.pixels.iter().map(|p| p.to_array()).collect();
    Rgb32Image { width: img.width, height: img.height, pixels, encoding: luster::image::Encoding::Linear }
}

fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * f64::from(p[0]) + 0.7152 * f64::from(p[1]) + 0.0722 * f64::from(p[2])
}

/// Mean z², share of |z| > 5, and the mean luminance's offset in standard errors.
fn judge(a: &Rgb32Image, b: &Rgb32Image, r: &Rgb32Image, ref_ratio: f64) -> (f64, f64, f64) {
    let n = f64::from(BLOCK * BLOCK);
    let (mut z2, mut out, mut count) = (0.0, 0usize, 0usize);
    for by in 0..a.height / BLOCK {
        for bx in 0..a.width / BLOCK {
            let (mut diff, mut noise) = ([0.0f64; 3], [0.0f64; 3]);
            let mut light = false;
            for y in by * BLOCK..(by + 1) * BLOCK {
                for x in bx * BLOCK..(bx + 1) * BLOCK {
                    let i = (y * a.width + x) as usize;
                    light |= r.pixels[i].iter().any(|&v| v > LIGHT);
                    for c in 0..3 {
                        let v = f64::from(a.pixels[i][c]);
                        diff[c] += v - f64::from(r.pixels[i][c]);
                        noise[c] += (v - f64::from(b.pixels[i][c])).powi(2);
                    }
                }
            }
            if light {
                continue;
            }
            for c in 0..3 {
                let var = noise[c] / (2.0 * n * n) * (1.0 + ref_ratio) + 1e-6;
                let z = diff[c] / n / var.sqrt();
                z2 += z * z;
                out += usize::from(z.abs() > 5.0);
                count += 1;
            }
        }
    }
    let m = a.pixels.len() as f64;
    let (mut d, mut noise) = (0.0, 0.0);
    for i in 0..a.pixels.len() {
        let (la, lb) = (luminance(a.pixels[i]), luminance(b.pixels[i]));
        d += la - luminance(r.pixels[i]);
        noise += (la - lb).powi(2);
    }
    let se = (noise / 2.0 * (1.0 + ref_ratio)).sqrt() / m;
    (z2 / count as f64, out as f64 / count as f64, (d / m) / se.max(1e-9))
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
        let (z2, out, lum) = judge(&a, &b, &reference, f64::from(spp) / 100.0);
        println!(
            "{:<48} {spp:>4} {z2:>8.2} {:>6.2}% {lum:>9.2}",
            format!("{expected} ({what})"),
            out * 100.0
        );
        if z2 > MAX_MEAN_Z2 || out > MAX_OUTLIERS || lum.abs() > MAX_LUMINANCE_SIGMAS {
            failures.push(format!(
                "{expected}: mean z² {z2:.2} (≤ {MAX_MEAN_Z2}), |z|>5 in {:.2}% (≤ {:.1}%), mean luminance \
                 {lum:.2} standard errors off (≤ {MAX_LUMINANCE_SIGMAS})",
                out * 100.0,
                MAX_OUTLIERS * 100.0
            ));
        }
    }
    assert!(failures.is_empty(), "hw7 images differ from the course's:\n{}", failures.join("\n"));
}
