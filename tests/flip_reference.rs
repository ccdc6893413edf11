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

use luster::image::{compare, CompareOptions, Rgb32Image};
use std::path::PathBuf;

/// (pair, mean LDR-FLIP by flip-evaluator 1.7), as tools/flip_reference.py prints them.
const REFERENCE: &[(&str, f64)] = &[
    ("bump_scale", 0.419578),
    ("frosted_seeds", 0.010580),
    ("perlin_scale", 0.352178),
    ("stars_blur", 0.084709),
    ("synthetic", 0.321597),
];

const TOLERANCE: f64 = 0.0005;

#[test]
fn ldr_flip_matches_the_reference_implementation() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/flip");
    let mut failures = Vec::new();
    for (name, expected) in REFERENCE {
        let load = |side: &str| {
            let p = dir.join(format!("{name}_{side}.png"));
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
        "LDR-FLIP differs from flip-evaluator by more than {TOLERANCE}:\n{}",
        failures.join("\n")
    );
}
