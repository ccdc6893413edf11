//! A light BVH ("light tree"): one of many lights chosen by its estimated contribution at a point.
//!
//! The spatially aware alternative to a choice by power alone (Conty Estevez and Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting"; pbrt-v4's `BVHLightSampler`).
//! Every bounded light gets a [`LightBounds`]: a world box, its power `φ`
//! ([`power::power`]), and a cone of emission — the normals lie within `θo`
//! of an axis `w`, and each point emits within `θe` of its normal (or of
//! `±w` when two-sided):
//!
//! | light | box | `w` | `θo` | `θe` | two-sided |
//! |---|---|---|---|---|---|
//! | point | its position | any | π | π/2 | no |
//! | spot | its position | its axis | 0 | coverage/2 | no |
//! | square area | its corners | its normal | 0 | π/2 | yes |
//! | mesh | its triangles | mean normal | widest normal | π/2 | yes |
//! | sphere | its box (an ellipsoid's when stretched) | any | π | π/2 | no |
//! | emissive shader | as its shape, with the largest emission probed | | | | |
//!
//! Boxes of a moving (`MotionBlur`) mesh or sphere cover both ends of the
//! motion. The lights go into a binary BVH split by pbrt's orientation-aware
//! surface-area heuristic over buckets of the boxes' centres. At a point
//! `p` (normal `n` on a surface) a node's importance
//! ([`LightBounds::importance`]) bounds what its lights can send to `p`:
//! zero where every direction from the box to `p` is outside the emission
//! cone, or the whole box is behind the surface; else `φ` times a cosine
//! factor over the squared distance (never less than the box's half
//! diagonal squared, so a point near or inside the box does not blow it up).
//! A choice walks down from the root, taking each child with its share of
//! the two children's importances and rescaling `u`; the chance of a light
//! is the product of the shares on its path, which [`LightTree::pmf`]
//! retraces from a per-light bit trail, so it is exactly the number
//! [`LightTree::choose`] reported.
//!
//! Directional and environment lights have no box. As in pbrt they share
//! `k / (k + 1)` of the choices uniformly (`k` of them), the tree the rest;
//! where the root's importance is zero (nothing in the tree can light `p`)
//! they take every choice. The bounds are conservative but not nested
//! tightly, so a walk can reach a node whose two children both have zero
//! importance: the choice then gives nothing (a wasted sample, not a bias),
//! and those lights' chances are zero. (In the tests: under 1% of the
//! choices on a floor below a cloud of lights, about 15% at random normals
//! inside it, where lights behind the surface and lights turned away share
//! nodes.) Lights of zero or non-finite power are never chosen.
//!
//! For multiple importance sampling, [`LightTree::pmf`] of a light hit by a
//! bounce must be asked at the `(p, n)` the light was chosen from: the
//! previous vertex's position and the normal that was passed there. `n` is
//! the unit normal of the side that receives light; pass `None` where light
//! may arrive from behind (a transmitting BSDF, a medium).

use super::{power, Light, LightMesh, LightSphere, ShadedShape};
use luster_core::math::{Aabb, Vec3};
use std::f32::consts::PI;

/// Buckets of box centres per axis where the split heuristic cuts.
const BUCKETS: usize = 12;
/// Below this depth splits follow the heuristic; deeper, a median split
/// by count bounds the depth (64, the bit trail's length) for any count
/// of lights below 2³².
const HEURISTIC_DEPTH: u32 = 32;
/// Importances are kept below this, so the sum of two stays finite.
const MAX_IMPORTANCE: f32 = f32::MAX / 4.0;
/// The largest `f32` below 1, where a rescaled `u` is clamped.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;
/// Widening of computed cones (radians or cosine), against rounding that
/// would make a bound a hair too tight.
const CONE_MARGIN: f32 = 1e-5;

/// What a node knows about its lights: where they are, how bright they are
/// together, and where they can shine.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    /// World box (covering the whole motion of a moving light).
    pub bounds: Aabb,
    /// Emitted power ([`power::power`]), summed over the lights.
    pub phi: f32,
    /// Unit axis of the cone of emitter normals.
    pub w: Vec3,
    /// `cos θo`: every normal lies within `θo` of `w`.
    pub cos_theta_o: f32,
    /// `cos θe`: every point emits within `θe` of its normal.
    pub cos_theta_e: f32,
    /// Whether the emitters shine from both faces (`w` then stands for `±w`).
    pub two_sided: bool,
}

