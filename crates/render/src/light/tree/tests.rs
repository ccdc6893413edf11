//! The light tree against its own definition: the chances sum to one, the
//! draws follow them (chi-square), `choose` and `pmf` agree bit for bit,
//! lights that cannot reach a point are never chosen, and the bounds hold
//! what they bound (moving lights, mesh normals, cone unions).

use super::*;
use crate::bsdf::lobe::tests::{chi_square_p, sidak};
use crate::light::test_rng::Rng;
use crate::light::{AreaLight, Environment, PointLight, ShadedLight, SpotLight};
use crate::texture::Image;
use luster_core::math::{orthonormal_basis, Transform};
use luster_scene::description::{EnvMapping, EnvSampling};
use std::sync::Arc;

/// A uniform unit vector.
fn unit(rng: &mut Rng) -> Vec3 {
    let z = 1.0 - 2.0 * rng.next();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.next();
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// A uniform point of the cube `[-half, half]³`.
fn in_cube(rng: &mut Rng, half: f32) -> Vec3 {
    Vec3::new(rng.next() - 0.5, rng.next() - 0.5, rng.next() - 0.5) * (2.0 * half)
}

/// A mesh of `count` random triangles within 1 of `c`.
fn random_mesh(rng: &mut Rng, c: Vec3, count: usize, radiance: f32) -> LightMesh {
    let tris: Vec<[Vec3; 3]> =
        (0..count).map(|_| [c + in_cube(rng, 1.0), c + in_cube(rng, 1.0), c + in_cube(rng, 1.0)]).collect();
    LightMesh::new(tris.into_iter(), &Transform::IDENTITY, Vec3::splat(radiance)).expect("random triangles")
}

/// A flat square mesh (two triangles) of normal `n` and edge `size` at `c`.
fn quad_mesh(c: Vec3, n: Vec3, size: f32, radiance: f32) -> LightMesh {
    let (u, v) = orthonormal_basis(n);
    let (u, v) = (u * (0.5 * size), v * (0.5 * size));
    let (a, b, d, e) = (c - u - v, c + u - v, c + u + v, c - u + v);
    LightMesh::new([[a, b, d], [a, d, e]].into_iter(), &Transform::IDENTITY, Vec3::splat(radiance))
        .expect("a square has area")
}

/// A square area light.
fn area(center: Vec3, normal: Vec3, size: f32, radiance: f32) -> AreaLight {
    let (u, v) = orthonormal_basis(normal);
    AreaLight {
        center,
        normal,
        edge_u: u * size,
        edge_v: v * size,
        area: size * size,
        radiance: Vec3::splat(radiance),
    }
}

/// A spot light of full coverage and fall-off angles in degrees.
fn spot(position: Vec3, axis: Vec3, intensity: f32, coverage: f32, falloff: f32) -> SpotLight {
    SpotLight {
        position,
        axis,
        intensity: Vec3::splat(intensity),
        cos_falloff: (0.5 * falloff).to_radians().cos(),
        cos_coverage: (0.5 * coverage).to_radians().cos(),
    }
}

fn point(position: Vec3, intensity: f32) -> Light {
    Light::Point(PointLight { position, intensity: Vec3::splat(intensity) })
}

fn environment() -> Light {
    let sky = Image::from_rgb32f(8, 4, vec![[0.5, 0.6, 0.9]; 32]).expect("valid size");
    let env = Environment::new(&sky, EnvMapping::LatLong, EnvSampling::Importance).expect("valid map");
    Light::Environment(Arc::new(env))
}

fn directional() -> Light {
    Light::Directional { direction: Vec3::new(0.3, -1.0, 0.2).normalize(), radiance: Vec3::splat(2.0) }
}

/// `count` lights of every bounded kind spread over `[-20, 20]³` with
/// skewed powers, some moving, a few black.
fn random_lights(rng: &mut Rng, count: usize) -> Vec<Light> {
    (0..count)
        .map(|k| {
            let c = in_cube(rng, 20.0);
            let bright = 0.05 + 10.0 * rng.next() * rng.next() * rng.next();
            let motion = if rng.next() < 0.3 { in_cube(rng, 3.0) } else { Vec3::ZERO };
            match k % 8 {
                0 => point(c, bright),
                1 => {
                    // Coverage up to 300°: spots wider than a hemisphere too.
                    let coverage = 10.0 + 290.0 * rng.next();
                    Light::Spot(spot(c, unit(rng), bright, coverage, coverage * rng.next()))
                }
                2 => Light::Area(area(c, unit(rng), 0.2 + 2.0 * rng.next(), bright)),
                3 => {
                    let mut m = random_mesh(rng, c, 1 + k % 5, bright);
                    m.motion = motion;
                    Light::Mesh(Arc::new(m))
                }
                4 => Light::Sphere(
                    LightSphere::new(c, 0.1 + rng.next(), &Transform::IDENTITY, Vec3::splat(bright))
                        .moving(motion),
                ),
                5 => {
                    let shape = if k % 16 == 5 {
                        let mut m = random_mesh(rng, c, 2, 0.0);
                        m.motion = motion;
                        ShadedShape::Mesh(m)
                    } else {
                        let radius = 0.1 + rng.next();
                        ShadedShape::Sphere(
                            LightSphere::new(c, radius, &Transform::IDENTITY, Vec3::ZERO).moving(motion),
                        )
                    };
                    Light::Shaded(Arc::new(ShadedLight { shape, prim: 0, probed_max: bright }))
                }
                6 => Light::Mesh(Arc::new(quad_mesh(c, unit(rng), 0.5 + rng.next(), bright))),
                // Black: never chosen.
                _ => point(c, 0.0),
            }
        })
        .collect()
}

/// A random shading point: anywhere around the lights (now and then on
/// one of them), with a normal half the time.
fn random_point(rng: &mut Rng, lights: &[Light]) -> (Vec3, Option<Vec3>) {
    let p = if rng.next() < 0.1 {
        let i = ((rng.next() * lights.len() as f32) as usize).min(lights.len() - 1);
        LightBounds::of(&lights[i], 1.0).map_or(Vec3::ZERO, |b| b.bounds.center())
    } else {
        in_cube(rng, 25.0)
    };
    let n = (rng.next() < 0.5).then(|| unit(rng));
    (p, n)
}

/// Each light's chance of being chosen at `(p, n)` with its relative
/// tolerance, and the chance of a walk stopping where both children have
/// zero importance, by a recursive walk of the whole tree in `f64` (not the
/// bit trails `pmf` follows). The `f32` share of a child taken with chance
/// `s` is off by up to an ulp of the larger share, `2⁻²⁴/s` relative.
fn walk(tree: &LightTree, p: Vec3, n: Option<Vec3>) -> (Vec<(f64, f64)>, f64) {
    type Out = (Vec<(f64, f64)>, f64);
    fn go(tree: &LightTree, at: usize, (prob, tol): (f64, f64), p: Vec3, n: Option<Vec3>, out: &mut Out) {
        match tree.nodes[at].kind {
            Kind::Leaf(i) => out.0[i] = (prob, tol),
            Kind::Interior(second) => {
                let a = f64::from(tree.nodes[at + 1].bounds.importance(p, n));
                let b = f64::from(tree.nodes[second].bounds.importance(p, n));
                if a + b == 0.0 {
                    out.1 += prob;
                    return;
                }
                for (c, w) in [(at + 1, a), (second, b)] {
                    if w > 0.0 {
                        let s = w / (a + b);
                        go(tree, c, (prob * s, tol + 1.2e-7 * (1.0 + 1.0 / s)), p, n, out);
                    }
                }
            }
        }
    }
    let mut out = (vec![(0.0, 0.0); tree.len()], 0.0);
    let k = tree.infinite.len() as f64;
    let lit = tree.nodes.first().is_some_and(|r| r.bounds.importance(p, n) > 0.0);
    let infinite = if k == 0.0 {
        0.0
    } else if lit {
        k / (k + 1.0)
    } else {
        1.0
    };
    for &i in &tree.infinite {
        out.0[i] = (infinite / k, 1e-6);
    }
    if lit {
        go(tree, 0, (1.0 - infinite, 1e-6), p, n, &mut out);
    }
    out
}

/// Σᵢ pmf(i) is one less the chance of a walk's dead end, whenever anything
/// can be chosen (exactly one where no walk dead-ends), and every pmf is the
/// chance an independent walk of the whole tree finds; where nothing can be
/// chosen every pmf is zero and `choose` gives nothing. Dead ends are rare.
#[test]
fn chances_sum_to_one_less_the_dead_ends_and_match_a_full_walk() {
    let mut rng = Rng(41);
    let mut bounded = random_lights(&mut rng, 300);
    let with_infinite = {
        let mut l = bounded.clone();
        l.insert(17, environment());
        l.push(directional());
        l
    };
    bounded.truncate(200);
    let (mut dead_total, mut points, mut exact, mut nothing) = (0.0, 0usize, 0usize, 0usize);
    for lights in [bounded, with_infinite] {
        let tree = LightTree::build(&lights, 30.0);
        for _ in 0..400 {
            let (p, n) = random_point(&mut rng, &lights);
            let (chance, dead) = walk(&tree, p, n);
            let pmf: Vec<f32> = (0..lights.len()).map(|i| tree.pmf(i, p, n)).collect();
            let sum: f64 = pmf.iter().map(|&x| f64::from(x)).sum();
            let reach: f64 = chance.iter().map(|c| c.0).sum();
            for (i, (&got, &(want, tol))) in pmf.iter().zip(&chance).enumerate() {
                let got = f64::from(got);
                assert!(got.is_finite() && got >= 0.0);
                assert!((got - want).abs() <= tol * want + 1e-30, "light {i} at {p:?}: {got} against {want}");
            }
            if reach > 0.0 {
                assert!((sum + dead - 1.0).abs() < 1e-4, "at {p:?} {n:?}: Σ pmf {sum}, dead ends {dead}");
                if dead == 0.0 {
                    assert!((sum - 1.0).abs() < 1e-4, "Σ pmf {sum}");
                    exact += 1;
                }
            } else {
                assert_eq!(sum, 0.0);
                assert!((0..64).all(|k| tree.choose(k as f32 / 64.0, p, n).is_none()));
                nothing += 1;
            }
            dead_total += dead;
            points += 1;
        }
        // Black lights are left out.
        for (i, l) in lights.iter().enumerate() {
            if power::power(l, 30.0) == 0.0 {
                assert_eq!((tree.slots[i], tree.pmf(i, Vec3::ZERO, None)), (Slot::Absent, 0.0));
            }
        }
    }
    // Dead ends come from bounds that mix lights hidden for different
    // reasons (behind the surface, turned away); random normals in a cloud
    // of lights are the worst case, a floor under them the usual one.
    let dead_mean = dead_total / points as f64;
    assert!(dead_mean < 0.25, "dead ends take {dead_mean} of the choices on average");
    assert!(exact > points / 10 && nothing < points / 4, "{exact} exact, {nothing} with nothing");
    let lights = random_lights(&mut rng, 300);
    let tree = LightTree::build(&lights, 30.0);
    let floor: f64 = (0..500)
        .map(|_| {
            let p = Vec3::new(50.0 * rng.next() - 25.0, -21.0, 50.0 * rng.next() - 25.0);
            let dead = walk(&tree, p, Some(Vec3::Y)).1;
            let sum: f64 = (0..lights.len()).map(|i| f64::from(tree.pmf(i, p, Some(Vec3::Y)))).sum();
            assert!((sum + dead - 1.0).abs() < 1e-4);
            dead
        })
        .sum();
    assert!(floor / 500.0 < 0.01, "dead ends take {} of the choices on a floor", floor / 500.0);
}

/// Stratified draws of `choose` land on each light as often as its pmf
/// says (a "nothing" bin for the dead ends), never on a light of pmf 0;
/// the same draws against the choice by power fail the test.
#[test]
fn choices_follow_the_pmf() {
    let mut rng = Rng(7);
    let mut lights = random_lights(&mut rng, 120);
    lights.push(environment());
    let tree = LightTree::build(&lights, 30.0);
    let powers: Vec<f64> = lights.iter().map(|l| f64::from(power::power(l, 30.0))).collect();
    let total_power: f64 = powers.iter().sum();
    const N: usize = 100_000;
    const CASES: usize = 8;
    let len = lights.len();
    for case in 0..CASES {
        let (p, n) = if case == 0 {
            (Vec3::new(0.0, -21.0, 0.0), Some(Vec3::Y))
        } else {
            random_point(&mut rng, &lights)
        };
        let pmf: Vec<f64> = (0..len).map(|i| f64::from(tree.pmf(i, p, n))).collect();
        let mut expected: Vec<f64> = pmf.iter().map(|x| x * N as f64).collect();
        expected.push((1.0 - pmf.iter().sum::<f64>()).max(0.0) * N as f64);
        let mut observed = vec![0.0; len + 1];
        for k in 0..N {
            let u = ((k as f32 + rng.next()) / N as f32).min(ONE_MINUS_EPSILON);
            match tree.choose(u, p, n) {
                Some((i, _)) => observed[i] += 1.0,
                None => observed[len] += 1.0,
            }
        }
        for i in 0..len {
            assert!(pmf[i] > 0.0 || observed[i] == 0.0, "light {i} of pmf 0 chosen {} times", observed[i]);
        }
        let pv = chi_square_p(&observed, &expected);
        assert!(pv > sidak(CASES), "case {case} at {p:?} {n:?}: p-value {pv}");
        // The test can fail: these draws do not follow the power pmf.
        let mut by_power: Vec<f64> = powers.iter().map(|w| w / total_power * N as f64).collect();
        by_power.push(0.0);
        assert!(chi_square_p(&observed, &by_power) < 1e-6, "case {case}: the tree chose by power");
    }
}

/// The chance `choose` reports is `pmf` of the light it chose, bit for bit,
/// with and without infinite lights, at random and extreme `u`.
#[test]
fn choose_reports_pmf_bit_for_bit() {
    let mut rng = Rng(99);
    let bounded = random_lights(&mut rng, 250);
    let mut with_infinite = bounded.clone();
    with_infinite.push(directional());
    with_infinite.insert(3, environment());
    for lights in [bounded, with_infinite] {
        let tree = LightTree::build(&lights, 30.0);
        let mut chosen = 0;
        for _ in 0..300 {
            let (p, n) = random_point(&mut rng, &lights);
            let us = (0..40).map(|_| rng.next()).chain([0.0, f32::EPSILON, 0.5, ONE_MINUS_EPSILON]);
            for u in us {
                if let Some((i, q)) = tree.choose(u, p, n) {
                    assert!(q > 0.0 && q <= 1.0);
                    assert_eq!(q.to_bits(), tree.pmf(i, p, n).to_bits(), "light {i} at {p:?} {n:?} u {u}");
                    chosen += 1;
                }
            }
        }
        assert!(chosen > 300 * 44 / 2, "only {chosen} choices");
    }
}

/// At a point on a floor facing up, a light wholly below the floor and a
/// spot above it pointing away get no chance and are never chosen (the one
/// below does off the surface); of two equal point lights the nearer gets
/// more.
#[test]
fn hidden_and_averted_lights_get_nothing_and_the_near_beats_the_far() {
    let (p, n) = (Vec3::ZERO, Some(Vec3::Y));
    let lights = vec![
        Light::Area(area(Vec3::new(0.5, -3.0, 0.0), Vec3::Y, 1.0, 5.0)),
        Light::Spot(spot(Vec3::new(0.0, 2.0, 0.0), Vec3::Y, 5.0, 60.0, 40.0)),
        point(Vec3::new(0.3, 1.0, 0.0), 1.0),
        point(Vec3::new(3.0, 10.0, -1.0), 1.0),
        Light::Spot(spot(Vec3::new(1.0, 2.0, 0.0), -Vec3::Y, 5.0, 60.0, 40.0)),
        Light::Sphere(LightSphere::new(Vec3::new(-4.0, -3.0, 2.0), 0.5, &Transform::IDENTITY, Vec3::ONE)),
    ];
    let tree = LightTree::build(&lights, 20.0);
    let pmf: Vec<f32> = (0..lights.len()).map(|i| tree.pmf(i, p, n)).collect();
    assert_eq!((pmf[0], pmf[1], pmf[5]), (0.0, 0.0, 0.0), "{pmf:?}");
    assert!(pmf[2] > pmf[3] && pmf[3] > 0.0 && pmf[4] > 0.0, "{pmf:?}");
    assert!((pmf.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{pmf:?}");
    for k in 0..4096 {
        let (i, _) = tree.choose((k as f32 + 0.5) / 4096.0, p, n).expect("lights above");
        assert!(pmf[i] > 0.0, "chose light {i}");
    }
    // Off a surface the light below counts; the spot still points away.
    assert!(tree.pmf(0, p, None) > 0.0 && tree.pmf(1, p, None) == 0.0);
    // The same holds for the importances on their own, wherever the pair sits.
    let mut rng = Rng(3);
    for _ in 0..200 {
        let (q, dir) = (in_cube(&mut rng, 10.0), unit(&mut rng));
        let near = LightBounds::of(&point(q + dir, 1.0), 1.0).expect("bounded");
        let far = LightBounds::of(&point(q + dir * 4.0, 1.0), 1.0).expect("bounded");
        let n = unit(&mut rng);
        let n = if n.dot(dir) < 0.0 { -n } else { n };
        assert!(near.importance(q, Some(n)) >= far.importance(q, Some(n)));
        assert!(near.importance(q, None) > far.importance(q, None));
        assert_eq!(near.importance(q, Some(-n)), 0.0);
    }
}

/// A moving mesh's or sphere's box holds every point of it at every time
/// of the shutter, and reaches the end of the motion; a mesh's cone holds
/// every triangle normal up to sign (tight for a flat one); a union of two
/// cones holds both.
#[test]
fn bounds_hold_moving_lights_mesh_normals_and_both_cones() {
    let mut rng = Rng(5);
    let inside = |b: &Aabb, q: Vec3| {
        let slack = 1e-5 * (1.0 + q.abs().max_element());
        (q - b.min).min_element() >= -slack && (b.max - q).min_element() >= -slack
    };
    for k in 0..200 {
        let motion = in_cube(&mut rng, 5.0);
        let c = in_cube(&mut rng, 10.0);
        let mut mesh = random_mesh(&mut rng, c, 1 + k % 6, 1.0);
        mesh.motion = motion;
        let sphere = LightSphere::new(c, 0.1 + rng.next(), &Transform::IDENTITY, Vec3::ONE).moving(motion);
        let lights = [
            Light::Mesh(Arc::new(mesh.clone())),
            Light::Sphere(sphere.clone()),
            Light::Shaded(Arc::new(ShadedLight {
                shape: ShadedShape::Mesh(mesh.clone()),
                prim: 0,
                probed_max: 1.0,
            })),
            Light::Shaded(Arc::new(ShadedLight {
                shape: ShadedShape::Sphere(sphere.clone()),
                prim: 0,
                probed_max: 1.0,
            })),
        ];
        for light in &lights {
            let b = LightBounds::of(light, 1.0).expect("bounded").bounds;
            for _ in 0..20 {
                let t = rng.next();
                let q = match light {
                    Light::Sphere(_) => sphere.center + unit(&mut rng) * sphere.radius,
                    Light::Shaded(l) if matches!(l.shape, ShadedShape::Sphere(_)) => {
                        sphere.center + unit(&mut rng) * sphere.radius
                    }
                    _ => mesh.point((rng.next(), rng.next())).0,
                };
                assert!(inside(&b, q + motion * t), "light {k} at time {t}");
                assert!(inside(&b, q + motion), "light {k} at the end");
            }
        }
        let lb = LightBounds::of(&lights[0], 1.0).expect("bounded");
        assert!(lb.two_sided);
        for nt in mesh.normals() {
            assert!(lb.w.dot(nt).abs() >= lb.cos_theta_o - 1e-6, "normal {nt:?} outside the cone");
        }
        // Two cones and directions inside each against their union.
        let cones =
            [(unit(&mut rng), 1.0 - 2.0 * rng.next()), (unit(&mut rng), 1.0 - 2.0 * rng.next().powi(3))];
        let (w, cos) = cone_union(cones[0], cones[1]);
        for (axis, c) in cones {
            let (u, v) = orthonormal_basis(axis);
            for _ in 0..50 {
                let ct = 1.0 - rng.next() * (1.0 - c);
                let st = (1.0 - ct * ct).max(0.0).sqrt();
                let phi = 2.0 * PI * rng.next();
                let d = axis * ct + (u * phi.cos() + v * phi.sin()) * st;
                assert!(w.dot(d) >= cos - 1e-5, "direction {d:?} outside the union of {cones:?}");
            }
        }
    }
    let flat = LightBounds::of(&Light::Mesh(Arc::new(quad_mesh(Vec3::ONE, Vec3::X, 2.0, 1.0))), 1.0);
    let flat = flat.expect("bounded");
    assert!(flat.cos_theta_o > 0.999 && flat.w.dot(Vec3::X).abs() > 0.999, "{flat:?}");
}

/// Degenerate scenes: none, only infinite lights, one light (also at its own
/// position), only black lights, nothing lit, a NaN point, many lights in
/// one place; never a NaN, and choose and pmf agree on what is possible.
#[test]
fn degenerate_scenes_choose_consistently_without_nan() {
    let us = [0.0, 0.3, 0.7, ONE_MINUS_EPSILON];
    let empty = LightTree::build(&[], 1.0);
    assert!(
        empty.is_empty()
            && empty.choose(0.5, Vec3::ZERO, None).is_none()
            && empty.pmf(0, Vec3::ZERO, None) == 0.0
    );

    let infinite = LightTree::build(&[directional(), environment()], 10.0);
    assert_eq!(infinite.choose(0.2, Vec3::ONE, Some(Vec3::Y)), Some((0, 0.5)));
    assert_eq!(infinite.choose(0.8, Vec3::ONE, Some(Vec3::Y)), Some((1, 0.5)));
    assert_eq!(infinite.pmf(1, Vec3::ONE, None), 0.5);

    let at = Vec3::new(1.0, 2.0, 3.0);
    let one = LightTree::build(&[point(at, 2.0)], 10.0);
    for p in [Vec3::ZERO, at] {
        for &u in &us {
            assert_eq!(one.choose(u, p, None), Some((0, 1.0)));
        }
        assert_eq!(one.pmf(0, p, None), 1.0);
        assert_eq!(one.pmf(0, p - Vec3::X, Some(Vec3::X)), 1.0);
    }

    let black = [point(at, 0.0), Light::Sphere(LightSphere::new(at, 1.0, &Transform::IDENTITY, Vec3::ZERO))];
    let tree = LightTree::build(&black, 10.0);
    assert!(us.iter().all(|&u| tree.choose(u, Vec3::ZERO, None).is_none()));
    assert_eq!(tree.pmf(0, Vec3::ZERO, None) + tree.pmf(1, Vec3::ZERO, None), 0.0);

    // Nothing lights the origin (two spots above it point up, an area
    // light lies below the floor): the tree gives nothing, or everything to
    // the directional light.
    let away = [Vec3::Y, Vec3::new(1.0, 1.0, 0.0)].map(|at| Light::Spot(spot(at, Vec3::Y, 1.0, 30.0, 20.0)));
    let below = Light::Area(area(-Vec3::Y, Vec3::Y, 0.5, 1.0));
    for (lights, up) in [(&away[..], None), (&[below][..], Some(Vec3::Y))] {
        let unlit = LightTree::build(lights, 10.0);
        assert!(us.iter().all(|&u| unlit.choose(u, Vec3::ZERO, up).is_none()));
        assert!((0..lights.len()).all(|i| unlit.pmf(i, Vec3::ZERO, up) == 0.0));
        let sky = LightTree::build(&[lights, &[directional()]].concat(), 10.0);
        let dir = lights.len();
        assert!(us.iter().all(|&u| sky.choose(u, Vec3::ZERO, up) == Some((dir, 1.0))));
        assert_eq!(sky.pmf(dir, Vec3::ZERO, up), 1.0);
        // Where the tree can light a point, it gets half the choices.
        let lit = if up.is_none() { Vec3::new(0.5, 3.0, 0.0) } else { Vec3::new(0.0, -3.0, 0.0) };
        assert!(sky.choose(0.9, lit, None).is_some_and(|(i, q)| i < dir && q > 0.0));
        assert_eq!(sky.pmf(dir, lit, None), 0.5);
    }

    // A NaN point lights nothing.
    let mut rng = Rng(1);
    let lights = random_lights(&mut rng, 40);
    let tree = LightTree::build(&lights, 30.0);
    let nan = Vec3::splat(f32::NAN);
    assert!(us.iter().all(|&u| tree.choose(u, nan, None).is_none()));
    assert!((0..40).all(|i| tree.pmf(i, nan, Some(Vec3::Y)) == 0.0));
    // A point inside each light's box gets finite chances summing to one.
    for l in &lights {
        let Some(b) = LightBounds::of(l, 30.0) else { continue };
        let p = b.bounds.center();
        let sum: f32 = (0..40).map(|i| tree.pmf(i, p, None)).sum();
        assert!(sum.is_finite() && sum <= 1.0 + 1e-4, "Σ pmf {sum} at {p:?}");
        for &u in &us {
            if let Some((_, q)) = tree.choose(u, p, None) {
                assert!(q.is_finite() && q > 0.0);
            }
        }
    }

    // Fifty equal lights in one place: median splits, equal chances; at
    // that very place (infinite importance, clamped) still a valid choice.
    let same: Vec<Light> = (0..50).map(|_| point(at, 1.0)).collect();
    let tree = LightTree::build(&same, 10.0);
    let pmf: Vec<f32> = (0..50).map(|i| tree.pmf(i, Vec3::ZERO, None)).collect();
    assert!(pmf.iter().all(|&x| (x - 0.02).abs() < 1e-6), "{pmf:?}");
    let pmf: Vec<f32> = (0..50).map(|i| tree.pmf(i, at, None)).collect();
    assert!(pmf.iter().all(|&x| x > 0.0) && (pmf.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{pmf:?}");
}

/// The lights under a node, by index.
fn leaves(tree: &LightTree, at: usize) -> Vec<usize> {
    match tree.nodes[at].kind {
        Kind::Leaf(i) => vec![i],
        Kind::Interior(second) => {
            let mut v = leaves(tree, at + 1);
            v.extend(leaves(tree, second));
            v
        }
    }
}

/// Two distant clusters split at the root, every light is a leaf once with
/// a trail that leads to it, and the same lights build the same tree.
#[test]
fn build_separates_clusters_covers_every_light_and_is_deterministic() {
    let mut rng = Rng(23);
    let lights = random_lights(&mut rng, 80);
    let points: Vec<Light> = (0..60)
        .map(|k| point(in_cube(&mut rng, 3.0) + Vec3::X * if k % 2 == 0 { -50.0 } else { 50.0 }, 1.0))
        .collect();
    let tree = LightTree::build(&points, 60.0);
    let Kind::Interior(second) = tree.nodes[0].kind else { panic!("one leaf for sixty lights") };
    for side in [leaves(&tree, 1), leaves(&tree, second)] {
        assert_eq!(side.len(), 30);
        assert!(side.iter().all(|&i| i % 2 == side[0] % 2), "clusters mixed: {side:?}");
    }
    let tree = LightTree::build(&lights, 60.0);
    let mut all = leaves(&tree, 0);
    all.sort_unstable();
    let want: Vec<usize> = (0..lights.len()).filter(|&i| !matches!(tree.slots[i], Slot::Absent)).collect();
    assert_eq!(all, want);
    for (i, slot) in tree.slots.iter().enumerate() {
        if let Slot::Tree { trail, depth } = *slot {
            let mut at = 0;
            for level in 0..depth {
                let Kind::Interior(second) = tree.nodes[at].kind else { panic!("trail past a leaf") };
                at = if trail >> level & 1 == 0 { at + 1 } else { second };
            }
            assert_eq!(tree.nodes[at].kind, Kind::Leaf(i));
        }
    }
    let again = LightTree::build(&lights, 60.0);
    assert_eq!(tree.slots, again.slots);
    for _ in 0..100 {
        let (p, n) = random_point(&mut rng, &lights);
        let u = rng.next();
        assert_eq!(tree.choose(u, p, n), again.choose(u, p, n));
    }
}
