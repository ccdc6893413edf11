//! Golden-image tests of hw3 (distribution ray tracing), at reduced sample
//! counts so that CI can afford them.
//!
//! The course's images took 16 to 900 samples per pixel; at those counts the
//! whole homework is too slow for CI. Each image is rendered twice
//! (seeds 0 and 1) at the reduced count below and judged by the noise-aware
//! rule of `luster::conformance::thresholds`: the means of 8×8-pixel blocks
//! must agree with the course's image in units of the noise that our two
//! renders measure at the count rendered here (per-block z-scores: mean z²
//! ≤ 2, at most 0.1% of blocks with |z| > 5; PSNR ≥ 25 dB and FLIP ≤ 0.1 as
//! a floor). Fewer samples mean more noise and so a wider σ, but a bias — a
//! wrong light falloff, a lens of the wrong size, an object in the wrong
//! place — adds `(bias/σ)²` to z² at any count. The resolution is kept (no downsampling of the reference),
//! so edges and sharp details are judged as they are.
//!
//! Renders, second-seed renders and FLIP heatmaps go under
//! `target/tmp/golden/hw3/`. Without `../shared/scenes/ceng795` the test says
//! it skipped (under `CI=true` it fails).

use crate::common;
use common::course_root;
use luster::conformance::{discover, run_case_with, CaseResult};
use luster::render::RenderOptions;
use std::path::PathBuf;
use std::time::Instant;

/// Samples per pixel per scene file (its name without extension, either
/// encoding), with why. A sample per pixel costs far more in some scenes
/// (wine_glass) than in others (spheres_dof); the counts keep all 13 images,
/// two renders each, affordable on CI, and each is at least 4 so that every
/// pixel is stratified over its area, lens and light.
const SPP: &[(&str, u32, &str)] = &[
    ("spheres_dof", 16, "cheapest scene (spheres only): 16 keeps its defocus blur smooth"),
    ("cornellbox_area", 16, "soft shadows are the whole test: 16 light samples per pixel"),
    ("chessboard_arealight", 9, "soft shadows on a high-contrast board"),
    ("chessboard_arealight_dof", 9, "as chessboard_arealight, plus a thin lens"),
    ("cornellbox_brushed_metal", 9, "glossy reflections and an area light"),
    ("cornellbox_boxes_dynamic", 9, "motion blur needs several shutter times per pixel"),
    ("metal_glass_plates", 9, "frosted dielectrics trace many rays per sample"),
    ("wine_glass_scene", 4, "the dearest scene (about 1 s per sample per pixel): 4 keeps it to seconds"),
];

/// Images with a bias we have found and not fixed: (image, largest mean z²,
/// largest share of |z| > 5 blocks, evidence). They must still fail the bar
/// (so the test notices the day they are fixed and the entry should go) but
/// stay within these bounds, so the bias cannot grow unnoticed; they must
/// still meet the PSNR and FLIP floor. Every other image must pass.
///
/// Empty: every hw3 image passes the bar.
const KNOWN_BIAS: &[(&str, f64, f64, &str)] = &[];

/// Images of the shared folder's hw3 that have an expected image: 5 XML
/// scenes and 8 JSON ones, one camera each.
const HW3_IMAGES: usize = 13;

#[test]
fn hw3_scenes_match_expected_images_within_their_noise() {
    let Some(root) = course_root("hw3") else { return };
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden").join("hw3");
    let _ = std::fs::create_dir_all(&out);
    let cases: Vec<_> =
        discover(&root).into_iter().filter(|c| c.hw == "hw3" && c.mentions_expected_image()).collect();
    assert!(!cases.is_empty(), "no hw3 scenes found under {}", root.display());

    let t0 = Instant::now();
    let mut failures = Vec::new();
    let mut compared = 0;
    println!(
        "{:<44} {:>4} {:>8} {:>7} {:>8} {:>7} {:>7} {:>7} {:>6}",
        "scene", "spp", "PSNR", "FLIP", "pairPSNR", "8×8 z²", "|z|>5", "max|z|", "sec"
    );
    for case in &cases {
        let name = case.scene.file_stem().map(|s| s.to_string_lossy().to_string()).unwrap_or_default();
        // A hw3 scene not in the table gets the lowest count.
        let spp = SPP.iter().find(|(stem, ..)| *stem == name).map_or(4, |e| e.1);
        let r: CaseResult =
            run_case_with(case, &out, &RenderOptions { spp: Some(spp), ..Default::default() });
        if let Some(e) = &r.error {
            failures.push(format!("{}: {e}", case.label()));
            continue;
        }
        for img in &r.images {
            let (Some(c), Some(p), Some(z)) = (&img.comparison, &img.pair, &img.block_z) else {
                if img.expected.is_some() {
                    failures.push(format!(
                        "{} {}: not compared: {:?}",
                        case.label(),
                        img.image_name,
                        img.error
                    ));
                }
                continue;
            };
            compared += 1;
            println!(
                "{:<44} {:>4} {:>8.2} {:>7.4} {:>8.2} {:>7.2} {:>6.2}% {:>7.1} {:>6.1} {}",
                case.label(),
                img.spp,
                c.psnr,
                c.flip,
                p.psnr,
                z.mean_z2,
                z.outliers * 100.0,
                z.max_abs_z,
                img.seconds,
                if img.pass { "ok" } else { "FAIL" }
            );
            let known = KNOWN_BIAS.iter().find(|k| k.0 == img.image_name);
            match known {
                Some(&(_, max_z2, max_out, why)) if !img.pass => {
                    println!("  known bias, still there: {why}");
                    if z.mean_z2 > max_z2
                        || z.outliers > max_out
                        || !img.bar.psnr_ok(c)
                        || !img.bar.flip_ok(c)
                    {
                        failures.push(format!(
                            "{} {}: the known bias grew: mean z² {:.2} (bound {max_z2}), |z|>5 in {:.2}% \
                             of blocks (bound {:.2}%), PSNR {:.2} dB, FLIP {:.4}",
                            case.label(),
                            img.image_name,
                            z.mean_z2,
                            z.outliers * 100.0,
                            max_out * 100.0,
                            c.psnr,
                            c.flip
                        ));
                    }
                }
                Some(_) => failures.push(format!(
                    "{} {} now passes: remove it from KNOWN_BIAS in tests/golden_hw3.rs",
                    case.label(),
                    img.image_name
                )),
                None if !img.pass => failures.push(format!(
                    "{} {} at {spp} spp: PSNR {:.2} dB, FLIP {:.4}, 8×8 block means: mean z² {:.2}, \
                     |z|>5 in {:.2}% (needs PSNR ≥ {}, FLIP ≤ {}, z² ≤ {}, ≤ {:.1}%); render {}",
                    case.label(),
                    img.image_name,
                    c.psnr,
                    c.flip,
                    z.mean_z2,
                    z.outliers * 100.0,
                    img.bar.min_psnr,
                    img.bar.max_flip,
                    img.bar.max_mean_z2,
                    img.bar.max_outliers * 100.0,
                    img.render.display()
                )),
                None => {}
            }
        }
    }
    println!("hw3: {compared} images in {:.1} s", t0.elapsed().as_secs_f64());
    // Pinned: a scene that goes missing, or stops being compared, fails.
    assert_eq!(compared, HW3_IMAGES, "hw3 images compared");
    assert!(failures.is_empty(), "{} hw3 image(s) failed:\n{}", failures.len(), failures.join("\n"));
}

