//! Golden-image tests of hw3 (distribution ray tracing), at reduced sample
//! counts so that CI can afford them.
//!
//! The course's images took 16 to 900 samples per pixel; at those counts the
//! whole homework takes over half an hour here. Each image is rendered twice
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

mod common;
use common::course_root;
use luster::conformance::{discover, run_case_with, CaseResult};
use luster::render::RenderOptions;
use std::path::PathBuf;
use std::time::Instant;

/// Samples per pixel per scene file (its name without extension, either
/// encoding), with why. The cost of one sample per pixel
/// of an 800×800 image ranges from 0.12 s (spheres_dof) to about 1 s
/// (wine_glass) on two cores; the counts keep all 13 images, two renders
/// each, near a minute and a half on two cores, and each at least 4
/// so that every pixel is stratified over its area, lens and light.
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
const KNOWN_BIAS: &[(&str, f64, f64, &str)] = &[(
    "wine_glass.png",
    WINE_Z2,
    WINE_OUT,
    "inside the bowl our image is brighter above the liquid line and darker in the liquid band than the \
     course's: the 8×8 block means differ by up to 36 levels there, a structure that does not average \
     out as noise does",
)];
// What the wine glass's mesh is (measured for issue 18; cause still open):
// 3,846 faces in 116 edge-connected pieces (across edges of two faces): a
// 3,056-face glass and a 558-face liquid, each wound consistently with
// outward normals (positive signed volume), and 114 fragments of 2–4 faces
// cut off by 162 edges that three or four faces share, where the liquid
// meets the glass. So the "opposite" winding is the liquid's outward normal
// facing the glass's inner wall on coincident faces, not a wrongly wound
// face. At 16 spp the 16×16 block means are darkest against the reference
// (−18 levels) in two bands: the liquid's top and the bottom of the bowl.
// Measured in session 7 (region means in 8-bit levels, ours against the
// course's 78 and 79): the bands are exactly where the liquid meets the glass,
// its top ring (image rows 353–358; region 64 against 78) and the 232 faces
// of the fragments (rows 403–420; region 69 against 79). Not the branch
// sampling: one sample per pixel tracing both rays (the course's tree) and
// 16 samples of one branch each agree within 0.2 levels in every region.
// Both bands hang on the interface rules: one more recursion level gives
// 74 and 77 there but 95 against 59 in the liquid band between them, and a
// `ShadowRayEpsilon` of 1e-4 or 1e-2 instead of 1e-3 moves the bottom band
// to 56 or 71. So the course's renderer crosses these coincident and
// non-manifold faces by a rule of its own (tie-breaking, offsets or its
// inside/outside test), not yet found.
/// wine_glass at 4 spp, seeds 0 and 1, measured: mean z² 4.68, |z| > 5 in
/// 0.99% of blocks; the bounds leave half as much again for other machines'
/// rounding, and a bias that grows beyond them fails.
const WINE_Z2: f64 = 7.0;
const WINE_OUT: f64 = 0.015;

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
