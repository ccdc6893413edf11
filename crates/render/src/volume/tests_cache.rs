//! Volume grids kept across builds (the cache `luster watch` uses), bakes
//! abandoned through the cancel flag, and what volume scripts see of their
//! context.

use super::tests::{build_with, desc, surface};
use super::*;
use luster_core::math::{Ray, Transform};
use luster_scene::description::VolumeKind;
use std::sync::atomic::AtomicBool;

fn medium(code: &str, grid: Option<u32>) -> luster_scene::description::VolumeDesc {
    let mut v = surface(code, 1.0, grid);
    v.kind = VolumeKind::Medium {
        absorption: Vec3::ONE,
        scattering: Vec3::ZERO,
        emission: Vec3::ZERO,
        anisotropy: 0.0,
        octaves: 1,
    };
    v
}

fn grids(v: &Volumes) -> (&Arc<Grid<f32>>, Option<&Arc<Grid<Vec3>>>) {
    let m = &v.media[0];
    let Field::Grid(d) = &m.field else { panic!("the density is not baked") };
    let e = match &m.kind {
        Kind::Medium { glow: Glow::Grid(g), .. } => Some(g),
        _ => None,
    };
    (d, e)
}

const GLOW: &str = "function density(s) return 0.5 + 0.25 * s.P.x end\n\
                    function emission(s) return s.P.y + 1, 0, 0 end";

#[test]
fn an_unchanged_volume_reuses_its_grids_and_a_changed_one_bakes_again() {
    let cache = GridCache::default();
    let baking = Baking { cache: Some(&cache), cancel: None };
    let d = desc(vec![medium(GLOW, Some(8))]);
    let a = build_with(&d, &baking).unwrap();
    let b = build_with(&d, &baking).unwrap();
    let (da, ea) = grids(&a);
    let (db, eb) = grids(&b);
    assert!(Arc::ptr_eq(da, db), "the density grid was baked again");
    assert!(Arc::ptr_eq(ea.expect("emission"), eb.expect("emission")), "the emission grid was baked again");
    assert_eq!(cache.len(), 1);
    // What a build without the cache bakes is the same field.
    let plain = build_with(&d, &Baking::default()).unwrap();
    let p = Vec3::new(0.3, -0.2, 0.1);
    let probe = Probe::at(0.0);
    assert_eq!(
        a.media[0].density(&a, p, &probe).unwrap(),
        plain.media[0].density(&plain, p, &probe).unwrap()
    );

    // Each input of the bake is part of the key.
    let mut changed = Vec::new();
    let mut code = d.clone();
    code.volumes[0].script.as_mut().unwrap().code = GLOW.replace("0.25", "0.5");
    changed.push(("the script text", code));
    let mut moved = d.clone();
    moved.volumes[0].transform = Transform::translation(Vec3::X);
    changed.push(("the transform", moved));
    let mut finer = d.clone();
    finer.volumes[0].grid = Some(9);
    changed.push(("the grid resolution", finer));
    let mut param = d.clone();
    param.volumes[0]
        .script
        .as_mut()
        .unwrap()
        .params
        .push(("k".into(), luster_shading::shader::ParamValue::Number(2.0)));
    assert_ne!(cache::key(&d, 0, 8), cache::key(&param, 0, 8), "a parameter is not in the key");
    for (what, d2) in changed {
        let c = build_with(&d2, &baking).unwrap();
        assert!(!Arc::ptr_eq(grids(&c).0, da), "a change of {what} reused the old grid");
    }
    // The changed script's field is the new one.
    let mut code = d.clone();
    code.volumes[0].script.as_mut().unwrap().code = GLOW.replace("0.25", "0.5");
    let c = build_with(&code, &baking).unwrap();
    let x = Vec3::new(0.5, 0.0, 0.0);
    assert!((c.media[0].density(&c, x, &probe).unwrap() - 0.75).abs() < 1e-5);
    assert!(cache.covers(&d) && cache.covers(&code));
}