impl LightBounds {
    /// The bounds of a light in a scene of bounds radius `scene_radius` (for
    /// the power); `None` for directional and environment lights.
    pub fn of(light: &Light, scene_radius: f32) -> Option<LightBounds> {
        let phi = power::power(light, scene_radius);
        let all_round = |bounds| LightBounds {
            bounds,
            phi,
            w: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        };
        let b = match light {
            Light::Point(l) => all_round(Aabb::new(l.position, l.position)),
            Light::Spot(l) => match l.axis.try_normalize() {
                Some(w) => LightBounds {
                    bounds: Aabb::new(l.position, l.position),
                    phi,
                    w,
                    cos_theta_o: 1.0,
                    cos_theta_e: l.cos_coverage.clamp(-1.0, 1.0),
                    two_sided: false,
                },
                None => all_round(Aabb::new(l.position, l.position)),
            },
            Light::Area(l) => {
                let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].map(|a| l.point(a));
                let bounds = Aabb::from_points(corners);
                match l.normal.try_normalize() {
                    Some(w) => {
                        LightBounds { bounds, phi, w, cos_theta_o: 1.0, cos_theta_e: 0.0, two_sided: true }
                    }
                    None => all_round(bounds),
                }
            }
            Light::Mesh(m) => mesh_bounds(m, phi),
            Light::Sphere(s) => all_round(sphere_box(s)),
            Light::Shaded(l) => match &l.shape {
                ShadedShape::Mesh(m) => mesh_bounds(m, phi),
                ShadedShape::Sphere(s) => all_round(sphere_box(s)),
            },
            Light::Directional { .. } | Light::Environment(_) => return None,
        };
        Some(b)
    }

    /// The centre of the box, what the split heuristic sorts by.
    #[inline]
    fn centroid(&self) -> Vec3 {
        self.bounds.center()
    }

    /// Bounds holding both.
    pub fn union(&self, o: &LightBounds) -> LightBounds {
        let (w, cos_theta_o) = cone_union((self.w, self.cos_theta_o), (o.w, o.cos_theta_o));
        LightBounds {
            bounds: self.bounds.union(o.bounds),
            phi: self.phi + o.phi,
            w,
            cos_theta_o,
            cos_theta_e: self.cos_theta_e.min(o.cos_theta_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    /// How much these lights may send to `p` (unit normal `n` of the
    /// receiving side, `None` off a surface): 0 where they certainly send
    /// nothing, else `φ · cos-factor / max(d², (diagonal/2)²)`, finite and
    /// never NaN. The cosine factor is `(cos θ' − cos θe) / (1 − cos θe)`,
    /// `θ'` the smallest angle between any emitter normal and any direction
    /// from the box to `p`: pbrt's `cos θ'` for lights with `θe = π/2`, and
    /// positive wherever a wide spot (`θe > π/2`) still shines. With `n`,
    /// 0 for a box wholly behind the surface, else times the cosine of the
    /// smallest angle between `n` and a direction into the box's bounding
    /// sphere.
    pub fn importance(&self, p: Vec3, n: Option<Vec3>) -> f32 {
        self.importance_from(&Sphere::of(self), p, n)
    }

    /// [`importance`](Self::importance) with the box's bounding sphere and
    /// `sin θo` worked out ahead (a node keeps them: a choice evaluates
    /// two nodes a level).
    #[inline]
    fn importance_from(&self, s: &Sphere, p: Vec3, n: Option<Vec3>) -> f32 {
        let (r, r2) = (s.radius, s.radius * s.radius);
        let to_p = p - s.center;
        let dist2 = to_p.length_squared();
        // A NaN or infinitely far point (`max` below would drop a NaN).
        if !dist2.is_finite() {
            return 0.0;
        }
        let d2 = dist2.max(r2);
        let inv_d = if dist2 > 0.0 { dist2.sqrt().recip() } else { 0.0 };
        let wi = to_p * inv_d;
        // The cone of directions from `p` into the box's bounding sphere,
        // everything from inside it.
        let (cos_b, sin_b) = if dist2 <= r2 {
            (-1.0, 0.0)
        } else {
            let sin_b = r * inv_d;
            (safe_sqrt(1.0 - sin_b * sin_b), sin_b)
        };
        // Lights that shine every way (θo = π) face every point.
        let cos_p = if self.cos_theta_o <= -1.0 {
            1.0
        } else {
            let mut cos_w = self.w.dot(wi);
            if self.two_sided {
                cos_w = cos_w.abs();
            }
            let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
            let (cos_x, sin_x) = angle_less((cos_w, sin_w), (self.cos_theta_o, s.sin_theta_o));
            angle_less((cos_x, sin_x), (cos_b, sin_b)).0
        };
        let cos_e = self.cos_theta_e;
        if cos_p <= cos_e {
            return 0.0;
        }
        let mut v = self.phi * ((cos_p - cos_e) * s.inv_one_minus_cos_e) / d2;
        if let Some(n) = n {
            // A box wholly behind the surface sends nothing: tested on the
            // box itself, tighter than the sphere's cone below, so a node
            // whose children are all behind is rarely thought to be lit.
            let (lo, hi) = (self.bounds.min - p, self.bounds.max - p);
            let reach = (n * lo).max(n * hi).element_sum();
            if reach.is_nan() || reach <= 0.0 {
                return 0.0;
            }
            // Towards the light is −wi.
            let cos_i = -n.dot(wi);
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            v *= angle_less((cos_i, sin_i), (cos_b, sin_b)).0;
        }
        // `v > 0` is false for NaN (a zero distance times a zero cosine).
        if v > 0.0 {
            v.min(MAX_IMPORTANCE)
        } else {
            0.0
        }
    }
}

/// `√max(x, 0)`.
#[inline]
fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `(cos, sin)` of `max(θa − θb, 0)` from those of `θa` and `θb` in `[0, π]`.
#[inline]
fn angle_less((cos_a, sin_a): (f32, f32), (cos_b, sin_b): (f32, f32)) -> (f32, f32) {
    if cos_a > cos_b {
        (1.0, 0.0)
    } else {
        (cos_a * cos_b + sin_a * sin_b, sin_a * cos_b - cos_a * sin_b)
    }
}

/// The box of a sphere light over its motion.
fn sphere_box(s: &LightSphere) -> Aabb {
    let (lo, hi) = s.bounds();
    moving(Aabb::new(lo, hi), s.motion)
}

/// A box at rest grown to cover its translation by `motion`.
fn moving(b: Aabb, motion: Vec3) -> Aabb {
    b.union(Aabb::new(b.min + motion, b.max + motion))
}

/// A mesh's bounds: two-sided, so a cone need only hold each normal up to
/// sign, whose axis is the sum of the normals turned towards the first one
/// and whose `cos θo` the least `|w · n|` (at most π/2 wide for any mesh).
fn mesh_bounds(m: &LightMesh, phi: f32) -> LightBounds {
    let (lo, hi) = m.bounds();
    let bounds = moving(Aabb::new(lo, hi), m.motion);
    let first = m.normals().next().unwrap_or(Vec3::Z);
    let sum = m.normals().fold(Vec3::ZERO, |s, n| if n.dot(first) < 0.0 { s - n } else { s + n });
    let (w, cos_theta_o) = match sum.try_normalize() {
        Some(w) => {
            let least = m.normals().map(|n| w.dot(n).abs()).fold(1.0f32, f32::min);
            (w, (least - CONE_MARGIN).max(0.0))
        }
        None => (Vec3::Z, 0.0),
    };
    LightBounds { bounds, phi, w, cos_theta_o, cos_theta_e: 0.0, two_sided: true }
}

/// The angle between two unit vectors, accurate near 0 and π.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).min(1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).min(1.0).asin()
    }
}

