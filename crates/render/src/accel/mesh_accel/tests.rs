//! Tests of the mesh accelerator against brute force: shared edges and
//! vertices, barycentrics, small meshes' flat any-hit test, scaled
//! directions, degenerate triangles.

use super::*;
use crate::accel::bvh::tests::Rng;

/// An n×n grid of quads, two triangles each, with random heights: every
/// interior edge and vertex is shared, and no two neighbours are coplanar.
/// Slopes stay below 20° so the rays of the leak test, steeper than 50°,
/// cross the surface instead of grazing a silhouette (where a ray
/// rounded past a vertex may rightly miss).
fn bumpy_grid(rng: &mut Rng, n: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut p = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            p.push(Vec3::new(i as f32 * 0.37, j as f32 * 0.29, rng.range(-0.05, 0.05)));
        }
    }
    let mut t = Vec::new();
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Alternate the diagonal so vertices have both 4 and 8 neighbours.
            if (i + j) % 2 == 0 {
                t.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                t.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            } else {
                t.push([id(i, j), id(i + 1, j), id(i, j + 1)]);
                t.push([id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
    }
    (p, t)
}

fn brute(pos: &[Vec3], tris: &[[u32; 3]], ray: &Ray, t_max: f32) -> Option<(f32, u32)> {
    let wr = WatertightRay::new(ray);
    let mut best: Option<(f32, u32)> = None;
    for (k, t) in tris.iter().enumerate() {
        let tri = Triangle::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize], k as u32);
        if let Some(h) = wr.intersect(&tri, 0.0, best.map_or(t_max, |b| b.0)) {
            best = Some((h.t, k as u32));
        }
    }
    best
}

#[test]
fn rays_through_shared_edges_and_vertices_never_leak() {
    let mut rng = Rng(11);
    let n = 24;
    let (pos, tris) = bumpy_grid(&mut rng, n);
    let mesh = MeshAccel::build(&pos, &tris);
    assert_eq!(mesh.triangle_count(), tris.len());
    let mut targets = Vec::new();
    // Every interior vertex, exactly.
    for j in 1..n {
        for i in 1..n {
            targets.push(pos[j * (n + 1) + i]);
        }
    }
    // Points on shared edges (as close as f32 gets), from random triangles.
    for _ in 0..20_000 {
        let t = tris[(rng.next_u64() % tris.len() as u64) as usize];
        let e = (rng.next_u64() % 3) as usize;
        let (a, b) = (pos[t[e] as usize], pos[t[(e + 1) % 3] as usize]);
        let s = rng.f();
        let p = a + (b - a) * s;
        let lo = pos[0].truncate();
        let hi = pos[pos.len() - 1].truncate();
        // Edges on the grid's border are not shared: rays may miss there.
        if p.x > lo.x + 1e-3 && p.y > lo.y + 1e-3 && p.x < hi.x - 1e-3 && p.y < hi.y - 1e-3 {
            targets.push(p);
        }
    }
    assert!(targets.len() > 10_000);
    for (k, &p) in targets.iter().enumerate() {
        // Origins above and below, directions deliberately not unit length.
        let o = p + Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(2.0, 4.0))
            * if k % 2 == 0 { 1.0 } else { -1.0 };
        let ray = Ray::new(o, (p - o) * rng.range(0.1, 10.0));
        assert!(brute(&pos, &tris, &ray, f32::INFINITY).is_some(), "ray {k} through {p} leaked");
        let hit = mesh.intersect(&ray, 0.0, f32::INFINITY);
        assert!(hit.is_some(), "ray {k} through shared point {p} lost in the BVH");
        assert!(mesh.occluded(&ray, 0.0, f32::INFINITY), "shadow ray {k} leaked");
    }
}

#[test]
fn closest_hit_matches_brute_force_with_barycentrics() {
    let mut rng = Rng(5);
    // A triangle soup, so hits overlap and ordering matters.
    // Triangles shrunk towards their centroids so rays get between them.
    let pos: Vec<Vec3> = (0..1000)
        .flat_map(|_| {
            let c = [rng.vec(-5.0, 5.0), rng.vec(-5.0, 5.0), rng.vec(-5.0, 5.0)];
            let m = (c[0] + c[1] + c[2]) / 3.0;
            c.map(|v| m + (v - m) * 0.3)
        })
        .collect();
    let tris: Vec<[u32; 3]> = (0..1000u32).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
    let mesh = MeshAccel::build(&pos, &tris);
    let mut hits = 0;
    for _ in 0..5000 {
        let ray = Ray::new(rng.vec(-8.0, 8.0), rng.dir() * rng.range(0.5, 2.0));
        let got = mesh.intersect(&ray, 0.0, f32::INFINITY);
        let want = brute(&pos, &tris, &ray, f32::INFINITY);
        assert_eq!(got.map(|h| (h.t, h.prim)), want);
        assert_eq!(mesh.occluded(&ray, 0.0, f32::INFINITY), want.is_some());
        if let Some(h) = got {
            hits += 1;
            let t = tris[h.prim as usize].map(|i| pos[i as usize]);
            let p = t[0] * (1.0 - h.u - h.v) + t[1] * h.u + t[2] * h.v;
            assert!((p - ray.at(h.t)).length() < 1e-3, "barycentrics disagree with t");
            assert!(h.u >= 0.0 && h.v >= 0.0 && h.u + h.v <= 1.0 + 1e-6);
            // t_max and t_min are exclusive bounds.
            assert!(mesh.intersect(&ray, 0.0, h.t).is_none_or(|h2| h2.t < h.t));
            assert!(mesh.intersect(&ray, h.t, f32::INFINITY).is_none_or(|h2| h2.t > h.t));
        }
    }
    assert!(hits > 200, "{hits}");
}

