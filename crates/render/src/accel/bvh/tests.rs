//! Tests of the BVH: against brute force, degenerate inputs, determinism.

use super::node::{fused_available, RayPre};
use super::*;
use glam::Vec3;

/// A small deterministic generator (SplitMix64), so tests need no crate.
pub(crate) struct Rng(pub u64);

impl Rng {
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub(crate) fn f(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f()
    }
    pub(crate) fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
    pub(crate) fn dir(&mut self) -> Vec3 {
        loop {
            let v = self.vec(-1.0, 1.0);
            if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                return v.normalize();
            }
        }
    }
}

fn random_boxes(rng: &mut Rng, n: usize) -> Vec<Aabb> {
    (0..n)
        .map(|_| {
            let c = rng.vec(-10.0, 10.0);
            let h = rng.vec(0.0, 0.6);
            Aabb::new(c - h, c + h)
        })
        .collect()
}

/// The primitive of these tests is the box itself, hit at its entry distance.
fn brute_closest(boxes: &[Aabb], ray: &Ray, t_max: f32) -> Option<f32> {
    let inv = ray.d.recip();
    boxes.iter().filter_map(|b| b.hit(ray.o, inv, t_max)).min_by(f32::total_cmp)
}

fn bvh_closest(bvh: &Bvh, boxes: &[Aabb], ray: &Ray, t_max: f32) -> Option<f32> {
    let inv = ray.d.recip();
    let mut best = None;
    let hit = bvh.closest(ray, t_max, |range, t| {
        let mut found = false;
        for &p in &bvh.prim_order()[range] {
            if let Some(te) = boxes[p as usize].hit(ray.o, inv, *t) {
                if best.is_none_or(|b| te < b) {
                    best = Some(te);
                    *t = te;
                    found = true;
                }
            }
        }
        found
    });
    assert_eq!(hit, best.is_some());
    best
}

fn bvh_any(bvh: &Bvh, boxes: &[Aabb], ray: &Ray, t_max: f32) -> bool {
    let inv = ray.d.recip();
    bvh.any(ray, t_max, |range, t| {
        bvh.prim_order()[range].iter().any(|&p| boxes[p as usize].hit(ray.o, inv, t).is_some())
    })
}

/// Checks the structural invariants: boxes nest, leaves partition
/// `prim_order`, which is a permutation of the valid inputs.
fn check_structure(bvh: &Bvh, boxes: &[Aabb]) {
    let mut covered = vec![false; bvh.prim_order().len()];
    let contains = |o: &Aabb, i: &Aabb| o.min.cmple(i.min).all() && o.max.cmpge(i.max).all();
    let mut leaf = |r: Range<usize>, b: &Aabb| {
        assert!(r.len() <= MAX_LEAF && !r.is_empty());
        for i in r {
            assert!(!covered[i], "prim in two leaves");
            covered[i] = true;
            assert!(contains(b, &boxes[bvh.prim_order()[i] as usize]));
        }
    };
    let mut todo = Vec::new();
    match bvh.root() {
        Child::Leaf(r) => leaf(r, &bvh.bounds()),
        Child::Node(i) => todo.push((i, bvh.bounds())),
        Child::Empty => assert!(bvh.prim_order().is_empty()),
    }
    let mut seen = 0;
    while let Some((i, parent)) = todo.pop() {
        seen += 1;
        let n = &bvh.nodes()[i];
        let mut used = 0;
        for k in 0..WIDTH {
            let b = n.child_bounds(k);
            match n.child(k) {
                Child::Empty => assert!(b.is_empty()),
                c => {
                    used += 1;
                    assert!(contains(&parent, &b));
                    match c {
                        Child::Leaf(r) => leaf(r, &b),
                        Child::Node(j) => {
                            assert!(j > i, "depth-first order");
                            todo.push((j, b));
                        }
                        Child::Empty => unreachable!(),
                    }
                }
            }
        }
        assert!(used >= 2);
    }
    assert_eq!(seen, bvh.node_count(), "every node reachable once");
    assert!(covered.iter().all(|&c| c), "a primitive is in no leaf");
    let mut order = bvh.prim_order().to_vec();
    order.sort_unstable();
    let valid: Vec<u32> = (0..boxes.len() as u32)
        .filter(|&i| !boxes[i as usize].is_empty() && boxes[i as usize].is_finite())
        .collect();
    assert_eq!(order, valid);
}

