//! The [`Bsdf`] interface against itself: a sample's density and value are
//! what [`Bsdf::pdf`] and [`Bsdf::f_cos`] give for the same direction, under
//! every [`Strategy`] and for every kind of material, and each strategy's
//! density integrates to one over the hemisphere.

use super::*;
use luster_scene::description::{BrdfDesc, BrdfKind};

/// PCG32 (O'Neill 2014) with a fixed seed: every run draws the same samples.
struct Pcg(u64);

impl Pcg {
    fn next(&mut self) -> f32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        let x = (((old >> 18) ^ old) >> 27) as u32;
        (x.rotate_right((old >> 59) as u32) >> 8) as f32 / (1u32 << 24) as f32
    }
}

/// Materials covering each path through the interface: the course's
/// Blinn-Phong without a BRDF, diffuse-only Phong (the cached value), glossy
/// Phong and Torrance–Sparrow (a shader closure has its own test below).
fn materials() -> Vec<(&'static str, Material)> {
    let kd = Vec3::new(0.5, 0.4, 0.3);
    let ks = Vec3::new(0.3, 0.3, 0.35);
    let brdf = |kind, exponent: f32| {
        Some(Brdf::from_desc(
            &BrdfDesc {
                id: "b".into(),
                kind,
                exponent: Some(exponent),
                normalized: true,
                kd_fresnel: true,
                loc: Default::default(),
            },
            exponent,
            1.5,
            2.0,
        ))
    };
    let make = |diffuse, specular, brdf| {
        let mut m = Material { diffuse, specular, phong: 20.0, brdf, ..Material::default() };
        m.refresh();
        m
    };
    vec![
        ("Blinn-Phong (course)", make(kd, ks, None)),
        ("diffuse-only Phong", make(kd, Vec3::ZERO, brdf(BrdfKind::ModifiedPhong, 10.0))),
        ("glossy Blinn-Phong", make(kd, ks, brdf(BrdfKind::ModifiedBlinnPhong, 40.0))),
        ("Torrance-Sparrow", make(kd, ks, brdf(BrdfKind::TorranceSparrow, 30.0))),
    ]
}

const STRATEGIES: [Strategy; 3] = [Strategy::Uniform, Strategy::Cosine, Strategy::Brdf];

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-4 * a.abs().max(b.abs()).max(1e-3)
}

#[test]
fn a_sample_is_what_pdf_and_f_cos_say_of_its_direction() {
    let mut rng = Pcg(0x853c_49e6_748f_ea9b);
    let n = Vec3::new(0.3, -0.2, 0.93).normalize();
    for (name, m) in materials() {
        for strategy in STRATEGIES {
            let mut drawn = 0;
            for _ in 0..2000 {
                // A viewer above the surface: `d` arrives against `n`.
                let d = -(n + Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5)).normalize();
                if d.dot(n) >= 0.0 {
                    continue;
                }
                let bsdf = Bsdf::new(&m, n, d);
                let Some(s) = bsdf.sample(strategy, rng.next(), (rng.next(), rng.next())) else { continue };
                drawn += 1;
                let cos = n.dot(s.wi);
                assert!(cos > 0.0 && s.pdf > 0.0, "{name} {strategy:?}: a sample above the surface");
                let pdf = bsdf.pdf(s.wi, cos, strategy);
                assert!(close(s.pdf, pdf), "{name} {strategy:?}: sample pdf {} vs pdf {pdf}", s.pdf);
                let f = bsdf.f_cos(s.wi, cos);
                for c in 0..3 {
                    assert!(close(s.f_cos[c], f[c]), "{name} {strategy:?}: f cos {} vs {f}", s.f_cos);
                }
                let (f2, pdf2) = bsdf.eval_pdf(s.wi, cos, strategy);
                assert_eq!(f2, f, "{name} {strategy:?}: eval_pdf's f cos is f_cos's");
                if strategy == Strategy::Brdf || m.brdf.is_none() {
                    assert!(close(pdf2, pdf), "{name} {strategy:?}: eval_pdf's density {pdf2} vs {pdf}");
                }
            }
            assert!(drawn > 1000, "{name} {strategy:?}: only {drawn} samples drawn");
        }
    }
}