#[test]
fn small_meshes_tested_flat_block_what_brute_force_blocks() {
    // Soups of 9 to 16 triangles: more than one leaf, yet tested by
    // any-hit queries without the tree (`FLAT_ANY_BLOCKS`).
    let mut rng = Rng(23);
    let mut trees = 0;
    for n in 9..=16u32 {
        let pos: Vec<Vec3> = (0..3 * n).map(|_| rng.vec(-2.0, 2.0)).collect();
        let tris: Vec<[u32; 3]> = (0..n).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let mesh = MeshAccel::build(&pos, &tris);
        assert!(mesh.any_flat && mesh.block_count() <= FLAT_ANY_BLOCKS);
        trees += mesh.bvh().single_leaf().is_none() as usize;
        for _ in 0..2000 {
            let ray = Ray::new(rng.vec(-4.0, 4.0), rng.dir() * rng.range(0.5, 2.0));
            let t_max = rng.range(0.5, 8.0);
            let want = brute(&pos, &tris, &ray, t_max).is_some();
            assert_eq!(mesh.occluded(&ray, 0.0, t_max), want);
        }
    }
    assert!(trees > 0, "no mesh had a tree of its own");
}

#[test]
fn scaled_directions_scale_t_and_back_faces_hit() {
    let pos = [Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let mesh = MeshAccel::build(&pos, &[[0, 1, 2]]);
    let front = Ray::new(Vec3::new(0.0, 0.0, 4.0), Vec3::new(0.0, 0.0, -2.0));
    assert_eq!(mesh.intersect(&front, 0.0, f32::INFINITY).map(|h| h.t), Some(2.0));
    let back = Ray::new(Vec3::new(0.0, 0.0, -4.0), Vec3::new(0.0, 0.0, 0.5));
    assert_eq!(mesh.intersect(&back, 0.0, f32::INFINITY).map(|h| h.t), Some(8.0));
    assert!(!mesh.occluded(&back, 0.0, 7.9));
    assert!(mesh.occluded(&back, 0.0, 8.1));
}

#[test]
fn degenerate_and_invalid_triangles_never_hit() {
    let pos = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0), // collinear with the two before
        Vec3::new(f32::NAN, 0.0, 0.0),
        Vec3::new(0.0, f32::INFINITY, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
    ];
    let tris = [[0, 1, 2], [0, 0, 1], [1, 1, 1], [0, 3, 5], [0, 4, 5], [0, 1, 99], [u32::MAX, 0, 1]];
    let mesh = MeshAccel::build(&pos, &tris);
    assert_eq!(mesh.triangle_count(), 0);
    assert!(mesh.bounds().is_empty());
    let mut rng = Rng(2);
    for k in 0..2000 {
        // Aim at the degenerate segment, including exactly edge-on.
        let target = Vec3::new(rng.range(-0.5, 2.5), 0.0, 0.0);
        let o = if k % 4 == 0 { Vec3::new(-1.0, 0.0, 0.0) } else { rng.vec(-3.0, 3.0) };
        let ray = Ray::new(o, target - o);
        assert!(mesh.intersect(&ray, 0.0, f32::INFINITY).is_none());
        assert!(!mesh.occluded(&ray, 0.0, f32::INFINITY));
    }
    // The direct test also rejects a degenerate triangle without NaN.
    let wr = WatertightRay::new(&Ray::new(Vec3::new(0.5, 0.0, 1.0), -Vec3::Z));
    assert!(wr.intersect(&Triangle::new(pos[0], pos[1], pos[2], 0), 0.0, f32::INFINITY).is_none());
    // A valid triangle among invalid ones is still found, with its input index.
    let mesh = MeshAccel::build(&pos, &[[0, 1, 2], [0, 1, 5], [0, 3, 5]]);
    assert_eq!(mesh.triangle_count(), 1);
    let hit = mesh.intersect(&Ray::new(Vec3::new(0.2, 0.2, 1.0), -Vec3::Z), 0.0, 10.0);
    assert_eq!(hit.map(|h| h.prim), Some(1));
    // Zero direction: no hit, no panic.
    assert!(mesh.intersect(&Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::ZERO), 0.0, 10.0).is_none());
}

#[test]
fn empty_mesh_and_thread_safety() {
    let mesh = MeshAccel::build(&[], &[]);
    assert_eq!(mesh.triangle_count(), 0);
    assert!(mesh.intersect(&Ray::new(Vec3::ZERO, Vec3::X), 0.0, f32::INFINITY).is_none());
    fn send_sync<T: Send + Sync>() {}
    send_sync::<MeshAccel>();
}