/// The smallest cone (axis, `cos θ`) holding two cones, by their spread
/// angles (pbrt's `DirectionCone` union).
fn cone_union((wa, ca): (Vec3, f32), (wb, cb): (Vec3, f32)) -> (Vec3, f32) {
    const SPHERE: (Vec3, f32) = (Vec3::Z, -1.0);
    let (ta, tb) = (ca.clamp(-1.0, 1.0).acos(), cb.clamp(-1.0, 1.0).acos());
    let td = angle_between(wa, wb);
    if (td + tb).min(PI) <= ta {
        return (wa, ca);
    }
    if (td + ta).min(PI) <= tb {
        return (wb, cb);
    }
    let to = 0.5 * (ta + td + tb) + CONE_MARGIN;
    if to >= PI {
        return SPHERE;
    }
    // Turn `wa` towards `wb` by the part of the new spread `wa`'s cone leaves.
    let Some(axis) = wa.cross(wb).try_normalize() else { return SPHERE };
    let tr = to - ta;
    let w = wa * tr.cos() + axis.cross(wa) * tr.sin();
    match w.try_normalize() {
        Some(w) => (w, to.cos()),
        None => SPHERE,
    }
}

/// The split heuristic's cost of a child (pbrt's `EvaluateCost`): its share
/// of the node's power, times the solid-angle measure of its cone `M_Ω`,
/// times its share of the node's surface area, times `Kr`, which favours
/// cutting the node's long axes. Boxes are measured with every edge at
/// least `floor`, so point lights (boxes of no area) still rank the cuts.
fn split_cost(b: &LightBounds, node: &LightBounds, kr: f32, floor: f32) -> f32 {
    let theta_o = b.cos_theta_o.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_theta_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o);
    let m_omega = 2.0 * PI * (1.0 - b.cos_theta_o)
        + 0.5
            * PI
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + b.cos_theta_o);
    let area = |a: &Aabb| {
        let e = a.extent().max(Vec3::splat(floor));
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    };
    (b.phi / node.phi) * m_omega * kr * (area(&b.bounds) / area(&node.bounds))
}

