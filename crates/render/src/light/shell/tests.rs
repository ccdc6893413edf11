//! Tests of the faces a light mesh's points are drawn on, against the
//! mesh's own shadow rays: the course's open box, closed boxes, meshes that
//! are no shell, a moving light, and the irradiance they give.

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

/// The mesh of `tris` as a light and a tree of its triangles.
fn light_and_accel(tris: &[[Vec3; 3]]) -> (LightMesh, MeshAccel) {
    let light = LightMesh::new(tris.iter().copied(), &Transform::IDENTITY, Vec3::ONE).expect("area");
    let positions: Vec<Vec3> = tris.iter().flatten().copied().collect();
    let idx: Vec<[u32; 3]> = (0..tris.len() as u32).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    (light, MeshAccel::build(&positions, &idx))
}

/// Draws points `o` in `room` and points `q` on the light by area, and
/// checks every `q` on a face that [`Shell::facing`] leaves out against the
/// mesh's own shadow ray: the segment is blocked before `q`. Returns how
/// many were left out and how many faced away from `o`.
fn check_against_rays(tris: &[[Vec3; 3]], room: (Vec3, Vec3), n: usize) -> (usize, usize) {
    let (light, accel) = light_and_accel(tris);
    let shell = Shell::new(tris);
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
        let left_out = shell.as_ref().is_some_and(|s| {
            let mask = s.facing(o);
            let face = s.face_of(q, nq).expect("a point of the shell is on a face");
            mask != 0 && mask >> face & 1 == 0
        });
        if left_out {
            hidden += 1;
            assert!(facing_away, "o {o} q {q}: left out though facing o");
            let ray = Ray::new(o, to / dist);
            assert!(
                accel.occluded(&ray, 1e-6, dist * (1.0 - 1e-6)),
                "o {o} q {q}: left out but the ray passes"
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
fn a_moving_light_is_seen_where_it_has_moved() {
    let tris = boxed(Vec3::splat(-1.0), Vec3::splat(1.0), &[0, 1, 2, 3, 4, 5]);
    let mut light = LightMesh::new(tris.into_iter(), &Transform::IDENTITY, Vec3::ONE).expect("area");
    light.motion = Vec3::new(10.0, 0.0, 0.0);
    // Seen from x = 5 (y, z inside the box's range), the box at rest shows
    // its +x face only; at time 1 it has moved past the point and shows its
    // −x face only.
    let o = Vec3::new(5.0, 0.2, 0.3);
    let mut rng = Rng(3);
    for (time, want) in [(0.0, Vec3::X), (1.0, -Vec3::X)] {
        for _ in 0..200 {
            let (_, n, _) = light.point_seen((rng.next(), rng.next()), o, time);
            assert_eq!(n, want, "time {time}");
        }
    }
}

/// The irradiance a point receives from a light of radiance 1, two ways:
/// points drawn on what it sees, each weighed by its density, and points
/// drawn by area over the whole mesh with the mesh's own shadow ray. The
/// two agree within noise (a z-test on the difference of the means).
fn irradiance_both_ways(tris: &[[Vec3; 3]], o: Vec3, n: Vec3, samples: usize) -> (f64, f64) {
    let (light, accel) = light_and_accel(tris);
    let mut rng = Rng(11);
    let (mut a, mut a2, mut b, mut b2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for _ in 0..samples {
        let (q, nq, area) = light.point_seen((rng.next(), rng.next()), o, 0.0);
        let to = q - o;
        let pdf = light.pdf(o, q, nq, 0.0);
        assert_eq!(pdf, LightMesh::pdf_drawn(o, q, nq, area), "the area drawn from is the one pdf() finds");
        let x = if pdf > 0.0 { f64::from(n.dot(to.normalize()).max(0.0) / pdf) } else { 0.0 };
        (a, a2) = (a + x, a2 + x * x);
        // By area, with visibility traced.
        let (q, nq) = light.point((rng.next(), rng.next()));
        let to = q - o;
        let (d2, dist) = (to.length_squared(), to.length());
        let cos_l = nq.dot(to).abs() / dist;
        let open = !accel.occluded(&Ray::new(o, to / dist), 1e-6, dist * (1.0 - 1e-5));
        let y = if open { f64::from(n.dot(to / dist).max(0.0) * cos_l * light.area() / d2) } else { 0.0 };
        (b, b2) = (b + y, b2 + y * y);
    }
    let m = samples as f64;
    let (ma, mb) = (a / m, b / m);
    let var = (a2 / m - ma * ma) / m + (b2 / m - mb * mb) / m;
    let z = (ma - mb) / var.sqrt().max(1e-12);
    assert!(z.abs() < 4.0, "o {o}: seen {ma} against traced {mb} (z {z:.2})");
    (ma, mb)
}

#[test]
fn drawing_only_the_seen_faces_keeps_the_irradiance() {
    let closed = boxed(Vec3::new(-0.5, -0.3, -0.1), Vec3::new(0.5, 0.3, 0.1), &[0, 1, 2, 3, 4, 5]);
    let course = course_box();
    let cases = [
        // Below the closed box, beside it, near a corner, above it, at an
        // angle to two faces, inside it.
        (&closed, Vec3::new(0.1, 0.0, -1.0), Vec3::Z),
        (&closed, Vec3::new(1.0, 0.0, 0.0), -Vec3::X),
        (&closed, Vec3::new(0.6, 0.4, -0.15), Vec3::new(-1.0, -1.0, 1.0).normalize()),
        (&closed, Vec3::new(0.0, 0.2, 2.0), -Vec3::Z),
        (&closed, Vec3::new(0.0, 0.0, 0.0), Vec3::Y),
        // The course's box open at the top: below it, on the ceiling beside
        // it (the hole's plane), and above the ceiling looking in.
        (&course, Vec3::new(0.1, -0.2, 0.5), Vec3::Z),
        (&course, Vec3::new(0.4, 0.1, 1.28), Vec3::new(-1.0, 0.0, -1.0).normalize()),
        (&course, Vec3::new(0.0, 0.1, 1.6), -Vec3::Z),
    ];
    for (tris, o, n) in cases {
        let (seen, traced) = irradiance_both_ways(tris, o, n, 40_000);
        assert!(seen > 0.0 && traced > 0.0, "o {o}: no light");
    }
}

#[test]
fn seen_faces_draw_nothing_that_is_hidden() {
    // Points drawn for a point below the closed box are never behind it.
    let tris = boxed(Vec3::splat(-1.0), Vec3::splat(1.0), &[0, 1, 2, 3, 4, 5]);
    let (light, accel) = light_and_accel(&tris);
    let mut rng = Rng(5);
    for _ in 0..5_000 {
        let o = Vec3::new(rng.next() * 8.0 - 4.0, rng.next() * 8.0 - 4.0, rng.next() * 8.0 - 4.0);
        if o.abs().max_element() <= 1.0 {
            continue;
        }
        let (q, _, _) = light.point_seen((rng.next(), rng.next()), o, 0.0);
        let to = q - o;
        let dist = to.length();
        assert!(!accel.occluded(&Ray::new(o, to / dist), 1e-6, dist * (1.0 - 1e-4)), "o {o} q {q}");
    }
}