/// The copper sphere of `cornellbox_brushed_metal` (roughness 5): at that
/// roughness the glossy offsets fill a square whose turn about the mirror
/// direction shows in the image, so the course's frame (see
/// `bsdf::specular::glossy_frame`) must be the one used. Judged on the
/// 80×64 pixels of the sphere's upper right, where another frame (Duff et
/// al.'s) leaves the image brighter than the course's: 64 samples
/// per pixel and seeds 0 and 1, by the suite's noise rule (8×8 blocks, the
/// course's 400 samples), mean luminance within 4 standard errors, mean
/// block z² ≤ 2 and no block past |z| > 5.
#[test]
fn brushed_copper_is_lit_as_the_courses_glossy_frame_lights_it() {
    use luster::conformance::noise::{block_z, NoiseModel};
    use luster::image::{Encoding, Rgb32Image};
    use luster::render::{render_with, Scene};
    use luster::scene::description::Projection;
    let Some(root) = course_root("hw3") else { return };
    let mut desc =
        luster::scene::load(&root.join("hw3/json/cornellbox_brushed_metal.json")).expect("the scene loads");
    let (x0, y0, x1, y1) = (504u32, 440u32, 584u32, 504u32);
    let cam = &mut desc.cameras[0];
    let (w, h) = cam.resolution;
    let Projection::Plane { gaze, near_plane: [l, r, b, t] } = cam.projection else {
        panic!("a NearPlane camera")
    };
    let (fw, fh) = ((r - l) / w as f32, (t - b) / h as f32);
    let plane = [l + fw * x0 as f32, l + fw * x1 as f32, t - fh * y1 as f32, t - fh * y0 as f32];
    cam.projection = Projection::Plane { gaze, near_plane: plane };
    cam.resolution = (x1 - x0, y1 - y0);
    let scene = Scene::build(&desc).expect("the scene builds");
    let spp = 64;
    let render = |seed| {
        let img =
            render_with(&scene, 0, &RenderOptions { spp: Some(spp), seed, ..Default::default() }, &|_| {});
        let px: Vec<[f32; 3]> =
            img.to_rgb8().chunks(3).map(|c| [0, 1, 2].map(|k| f32::from(c[k]) / 255.0)).collect();
        Rgb32Image::from_pixels(x1 - x0, y1 - y0, px, Encoding::Srgb).expect("a whole image")
    };
    let (a, b) = (render(0), render(1));
    let full =
        Rgb32Image::load(root.join("hw3/expected/cornellbox_brushed_metal.png")).expect("the course's image");
    let reference = Rgb32Image::from_fn(x1 - x0, y1 - y0, Encoding::Srgb, |x, y| {
        full.pixels[((y + y0) * full.width + x + x0) as usize]
    });
    let z = block_z(&a, &b, &reference, &NoiseModel::display(spp, 400)).expect("blocks to judge");
    println!(
        "copper, upper right: mean luminance {:.2} against the course's {:.2} ({:+.1} σ), mean z² {:.2}, \
         |z|>5 in {:.2}% of {} blocks",
        z.mean_luminance[0] * 255.0,
        z.mean_luminance[1] * 255.0,
        z.luminance_z,
        z.mean_z2,
        z.outliers * 100.0,
        z.count
    );
    assert!(
        z.luminance_z.abs() < 4.0 && z.mean_z2 <= 2.0 && z.outliers == 0.0,
        "the copper sphere's upper right differs from the course's: {:.2} against {:.2} levels ({:+.1} σ), \
         mean z² {:.2}, |z|>5 in {:.2}% of blocks",
        z.mean_luminance[0] * 255.0,
        z.mean_luminance[1] * 255.0,
        z.luminance_z,
        z.mean_z2,
        z.outliers * 100.0
    );
}
