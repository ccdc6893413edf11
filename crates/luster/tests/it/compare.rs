//! `luster compare` through the binary: metrics printed, exit codes 0/1/2,
//! one-sentence errors, and the heatmap written on request.

use image::{Rgb, RgbImage};
use std::path::Path;
use std::process::{Command, Output};

fn luster(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_luster")).args(args).output().expect("the luster binary runs")
}

fn gradient(w: u32, h: u32, bump: u8) -> RgbImage {
    RgbImage::from_fn(w, h, |x, y| {
        let v = ((x * 255 / w.max(1)) as u8).saturating_add(if x == w / 2 && y == h / 2 { bump } else { 0 });
        Rgb([v, (y * 255 / h.max(1)) as u8, 128])
    })
}

fn save(img: &RgbImage, dir: &Path, name: &str) -> String {
    let p = dir.join(name);
    img.save(&p).unwrap();
    p.to_str().unwrap().to_string()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn identical_images_exit_0_with_infinite_psnr() {
    let dir = tempfile::tempdir().unwrap();
    let a = save(&gradient(32, 24, 0), dir.path(), "a.png");
    let b = save(&gradient(32, 24, 0), dir.path(), "b.png");
    let heat = dir.path().join("heat.png");
    let out = luster(&[
        "compare",
        &a,
        &b,
        "--heatmap",
        heat.to_str().unwrap(),
        "--max-error",
        "0",
        "--min-psnr",
        "99",
    ]);
    let s = stdout(&out);
    assert_eq!(out.status.code(), Some(0), "{s}{}", stderr(&out));
    assert!(s.contains("inf dB"), "{s}");
    assert!(s.contains("0 of 768 pixels"), "{s}");
    assert!(s.contains("display values"), "{s}");
    assert!(s.contains("bbox       none"), "{s}");
    let written = image::open(&heat).unwrap().to_rgb8();
    assert_eq!(written.dimensions(), (32, 24));
}

#[test]
fn different_sizes_exit_2_naming_both_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let a = save(&gradient(32, 24, 0), dir.path(), "a.png");
    let b = save(&gradient(16, 24, 0), dir.path(), "b.png");
    let out = luster(&["compare", &a, &b]);
    assert_eq!(out.status.code(), Some(2));
    let e = stderr(&out);
    assert!(e.contains("32×24") && e.contains("16×24"), "{e}");
    assert_eq!(e.trim().lines().count(), 1, "one sentence: {e}");
}

#[test]
fn unreadable_image_exits_2_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let a = save(&gradient(8, 8, 0), dir.path(), "a.png");
    let missing = dir.path().join("missing.png");
    let out = luster(&["compare", &a, missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("missing.png"), "{}", stderr(&out));
}

#[test]
fn unmet_bounds_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let a = save(&gradient(32, 24, 0), dir.path(), "a.png");
    let b = save(&gradient(32, 24, 100), dir.path(), "b.png");

    let plain = luster(&["compare", &a, &b]);
    assert_eq!(plain.status.code(), Some(0), "no bounds, no failure");
    let s = stdout(&plain);
    assert!(s.contains("1 of 768 pixels"), "{s}");
    assert!(s.contains("x 16..=16, y 12..=12"), "{s}");

    let psnr = luster(&["compare", &a, &b, "--min-psnr", "80"]);
    assert_eq!(psnr.status.code(), Some(1));
    assert!(stdout(&psnr).contains("below --min-psnr 80"), "{}", stdout(&psnr));

    let flip = luster(&["compare", &a, &b, "--max-error", "0"]);
    assert_eq!(flip.status.code(), Some(1));
    assert!(stdout(&flip).contains("above --max-error 0"), "{}", stdout(&flip));

    let lenient = luster(&["compare", &a, &b, "--max-error", "0.5", "--min-psnr", "10"]);
    assert_eq!(lenient.status.code(), Some(0));

    let tolerant = luster(&["compare", &a, &b, "--tolerance", "255"]);
    assert!(stdout(&tolerant).contains("0 of 768 pixels"), "{}", stdout(&tolerant));
}