/// The density over the upper hemisphere integrates to the chance that
/// [`Bsdf::sample`] returns a direction at all (1 for the cosine and uniform
/// strategies; a lobe's mass below the horizon is lost): midpoint quadrature
/// of `pdf` against the accepted share of many samples, within four standard
/// deviations of that share plus the quadrature's error.
#[test]
fn every_strategys_density_integrates_to_its_acceptance() {
    let n = Vec3::Z;
    let (nc, np) = (400, 400);
    let mut rng = Pcg(0xda3e_39cb_94b9_5bdb);
    for (name, m) in materials() {
        let bsdf = Bsdf::new(&m, n, -Vec3::new(0.4, 0.1, 0.8).normalize());
        for strategy in STRATEGIES {
            let mut total = 0.0f64;
            for i in 0..nc {
                let cos = (i as f32 + 0.5) / nc as f32;
                let sin = (1.0 - cos * cos).sqrt();
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * std::f32::consts::TAU;
                    let wi = Vec3::new(sin * phi.cos(), sin * phi.sin(), cos);
                    total += f64::from(bsdf.pdf(wi, cos, strategy));
                }
            }
            let integral = total * std::f64::consts::TAU / (nc * np) as f64;
            let draws = 200_000;
            let accepted = (0..draws)
                .filter(|_| bsdf.sample(strategy, rng.next(), (rng.next(), rng.next())).is_some())
                .count();
            let share = accepted as f64 / draws as f64;
            let sigma = (share * (1.0 - share) / draws as f64).sqrt();
            assert!(
                (integral - share).abs() < 4.0 * sigma + 0.005,
                "{name} {strategy:?}: ∫ p dω = {integral}, accepted {share}"
            );
            if strategy != Strategy::Brdf || m.brdf.is_none() {
                assert!((integral - 1.0).abs() < 0.005, "{name} {strategy:?}: ∫ p dω = {integral}");
            }
        }
    }
}

#[test]
fn flags_name_the_lobes_a_material_has() {
    let (kd, ks) = (Vec3::splat(0.5), Vec3::splat(0.2));
    let m = Material { diffuse: kd, ..Material::default() };
    assert_eq!(m.flags(), Flags::DIFFUSE | Flags::REFLECTION);
    let m = Material { diffuse: kd, specular: ks, ..Material::default() };
    assert!(m.flags().contains(Flags::DIFFUSE | Flags::GLOSSY) && !m.flags().intersects(Flags::SPECULAR));
    let glass =
        Material { kind: Specular::Dielectric { ior: 1.5, absorption: Vec3::ZERO }, ..Material::default() };
    assert_eq!(glass.flags(), Flags::SPECULAR | Flags::REFLECTION | Flags::TRANSMISSION);
    let mirror = Material { kind: Specular::Mirror, ..Material::default() };
    assert!(mirror.flags().contains(Flags::SPECULAR) && !mirror.flags().intersects(Flags::TRANSMISSION));
    assert_eq!(Material::default().flags(), Flags::NONE);
}

/// A shader closure through the same interface: in world space, under every
/// strategy (a closure samples its own lobes under each), a sample's density
/// and value are what `pdf` and `f_cos` say, transmitted directions
/// included, and the flags name its transmission.
#[test]
fn a_closures_sample_is_what_pdf_and_f_cos_say_of_its_direction() {
    use super::closure::At;
    use super::lobe::{Conductor, Dielectric, Diffuse, Lobe};
    let mut rng = Pcg(0x2545_f491_4f6c_dd1d);
    let n = Vec3::new(-0.2, 0.4, 0.89).normalize();
    let m = Material { closure: true, ..Material::default() };
    let parts = [
        (Vec3::splat(0.5), Lobe::Diffuse(Diffuse::new(Vec3::new(0.7, 0.5, 0.3), 0.4))),
        (Vec3::splat(0.3), Lobe::Conductor(Conductor::new(Vec3::splat(0.9), Vec3::ONE, 0.3, 0.5))),
        (Vec3::splat(0.2), Lobe::Dielectric(Dielectric::new(1.5, 0.3, 0.0, Vec3::ONE, Vec3::ONE, false))),
    ];
    let mut transmitted = 0;
    for strategy in STRATEGIES {
        for _ in 0..2000 {
            let d = -(n + Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5)).normalize();
            if d.dot(n) >= 0.0 {
                continue;
            }
            let lobes = Lobes::of(&parts, &At::new(n, n, Vec3::X, d)).unwrap();
            let bsdf = Bsdf::closure(&m, &lobes, d);
            assert!(bsdf.flags().contains(Flags::TRANSMISSION | Flags::DIFFUSE | Flags::GLOSSY));
            let Some(s) = bsdf.sample(strategy, rng.next(), (rng.next(), rng.next())) else { continue };
            let cos = n.dot(s.wi);
            transmitted += usize::from(cos < 0.0);
            let pdf = bsdf.pdf(s.wi, cos, strategy);
            assert!(close(s.pdf, pdf), "{strategy:?}: sample pdf {} vs pdf {pdf}", s.pdf);
            let f = bsdf.f_cos(s.wi, cos);
            for c in 0..3 {
                assert!(close(s.f_cos[c], f[c]), "{strategy:?}: f cos {} vs {f}", s.f_cos);
            }
            assert_eq!(bsdf.eval_pdf(s.wi, cos, strategy), (f, pdf));
        }
    }
    assert!(transmitted > 100, "only {transmitted} transmitted samples");
}