/// The bucket of a centre along `dim` of the centres' box `cent`.
#[inline]
fn bucket(c: Vec3, cent: &Aabb, dim: usize) -> usize {
    let span = cent.max[dim] - cent.min[dim];
    (((c[dim] - cent.min[dim]) / span * BUCKETS as f32) as usize).min(BUCKETS - 1)
}

/// Where the lights are: a leaf's bit trail from the root (bit `k` set: the
/// second child at depth `k`), or none.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Slot {
    /// Not chosen (zero or non-finite power).
    Absent,
    /// A directional or environment light.
    Infinite,
    /// A leaf of the tree `depth` levels down.
    Tree { trail: u64, depth: u32 },
}

/// A node of the tree, in depth-first order: the first child follows its
/// parent.
#[derive(Clone, Copy, Debug)]
struct Node {
    /// Bounds of every light under it.
    bounds: LightBounds,
    /// Its box's bounding sphere and `sin θo`.
    sphere: Sphere,
    /// What it is.
    kind: Kind,
}

impl Node {
    fn new(bounds: LightBounds, kind: Kind) -> Node {
        Node { bounds, sphere: Sphere::of(&bounds), kind }
    }

    /// [`LightBounds::importance`] of the node.
    #[inline]
    fn importance(&self, p: Vec3, n: Option<Vec3>) -> f32 {
        self.bounds.importance_from(&self.sphere, p, n)
    }
}

/// What [`LightBounds::importance`] derives from the bounds alone.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Sphere {
    /// The box's centre.
    center: Vec3,
    /// Half its diagonal.
    radius: f32,
    /// `sin θo`.
    sin_theta_o: f32,
    /// `1 / (1 − cos θe)`.
    inv_one_minus_cos_e: f32,
}

impl Sphere {
    fn of(b: &LightBounds) -> Sphere {
        Sphere {
            center: b.bounds.center(),
            radius: 0.5 * b.bounds.extent().length(),
            sin_theta_o: safe_sqrt(1.0 - b.cos_theta_o * b.cos_theta_o),
            inv_one_minus_cos_e: 1.0 / (1.0 - b.cos_theta_e),
        }
    }
}

/// A leaf or an interior node.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Kind {
    /// The index of its light in the lights the tree was built from.
    Leaf(usize),
    /// The index of its second child.
    Interior(usize),
}

/// The light tree (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct LightTree {
    /// The bounded lights' BVH, root first; empty without any.
    nodes: Vec<Node>,
    /// For each light of the slice built from, where it is.
    slots: Vec<Slot>,
    /// The directional and environment lights' indices.
    infinite: Vec<usize>,
    /// Their joint chance `k / (k + 1)` where the tree can light a point.
    infinite_share: f32,
    /// The tree's chance `1 / (k + 1)` there.
    tree_share: f32,
}

impl LightTree {
    /// The tree over `lights` in a scene whose bounds have radius
    /// `scene_radius` (for the powers of [`power::power`]). Deterministic:
    /// the same lights give the same tree.
    pub fn build(lights: &[Light], scene_radius: f32) -> LightTree {
        let mut slots = vec![Slot::Absent; lights.len()];
        let mut infinite = Vec::new();
        let mut items = Vec::new();
        for (i, light) in lights.iter().enumerate() {
            match LightBounds::of(light, scene_radius) {
                None => {
                    slots[i] = Slot::Infinite;
                    infinite.push(i);
                }
                Some(b) if b.phi > 0.0 && b.phi.is_finite() && b.bounds.is_finite() => items.push((i, b)),
                Some(_) => {}
            }
        }
        let k = infinite.len() as f32;
        let mut tree = LightTree {
            nodes: Vec::with_capacity(2 * items.len()),
            slots,
            infinite,
            infinite_share: k / (k + 1.0),
            tree_share: 1.0 / (k + 1.0),
        };
        if !items.is_empty() {
            tree.build_node(&mut items, 0, 0);
        }
        tree
    }

