//! Environment light: orientation against hw5's formulas, the pdf over the
//! sphere, sampling against the pdf (chi-square), and a furnace test.

use super::*;
use crate::light::Light;
use crate::render::sampler::PixelSampler;

use crate::light::test_rng::Rng;

/// A sky-like map: a vertical gradient, a dark band, and one bright texel
/// (the "sun"), so the distribution is far from uniform.
fn sky(w: u32, h: u32) -> Image {
    let mut t = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let g = 0.2 + 2.0 * (1.0 - y as f32 / h as f32);
            let c = if x == w / 4 && y == h / 5 {
                [400.0, 380.0, 300.0]
            } else if y == h / 2 {
                [0.0, 0.0, 0.0]
            } else {
                [g * 0.6, g * 0.8, g + (x % 3) as f32 * 0.1]
            };
            t.push(c);
        }
    }
    Image::from_rgb32f(w, h, t).expect("valid size")
}

fn constant(l: f32) -> Image {
    Image::from_rgb32f(8, 4, vec![[l, l, l]; 32]).expect("valid size")
}

/// `∫ f(ω) dω` by the midpoint rule on an `n × 2n` grid in (cos θ, φ), whose
/// cells have equal solid angle.
fn integrate(f: impl Fn(Vec3) -> f64, n: usize) -> f64 {
    let mut sum = 0.0;
    for i in 0..n {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..2 * n {
            let phi = std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
            sum += f(Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32));
        }
    }
    sum * 4.0 * std::f64::consts::PI / (2 * n * n) as f64
}

#[test]
fn latlong_orientation_follows_hw5() {
    let env = Environment::new(&sky(16, 8), EnvMapping::LatLong, EnvSampling::Importance).expect("valid map");
    // u = (1 + atan2(dx, -dz)/π)/2, v = acos(dy)/π.
    let cases = [
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(0.5, 0.5)),
        (Vec3::new(1.0, 0.0, 0.0), Vec2::new(0.75, 0.5)),
        (Vec3::new(-1.0, 0.0, 0.0), Vec2::new(0.25, 0.5)),
        (Vec3::new(0.0, 0.0, 1.0), Vec2::new(1.0, 0.5)),
    ];
    for (d, uv) in cases {
        assert!((env.uv(d) - uv).length() < 1e-6, "{d:?}: {:?} vs {uv:?}", env.uv(d));
    }
    // At the poles u is arbitrary; v is 0 straight up and 1 straight down.
    assert_eq!(env.uv(Vec3::Y).y, 0.0);
    assert_eq!(env.uv(-Vec3::Y).y, 1.0);
    // direction() inverts uv().
    let mut rng = Rng(3);
    for _ in 0..1000 {
        let uv = Vec2::new(rng.next(), 0.01 + 0.98 * rng.next());
        let d = env.direction(uv).expect("every lat-long point is a direction");
        assert!((d.length() - 1.0).abs() < 1e-5);
        assert!((env.uv(d) - uv).length() < 1e-4, "{uv:?} → {d:?} → {:?}", env.uv(d));
    }
}

