//! Golden-image tests: render every complete course scene of the implemented
//! homeworks (both encodings) and compare with the course's expected image.
//!
//! Metric and bars live in `luster::conformance::thresholds` (shared with
//! `luster suite`): PSNR on 8-bit RGB and mean LDR-FLIP, by default
//! PSNR ≥ 40 dB and FLIP ≤ 0.01 per image (hw3, which is noisy, is in
//! `golden_hw3.rs`). Every render and a FLIP heatmap is written under
//! `target/tmp/golden/`, so a failure can be looked at.
//!
//! The course folder is read from `../shared/scenes/ceng795`; without it the
//! tests say they skipped, except under `CI=true`, where they fail.

use crate::common;
use common::course_root;
use luster::conformance::{discover, run_case, CaseResult};
use std::path::PathBuf;

/// Runs every scene of `hw` and checks each image; `images` is how many the
/// shared folder has with an expected image, pinned so a lost scene fails.
fn check_homework(hw: &str, images: usize) {
    let Some(root) = course_root(hw) else { return };
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden").join(hw);
    let _ = std::fs::create_dir_all(&out);
    let cases: Vec<_> = discover(&root).into_iter().filter(|c| c.hw == hw).collect();
    assert!(!cases.is_empty(), "no {hw} scenes found under {}", root.display());
    let results: Vec<CaseResult> = cases.iter().map(|c| run_case(c, &out)).collect();

    let mut failures = Vec::new();
    let mut compared = 0;
    println!("{:<48} {:<28} {:>8} {:>7} {:>7} {:>7}", "scene", "image", "PSNR", "SSIM", "FLIP", "sec");
    for r in &results {
        if let Some(e) = &r.error {
            println!("{:<48} LOAD/BUILD FAILED: {e}", r.case.label());
            failures.push(format!("{}: {e}", r.case.label()));
            continue;
        }
        for img in &r.images {
            let Some(c) = &img.comparison else {
                if let Some(e) = &img.error {
                    failures.push(format!("{} {}: {e}", r.case.label(), img.image_name));
                }
                continue;
            };
            compared += 1;
            println!(
                "{:<48} {:<28} {:>8.2} {:>7.4} {:>7.4} {:>7.2} {}",
                r.case.label(),
                img.image_name,
                c.psnr,
                c.ssim,
                c.flip,
                img.seconds,
                if img.pass { "ok" } else { "FAIL" }
            );
            if !img.pass {
                failures.push(format!(
                    "{} {}: PSNR {:.2} dB, FLIP {:.4} (needs PSNR ≥ {} and FLIP ≤ {}); render {} heatmap {}",
                    r.case.label(),
                    img.image_name,
                    c.psnr,
                    c.flip,
                    img.bar.min_psnr,
                    img.bar.max_flip,
                    img.render.display(),
                    img.heatmap.as_ref().map(|p| p.display().to_string()).unwrap_or_default()
                ));
            }
        }
    }
    assert_eq!(compared, images, "{hw} images compared");
    assert!(failures.is_empty(), "{} {hw} image(s) failed:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn hw1_scenes_match_expected_images() {
    check_homework("hw1", 32);
}

#[test]
fn hw2_scenes_match_expected_images() {
    check_homework("hw2", 9);
}