#[test]
fn closest_and_any_match_brute_force() {
    let mut rng = Rng(1);
    // Big enough that the parallel build paths run too.
    let mut boxes = random_boxes(&mut rng, 20_000);
    // Boxes that must be skipped: empty, infinite, NaN.
    boxes[7] = Aabb::EMPTY;
    boxes[100] = Aabb::new(Vec3::ZERO, Vec3::splat(f32::INFINITY));
    boxes[2000] = Aabb::new(Vec3::splat(f32::NAN), Vec3::ONE);
    let bvh = Bvh::build(&boxes);
    check_structure(&bvh, &boxes);
    assert_eq!(bvh.prim_order().len(), boxes.len() - 3);
    let valid: Vec<Aabb> = boxes.iter().copied().filter(|b| !b.is_empty() && b.is_finite()).collect();
    let mut hits = 0;
    for i in 0..5000 {
        let o = rng.vec(-15.0, 15.0);
        // Aim at some box half the time so most rays hit something.
        let d =
            if i % 2 == 0 { (valid[i % valid.len()].center() - o) * rng.range(0.2, 3.0) } else { rng.dir() };
        let ray = Ray::new(o, d);
        let t_max = if i % 3 == 0 { rng.range(0.0, 20.0) } else { f32::INFINITY };
        let want = brute_closest(&valid, &ray, t_max);
        assert_eq!(bvh_closest(&bvh, &boxes, &ray, t_max), want, "ray {i}: {ray:?}");
        assert_eq!(bvh_any(&bvh, &boxes, &ray, t_max), want.is_some(), "ray {i}");
        hits += want.is_some() as usize;
    }
    assert!(hits > 1000 && hits < 5000, "test rays should both hit and miss: {hits}");
}

#[test]
fn axis_aligned_rays_along_box_faces_hit() {
    // Zero direction components with the origin on a slab plane: the
    // naive slab test computes 0 * inf = NaN here.
    let boxes = [Aabb::new(Vec3::ZERO, Vec3::ONE), Aabb::new(Vec3::splat(2.0), Vec3::splat(3.0))];
    let bvh = Bvh::build(&boxes);
    let ray = Ray::new(Vec3::new(0.0, 0.5, -1.0), Vec3::Z);
    let mut leaves = 0;
    bvh.closest(&ray, f32::INFINITY, |r, _| {
        leaves += bvh.prim_order()[r].contains(&0) as usize;
        false
    });
    assert_eq!(leaves, 1);
}

#[test]
fn empty_and_single_builds() {
    let empty = Bvh::build(&[]);
    assert_eq!(empty.node_count(), 0);
    assert_eq!(empty.depth(), 0);
    assert!(empty.bounds().is_empty());
    let ray = Ray::new(Vec3::ZERO, Vec3::X);
    assert!(!empty.closest(&ray, f32::INFINITY, |_, _| panic!("no leaves")));
    assert!(!empty.any(&ray, f32::INFINITY, |_, _| panic!("no leaves")));
    // Only unusable boxes: also empty.
    assert_eq!(Bvh::build(&[Aabb::EMPTY]).node_count(), 0);

    let b = Aabb::new(Vec3::splat(1.0), Vec3::splat(2.0));
    let one = Bvh::build(&[b]);
    assert_eq!((one.node_count(), one.depth(), one.prim_order()), (0, 1, &[0u32][..]));
    assert_eq!(one.root(), Child::Leaf(0..1));
    assert_eq!(one.bounds(), b);
    let toward = Ray::new(Vec3::ZERO, Vec3::ONE);
    assert!(one.closest(&toward, f32::INFINITY, |r, _| r == (0..1)));
    assert!(one.any(&toward, f32::INFINITY, |r, _| r == (0..1)));
    assert!(!one.any(&toward, 0.5, |_, _| panic!("box is beyond t_max")));
    assert!(!one.closest(&ray, f32::INFINITY, |_, _| panic!("ray misses")));
}

