//! Tests of flattened closures: the weights layers and mixes give, what is
//! set apart (emission, cut-outs), the mixture's sampling against its
//! density, and white furnaces of layered stacks.

use super::*;
use crate::bsdf::lobe::tests::Pcg as Rng;
use luster_shading::shader::closure::MAX_NODES;

/// A closure built bottom-up, as the Lua side writes it.
#[derive(Default)]
struct Tree(Closure);

impl Tree {
    fn add(&mut self, kind: NodeKind, c: [[f32; 3]; 3], x: [f32; 3], a: u8, b: u8, thin: bool) -> u8 {
        let i = self.0.len;
        self.0.nodes[i as usize] = Node { kind, a, b, thin, c, x };
        self.0.len += 1;
        self.0.root = i;
        i
    }
    fn lobe(&mut self, kind: NodeKind, c0: f32, x: [f32; 3]) -> u8 {
        self.add(kind, [[c0; 3], [1.0; 3], [1.0; 3]], x, 0, 0, false)
    }
    fn diffuse(&mut self, albedo: f32) -> u8 {
        self.lobe(NodeKind::Diffuse, albedo, [0.0; 3])
    }
    /// A dielectric of index `ior` and roughness `r`, untinted.
    fn glass(&mut self, ior: f32, r: f32) -> u8 {
        self.add(NodeKind::Dielectric, [[1.0; 3]; 3], [ior, r, 0.0], 0, 0, false)
    }
    fn scale(&mut self, w: f32, a: u8) -> u8 {
        self.add(NodeKind::Scale, [[w; 3], [0.0; 3], [0.0; 3]], [0.0; 3], a, 0, false)
    }
    fn plus(&mut self, a: u8, b: u8) -> u8 {
        self.add(NodeKind::Add, [[0.0; 3]; 3], [0.0; 3], a, b, false)
    }
    fn layer(&mut self, top: u8, base: u8) -> u8 {
        self.add(NodeKind::Layer, [[0.0; 3]; 3], [0.0; 3], top, base, false)
    }
    fn flat(&self, cos: f32) -> Lobes {
        Lobes::flatten(&self.0, &at(cos)).unwrap()
    }
}

/// Seen from outside at `cos` to the normal (`+z`).
fn at(cos: f32) -> At {
    let wo = Vec3::new((1.0 - cos * cos).max(0.0).sqrt(), 0.0, cos);
    At { frame: Frame::AXES, wo, outside: true }
}

/// The Monte Carlo estimate of the closure's albedo: the mean of
/// `f cos / p` over its own samples, and its standard error.
fn furnace(l: &Lobes, n: usize) -> (f32, f32) {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let v = match l.sample(rng.next(), (rng.next(), rng.next())) {
            Some(s) => f64::from((s.f_cos / s.pdf).dot(LUMINANCE)),
            None => 0.0,
        };
        sum += v;
        sum2 += v * v;
    }
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(0.0);
    (mean as f32, (var / n as f64).sqrt() as f32)
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn mix_and_scale_weigh_the_lobes() {
    let mut t = Tree::default();
    let a = t.diffuse(0.5);
    let b = t.diffuse(0.9);
    let (sa, sb) = (t.scale(0.75, a), t.scale(0.25, b));
    t.plus(sa, sb);
    let l = t.flat(0.7);
    assert_eq!(l.len(), 2);
    assert!(close(l.lobe(0).1, Vec3::splat(0.75), 1e-6) && close(l.lobe(1).1, Vec3::splat(0.25), 1e-6));
    // Picked by weighted albedo: 0.375 against 0.225.
    assert!((l.chance(0) - 0.375 / 0.6).abs() < 1e-3, "{}", l.chance(0));
    // A lobe of weight zero is left out.
    let mut t = Tree::default();
    let a = t.diffuse(0.5);
    let z = t.scale(0.0, a);
    let b = t.diffuse(0.5);
    t.plus(z, b);
    assert_eq!(t.flat(0.5).len(), 1);
}

#[test]
fn a_layer_passes_its_base_what_the_top_lets_through() {
    for cos in [0.2, 0.6, 1.0] {
        let mut t = Tree::default();
        let top = t.glass(1.5, 0.1);
        let base = t.diffuse(1.0);
        t.layer(top, base);
        let l = t.flat(cos);
        assert_eq!(l.len(), 2);
        let (coat, w) = l.lobe(0);
        assert!(close(w, Vec3::ONE, 0.0));
        assert!(coat.flags() == (Flags::GLOSSY | Flags::REFLECTION), "a coat reflects only");
        let through = coat.transmittance(at(cos).wo);
        assert!(close(l.lobe(1).1, through, 1e-6));
        // The coat reflects a little head on and much at grazing angles.
        let r = 1.0 - through.x;
        assert!(r > 0.03 && r < 0.9, "coat reflectance {r} at cos {cos}");
    }
    // A top of weight one half lets through half its reflection more.
    let mut t = Tree::default();
    let g = t.glass(1.5, 0.1);
    let top = t.scale(0.5, g);
    let base = t.diffuse(1.0);
    t.layer(top, base);
    let l = t.flat(0.5);
    let through = l.lobe(0).0.transmittance(at(0.5).wo);
    assert!(close(l.lobe(0).1, Vec3::splat(0.5), 1e-6));
    assert!(close(l.lobe(1).1, Vec3::ONE - 0.5 * (Vec3::ONE - through), 1e-6));
}

