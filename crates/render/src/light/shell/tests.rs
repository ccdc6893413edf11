//! Tests of the convex-shell test of light meshes against the mesh's own
//! shadow rays: the course's open box, closed boxes, meshes that are no
//! shell, and a moving light.

use super::*;
use crate::accel::MeshAccel;
use crate::light::test_rng::Rng;
use crate::light::LightMesh;
use luster_core::math::{Ray, Transform};

/// The corners of the box `lo..hi` as triangles, one face per entry of
/// `faces` (`-x +x -y +y -z +z` as 0..6), windings mixed as in the course's
/// light boxes.
fn boxed(lo: Vec3, hi: Vec3, faces: &[usize]) -> Vec<[Vec3; 3]> {
    let c = |i: usize| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][i >> 2]);
    // Each face's corners in order around it.
    let quads = [[0, 2, 6, 4], [1, 3, 7, 5], [0, 1, 5, 4], [2, 3, 7, 6], [0, 1, 3, 2], [4, 5, 7, 6]];
    let mut tris = Vec::new();
    for (k, &f) in faces.iter().enumerate() {
        let [a, b, cc, d] = quads[f].map(c);
        if k % 2 == 0 {
            tris.extend([[a, b, cc], [cc, d, a]]);
        } else {
            tris.extend([[a, cc, b], [a, d, cc]]);
        }
    }
    tris
}

/// The course's hw7 light: a 0.5 × 0.5 × 0.12 box open at the top.
fn course_box() -> Vec<[Vec3; 3]> {
    boxed(Vec3::new(-0.25, -0.25, 1.16), Vec3::new(0.25, 0.25, 1.28), &[0, 1, 2, 3, 4])
}