    /// Appends the subtree over `items` (non-empty) at `depth`, reached by
    /// `trail`, and returns its bounds.
    fn build_node(&mut self, items: &mut [(usize, LightBounds)], trail: u64, depth: u32) -> LightBounds {
        let at = self.nodes.len();
        if let [(i, b)] = items {
            self.nodes.push(Node::new(*b, Kind::Leaf(*i)));
            self.slots[*i] = Slot::Tree { trail, depth };
            return *b;
        }
        // A placeholder until the children's bounds are known.
        self.nodes.push(Node::new(items[0].1, Kind::Leaf(items[0].0)));
        let mid = split(items, depth);
        let (first, second) = items.split_at_mut(mid);
        let a = self.build_node(first, trail, depth + 1);
        let second_at = self.nodes.len();
        debug_assert!(depth < 64, "the bit trail holds 64 levels");
        let b = self.build_node(second, trail | 1 << depth, depth + 1);
        let bounds = a.union(&b);
        self.nodes[at] = Node::new(bounds, Kind::Interior(second_at));
        bounds
    }

    /// The joint chance of the infinite lights and that of the tree at
    /// `(p, n)`: the tree gets nothing where its root's importance is zero.
    #[inline]
    fn shares(&self, p: Vec3, n: Option<Vec3>) -> (f32, f32) {
        let root = self.nodes.first();
        // Without infinite lights an interior root's importance decides
        // nothing the walk would not: where it is 0, so are its children's.
        if self.infinite.is_empty() && root.is_some_and(|r| matches!(r.kind, Kind::Interior(_))) {
            return (0.0, 1.0);
        }
        match (self.infinite.is_empty(), root.is_some_and(|r| r.importance(p, n) > 0.0)) {
            (true, true) => (0.0, 1.0),
            (true, false) => (0.0, 0.0),
            (false, true) => (self.infinite_share, self.tree_share),
            (false, false) => (1.0, 0.0),
        }
    }

    /// The chance of the first child of interior node `at` (second child
    /// `second`) at `(p, n)`; `None` where neither child can be chosen.
    #[inline]
    fn first_share(&self, at: usize, second: usize, p: Vec3, n: Option<Vec3>) -> Option<f32> {
        let i0 = self.nodes[at + 1].importance(p, n);
        let i1 = self.nodes[second].importance(p, n);
        let sum = i0 + i1;
        (sum > 0.0).then(|| i0 / sum)
    }

    /// A light for the uniform `u` in `[0, 1)` at point `p` (unit normal `n`
    /// of the receiving side, `None` off a surface or where light may come
    /// from behind): its index in the lights the tree was built from, and
    /// the chance of choosing it, which [`pmf`](Self::pmf) repeats exactly.
    /// `None` where no light can be chosen.
    pub fn choose(&self, u: f32, p: Vec3, n: Option<Vec3>) -> Option<(usize, f32)> {
        let (infinite, tree) = self.shares(p, n);
        if u < infinite {
            let k = self.infinite.len();
            let j = ((u / infinite * k as f32) as usize).min(k - 1);
            return Some((self.infinite[j], infinite / k as f32));
        }
        if tree <= 0.0 {
            return None;
        }
        let mut u = ((u - infinite) / tree).min(ONE_MINUS_EPSILON);
        let mut pmf = tree;
        let mut at = 0;
        loop {
            match self.nodes[at].kind {
                // A chance that underflowed is no chance (and `pmf` says 0).
                Kind::Leaf(i) => return (pmf > 0.0).then_some((i, pmf)),
                Kind::Interior(second) => {
                    let first = self.first_share(at, second, p, n)?;
                    if u < first {
                        pmf *= first;
                        u = (u / first).min(ONE_MINUS_EPSILON);
                        at += 1;
                    } else {
                        let rest = 1.0 - first;
                        pmf *= rest;
                        u = ((u - first) / rest).min(ONE_MINUS_EPSILON);
                        at = second;
                    }
                }
            }
        }
    }

