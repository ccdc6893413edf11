//! luster's LDR-FLIP against NVIDIA's reference implementation.
//!
//! The mean LDR-FLIP of each image pair in `tests/fixtures/flip/` was
//! computed by the `flip-evaluator` package (PyPI, version 1.7: NVlabs/flip's
//! own code) with `tools/flip_reference.py`, at the defaults both share (LDR,
//! sRGB inputs, 67 pixels per degree). The pairs are 128×128 crops of our own
//! renders, chosen to span the range the conformance bars use: Monte Carlo
//! noise between two seeds (0.01), a background blurred by half a texel
//! (0.08), Perlin patterns at two noise scales (0.35, 0.42), and a synthetic
//! hue shift with isolated bright dots (0.32). luster must agree to within
//! 0.0005 absolute, a twentieth of the 0.01 FLIP bar of deterministic scenes.
//!
//! The HDR pairs (`hdr_*.exr`, half floats, 96×96) are crops of two renders
//! of hw5 `cube_point_hdr`, the second with its point light moved and
//! tinted: a falloff and a cube edge (2 exposures each), a shadow edge and
//! the cube against its shadow (4 and 5 exposures, spanning 4 stops). Their
//! mean HDR-FLIP by the same package must agree to within 0.0005 as well.

use luster::image::Rgb32Image;
use luster::metrics::{compare, CompareOptions};
use std::path::PathBuf;

/// (pair, mean LDR-FLIP by flip-evaluator 1.7), as tools/flip_reference.py prints them.
const REFERENCE: &[(&str, f64)] = &[
    ("bump_scale", 0.419578),
    ("frosted_seeds", 0.010580),
    ("perlin_scale", 0.352178),
    ("stars_blur", 0.084709),
    ("synthetic", 0.321597),
];

/// (pair, mean HDR-FLIP by flip-evaluator 1.7), as tools/flip_reference.py prints them.
const HDR_REFERENCE: &[(&str, f64)] = &[
    ("hdr_cube_edge", 0.204707),
    ("hdr_cube_shadow", 0.053171),
    ("hdr_falloff", 0.134917),
    ("hdr_shadow_edge", 0.020417),
];

const TOLERANCE: f64 = 0.0005;

#[test]
fn ldr_flip_matches_the_reference_implementation() {
    check(REFERENCE, "png", "LDR-FLIP");
}

#[test]
fn hdr_flip_matches_the_reference_implementation() {
    check(HDR_REFERENCE, "exr", "HDR-FLIP");
}

fn check(table: &[(&str, f64)], ext: &str, what: &str) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/flip");
    let mut failures = Vec::new();
    for (name, expected) in table {
        let load = |side: &str| {
            let p = dir.join(format!("{name}_{side}.{ext}"));
            Rgb32Image::load(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
        };
        let c = compare(&load("ref"), &load("test"), &CompareOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        println!("{name:<14} luster {:.6}  reference {expected:.6}  Δ {:+.6}", c.flip, c.flip - expected);
        if (c.flip - expected).abs() > TOLERANCE {
            failures.push(format!("{name}: luster {:.6}, reference {expected:.6}", c.flip));
        }
    }
    assert!(
        failures.is_empty(),
        "{what} differs from flip-evaluator by more than {TOLERANCE}:\n{}",
        failures.join("\n")
    );
}