#[test]
fn nested_layers_multiply_what_each_top_lets_through() {
    // layer{top = A, base = layer{top = B, base = C}} and
    // layer{top = layer{top = A, base = B}, base = C} give C the same weight.
    // What each top lets through on its own, as the flattening measures it.
    let wo = at(0.4).wo;
    let through =
        |eta, r| Lobe::Dielectric(Dielectric::coat(eta, r, 0.0, Vec3::ONE, Vec3::ONE)).transmittance(wo);
    let (ta, tb) = (through(1.5, 0.05), through(1.3, 0.4));
    let mut t = Tree::default();
    let a = t.glass(1.5, 0.05);
    let b = t.glass(1.3, 0.4);
    let c = t.diffuse(1.0);
    let inner = t.layer(b, c);
    t.layer(a, inner);
    let l = t.flat(0.4);
    assert!(close(l.lobe(2).1, ta * tb, 1e-5), "{} vs {}", l.lobe(2).1, ta * tb);
    let mut t = Tree::default();
    let a = t.glass(1.5, 0.05);
    let b = t.glass(1.3, 0.4);
    let top = t.layer(a, b);
    let c = t.diffuse(1.0);
    t.layer(top, c);
    let l = t.flat(0.4);
    assert!(close(l.lobe(2).1, ta * tb, 1e-5), "{} vs {}", l.lobe(2).1, ta * tb);
}

#[test]
fn emission_and_cut_outs_are_set_apart() {
    let mut t = Tree::default();
    let e = t.lobe(NodeKind::Emission, 4.0, [0.0; 3]);
    let half = t.scale(0.5, e);
    let hole = t.lobe(NodeKind::Transparent, 1.0, [0.0; 3]);
    let h = t.scale(0.25, hole);
    let d = t.diffuse(0.5);
    let s = t.plus(half, h);
    t.plus(s, d);
    let l = t.flat(1.0);
    assert_eq!(l.len(), 1);
    assert!(close(l.emission, Vec3::splat(2.0), 1e-6));
    assert!(close(l.transparency, Vec3::splat(0.25), 1e-6));
    // A hole in a layer's top is no hole in the surface.
    let mut t = Tree::default();
    let hole = t.lobe(NodeKind::Transparent, 1.0, [0.0; 3]);
    let base = t.diffuse(0.5);
    t.layer(hole, base);
    let l = t.flat(1.0);
    assert_eq!(l.transparency, Vec3::ZERO);
    assert!(close(l.lobe(0).1, Vec3::ONE, 1e-6));
}

#[test]
fn more_lobes_than_the_limit_fail() {
    let mut t = Tree::default();
    let mut sum = t.diffuse(0.1);
    for _ in 0..MAX_LOBES {
        let d = t.diffuse(0.1);
        sum = t.plus(sum, d);
    }
    assert!(usize::from(t.0.len) < MAX_NODES);
    assert_eq!(Lobes::flatten(&t.0, &at(1.0)).unwrap_err(), TooManyLobes);
}

#[test]
fn a_sample_carries_the_mixtures_value_and_density() {
    let mut t = Tree::default();
    let coat = t.glass(1.5, 0.2);
    let d = t.diffuse(0.7);
    let metal = t.lobe(NodeKind::Conductor, 0.9, [0.4, 0.0, 0.0]);
    let m = t.scale(0.3, metal);
    let base = t.plus(d, m);
    t.layer(coat, base);
    let l = t.flat(0.6);
    let mut rng = Rng(7);
    let mut n = 0;
    for _ in 0..2000 {
        let Some(s) = l.sample(rng.next(), (rng.next(), rng.next())) else { continue };
        let (f, p) = l.eval(s.wi);
        assert!(close(f, s.f_cos, 1e-4 * f.max_element().max(1.0)), "{f} vs {}", s.f_cos);
        assert!((p - s.pdf).abs() <= 1e-4 * p.max(1.0), "{p} vs {}", s.pdf);
        n += 1;
    }
    assert!(n > 1500, "{n} samples of 2000");
}

#[test]
fn the_mixtures_density_integrates_to_one() {
    // Over the sphere of directions, by stratified quadrature in (cos θ, φ).
    let mut t = Tree::default();
    let coat = t.glass(1.5, 0.3);
    let d = t.diffuse(0.7);
    t.layer(coat, d);
    let l = t.flat(0.5);
    let (nt, np) = (400, 200);
    let mut sum = 0.0f64;
    for i in 0..nt {
        for j in 0..np {
            let z = -1.0 + 2.0 * (i as f32 + 0.5) / nt as f32;
            let phi = std::f32::consts::TAU * (j as f32 + 0.5) / np as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            sum += f64::from(l.pdf(wi));
        }
    }
    let integral = sum * 4.0 * std::f64::consts::PI / (nt * np) as f64;
    assert!((integral - 1.0).abs() < 0.02, "{integral}");
}

#[test]
fn a_clear_coat_over_white_keeps_the_light() {
    for (cos, r) in [(1.0, 0.0), (0.5, 0.1), (0.2, 0.3), (0.7, 0.8)] {
        let mut t = Tree::default();
        let coat = t.glass(1.5, r);
        let base = t.diffuse(1.0);
        t.layer(coat, base);
        let l = t.flat(cos);
        let (e, se) = furnace(&l, 200_000);
        assert!(e >= 0.99 - 3.0 * se && e <= 1.01 + 3.0 * se, "cos {cos} roughness {r}: {e} ± {se}");
    }
}