    /// The chance that [`choose`](Self::choose) at `(p, n)` gives light
    /// `i`: bit for bit the number it reports, 0 for a light it never
    /// gives there (or an index out of range).
    pub fn pmf(&self, i: usize, p: Vec3, n: Option<Vec3>) -> f32 {
        match self.slots.get(i) {
            None | Some(Slot::Absent) => 0.0,
            Some(Slot::Infinite) => self.shares(p, n).0 / self.infinite.len() as f32,
            Some(&Slot::Tree { trail, depth }) => {
                let tree = self.shares(p, n).1;
                if tree <= 0.0 {
                    return 0.0;
                }
                // The same products, in the same order, as `choose`.
                let mut pmf = tree;
                let mut at = 0;
                for level in 0..depth {
                    let Kind::Interior(second) = self.nodes[at].kind else { return 0.0 };
                    let Some(first) = self.first_share(at, second, p, n) else { return 0.0 };
                    if trail >> level & 1 == 0 {
                        pmf *= first;
                        at += 1;
                    } else {
                        pmf *= 1.0 - first;
                        at = second;
                    }
                }
                pmf
            }
        }
    }

    /// The number of lights the tree was built from.
    pub fn len(&self) -> usize {
        self.slots.len()
    }

    /// Whether it was built from none.
    pub fn is_empty(&self) -> bool {
        self.slots.is_empty()
    }
}

/// Orders `items` (two or more) for a split and returns where the second
/// child's lights start: the cheapest cut between buckets by
/// [`split_cost`] over the three axes, else (all centres in one bucket,
/// or past [`HEURISTIC_DEPTH`]) half of them by count along the axis the
/// centres spread most. Ties keep the light order, so the tree is
/// deterministic.
fn split(items: &mut [(usize, LightBounds)], depth: u32) -> usize {
    let n = items.len();
    let cent = items.iter().fold(Aabb::EMPTY, |b, (_, l)| b.grow(l.centroid()));
    if depth < HEURISTIC_DEPTH {
        if let Some((dim, cut)) = cheapest_cut(items, &cent) {
            items.sort_by_key(|(_, l)| bucket(l.centroid(), &cent, dim) > cut);
            let mid = items.partition_point(|(_, l)| bucket(l.centroid(), &cent, dim) <= cut);
            if mid > 0 && mid < n {
                return mid;
            }
        }
    }
    let e = cent.extent();
    let dim = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    items.sort_by(|(i, a), (j, b)| a.centroid()[dim].total_cmp(&b.centroid()[dim]).then(i.cmp(j)));
    n / 2
}

/// The axis and last bucket of the first child of the cheapest cut, if
/// any axis has centres in more than one place.
fn cheapest_cut(items: &[(usize, LightBounds)], cent: &Aabb) -> Option<(usize, usize)> {
    let node = items[1..].iter().fold(items[0].1, |b, (_, l)| b.union(l));
    let extent = node.bounds.extent();
    let floor = 1e-3 * extent.length();
    let mut best: Option<(f32, usize, usize)> = None;
    for dim in 0..3 {
        if cent.max[dim] <= cent.min[dim] {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, l) in items {
            let b = &mut buckets[bucket(l.centroid(), cent, dim)];
            *b = Some(b.map_or(*l, |x| x.union(l)));
        }
        let join = |acc: Option<LightBounds>, b: &Option<LightBounds>| match (acc, b) {
            (Some(a), Some(b)) => Some(a.union(b)),
            (a, b) => a.or(*b),
        };
        // Bounds of buckets `..=i` and of `i..`.
        let below: Vec<Option<LightBounds>> = buckets
            .iter()
            .scan(None, |acc, b| {
                *acc = join(*acc, b);
                Some(*acc)
            })
            .collect();
        let mut above: Vec<Option<LightBounds>> = buckets
            .iter()
            .rev()
            .scan(None, |acc, b| {
                *acc = join(*acc, b);
                Some(*acc)
            })
            .collect();
        above.reverse();
        let kr = extent.max_element() / extent[dim];
        for cut in 0..BUCKETS - 1 {
            let (Some(a), Some(b)) = (below[cut], above[cut + 1]) else { continue };
            let cost = split_cost(&a, &node, kr, floor) + split_cost(&b, &node, kr, floor);
            if cost < best.map_or(f32::INFINITY, |(c, _, _)| c) {
                best = Some((cost, dim, cut));
            }
        }
    }
    best.map(|(_, dim, cut)| (dim, cut))
}

#[cfg(test)]
mod tests;