/// Draws `(o, q, n, hidden)` for points `o` in `room` and samples of the
/// light, and checks every hidden one against the mesh's own shadow ray:
/// the segment is blocked before `q`. Returns how many were hidden and how
/// many faced away from `o`.
fn check_against_rays(tris: &[[Vec3; 3]], room: (Vec3, Vec3), n: usize) -> (usize, usize) {
    let light = LightMesh::new(tris.iter().copied(), &Transform::IDENTITY, Vec3::ONE).expect("area");
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let idx: Vec<[u32; 3]> = (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let accel = MeshAccel::build(&positions, &idx);
    let mut rng = Rng(7);
    let (mut hidden, mut away) = (0, 0);
    for _ in 0..n {
        let u = Vec3::new(rng.next(), rng.next(), rng.next());
        let o = room.0 + (room.1 - room.0) * u;
        let (q, nq) = light.point((rng.next(), rng.next()));
        let to = q - o;
        let dist = to.length();
        if dist < 1e-3 {
            continue;
        }
        let facing_away = nq.dot(o - q) < 0.0;
        away += usize::from(facing_away);
        if light.hides(o, q, nq, 0.0) {
            hidden += 1;
            assert!(facing_away, "o {o} q {q}: hidden though facing o");
            let ray = Ray::new(o, to / dist);
            assert!(
                accel.occluded(&ray, 1e-6, dist * (1.0 - 1e-6)),
                "o {o} q {q}: hidden but the ray passes"
            );
        }
    }
    (hidden, away)
}

#[test]
fn a_closed_box_hides_its_far_side_from_outside() {
    let tris = boxed(Vec3::splat(-1.0), Vec3::splat(1.0), &[0, 1, 2, 3, 4, 5]);
    let shell = Shell::new(&tris).expect("a closed box is a shell");
    assert_eq!((shell.faces.len(), shell.hole), (6, None));
    let (hidden, away) = check_against_rays(&tris, (Vec3::splat(-4.0), Vec3::splat(4.0)), 20_000);
    // Outside points only see at most three of the six faces: about half
    // the area faces away, and all of that is hidden, except for the few
    // points inside the box.
    assert!(hidden > 8_000 && away - hidden < 500, "hidden {hidden} of {away} facing away");
}

#[test]
fn the_course_box_open_at_the_ceiling_hides_only_below_it() {
    let tris = course_box();
    let shell = Shell::new(&tris).expect("the course's box is a shell");
    let hole = shell.hole.expect("open at the top");
    assert!((hole.n - Vec3::Z).length() < 1e-6 && (hole.d - 1.28).abs() < 1e-6);
    // The room below the ceiling: every sample facing away is hidden.
    let room = (Vec3::new(-1.27, -1.25, -1.25), Vec3::new(1.29, 1.30, 1.28 - 1e-3));
    let (hidden, away) = check_against_rays(&tris, room, 20_000);
    // (Points inside the box, 0.2% of the room, see every face from behind.)
    assert!(hidden > 4_000 && away - hidden < 100, "hidden {hidden} of {away} facing away");
    // Above the ceiling the open top shows the inside: nothing is hidden.
    let above = (Vec3::new(-1.0, -1.0, 1.3), Vec3::new(1.0, 1.0, 3.0));
    assert_eq!(check_against_rays(&tris, above, 5_000).0, 0);
}

#[test]
fn nothing_is_hidden_from_inside() {
    let tris = boxed(Vec3::splat(-1.0), Vec3::splat(1.0), &[0, 1, 2, 3, 4, 5]);
    let (hidden, away) = check_against_rays(&tris, (Vec3::splat(-0.9), Vec3::splat(0.9)), 5_000);
    assert_eq!(hidden, 0);
    assert!(away > 4_000, "{away}");
}

#[test]
fn meshes_that_are_no_convex_shell_have_none() {
    let unit = |faces: &[usize]| boxed(Vec3::ZERO, Vec3::ONE, faces);
    // Flat: one quad.
    assert!(Shell::new(&unit(&[4])).is_none());
    // Two faces missing that share an edge: the holes' edges are on two planes.
    assert!(Shell::new(&unit(&[0, 2, 3, 4])).is_none());
    // Two boxes in one mesh.
    let mut two = unit(&[0, 1, 2, 3, 4, 5]);
    two.extend(boxed(Vec3::splat(2.0), Vec3::splat(3.0), &[0, 1, 2, 3, 4, 5]));
    assert!(Shell::new(&two).is_none());
    // Concave: a box with a dent pushed into its top (the top's four
    // triangles meet at a point below the top plane).
    let mut dented = unit(&[0, 1, 2, 3, 4]);
    let m = Vec3::new(0.5, 0.5, 0.6);
    let top = [
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(0.0, 1.0, 1.0),
    ];
    dented.extend((0..4).map(|k| [top[k], top[(k + 1) % 4], m]));
    assert!(Shell::new(&dented).is_none());
    // A triangle used twice makes its edges non-manifold.
    let mut doubled = unit(&[0, 1, 2, 3, 4, 5]);
    doubled.push(doubled[0]);
    assert!(Shell::new(&doubled).is_none());
    // A lid hovering above the open box: a hole whose plane is not the hull's.
    let mut lidded = unit(&[0, 1, 2, 3, 4]);
    lidded.extend(boxed(Vec3::new(0.0, 0.0, 2.0), Vec3::new(1.0, 1.0, 2.0), &[4]));
    assert!(Shell::new(&lidded).is_none());
}

#[test]
fn a_mesh_without_a_shell_hides_nothing() {
    let tris = boxed(Vec3::ZERO, Vec3::ONE, &[0, 2, 3, 4]);
    assert_eq!(check_against_rays(&tris, (Vec3::splat(-2.0), Vec3::splat(3.0)), 5_000).0, 0);
}

#[test]
fn a_moving_light_hides_where_it_has_moved() {
    let tris = boxed(Vec3::splat(-1.0), Vec3::splat(1.0), &[0, 1, 2, 3, 4, 5]);
    let mut light = LightMesh::new(tris.into_iter(), &Transform::IDENTITY, Vec3::ONE).expect("area");
    light.motion = Vec3::new(10.0, 0.0, 0.0);
    // The +x face's point seen from x = 5: at time 0 the box is at rest and
    // the face looks at the point; at time 1 the box has moved past it, so
    // the same face (moved) is its far side.
    let (q, n) = (Vec3::new(1.0, 0.2, 0.3), Vec3::X);
    let o = Vec3::new(5.0, 0.0, 0.0);
    assert!(!light.hides(o, q, n, 0.0));
    assert!(light.hides(o, q + light.motion, n, 1.0));
}