#[test]
fn probe_orientation_centre_is_minus_z_and_rim_is_plus_z() {
    let env = Environment::new(&sky(16, 16), EnvMapping::Probe, EnvSampling::Importance).expect("valid map");
    assert!((env.uv(Vec3::new(0.0, 0.0, -1.0)) - Vec2::new(0.5, 0.5)).length() < 1e-6);
    // 90° from -z is half-way to the rim; +y is up (smaller v).
    assert!((env.uv(Vec3::new(0.0, 1.0, 0.0)) - Vec2::new(0.5, 0.25)).length() < 1e-6);
    assert!((env.uv(Vec3::new(1.0, 0.0, 0.0)) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    let near_back = Vec3::new(0.0, 1e-3, 1.0).normalize();
    assert!((env.uv(near_back) - Vec2::new(0.5, 0.0)).length() < 1e-3);
    assert!(env.direction(Vec2::new(0.02, 0.02)).is_none(), "a corner lies outside the circle");
    let mut rng = Rng(5);
    for _ in 0..1000 {
        let uv = Vec2::new(rng.next(), rng.next());
        if let Some(d) = env.direction(uv) {
            assert!((env.uv(d) - uv).length() < 1e-3, "{uv:?} → {d:?} → {:?}", env.uv(d));
        }
    }
}

#[test]
fn pdf_integrates_to_one_over_the_sphere() {
    for mapping in [EnvMapping::LatLong, EnvMapping::Probe] {
        let env = Environment::new(&sky(32, 16), mapping, EnvSampling::Importance).expect("valid map");
        let total = integrate(|d| env.pdf(d) as f64, 1000);
        assert!((total - 1.0).abs() < 5e-3, "{mapping:?}: ∫pdf = {total}");
    }
}

/// The value and density a draw returns are the radiance and density of
/// its direction looked up again, for every sampling mode (the density is
/// what MIS weighs a bounce that leaves the same way with).
#[test]
fn sampled_value_is_radiance_over_pdf() {
    let n = Vec3::new(0.3, 0.8, -0.2).normalize();
    for (mapping, sampling, normal) in [
        (EnvMapping::LatLong, EnvSampling::Importance, None),
        (EnvMapping::Probe, EnvSampling::Importance, None),
        (EnvMapping::LatLong, EnvSampling::Importance, Some(n)),
        (EnvMapping::LatLong, EnvSampling::Uniform, Some(n)),
        (EnvMapping::LatLong, EnvSampling::Cosine, Some(n)),
    ] {
        let env = Environment::new(&sky(32, 16), mapping, sampling).expect("valid map");
        let mut rng = Rng(11);
        for _ in 0..2000 {
            let Some((d, e, pdf)) = env.sample(normal, (rng.next(), rng.next())) else { continue };
            let want_pdf = env.sampling_pdf(normal, d);
            assert!((pdf - want_pdf).abs() <= 2e-3 * want_pdf, "{sampling:?}: pdf {pdf} vs {want_pdf}");
            let expect = env.eval(d) / want_pdf;
            assert!(
                (e - expect).abs().max_element() <= 2e-3 * expect.max_element().max(1.0),
                "{sampling:?}: {e:?} vs {expect:?}"
            );
            let (le, p) = env.eval_with_pdf(normal, d);
            assert_eq!((le, p), (env.eval(d), want_pdf), "eval_with_pdf is eval and sampling_pdf");
        }
    }
}

/// Pearson's chi-square of importance-sampled directions binned on a
/// 10 × 20 equal-area grid in (cos θ, φ), against the pdf integrated over each
/// bin, and the test's limit. Bins expecting fewer than 5 samples are pooled
/// into one. The 99.9% point of χ²(k) is below k + 3.1√(2k) + 2 for the k here.
fn chi_square(env: &Environment, seed: u64) -> (f64, usize, f64) {
    let (nz, nphi) = (10usize, 20usize);
    let bin = |d: Vec3| {
        let z = (((d.z + 1.0) * 0.5 * nz as f32) as usize).min(nz - 1);
        let phi = d.y.atan2(d.x).rem_euclid(2.0 * std::f32::consts::PI);
        let p = ((phi / (2.0 * std::f32::consts::PI) * nphi as f32) as usize).min(nphi - 1);
        z * nphi + p
    };
    let n = 400_000usize;
    let mut observed = vec![0f64; nz * nphi];
    let mut rng = Rng(seed);
    for _ in 0..n {
        if let Some((d, _, _)) = env.sample(None, (rng.next(), rng.next())) {
            observed[bin(d)] += 1.0;
        }
    }
    let mut expected = vec![0f64; nz * nphi];
    let m = 1200;
    for i in 0..m {
        let z = -1.0 + 2.0 * (i as f64 + 0.5) / m as f64;
        let r = (1.0 - z * z).sqrt();
        for j in 0..2 * m {
            let phi = std::f64::consts::PI * (j as f64 + 0.5) / m as f64;
            let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            expected[bin(d)] += env.pdf(d) as f64;
        }
    }
    let scale = 4.0 * std::f64::consts::PI / (2 * m * m) as f64 * n as f64;
    let (mut chi2, mut k) = (0.0, 0usize);
    let (mut pool_o, mut pool_e) = (0.0, 0.0);
    for (o, e) in observed.iter().zip(&expected) {
        let e = e * scale;
        if e < 5.0 {
            pool_o += o;
            pool_e += e;
        } else {
            chi2 += (o - e).powi(2) / e;
            k += 1;
        }
    }
    if pool_e >= 5.0 {
        chi2 += (pool_o - pool_e).powi(2) / pool_e;
        k += 1;
    }
    let dof = (k - 1) as f64;
    (chi2, k, dof + 3.1 * (2.0 * dof).sqrt() + 2.0)
}

#[test]
fn sampling_matches_pdf_chi_square() {
    for mapping in [EnvMapping::LatLong, EnvMapping::Probe] {
        let env = Environment::new(&sky(32, 16), mapping, EnvSampling::Importance).expect("valid map");
        let (chi2, k, limit) = chi_square(&env, 17);
        assert!(chi2 < limit, "{mapping:?}: χ² = {chi2:.1} over {k} bins (limit {limit:.1})");
    }
}

/// `d` turned by `deg` about `+y`, counter-clockwise seen from above.
fn turned(d: Vec3, deg: f32) -> Vec3 {
    let (s, c) = deg.to_radians().sin_cos();
    Vec3::new(c * d.x + s * d.z, d.y, c * d.z - s * d.x)
}

/// A turned map: what the unturned map shows at `d` is seen at `R(γ) d`;
/// the pdf still integrates to one, samples follow it (chi-square), and a
/// sample's value is the looked-up radiance over the pdf.
#[test]
fn rotation_turns_lookup_sampling_and_pdf_together() {
    let plain = Environment::new(&sky(32, 16), EnvMapping::LatLong, EnvSampling::Importance).expect("valid");
    // -z (the map's centre) turned 90° counter-clockwise seen from above is -x.
    let quarter = Environment::new(&sky(32, 16), EnvMapping::LatLong, EnvSampling::Importance)
        .and_then(|e| e.placed(90.0, 1.0))
        .expect("valid");
    assert!((quarter.uv(Vec3::NEG_X) - Vec2::new(0.5, 0.5)).length() < 1e-6, "{:?}", quarter.uv(Vec3::NEG_X));
    assert!((quarter.uv(Vec3::NEG_Z) - Vec2::new(0.75, 0.5)).length() < 1e-6);
    for (mapping, deg) in
        [(EnvMapping::LatLong, 37.0), (EnvMapping::LatLong, -150.0), (EnvMapping::Probe, 200.0)]
    {
        let unturned = Environment::new(&sky(32, 16), mapping, EnvSampling::Importance).expect("valid");
        let env = Environment::new(&sky(32, 16), mapping, EnvSampling::Importance)
            .and_then(|e| e.placed(deg, 1.0))
            .expect("valid");
        let mut rng = Rng(23);
        for _ in 0..2000 {
            let z = 2.0 * rng.next() - 1.0;
            let phi = 2.0 * std::f32::consts::PI * rng.next();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let d = Vec3::new(r * phi.cos(), z, r * phi.sin());
            let seen = turned(d, deg);
            assert_eq!(env.eval(seen), unturned.eval(d), "{mapping:?} {deg}: {d:?}");
            let (a, b) = (env.pdf(seen), unturned.pdf(d));
            assert!((a - b).abs() <= 1e-3 * b.max(1e-3), "{mapping:?} {deg}: pdf {a} vs {b}");
        }
        let total = integrate(|d| env.pdf(d) as f64, 1000);
        assert!((total - 1.0).abs() < 5e-3, "{mapping:?} {deg}: ∫pdf = {total}");
        let (chi2, k, limit) = chi_square(&env, 29);
        assert!(chi2 < limit, "{mapping:?} {deg}: χ² = {chi2:.1} over {k} bins (limit {limit:.1})");
        for _ in 0..2000 {
            let Some((d, e, _)) = env.sample(None, (rng.next(), rng.next())) else { continue };
            let expect = env.eval(d) / env.pdf(d);
            assert!(
                (e - expect).abs().max_element() <= 2e-3 * expect.max_element().max(1.0),
                "{mapping:?} {deg}: {e:?} vs {expect:?}"
            );
        }
    }
    // A whole turn is no turn; the course's maps keep their exact lookups.
    let whole = Environment::new(&sky(32, 16), EnvMapping::LatLong, EnvSampling::Importance)
        .and_then(|e| e.placed(360.0, 1.0))
        .expect("valid");
    let d = Vec3::new(0.3, 0.4, -0.866).normalize();
    assert_eq!(whole.uv(d), plain.uv(d));
}

/// Strength scales every value and no density; a product that overflows is
/// refused with the texel named.
#[test]
fn strength_scales_radiance_not_the_density() {
    let plain = Environment::new(&sky(32, 16), EnvMapping::LatLong, EnvSampling::Importance).expect("valid");
    let bright = Environment::new(&sky(32, 16), EnvMapping::LatLong, EnvSampling::Importance)
        .and_then(|e| e.placed(0.0, 255.0))
        .expect("valid");
    let mut rng = Rng(31);
    for _ in 0..500 {
        let d = Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5).normalize();
        assert_eq!(bright.eval(d), plain.eval(d) * 255.0);
        assert_eq!(bright.pdf(d), plain.pdf(d));
    }
    let huge = Image::from_rgb32f(4, 2, vec![[3e38, 1.0, 1.0]; 8]).expect("valid size");
    let e = Environment::new(&huge, EnvMapping::LatLong, EnvSampling::Importance)
        .and_then(|e| e.placed(0.0, 10.0))
        .expect_err("overflows");
    assert!(e.contains("(0, 0)") && e.contains("too bright"), "{e}");
}

/// The furnace: under a constant environment `L`, a diffuse surface with
/// coefficient `kd` receives `∫ kd L cos θ dω = π kd L` (the course's diffuse
/// term has no 1/π). Every sampler must converge to it; the mean of 65 536
/// stratified light samples is held to 1% (the estimator's standard error
/// here is under 0.4% for the noisiest, the uniform sampler).
#[test]
fn furnace_constant_environment_gives_pi_kd_l() {
    let l = 2.0;
    let n = Vec3::new(0.3, 0.8, -0.52).normalize();
    for mapping in [EnvMapping::LatLong, EnvMapping::Probe] {
        for sampling in [EnvSampling::Importance, EnvSampling::Uniform, EnvSampling::Cosine] {
            let light = Light::Environment(std::sync::Arc::new(
                Environment::new(&constant(l), mapping, sampling).expect("valid map"),
            ));
            let count = 65_536u32;
            let mut sum = 0.0f64;
            for i in 0..count {
                let mut s = PixelSampler::new(9, 1, 2, i, count);
                if let Some(ls) = light.sample(Vec3::ZERO, Some(n), 0.0, &mut s) {
                    let cos = ls.wi.dot(n);
                    if cos > 0.0 {
                        sum += (ls.e.x * cos) as f64;
                    }
                }
            }
            let mean = sum / count as f64;
            let expect = std::f64::consts::PI * l as f64;
            assert!((mean / expect - 1.0).abs() < 0.01, "{mapping:?} {sampling:?}: {mean} vs π L = {expect}");
        }
    }
}

#[test]
fn bad_texels_are_refused() {
    for (v, word) in [(f32::NAN, "NaN"), (f32::INFINITY, "infinite"), (-1.0, "negative")] {
        let mut t = vec![[1.0f32; 3]; 8];
        t[5] = [1.0, v, 1.0];
        let img = Image::from_rgb32f(4, 2, t).expect("valid size");
        let e =
            Environment::new(&img, EnvMapping::LatLong, EnvSampling::Importance).expect_err("must refuse");
        assert!(e.contains(word) && e.contains("(1, 1)"), "{e}");
    }
}

#[test]
fn black_environment_gives_no_light_and_no_nan() {
    let env =
        Environment::new(&constant(0.0), EnvMapping::LatLong, EnvSampling::Importance).expect("valid map");
    let mut rng = Rng(1);
    for _ in 0..100 {
        if let Some((d, e, _)) = env.sample(None, (rng.next(), rng.next())) {
            assert!((d.length() - 1.0).abs() < 1e-5);
            assert_eq!(e, Vec3::ZERO);
        }
    }
}
