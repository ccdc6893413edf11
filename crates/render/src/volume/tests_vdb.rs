//! VDB loading tests on `tests-data/grids.vdb` (written by
//! `tools/make_vdb.py`, which lists what each grid holds).

use super::*;
use crate::texture::Textures;
use crate::volume::{Probe, Volumes};
use luster_scene::description::{VolumeDesc, VolumeKind};
use luster_scene::Loc;
use std::path::PathBuf;

fn fixture() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests-data/grids.vdb")
}

fn bytes() -> Vec<u8> {
    std::fs::read(fixture()).expect("tests-data/grids.vdb")
}

fn lattice(density: &str, emission: Option<&str>) -> Lattice {
    read(&bytes(), density, emission).unwrap_or_else(|e| panic!("{density}: {e}"))
}

fn refusal(density: &str, emission: Option<&str>) -> String {
    read(&bytes(), density, emission).expect_err("the grid should be refused")
}

/// The world point of `few`'s voxel (i, j, k): index × (0.5, 0.25, 1) + (1, 2, 3).
fn few_world(i: i32, j: i32, k: i32) -> Vec3 {
    Vec3::new(1.0 + 0.5 * i as f32, 2.0 + 0.25 * j as f32, 3.0 + k as f32)
}

#[test]
fn voxels_land_at_their_world_positions_with_a_padding_of_zeros() {
    for name in ["few"] {
        let l = lattice(name, None);
        // Active voxels (2, 3, 4)–(5, 7, 9), one more on every side.
        assert_eq!(l.dims, [6, 7, 8], "{name}");
        assert_eq!(l.voxel, Vec3::new(0.5, 0.25, 1.0));
        assert_eq!(l.bounds.min, few_world(1, 2, 3));
        assert_eq!(l.bounds.max, few_world(6, 8, 10));
        let (g, e) = l.grids(None, Vec3::ONE).unwrap();
        assert!(e.is_none());
        // Lattice point = index − (1, 2, 3).
        assert_eq!(g.sample(1, 1, 1), 1.0, "{name}");
        assert_eq!(g.sample(2, 1, 1), 0.5, "{name}");
        assert_eq!(g.sample(4, 5, 6), 0.25, "{name}");
        // Negative values are stored as 0.
        assert_eq!(g.sample(3, 3, 3), 0.0, "{name}");
        let [nx, ny, nz] = g.dims();
        let total: f32 = (0..nz)
            .flat_map(|z| (0..ny).flat_map(move |y| (0..nx).map(move |x| (x, y, z))))
            .map(|(x, y, z)| g.sample(x, y, z))
            .sum();
        assert_eq!(total, 1.75, "{name}: only the three positive voxels hold density");
        for x in 0..nx {
            for y in 0..ny {
                assert_eq!((g.sample(x, y, 0), g.sample(x, y, nz - 1)), (0.0, 0.0), "{name}: padding");
            }
        }
        // Looked up in world space: values at the voxels, linear between them.
        assert_eq!(g.at(few_world(2, 3, 4)), 1.0);
        assert!((g.at(few_world(2, 3, 4) + Vec3::new(0.25, 0.0, 0.0)) - 0.75).abs() < 1e-6);
        assert!((g.at(few_world(5, 7, 9)) - 0.25).abs() < 1e-6);
        assert_eq!(g.at(few_world(2, 3, 4) - Vec3::new(0.5, 0.0, 0.0)), 0.0);
    }
}

#[test]
fn tiles_fill_their_block() {
    // A pruned constant block of voxels 8–15 under a uniform 0.1 scale.
    let l = lattice("tile", None);
    assert_eq!(l.dims, [10, 10, 10]);
    assert!((l.bounds.min - Vec3::splat(0.7)).abs().max_element() < 1e-6, "{:?}", l.bounds);
    assert!((l.bounds.max - Vec3::splat(1.6)).abs().max_element() < 1e-6, "{:?}", l.bounds);
    let (g, _) = l.grids(None, Vec3::ONE).unwrap();
    for i in 1..9 {
        assert_eq!((g.sample(i, 1, 8), g.sample(8, i, 1), g.sample(i, i, i)), (0.75, 0.75, 0.75));
    }
    assert_eq!((g.sample(0, 4, 4), g.sample(9, 4, 4)), (0.0, 0.0));
}

