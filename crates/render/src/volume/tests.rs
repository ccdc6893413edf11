//! Volume unit tests: building from a description, density and emission
//! sources, and the hypertexture crossing search.

use super::*;
use luster_core::math::{Ray, Transform};
use luster_scene::description::{BoundDesc, ScriptDesc, VolumeDesc, VolumeKind};
use luster_scene::Loc;

pub(super) fn desc(volumes: Vec<VolumeDesc>) -> Description {
    let mut d = luster_scene::description::Description {
        file: "v.xml".into(),
        base_dir: ".".into(),
        shader_libraries: Vec::new(),
        max_recursion_depth: 1,
        background: Vec3::ZERO,
        shadow_ray_epsilon: Some(1e-3),
        intersection_test_epsilon: 1e-6,
        cameras: Vec::new(),
        ambient_light: Vec3::ZERO,
        point_lights: Vec::new(),
        area_lights: Vec::new(),
        directional_lights: Vec::new(),
        spot_lights: Vec::new(),
        environment_light: None,
        studio: None,
        emitters: Vec::new(),
        materials: Vec::new(),
        vertices: Vec::new(),
        tex_coords: Vec::new(),
        images: Vec::new(),
        texture_maps: Vec::new(),
        background_texture: None,
        objects: Vec::new(),
        volumes: Vec::new(),
        media: Vec::new(),
        interiors: Vec::new(),
        display: Default::default(),
        warnings: Vec::new(),
    };
    d.volumes = volumes;
    d
}

pub(super) fn surface(code: &str, radius: f32, grid: Option<u32>) -> VolumeDesc {
    VolumeDesc {
        id: "h".into(),
        bound: Some(BoundDesc::Sphere { center: Vec3::ZERO, radius }),
        transform: Transform::IDENTITY,
        density: 1.0,
        script: Some(ScriptDesc { path: "h.lua".into(), code: code.into(), params: Vec::new() }),
        vdb: None,
        step: None,
        grid,
        kind: VolumeKind::Surface { material: 0, threshold: 0.5, textures: Vec::new() },
        loc: Loc::default(),
        attributes: Vec::new(),
    }
}

fn build(v: Vec<VolumeDesc>) -> Result<Volumes, SceneError> {
    Volumes::build(&desc(v), &mut Textures::default(), None, luster_shading::shader::DEFAULT_TIMEOUT)
}

pub(super) fn build_with(d: &Description, baking: &Baking) -> Result<Volumes, SceneError> {
    Volumes::build_baking(d, &mut Textures::default(), None, luster_shading::shader::DEFAULT_TIMEOUT, baking)
}

#[test]
fn crossings_of_a_falloff_ball() {
    // Density 1 − |P|/2 is 0.5 at radius 1, inside a bound of radius 1.5.
    let v = build(vec![surface("function density(s) return 1 - length(s.P) / 2 end", 1.5, None)]).unwrap();
    let ray = Ray::new(Vec3::new(0.3, 0.0, -5.0), Vec3::Z);
    let c = v.surface_hit(&ray, 1e-4, f32::INFINITY, &Probe::at(0.0)).unwrap().expect("a hit");
    let want = 5.0 - (1.0f32 - 0.09).sqrt();
    assert!((c.t - want).abs() < 1e-3, "{} vs {want}", c.t);
    let n_want = ray.at(c.t).normalize();
    assert!((c.normal - n_want).length() < 1e-2, "{} vs {n_want}", c.normal);
    // From inside, the ray leaves the surface where it crosses back.
    let inside = Ray::new(Vec3::ZERO, Vec3::X);
    let c = v.surface_hit(&inside, 1e-4, f32::INFINITY, &Probe::at(0.0)).unwrap().expect("an exit");
    assert!((c.t - 1.0).abs() < 1e-3 && c.normal.x > 0.99, "{c:?}");
    // A ray that passes the ball by meets nothing; a limit before it, neither.
    assert!(v
        .surface_hit(&Ray::new(Vec3::new(1.2, 0.0, -5.0), Vec3::Z), 1e-4, f32::INFINITY, &Probe::at(0.0))
        .unwrap()
        .is_none());
    assert!(v.surface_hit(&ray, 1e-4, 3.0, &Probe::at(0.0)).unwrap().is_none());
}

#[test]
fn a_grid_keeps_the_surface_where_it_was() {
    let v =
        build(vec![surface("function density(s) return 1 - length(s.P) / 2 end", 1.5, Some(48))]).unwrap();
    let ray = Ray::new(Vec3::new(0.0, 0.2, -5.0), Vec3::Z);
    let c = v.surface_hit(&ray, 1e-4, f32::INFINITY, &Probe::at(0.0)).unwrap().expect("a hit");
    let want = 5.0 - (1.0f32 - 0.04).sqrt();
    assert!((c.t - want).abs() < 0.01, "{} vs {want}", c.t);
}

#[test]
fn scripts_must_define_density() {
    let e = build(vec![surface("function color(s) return 1, 1, 1 end", 1.0, None)]).unwrap_err();
    assert!(e.to_string().contains("defines no density(s)"), "{e}");
    let e = build(vec![surface("function density(s) return 1 +", 1.0, None)]).unwrap_err();
    assert!(e.to_string().contains("h.lua:1"), "{e}");
}

#[test]
fn negative_densities_count_as_empty_and_scale_applies() {
    let mut d = surface("function density(s) return s.P.x end", 2.0, None);
    d.density = 3.0;
    d.kind = VolumeKind::Medium {
        absorption: Vec3::ONE,
        scattering: Vec3::ZERO,
        emission: Vec3::ONE,
        anisotropy: 0.0,
        octaves: 1,
    };
    let v = build(vec![d]).unwrap();
    let m = &v.media[0];
    assert_eq!(m.density(&v, Vec3::new(-0.5, 0.0, 0.0), &Probe::at(0.0)).unwrap(), 0.0);
    assert_eq!(m.density(&v, Vec3::new(0.5, 0.0, 0.0), &Probe::at(0.0)).unwrap(), 1.5);
    // Without emission(s), emission is the constant times the density.
    assert_eq!(m.emission(&v, Vec3::ZERO, &Probe::at(0.0), 1.5).unwrap(), Vec3::splat(1.5));
}