#[test]
fn saving_a_required_module_makes_its_grids_stale() {
    let dir = tempfile::tempdir().unwrap();
    let module = dir.path().join("fieldlib.lua");
    std::fs::write(&module, "return { k = 0.25 }").unwrap();
    let mut d =
        desc(vec![medium("local f = require 'fieldlib'\nfunction density(s) return f.k end", Some(4))]);
    d.base_dir = dir.path().to_path_buf();
    let cache = GridCache::default();
    let baking = Baking { cache: Some(&cache), cancel: None };
    let a = build_with(&d, &baking).unwrap();
    assert_eq!(a.shader_modules(), vec![module.canonicalize().unwrap()]);
    let b = build_with(&d, &baking).unwrap();
    assert!(Arc::ptr_eq(grids(&a).0, grids(&b).0));
    std::fs::write(&module, "return { k = 0.75 }").unwrap();
    assert!(!cache.covers(&d), "a saved module leaves the grid current");
    let c = build_with(&d, &baking).unwrap();
    assert_eq!(c.media[0].density(&c, Vec3::ZERO, &Probe::at(0.0)).unwrap(), 0.75);
}

#[test]
fn a_set_cancel_flag_abandons_the_bake() {
    let stop = AtomicBool::new(true);
    let cache = GridCache::default();
    let baking = Baking { cache: Some(&cache), cancel: Some(&stop) };
    let e = build_with(&desc(vec![medium(GLOW, Some(16))]), &baking).unwrap_err();
    assert!(e.to_string().contains(cache::CANCELLED), "{e}");
    assert!(cache.is_empty(), "an abandoned bake was kept");
    // A volume without a grid has nothing to bake and builds.
    assert!(build_with(&desc(vec![medium(GLOW, None)]), &baking).is_ok());
}

#[test]
fn volume_scripts_see_camera_ray_pixel_and_object() {
    // Each returns one context value (plus 10, to stay a positive density).
    let v = |expr: &str, grid: Option<u32>| {
        let mut second = medium(&format!("function density(s) return 10 + {expr} end"), grid);
        second.id = "b".into();
        build_with(&desc(vec![medium("function density(s) return 1 end", None), second]), &Baking::default())
            .unwrap()
    };
    let view =
        crate::texture::View { eye: Vec3::new(0.0, 0.0, 5.0), right: Vec3::X, up: Vec3::Y, back: Vec3::Z };
    let probe = Probe { time: 0.25, dir: -Vec3::Z, view, pixel: [7, 3] };
    let p = Vec3::new(0.5, 0.25, -0.5);
    let at = |expr: &str| {
        let vols = v(expr, None);
        vols.media[1].density(&vols, p, &probe).unwrap() - 10.0
    };
    assert_eq!(at("s.Pc.z"), -5.5, "the camera-space point");
    assert_eq!(at("s.Pw.x + s.P.y"), 0.75);
    assert_eq!(at("s.I.z"), -1.0);
    assert_eq!(at("s.V.z"), 1.0);
    assert_eq!(at("s.pixel_x * 10 + s.pixel_y"), 73.0);
    assert_eq!(at("s.time"), 0.25);
    assert_eq!(at("s.object_id + s.instance_id"), 2.0, "the second volume is index 1");
    // The step is the bound's diagonal (2√3) over 64, in the bound's own space.
    let fw = at("s.filterwidth");
    assert!((fw - 2.0 * 3f32.sqrt() / 64.0).abs() < 1e-6, "{fw}");
    // Baked, the footprint is a cell: the box (2 across) over n − 1.
    let vols = v("s.filterwidth", Some(5));
    assert!((vols.media[1].density(&vols, p, &probe).unwrap() - 10.5).abs() < 1e-6);
    let r = at("s.random");
    assert!((0.0..1.0).contains(&r));
    // A hypertexture's crossing sees the ray too.
    let mut h = surface("function density(s) return s.I.z < 0 and 1 or 0 end", 1.0, None);
    h.kind = VolumeKind::Surface { material: 0, threshold: 0.5, textures: Vec::new() };
    let hv = build_with(&desc(vec![h]), &Baking::default()).unwrap();
    let towards = Ray::new(Vec3::new(0.0, 0.0, 5.0), -Vec3::Z);
    let pr = Probe { dir: towards.d, ..Probe::at(0.0) };
    assert!(hv.surface_hit(&towards, 1e-4, f32::INFINITY, &pr).unwrap().is_some());
    let away = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
    let pr = Probe { dir: away.d, ..Probe::at(0.0) };
    assert!(hv.surface_hit(&away, 1e-4, f32::INFINITY, &pr).unwrap().is_none());
}