#[test]
fn an_emission_grid_shares_the_lattice_over_both_boxes() {
    // `glow` reaches voxel (7, 8, 9), beyond `few`'s box.
    let l = lattice("few", Some("glow"));
    assert_eq!(l.dims, [8, 8, 8]);
    assert_eq!(l.bounds.max, few_world(8, 9, 10));
    let (g, e) = l.grids(None, Vec3::new(1.0, 0.5, 0.0)).unwrap();
    let e = e.expect("an emission grid");
    assert_eq!(g.sample(1, 1, 1), 1.0);
    assert_eq!(e.sample(2, 2, 2), Vec3::new(2.0, 1.0, 0.0));
    assert_eq!(e.at(few_world(7, 8, 9)), Vec3::new(4.0, 2.0, 0.0));
    assert_eq!(e.sample(1, 1, 1), Vec3::ZERO);
}

#[test]
fn an_unturned_ellipsoid_moves_the_box_and_a_turned_one_resamples() {
    let bound = BoundDesc::Ellipsoid {
        center: Vec3::new(2.0, 3.0, 9.0),
        radii: Vec3::new(2.0, 1.0, 4.0),
        rotation: Quat::IDENTITY,
    };
    let (g, _) = lattice("few", None).grids(Some(&bound), Vec3::ONE).unwrap();
    // The unit ball's space: (p − centre) / radii.
    let local = |p: Vec3| (p - Vec3::new(2.0, 3.0, 9.0)) / Vec3::new(2.0, 1.0, 4.0);
    assert_eq!(g.dims(), [6, 7, 8]);
    assert!((g.at(local(few_world(2, 3, 4))) - 1.0).abs() < 1e-5);
    assert!((g.at(local(few_world(5, 7, 9))) - 0.25).abs() < 1e-5);

    // Turned a quarter about z: the constant tile's inside stays 0.75.
    let rotation = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let bound = BoundDesc::Ellipsoid { center: Vec3::splat(1.15), radii: Vec3::new(0.3, 0.2, 0.3), rotation };
    let (g, _) = lattice("tile", None).grids(Some(&bound), Vec3::ONE).unwrap();
    assert_eq!(g.bounds().min, Vec3::splat(-1.0));
    assert!((g.at(Vec3::ZERO) - 0.75).abs() < 1e-5);
    // Local x runs along world y: 0.3 from the centre is world y 1.45, inside the tile.
    assert!((g.at(Vec3::new(0.95, 0.0, 0.0)) - 0.75).abs() < 1e-5);
    // Local y runs along −x: 0.2 from the centre is inside too; the cell is a voxel or less.
    assert!((g.at(Vec3::new(0.0, 0.9, 0.0)) - 0.75).abs() < 1e-5);
    assert!(g.dims().iter().all(|&d| d >= 5), "{:?}", g.dims());
}

#[test]
fn the_step_follows_the_voxel() {
    let l = lattice("few", None);
    assert_eq!(l.world_step(&Transform::IDENTITY), 0.25);
    let twice = Transform::scaling(Vec3::splat(2.0)).unwrap();
    assert_eq!(l.world_step(&twice), 0.5);
}

#[test]
fn bad_grids_are_refused_in_a_sentence() {
    let cases: &[(&str, Option<&str>, &str)] = &[
        ("smoke", None, "no grid named \"smoke\""),
        ("few", Some("flame"), "no grid named \"flame\""),
        ("velocity", None, "grid \"velocity\" is not a float grid"),
        ("double", None, "grid \"double\" is not a float grid"),
        ("few", Some("velocity"), "grid \"velocity\" is not a float grid"),
        ("empty", None, "grid \"empty\" has no active voxels"),
        ("rotated", None, "grid \"rotated\" has a transform other than a scale and a translation"),
        ("few", Some("shifted"), "different transforms"),
        ("nan", None, "grid \"nan\" holds a value that is not finite"),
        ("half", None, "grid \"half\" is saved as 16-bit half floats"),
        ("huge", None, "2003×2003×2003 voxels with padding, 32.1 GB"),
    ];
    for (density, emission, words) in cases {
        let e = refusal(density, *emission);
        assert!(e.contains(words), "{density}/{emission:?}: {e:?} lacks {words:?}");
    }
}