#[test]
fn identical_and_point_boxes_build_shallow_trees() {
    // All centroids equal: no SAH split exists, median splits take over.
    let b = Aabb::new(Vec3::ZERO, Vec3::ONE);
    let boxes = vec![b; 10_000];
    let bvh = Bvh::build(&boxes);
    check_structure(&bvh, &boxes);
    assert!(bvh.depth() <= 15, "depth {}", bvh.depth());
    let ray = Ray::new(Vec3::splat(-1.0), Vec3::ONE);
    let mut seen = 0;
    bvh.any(&ray, f32::INFINITY, |r, _| {
        seen += r.len();
        false
    });
    assert_eq!(seen, 10_000, "any() must visit every leaf when no leaf reports a hit");
    // Point boxes (zero-area triangles have them) are valid primitives.
    let pts: Vec<Aabb> = (0..100).map(|i| Aabb::new(Vec3::splat(i as f32), Vec3::splat(i as f32))).collect();
    check_structure(&Bvh::build(&pts), &pts);
}

#[test]
fn exponential_spacing_keeps_depth_bounded() {
    // Centroids at 2^i: the SAH peels one primitive off per level, the
    // worst case for depth. The cut-off must keep it within the stack.
    let boxes: Vec<Aabb> = (0..2000)
        .map(|i| {
            let x = 1.02f32.powi(i);
            Aabb::new(Vec3::new(x, 0.0, 0.0), Vec3::new(x * 1.01, 1.0, 1.0))
        })
        .collect();
    let bvh = Bvh::build(&boxes);
    check_structure(&bvh, &boxes);
    assert!((WIDTH - 1) * bvh.depth() < STACK, "depth {}", bvh.depth());
    let ray = Ray::new(Vec3::new(0.0, 0.5, 0.5), Vec3::X);
    assert_eq!(bvh_closest(&bvh, &boxes, &ray, f32::INFINITY), brute_closest(&boxes, &ray, f32::INFINITY));
}

#[test]
fn build_is_deterministic_across_thread_counts() {
    let boxes = random_boxes(&mut Rng(7), 50_000);
    let a = Bvh::build(&boxes);
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let three = rayon::ThreadPoolBuilder::new().num_threads(3).build().unwrap();
    assert_eq!(a, one.install(|| Bvh::build(&boxes)));
    assert_eq!(a, three.install(|| Bvh::build(&boxes)));
    assert_eq!(size_of::<Node8>(), 256);
}

#[test]
fn sah_beats_one_leaf_per_primitive() {
    // On clustered input the SAH should make multi-primitive leaves and
    // a tree far shallower than a list.
    let boxes = random_boxes(&mut Rng(3), 4096);
    let bvh = Bvh::build(&boxes);
    let leaves = bvh.leaf_count();
    assert!(leaves < 4096 && leaves > 4096 / MAX_LEAF, "{leaves} leaves");
    assert!(bvh.binary_depth() < 40, "depth {}", bvh.binary_depth());
    // The collapse fills nodes; only nodes whose binary descendants run
    // out of inner nodes stay narrow (a collapse that stopped at two
    // children would use a quarter of the eight slots).
    let slots = bvh.node_count() * WIDTH;
    let used = leaves + bvh.node_count() - 1;
    assert!(used as f32 > 0.55 * slots as f32, "{used} of {slots} child slots used");
}

#[test]
fn huge_coordinates_and_nan_rays_stay_in_range() {
    // Boxes at up to ±f32::MAX: an unhalved centroid sum overflows to
    // infinity, which empties a child and makes a leaf of no primitives.
    let m = f32::MAX;
    let mut boxes: Vec<Aabb> = (0..9)
        .map(|i| {
            let x = [-m, -1e38, -1.0, 0.0, 1.0, 1e30, 1e38, 3e38, m][i];
            Aabb::new(Vec3::new(x.min(m / 2.0), 0.0, 0.0), Vec3::new(x, 1.0, 1.0))
        })
        .collect();
    boxes.extend(
        (0..40).map(|i| Aabb::new(Vec3::splat(i as f32 * 1e37), Vec3::splat(i as f32 * 1e37 + 1e36))),
    );
    let bvh = Bvh::build(&boxes);
    check_structure(&bvh, &boxes);
    let in_range = |r: std::ops::Range<usize>| r.end <= bvh.prim_order().len();
    // A NaN ray passes every box test, unused child slots included.
    for ray in [Ray::new(Vec3::splat(f32::NAN), Vec3::X), Ray::new(Vec3::ZERO, Vec3::splat(f32::NAN))] {
        bvh.closest(&ray, f32::INFINITY, |r, _| {
            assert!(in_range(r));
            false
        });
        bvh.any(&ray, f32::INFINITY, |r, _| {
            assert!(in_range(r));
            false
        });
    }
}

