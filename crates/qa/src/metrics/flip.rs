//! LDR-FLIP: a perceptual difference map for images viewed by flipping between them.
//!
//! Implements the LDR version of
//!
//! > P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström and
//! > M. D. Fairchild, "FLIP: A Difference Evaluator for Alternating Images",
//! > *Proc. ACM Comput. Graph. Interact. Tech.* 3(2), HPG 2020.
//!
//! following the paper's equations and the authors' reference implementation
//! (NVlabs/flip) for the details the paper leaves open (border handling, the
//! exact colour matrices). Inputs are linear RGB in [0, 1]; the output is one
//! error in [0, 1] per pixel.
//!
//! # Colour pipeline
//! 1. Linear RGB → CIE XYZ (D65, sRGB primaries) → YyCxCz, the linearised
//!    L\*a\*b\* opponent space: `Yy = 116·Y/Yn − 16`, `Cx = 500·(X/Xn − Y/Yn)`,
//!    `Cz = 200·(Y/Yn − Z/Zn)`, white `(Xn, Yn, Zn)` = XYZ of RGB (1, 1, 1).
//! 2. Each channel is filtered with a contrast sensitivity function modelled as
//!    a sum of Gaussians (paper eq. 2),
//!    `S(x) = a1·√(π/b1)·exp(−π²x²/b1) + a2·√(π/b2)·exp(−π²x²/b2)`, x in degrees,
//!    normalised to unit sum. The kernel radius is
//!    `⌈3·√(b_max / (2π²))·ppd⌉` with `b_max = 0.04`.
//! 3. Back to linear RGB, clamped to [0, 1]; then to L\*a\*b\* and Hunt-adjusted
//!    (`a ← 0.01·L·a`, `b ← 0.01·L·b`).
//! 4. HyAB distance `|ΔL| + √(Δa² + Δb²)`, raised to `qc`, then redistributed
//!    to [0, 1]: values below `pc·cmax` map linearly to [0, `pt`), the rest
//!    linearly to [`pt`, 1], where `cmax` is the `qc`-th power of the HyAB
//!    distance between Hunt-adjusted green (0,1,0) and blue (0,0,1) — the
//!    largest in the sRGB gamut (≈ 203.4, so `cmax` ≈ 41.4).
//!
//! # Feature pipeline
//! On the unfiltered normalised luminance `Y/Yn`, edges are detected with the
//! first derivative and points with the second derivative of a Gaussian of
//! standard deviation `σ = 0.5·w·ppd` (radius `⌈3σ⌉`), each normalised so its
//! positive weights sum to 1 and its negative weights to −1, applied in x and
//! y. The feature difference is
//! `ΔEf = (max(| ‖edge_ref‖ − ‖edge_test‖ |, | ‖point_ref‖ − ‖point_test‖ |) / √2)^qf`.
//!
//! # Combination
//! `FLIP = ΔEc^(1 − ΔEf)`: feature differences pull the colour error towards 1.
//!
//! # Constants
//! | constant | value | meaning |
//! |---|---|---|
//! | achromatic CSF `a1, b1` | 1, 0.0047 | colour pipeline, one Gaussian |
//! | red–green CSF `a1, b1` | 1, 0.0053 | colour pipeline, one Gaussian |
//! | blue–yellow CSF `a1, b1, a2, b2` | 34.1, 0.04, 13.5, 0.025 | colour pipeline, two Gaussians |
//! | `qc` | 0.7 | colour error exponent |
//! | `pc`, `pt` | 0.4, 0.95 | error redistribution knee |
//! | `w` | 0.082° | peak-to-trough width of the edge detector (feature pipeline) |
//! | `qf` | 0.5 | feature error exponent |
//! | ppd | 67.0 | default pixels per degree: a 0.7 m wide 3840-pixel monitor seen from 0.7 m, `3840·π/180 ≈ 67.02`, rounded as the paper quotes it |
//!
//! The separable structure (the 2-D Gaussians factor; the derivative filters
//! are a 1-D derivative times a 1-D Gaussian, and their per-sign
//! normalisation factors too because the sign depends on one axis only) makes
//! every filter two 1-D passes, which gives exactly the reference's 2-D result.

use std::f32::consts::PI;

use rayon::prelude::*;

use super::filter::{filter_cols, filter_rows, normalize};

/// The paper's default viewing condition, in pixels per degree of visual angle.
pub const DEFAULT_PIXELS_PER_DEGREE: f32 = 67.0;

/// Colour error exponent `qc`.
const QC: f32 = 0.7;
/// Feature error exponent `qf`.
const QF: f32 = 0.5;
/// Redistribution knee: fraction of `cmax` ...
const PC: f32 = 0.4;
/// ... mapped to this fraction of the output range.
const PT: f32 = 0.95;
/// Peak-to-trough width of the edge detector, in degrees.
const FEATURE_W: f32 = 0.082;