#[test]
fn truncated_and_foreign_files_are_errors() {
    let b = bytes();
    assert!(read(&[], "density", None).unwrap_err().contains("not an OpenVDB file"));
    assert!(read(b"#!/bin/sh\necho hello\n", "density", None).unwrap_err().contains("not an OpenVDB file"));
    // Every length cut short: an error, never a panic caught along the way;
    // or, once the two grids are whole, the same lattice.
    let whole = lattice("few", Some("glow"));
    let mut cuts = (0..200).collect::<Vec<_>>();
    cuts.extend((200..b.len()).step_by(61));
    for n in cuts {
        match read(&b[..n], "few", Some("glow")) {
            Ok(l) => assert!(
                l.density == whole.density && l.emission == whole.emission && l.bounds == whole.bounds,
                "cut at {n}: read, but not as the whole file"
            ),
            Err(e) => assert!(
                !e.contains("cannot be read") && !e.is_empty(),
                "cut at {n}: {e:?} (vdb-rs panicked or failed oddly)"
            ),
        }
    }
    let mut newer = b.clone();
    newer[8] = 230;
    assert!(read(&newer, "few", None).unwrap_err().contains("file format 230; formats 218 to 224"));
}

#[test]
fn a_medium_takes_the_density_emission_bound_and_step_from_the_file() {
    let medium = |vdb: VdbDesc, bound: Option<BoundDesc>, step: Option<f32>| VolumeDesc {
        id: "p".into(),
        bound,
        transform: Transform::translation(Vec3::new(10.0, 0.0, 0.0)),
        density: 2.0,
        script: None,
        vdb: Some(vdb),
        step,
        grid: None,
        kind: VolumeKind::Medium {
            absorption: Vec3::ONE,
            scattering: Vec3::ZERO,
            emission: Vec3::new(1.0, 0.5, 0.25),
            anisotropy: 0.0,
            octaves: 1,
        },
        loc: Loc::default(),
        attributes: Vec::new(),
    };
    let file = |density: &str, emission: Option<&str>| VdbDesc {
        path: fixture(),
        density_grid: density.into(),
        emission_grid: emission.map(Into::into),
        loc: Loc { line: Some(7), path: "Scene/Volumes/Volume[id=p]/VdbFile".into() },
    };
    let build = |v: VolumeDesc| {
        let d = crate::volume::tests::desc(vec![v]);
        Volumes::build(&d, &mut Textures::default(), None, luster_shading::shader::DEFAULT_TIMEOUT)
    };
    let shift = Vec3::new(10.0, 0.0, 0.0);
    let v = build(medium(file("few", Some("glow")), None, None)).unwrap();
    let m = &v.media[0];
    let probe = Probe::at(0.0);
    // No bound: the lattice's box, moved by the volume's transform.
    assert!((m.bound.world_box().min - (few_world(1, 2, 3) + shift)).abs().max_element() < 1e-5);
    assert_eq!(m.step, 0.25);
    assert_eq!(m.density(&v, few_world(2, 3, 4) + shift, &probe).unwrap(), 2.0);
    // The emission grid times Emission, whatever the density.
    let glow = m.emission(&v, few_world(7, 8, 9) + shift, &probe, 0.0).unwrap();
    assert!((glow - Vec3::new(4.0, 2.0, 1.0)).abs().max_element() < 1e-5, "{glow}");

    // A bound clips; StepSize wins; without an emission grid, Emission × density.
    let ball = BoundDesc::Sphere { center: few_world(2, 3, 4), radius: 0.6 };
    let v = build(medium(file("few", None), Some(ball), Some(0.1))).unwrap();
    let m = &v.media[0];
    assert_eq!(m.step, 0.1);
    assert_eq!(m.bound.interval(&luster_core::math::Ray::new(few_world(5, 7, 9) + shift, Vec3::X)), None);
    assert_eq!(m.emission(&v, few_world(2, 3, 4) + shift, &probe, 2.0).unwrap(), Vec3::new(2.0, 1.0, 0.5));

    // File errors name the VdbFile element and the file.
    let e = build(medium(file("smoke", None), None, None)).unwrap_err().to_string();
    assert!(e.contains("line 7, Scene/Volumes/Volume[id=p]/VdbFile") && e.contains("grids.vdb"), "{e}");
    let mut missing = file("density", None);
    missing.path = fixture().with_file_name("no_such.vdb");
    let e = build(medium(missing, None, None)).unwrap_err().to_string();
    assert!(e.contains("cannot read VDB file") && e.contains("no_such.vdb: no such file"), "{e}");
}