/// The AVX2 + FMA node test lets through every box the SSE test does (it
/// may add a few by its margin), and traversals with either test find the
/// same closest hits and the same occlusion.
#[cfg(target_arch = "x86_64")]
#[test]
fn fused_node_test_is_conservative_and_traversals_agree() {
    if !fused_available() {
        eprintln!("this CPU has no AVX2 and FMA: only the SSE traversal exists here");
        return;
    }
    let mut rng = Rng(23);
    let boxes = random_boxes(&mut rng, 5000);
    let bvh = Bvh::build(&boxes);
    let (mut plain_hits, mut extra) = (0usize, 0usize);
    for k in 0..3000 {
        // Origins inside the cloud, far outside it, and on box faces; some
        // directions with exactly zero components.
        let o = match k % 3 {
            0 => rng.vec(-12.0, 12.0),
            1 => rng.vec(-12.0, 12.0) + Vec3::splat(1e4),
            _ => boxes[k % boxes.len()].min,
        };
        let mut d = rng.dir() * rng.range(0.1, 10.0);
        if k % 7 == 0 {
            d.x = 0.0;
        }
        if k % 11 == 0 {
            d = Vec3::new(0.0, 0.0, -1.0);
        }
        let ray = Ray::new(o, d);
        let t_max = if k % 4 == 0 { rng.range(1.0, 30.0) } else { f32::INFINITY };
        let r = RayPre::new(&ray);
        assert!(r.fused_ok, "ray {k}");
        for n in bvh.nodes() {
            let plain = r.hit(n, t_max).1;
            // SAFETY: AVX2 and FMA were detected, and `fused_ok` holds.
            let (fused_tn, fused) = unsafe { r.hit_fused(n, t_max) };
            // The traversals' form of the fused test (constants broadcast
            // once per ray) computes the same lanes.
            let (pre_tn, pre) = r.node_test::<true>().hit(&r, n, t_max);
            assert_eq!(pre, fused, "ray {k}: the traversal's fused test disagrees");
            assert_eq!(pre_tn.map(f32::to_bits), fused_tn.map(f32::to_bits), "ray {k}");
            // The one-node root's form (rows reordered by sign) too.
            let root = super::node::SignedRoot::new(n);
            let (root_tn, by_root) =
                r.node_test::<true>().hit_root(&r, std::slice::from_ref(n), &root, t_max);
            assert_eq!((by_root, root_tn.map(f32::to_bits)), (fused, fused_tn.map(f32::to_bits)), "ray {k}");
            assert_eq!(fused & plain, plain, "ray {k}: the fused test culled a box the plain one enters");
            plain_hits += plain.count_ones() as usize;
            extra += (fused & !plain).count_ones() as usize;
        }
        let inv = ray.d.recip();
        let closest = |fused: bool| {
            let mut best = None;
            let leaf = |range: Range<usize>, t: &mut f32| {
                let mut found = false;
                for &p in &bvh.prim_order()[range] {
                    if let Some(te) = boxes[p as usize].hit(ray.o, inv, *t) {
                        if best.is_none_or(|b: (f32, u32)| te < b.0) {
                            best = Some((te, p));
                            *t = te;
                            found = true;
                        }
                    }
                }
                found
            };
            // SAFETY: AVX2 and FMA were detected.
            let hit = if fused {
                unsafe { bvh.closest_fused(&ray, t_max, FnLeaf(leaf)) }
            } else {
                bvh.closest_plain::<false, _>(&ray, t_max, FnLeaf(leaf))
            };
            (hit, best)
        };
        assert_eq!(closest(true), closest(false), "ray {k}");
        let blocked = |range: Range<usize>, t: f32| {
            bvh.prim_order()[range].iter().any(|&p| boxes[p as usize].hit(ray.o, inv, t).is_some())
        };
        // SAFETY: AVX2 and FMA were detected.
        let any_fused = unsafe { bvh.any_fused(&ray, t_max, FnLeaf(blocked)) };
        assert_eq!(any_fused, bvh.any_plain::<false, _>(&ray, t_max, FnLeaf(blocked)), "ray {k}");
    }
    assert!(plain_hits > 10_000, "{plain_hits}");
    // The margin is a few ulps: it should almost never matter.
    assert!(extra * 1000 < plain_hits, "{extra} extra boxes against {plain_hits}");
}