/// A contrast sensitivity function `a1·√(π/b1)·e^(−π²x²/b1) + a2·√(π/b2)·e^(−π²x²/b2)`.
struct Csf {
    a1: f32,
    b1: f32,
    a2: f32,
    b2: f32,
}

const CSF_ACHROMATIC: Csf = Csf { a1: 1.0, b1: 0.0047, a2: 0.0, b2: 1e-5 };
const CSF_RED_GREEN: Csf = Csf { a1: 1.0, b1: 0.0053, a2: 0.0, b2: 1e-5 };
const CSF_BLUE_YELLOW: Csf = Csf { a1: 34.1, b1: 0.04, a2: 13.5, b2: 0.025 };
/// The widest scale parameter of the three CSFs; sets the common kernel radius.
const CSF_MAX_B: f32 = 0.04;

/// Linear sRGB → XYZ (D65), exact rationals as in the FLIP reference code.
const RGB_TO_XYZ: [[f32; 3]; 3] = [
    [10_135_552.0 / 24_577_794.0, 8_788_810.0 / 24_577_794.0, 4_435_075.0 / 24_577_794.0],
    [2_613_072.0 / 12_288_897.0, 8_788_810.0 / 12_288_897.0, 887_015.0 / 12_288_897.0],
    [1_425_312.0 / 73_733_382.0, 8_788_810.0 / 73_733_382.0, 70_074_185.0 / 73_733_382.0],
];
/// The inverse of [`RGB_TO_XYZ`].
const XYZ_TO_RGB: [[f32; 3]; 3] = [
    [3.241_003_3, -1.537_398_9, -0.498_615_86],
    [-0.969_224_3, 1.875_930_1, 0.041_554_224],
    [0.055_639_423, -0.204_011_2, 1.057_148_9],
];
/// XYZ of the white point, RGB (1, 1, 1).
const WHITE: [f32; 3] = [0.950_428_5, 1.0, 1.088_900_4];

fn mat_mul(m: &[[f32; 3]; 3], v: [f32; 3]) -> [f32; 3] {
    [
        m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2],
        m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
        m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2],
    ]
}

fn linear_rgb_to_ycxcz(rgb: [f32; 3]) -> [f32; 3] {
    let xyz = mat_mul(&RGB_TO_XYZ, rgb);
    let (x, y, z) = (xyz[0] / WHITE[0], xyz[1] / WHITE[1], xyz[2] / WHITE[2]);
    [116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)]
}

fn ycxcz_to_linear_rgb(c: [f32; 3]) -> [f32; 3] {
    let y = (c[0] + 16.0) / 116.0;
    let x = y + c[1] / 500.0;
    let z = y - c[2] / 200.0;
    mat_mul(&XYZ_TO_RGB, [x * WHITE[0], y * WHITE[1], z * WHITE[2]])
}

