//! The bounce to the last vertex of the course's variant without light
//! samples, skipped where it misses the emitters' boxes: that vertex's light
//! is then exactly zero, and the skip is made only where nothing but the
//! emitters shines.

use super::super::next_event::tests::{scene_of, SCENE};
use super::*;
use crate::integrator::RayStats;
use crate::render::sampler::PixelSampler;

/// Rays from points in the box: every other one in a direction spread over
/// the sphere, the others towards points around the light box.
fn rays() -> impl Iterator<Item = (u32, Ray)> {
    (0..2000u32).map(|k| {
        let (a, b) = (k as f32 * 0.618_034, k as f32 * 0.381_966 + 0.1);
        let o = Vec3::new((a * 7.0).sin() * 1.5, (a * 5.0).cos() * 1.5, (b * 3.0).sin() * 1.5);
        let d = if k % 2 == 0 {
            let z = (b * 11.0).fract() * 2.0 - 1.0;
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * (a * 13.0).cos(), r * (a * 13.0).sin(), z)
        } else {
            (Vec3::new((a * 3.0).sin() * 0.6, 1.85, (b * 5.0).cos() * 0.6) - o).normalize()
        };
        (k, Ray::new(o, d))
    })
}

#[test]
fn a_last_bounce_that_misses_the_emitters_brings_no_light() {
    let scene = scene_of(SCENE);
    // The course's plain variant: no light samples, no roulette.
    let p = PathParams::default();
    let (mut skipped, mut kept) = (0, 0);
    for (k, ray) in rays() {
        if scene.may_bring_light(&ray) {
            kept += 1;
            continue;
        }
        skipped += 1;
        let mut st = PathState::new(RayStats::default(), 0.0, PixelSampler::new(3, k % 8, k / 8, 0, 16));
        let came = Came::Bounce { pdf: 0.5, n: -ray.d, from: ray.o };
        let l = li::<0>(&scene, &ray, scene.max_depth, Vec3::ONE, came, p, &mut st);
        assert_eq!(l, Vec3::ZERO, "ray {k}");
    }
    assert!(skipped > 800 && kept > 200, "{skipped} rays skipped, {kept} kept");
    // Rays that reach the light box find it: those are never skipped.
    let up = Ray::new(Vec3::new(0.0, 0.0, 0.0), Vec3::Y);
    assert!(scene.may_bring_light(&up));
}

#[test]
fn light_from_elsewhere_keeps_every_last_bounce() {
    let grey = SCENE.replacen("<Cameras>", "<BackgroundColor>10 10 10</BackgroundColor><Cameras>", 1);
    let textured = SCENE
        .replacen(
            "<Materials>",
            r#"<Textures><TextureMap id="1" type="perlin"><NoiseScale>3</NoiseScale>
              <DecalMode>replace_all</DecalMode></TextureMap></Textures><Materials>"#,
            1,
        )
        .replacen("<Center>9</Center>", "<Textures>1</Textures><Center>9</Center>", 1);
    for (what, text) in [("a grey background", grey), ("an unlit texture", textured)] {
        let scene = scene_of(&text);
        assert!(rays().all(|(_, r)| scene.may_bring_light(&r)), "with {what}");
    }
}

#[test]
fn past_the_depth_limit_the_background_is_no_light() {
    let grey = SCENE.replacen("<Cameras>", "<BackgroundColor>10 10 10</BackgroundColor><Cameras>", 1);
    let scene = scene_of(&grey);
    let p = PathParams { mis: true, ..PathParams::default() };
    // From outside the box, away from it: the ray finds nothing.
    let ray = Ray::new(Vec3::new(0.0, 0.0, 5.0), Vec3::Z);
    let came = Came::Bounce { pdf: 0.5, n: Vec3::Z, from: Vec3::ZERO };
    let mut st = PathState::new(RayStats::default(), 0.0, PixelSampler::new(3, 0, 0, 0, 16));
    let within = li::<8>(&scene, &ray, scene.max_depth, Vec3::ONE, came, p, &mut st);
    let past = li::<8>(&scene, &ray, scene.max_depth + 1, Vec3::ONE, came, p, &mut st);
    assert_eq!(within, Vec3::splat(10.0));
    assert_eq!(past, Vec3::ZERO);
}