fn linear_rgb_to_lab(rgb: [f32; 3]) -> [f32; 3] {
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA * DELTA * DELTA {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let xyz = mat_mul(&RGB_TO_XYZ, rgb);
    let (fx, fy, fz) = (f(xyz[0] / WHITE[0]), f(xyz[1] / WHITE[1]), f(xyz[2] / WHITE[2]));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Hunt adjustment: chroma shrinks with lightness (`a, b ← 0.01·L·a, 0.01·L·b`).
fn hunt(lab: [f32; 3]) -> [f32; 3] {
    let s = 0.01 * lab[0];
    [lab[0], s * lab[1], s * lab[2]]
}

/// HyAB distance: city-block in lightness, Euclidean in chroma.
fn hyab(p: [f32; 3], q: [f32; 3]) -> f32 {
    let (dl, da, db) = (p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    dl.abs() + (da * da + db * db).sqrt()
}

/// `cmax = HyAB(hunt(lab(green)), hunt(lab(blue)))^qc`.
fn cmax() -> f32 {
    let green = hunt(linear_rgb_to_lab([0.0, 1.0, 0.0]));
    let blue = hunt(linear_rgb_to_lab([0.0, 0.0, 1.0]));
    hyab(green, blue).powf(QC)
}

/// Maps `HyAB^qc` to [0, 1]: [0, pc·cmax) → [0, pt), [pc·cmax, cmax] → [pt, 1].
fn redistribute(e: f32, cmax: f32) -> f32 {
    let knee = PC * cmax;
    if e < knee {
        PT / knee * e
    } else {
        PT + (e - knee) / (cmax - knee) * (1.0 - PT)
    }
}

/// The 1-D kernels of a CSF: one or two unit-sum Gaussians and their weights.
struct CsfKernels {
    terms: Vec<(f32, Vec<f32>)>,
}

impl CsfKernels {
    fn new(csf: &Csf, ppd: f32, radius: usize) -> Self {
        // The 2-D kernel is Σ aᵢ√(π/bᵢ)·gᵢ(x)gᵢ(y), with gᵢ(x) = exp(−π²(x/ppd)²/bᵢ),
        // divided by its total Σ aᵢ√(π/bᵢ)·(Σₓ gᵢ)². With ĝᵢ = gᵢ / Σgᵢ it is
        // Σ wᵢ·ĝᵢ(x)ĝᵢ(y) with wᵢ = aᵢ√(π/bᵢ)(Σgᵢ)² / total.
        let mut raw = Vec::new();
        for (a, b) in [(csf.a1, csf.b1), (csf.a2, csf.b2)] {
            if a == 0.0 {
                continue;
            }
            let g: Vec<f32> = (-(radius as i64)..=radius as i64)
                .map(|x| {
                    let d = x as f32 / ppd;
                    (-PI * PI * d * d / b).exp()
                })
                .collect();
            let sum: f32 = g.iter().sum();
            raw.push((a * (PI / b).sqrt() * sum * sum, normalize(g)));
        }
        let total: f32 = raw.iter().map(|(w, _)| w).sum();
        let terms = raw.into_iter().map(|(w, g)| (w / total, g)).collect();
        Self { terms }
    }

    fn apply(&self, plane: &[f32], width: usize) -> Vec<f32> {
        let mut out = vec![0.0; plane.len()];
        for (w, g) in &self.terms {
            let filtered = filter_cols(&filter_rows(plane, width, g), width, g);
            out.par_iter_mut().zip(filtered.par_iter()).for_each(|(o, f)| *o += w * f);
        }
        out
    }
}

/// The 1-D pieces of the edge and point detectors.
struct FeatureKernels {
    /// Unit-sum Gaussian (the smoothing axis).
    gauss: Vec<f32>,
    /// First derivative, positive and negative parts each normalised to ±1.
    edge: Vec<f32>,
    /// Second derivative, positive and negative parts each normalised to ±1.
    point: Vec<f32>,
}

impl FeatureKernels {
    fn new(ppd: f32) -> Self {
        let sd = 0.5 * FEATURE_W * ppd;
        let radius = (3.0 * sd).ceil() as i64;
        let xs: Vec<f32> = (-radius..=radius).map(|x| x as f32).collect();
        let g: Vec<f32> = xs.iter().map(|x| (-x * x / (2.0 * sd * sd)).exp()).collect();
        let edge = xs.iter().zip(&g).map(|(x, g)| -x * g).collect();
        let point = xs.iter().zip(&g).map(|(x, g)| (x * x / (sd * sd) - 1.0) * g).collect();
        Self { gauss: normalize(g), edge: normalize_by_sign(edge), point: normalize_by_sign(point) }
    }
}

/// Scales positive weights to sum to 1 and negative weights to sum to −1.
fn normalize_by_sign(mut k: Vec<f32>) -> Vec<f32> {
    let pos: f32 = k.iter().filter(|w| **w > 0.0).sum();
    let neg: f32 = -k.iter().filter(|w| **w < 0.0).sum::<f32>();
    for w in &mut k {
        if *w > 0.0 && pos > 0.0 {
            *w /= pos;
        } else if *w < 0.0 && neg > 0.0 {
            *w /= neg;
        }
    }
    k
}

/// What each image contributes to the final per-pixel comparison.
struct Prepared {
    /// Hunt-adjusted L*a*b* of the CSF-filtered image.
    lab: Vec<[f32; 3]>,
    /// Edge response magnitude.
    edges: Vec<f32>,
    /// Point response magnitude.
    points: Vec<f32>,
}

fn prepare(rgb: &[[f32; 3]], width: usize, ppd: f32, features: &FeatureKernels) -> Prepared {
    let n = rgb.len();
    let mut planes = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    for (i, p) in rgb.iter().enumerate() {
        let c = linear_rgb_to_ycxcz(*p);
        planes[0][i] = c[0];
        planes[1][i] = c[1];
        planes[2][i] = c[2];
    }

    // Colour: CSF filtering per opponent channel.
    let radius = (3.0 * (CSF_MAX_B / (2.0 * PI * PI)).sqrt() * ppd).ceil() as usize;
    let csfs = [&CSF_ACHROMATIC, &CSF_RED_GREEN, &CSF_BLUE_YELLOW];
    let filtered: Vec<Vec<f32>> = csfs
        .par_iter()
        .zip(planes.par_iter())
        .map(|(csf, plane)| CsfKernels::new(csf, ppd, radius).apply(plane, width))
        .collect();
    let lab = (0..n)
        .into_par_iter()
        .map(|i| {
            let rgb = ycxcz_to_linear_rgb([filtered[0][i], filtered[1][i], filtered[2][i]]);
            hunt(linear_rgb_to_lab(rgb.map(|c| c.clamp(0.0, 1.0))))
        })
        .collect();

    // Features: on normalised luminance Y/Yn = (Yy + 16) / 116 of the unfiltered image.
    let lum: Vec<f32> = planes[0].iter().map(|y| (y + 16.0) / 116.0).collect();
    let rows_g = filter_rows(&lum, width, &features.gauss);
    let rows_e = filter_rows(&lum, width, &features.edge);
    let rows_p = filter_rows(&lum, width, &features.point);
    let (edges, points) = rayon::join(
        || {
            let ex = filter_cols(&rows_e, width, &features.gauss);
            let ey = filter_cols(&rows_g, width, &features.edge);
            ex.iter().zip(&ey).map(|(x, y)| (x * x + y * y).sqrt()).collect()
        },
        || {
            let px = filter_cols(&rows_p, width, &features.gauss);
            let py = filter_cols(&rows_g, width, &features.point);
            px.iter().zip(&py).map(|(x, y)| (x * x + y * y).sqrt()).collect()
        },
    );
    Prepared { lab, edges, points }
}

/// The per-pixel LDR-FLIP error between two linear-RGB images in [0, 1].
///
/// `reference` and `test` are row-major with `width` pixels per row and must
/// have the same length; `ppd` is the observer's pixels per degree
/// ([`DEFAULT_PIXELS_PER_DEGREE`] for the paper's setup).
pub fn ldr_flip_map(reference: &[[f32; 3]], test: &[[f32; 3]], width: usize, ppd: f32) -> Vec<f32> {
    debug_assert_eq!(reference.len(), test.len());
    if reference.is_empty() || width == 0 {
        return Vec::new();
    }
    let features = FeatureKernels::new(ppd);
    let (r, t) =
        rayon::join(|| prepare(reference, width, ppd, &features), || prepare(test, width, ppd, &features));
    let cmax = cmax();
    let sqrt_half = std::f32::consts::FRAC_1_SQRT_2;
    (0..reference.len())
        .into_par_iter()
        .map(|i| {
            let color = redistribute(hyab(r.lab[i], t.lab[i]).powf(QC), cmax);
            let edge = (r.edges[i] - t.edges[i]).abs();
            let point = (r.points[i] - t.points[i]).abs();
            let feature = (sqrt_half * edge.max(point)).powf(QF);
            color.powf(1.0 - feature)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_transforms_round_trip() {
        for rgb in [[0.2, 0.5, 0.9], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [1.0, 1.0, 1.0]] {
            let back = ycxcz_to_linear_rgb(linear_rgb_to_ycxcz(rgb));
            for c in 0..3 {
                assert!((back[c] - rgb[c]).abs() < 1e-4, "{rgb:?} -> {back:?}");
            }
        }
        let white = linear_rgb_to_lab([1.0, 1.0, 1.0]);
        assert!((white[0] - 100.0).abs() < 1e-3 && white[1].abs() < 1e-3 && white[2].abs() < 1e-3);
    }

    #[test]
    fn cmax_matches_the_paper() {
        // HyAB(green, blue) in Hunt-adjusted L*a*b* is about 203.4.
        let d = cmax().powf(1.0 / QC);
        assert!((d - 203.4).abs() < 0.5, "{d}");
    }

    #[test]
    fn redistribution_is_continuous_and_bounded() {
        let c = cmax();
        assert!((redistribute(PC * c - 1e-4, c) - PT).abs() < 1e-3);
        assert!((redistribute(c, c) - 1.0).abs() < 1e-6);
        assert_eq!(redistribute(0.0, c), 0.0);
    }

    #[test]
    fn kernels_are_normalised() {
        let f = FeatureKernels::new(DEFAULT_PIXELS_PER_DEGREE);
        assert_eq!(f.gauss.len(), 19); // σ = 2.747, radius ⌈8.24⌉ = 9
        assert!((f.gauss.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        let pos: f32 = f.point.iter().filter(|w| **w > 0.0).sum();
        let neg: f32 = f.point.iter().filter(|w| **w < 0.0).sum();
        assert!((pos - 1.0).abs() < 1e-5 && (neg + 1.0).abs() < 1e-5);
        assert!(f.edge.iter().sum::<f32>().abs() < 1e-5);
        let csf = CsfKernels::new(&CSF_BLUE_YELLOW, DEFAULT_PIXELS_PER_DEGREE, 10);
        let total: f32 = csf.terms.iter().map(|(w, g)| w * g.iter().sum::<f32>().powi(2)).sum();
        assert!((total - 1.0).abs() < 1e-5);
    }
}
