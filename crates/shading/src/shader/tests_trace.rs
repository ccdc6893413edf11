//! Rays from shaders against a small scene of rectangles and spheres:
//! `trace()`'s hit record, a miss with no tracer installed, the ray cap,
//! `occlusion()` and `edgewear()` against their analytic fractions, `bevel()`
//! at an edge, and determinism across threads.

use super::tests::set_of;
use super::*;

/// An axis-aligned rectangle: the plane `p[axis] = at`, its normal along
/// `+axis` or `-axis` (`sign`), and its extent on the other two axes.
#[derive(Clone, Copy)]
struct Rect {
    axis: usize,
    at: f32,
    sign: f32,
    lo: [f32; 2],
    hi: [f32; 2],
    id: u32,
}

/// Rectangles and spheres (centre, radius, id), seen from both sides.
#[derive(Default)]
struct Shapes {
    rects: Vec<Rect>,
    spheres: Vec<([f32; 3], f32, u32)>,
}

fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn at(o: [f32; 3], d: [f32; 3], t: f32) -> [f32; 3] {
    [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t]
}

impl Tracer for Shapes {
    fn trace(&self, ray: &TraceRay) -> Option<TraceHit> {
        // Off the surface the ray leaves, on its side, as a renderer does.
        let side = if dot(ray.dir, ray.ng) < 0.0 { -1e-4 } else { 1e-4 };
        let o = at(ray.origin, ray.ng, side);
        let d = ray.dir;
        let lead = dot(ray.ng, d) * side;
        let mut best: Option<TraceHit> = None;
        let mut keep = |t: f32, n: [f32; 3], id: u32| {
            let t_from = t + lead;
            if t > 1e-6 && t_from <= ray.max_dist && best.is_none_or(|b| t_from < b.t) {
                best = Some(TraceHit { t: t_from, p: at(o, d, t), n, ng: n, object_id: id, instance_id: id });
            }
        };
        for r in &self.rects {
            if d[r.axis] == 0.0 {
                continue;
            }
            let t = (r.at - o[r.axis]) / d[r.axis];
            let p = at(o, d, t);
            let (a, b) = ((r.axis + 1) % 3, (r.axis + 2) % 3);
            if p[a] >= r.lo[0] && p[a] <= r.hi[0] && p[b] >= r.lo[1] && p[b] <= r.hi[1] {
                let mut n = [0.0; 3];
                n[r.axis] = r.sign;
                keep(t, n, r.id);
            }
        }
        for &(c, radius, id) in &self.spheres {
            let oc = [o[0] - c[0], o[1] - c[1], o[2] - c[2]];
            let (b, cc) = (dot(oc, d), dot(oc, oc) - radius * radius);
            let disc = b * b - cc;
            if disc < 0.0 {
                continue;
            }
            for t in [-b - disc.sqrt(), -b + disc.sqrt()] {
                let p = at(o, d, t);
                let n = [(p[0] - c[0]) / radius, (p[1] - c[1]) / radius, (p[2] - c[2]) / radius];
                keep(t, n, id);
            }
        }
        best
    }
}

const BIG: f32 = 1e4;

/// The floor `z = 0`, facing up, object 1.
fn floor() -> Rect {
    Rect { axis: 2, at: 0.0, sign: 1.0, lo: [-BIG, -BIG], hi: [BIG, BIG], id: 1 }
}

/// A solid filling `x < 0, z < 0` (object 3): its top face and its side,
/// meeting in a convex edge along the y axis.
fn edge() -> Shapes {
    Shapes {
        rects: vec![
            Rect { axis: 2, at: 0.0, sign: 1.0, lo: [-BIG, -BIG], hi: [0.0, BIG], id: 3 },
            Rect { axis: 0, at: 0.0, sign: 1.0, lo: [-BIG, -BIG], hi: [BIG, 0.0], id: 3 },
        ],
        spheres: Vec::new(),
    }
}

/// The shading point on a surface at `pw` with normal `n`.
fn point(pw: [f32; 3], n: [f32; 3]) -> ShadeInput {
    ShadeInput { p: pw, pw, n, ng: n, time: 0.5, instance_id: 3, object_id: 3, ..ShadeInput::default() }
}

const UP: [f32; 3] = [0.0, 0.0, 1.0];

/// The fraction of the cosine-weighted hemisphere around +z whose rays
/// from a point `d` from the wall `x = 0` (the wall on the side of -x)
/// meet it within `reach`: the hemisphere's directions project uniformly
/// onto the unit disc, and a ray hits when its x component is below
/// `-d / reach`, a segment of the disc.
fn wall_fraction(d: f64, reach: f64) -> f64 {
    let a = (d / reach).min(1.0);
    (a.acos() - a * (1.0 - a * a).sqrt()) / std::f64::consts::PI
}

#[test]
fn trace_returns_the_nearest_hit_as_a_record() {
    let scene = Shapes { rects: vec![floor()], spheres: vec![([0.0, 0.0, 5.0], 1.0, 7)] };
    let set = set_of(
        "function color(s)
           local h = trace(s.Pw, vec3(0, 0, 2))
           if h == nil then return -1, -1, -1 end
           if trace(s.Pw, vec3(0, 0, 1), 3.5) ~= nil then return -2, -2, -2 end
           if trace(s.Pw, vec3(1, 0, 0)) ~= nil then return -3, -3, -3 end
           return h.t + h.object_id * 100 + h.instance_id * 1000, h.P.z + h.N.z * 10, h.Ng.z
         end",
    )
    .unwrap();
    let input = point([0.0, 0.0, 0.0], UP);
    let c = with_tracer(&scene, || set.color(0, &input)).unwrap();
    assert!((c[0] - 7704.0).abs() < 1e-3, "t and ids: {c:?}");
    assert!((c[1] - (4.0 - 10.0)).abs() < 1e-3, "P and N: {c:?}");
    assert!((c[2] + 1.0).abs() < 1e-6, "Ng: {c:?}");
}

#[test]
fn a_ray_from_the_surface_never_finds_the_surface_it_leaves() {
    // Grazing and straight down: the floor the point lies on is not hit
    // going up or along it, and is hit from below only by a ray going up.
    let scene = Shapes { rects: vec![floor()], spheres: Vec::new() };
    let set = set_of(
        "function color(s)
           local a = trace(s.Pw, vec3(1, 0, 1e-4))
           local b = trace(s.Pw, vec3(0, 0, -1))
           return a and 1 or 0, b and 1 or 0, 0
         end",
    )
    .unwrap();
    let c = with_tracer(&scene, || set.color(0, &point([0.3, 0.2, 0.0], UP))).unwrap();
    assert_eq!(c, [0.0, 0.0, 0.0]);
}

#[test]
fn with_no_tracer_every_ray_misses() {
    let set = set_of(
        "function color(s)
           return trace(s.Pw, vec3(0, 0, 1)) == nil and 1 or 0, occlusion(s), edgewear(s, 20)
         end",
    )
    .unwrap();
    assert_eq!(set.color(0, &point([0.0; 3], UP)).unwrap(), [1.0, 0.0, 0.0]);
    // Installed, then put back: the next call has none again.
    let inside = Shapes { rects: Vec::new(), spheres: vec![([0.0; 3], 10.0, 2)] };
    let c = with_tracer(&inside, || set.color(0, &point([0.0; 3], UP))).unwrap();
    assert_eq!(c, [0.0, 1.0, 1.0]);
    assert_eq!(set.color(0, &point([0.0; 3], UP)).unwrap(), [1.0, 0.0, 0.0]);
}

#[test]
fn rays_past_the_cap_are_an_error_at_the_scripts_line() {
    let scene = Shapes { rects: vec![floor()], spheres: Vec::new() };
    let script = |count: i32| {
        format!(
            "local count = {count}
             function color(s)
               for i = 1, count do
                 trace(s.Pw, vec3(0, 0, 1))
               end
               return occlusion(s, 100), 0, 0
             end"
        )
    };
    // 156 + 100 rays: exactly the cap, call after call (the count restarts).
    let ok = set_of(&script(MAX_RAYS - 100)).unwrap();
    for _ in 0..3 {
        with_tracer(&scene, || ok.color(0, &point([0.0; 3], UP))).unwrap();
    }
    let over = set_of(&script(MAX_RAYS - 99)).unwrap();
    let e = with_tracer(&scene, || over.color(0, &point([0.0; 3], UP))).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::Runtime);
    assert!(e.message.starts_with("test.lua:6: occlusion:"), "{e}");
    assert!(e.message.contains(&format!("cap of {MAX_RAYS} rays")), "{e}");
    // The loop itself: the 257th trace.
    let e = set_of(&script(MAX_RAYS + 1)).unwrap();
    let e = with_tracer(&scene, || e.color(0, &point([0.0; 3], UP))).unwrap_err();
    assert!(e.message.starts_with("test.lua:4: trace:"), "{e}");
    // bevel's rays count too.
    let b = set_of(&format!(
        "function color(s)
           for i = 1, {} do trace(s.Pw, vec3(0, 0, 1)) end
           local n = bevel(0.5, 8)
           return n.x, n.y, n.z
         end",
        MAX_RAYS - 4
    ))
    .unwrap();
    let e = with_tracer(&edge(), || b.color(0, &point([-0.1, 0.0, 0.0], UP))).unwrap_err();
    assert!(e.message.starts_with("test.lua:3: bevel:"), "{e}");
}

/// Under automatic derivatives an entry runs three times (and the first
/// call that asks is run again): each run has the whole budget, so a
/// shader that fits the cap fits it with derivatives too.
#[test]
fn each_derivative_run_has_the_whole_ray_budget() {
    let scene = Shapes { rects: vec![floor()], spheres: Vec::new() };
    let script = |count: i32| {
        format!(
            "function color(s)
               local hits = 0
               for i = 1, {count} do
                 if trace(s.Pw + vec3(0, 0, 1), vec3(0, 0, -1)) then hits = hits + 1 end
               end
               return hits, Dx(s.P.x), 0
             end"
        )
    };
    let mut p = point([0.25, 0.0, 0.0], UP);
    (p.dpdx, p.dpwdx) = ([0.5, 0.0, 0.0], [0.5, 0.0, 0.0]);
    let full = set_of(&script(MAX_RAYS)).unwrap();
    for _ in 0..3 {
        let c = with_tracer(&scene, || full.color(0, &p)).unwrap();
        assert_eq!((c[0], c[1]), (MAX_RAYS as f32, 0.5), "{c:?}");
    }
    let over = set_of(&script(MAX_RAYS + 1)).unwrap();
    let e = with_tracer(&scene, || over.color(0, &p)).unwrap_err();
    assert!(e.message.starts_with("test.lua:4: trace:"), "{e}");
}

#[test]
fn bad_arguments_name_the_built_in_and_the_line() {
    let cases = [
        ("trace(1, vec3(0, 0, 1))", "trace: origin must be a vec3, got a number"),
        ("trace(s.Pw, vec3(0, 0, 0))", "trace: dir must not be the zero vector"),
        ("trace(s.Pw, s.N, -1)", "trace: maxdist must be a positive number"),
        ("occlusion(s, 0)", "occlusion: samples must be a whole number from 1 to 256"),
        ("occlusion(s.Pw, vec3(0, 0, 0))", "occlusion: N must not be the zero vector"),
        ("occlusion(s.Pw, vec3(0 / 0, 0, 1))", "occlusion: N must be finite"),
        ("edgewear(s)", "edgewear: the radius is missing"),
        ("bevel(s, -2)", "bevel: radius must be a positive number"),
    ];
    for (call, want) in cases {
        let e = set_of(&format!("function color(s)\n  local x = {call}\n  return 0, 0, 0\nend")).unwrap();
        let e = e.color(0, &point([0.0; 3], UP)).unwrap_err();
        assert!(e.message.starts_with(&format!("test.lua:2: {want}")), "{call}: {e}");
    }
}

#[test]
fn occlusion_is_zero_in_the_open_and_one_when_enclosed() {
    let set =
        set_of("function color(s) return occlusion(s, 64), occlusion(s.Pw, s.N, 8, 0.5), 0 end").unwrap();
    let open = Shapes { rects: vec![floor()], spheres: Vec::new() };
    let c = with_tracer(&open, || set.color(0, &point([0.2, -0.4, 0.0], UP))).unwrap();
    assert_eq!(c, [0.0, 0.0, 0.0]);
    // A closed box of six faces around the point, 0.3 to 1 away.
    let face = |axis, at, sign| Rect { axis, at, sign, lo: [-1.0, -1.0], hi: [1.0, 1.0], id: 4 };
    let sides = [face(0, -1.0, 1.0), face(0, 1.0, -1.0), face(1, -1.0, 1.0), face(1, 1.0, -1.0)];
    let mut rects = sides.to_vec();
    rects.extend([face(2, 0.3, -1.0), face(2, -1.0, 1.0)]);
    let boxed = Shapes { rects, spheres: Vec::new() };
    let c = with_tracer(&boxed, || set.color(0, &point([0.0; 3], UP))).unwrap();
    assert_eq!(c[0], 1.0);
    // Within 0.5 only the lid, 0.3 above, is near enough straight up.
    assert!(c[1] > 0.0 && c[1] < 1.0, "{c:?}");
}

/// Many points at distances `d` from a wall: each estimate's error from
/// the analytic fraction, their mean (which must be zero within its
/// standard error) and the largest.
fn errors(set: &ShaderSet, scene: &Shapes, reach: f64, n: usize) -> (f64, f64, f64) {
    let mut e = Vec::new();
    for i in 0..n {
        // Distances across (0, reach), positions along the wall spread
        // so every point gets its own rotation.
        let d = reach * (i as f64 + 0.5) / n as f64;
        let y = (i as f64 * 0.618_034).fract() * 10.0;
        let c = with_tracer(scene, || set.color(0, &point([-(d as f32), y as f32, 0.0], UP))).unwrap();
        e.push(f64::from(c[0]) - wall_fraction(d, reach));
    }
    let mean = e.iter().sum::<f64>() / n as f64;
    let var = e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
    (mean, (var / n as f64).sqrt(), e.iter().fold(0.0, |m: f64, x| m.max(x.abs())))
}

#[test]
fn occlusion_beside_a_wall_matches_the_cosine_weighted_fraction() {
    // The floor z = 0 and the wall x = 0 facing -x.
    let wall = Rect { axis: 0, at: 0.0, sign: -1.0, lo: [-BIG, 0.0], hi: [BIG, BIG], id: 5 };
    let scene = Shapes { rects: vec![floor(), wall], spheres: Vec::new() };
    let set = set_of("function color(s) return occlusion(s, 32, 2), 0, 0 end").unwrap();
    let (mean, se, worst) = errors(&set, &scene, 2.0, 400);
    assert!(mean.abs() < 4.0 * se + 1e-3, "mean error {mean} (standard error {se})");
    // 32 stratified directions: every point within a few strata.
    assert!(worst < 0.1, "largest error {worst}");
    // Uniform instead of cosine-weighted directions would be off by far more.
    let uniform = |d: f64| 1.0 - (d / 2.0).min(1.0).asin() * 2.0 / std::f64::consts::PI;
    assert!((uniform(1.0) / 2.0 - wall_fraction(1.0, 2.0)).abs() > 0.05);
}

#[test]
fn edgewear_near_a_convex_edge_matches_the_fraction_of_rays_that_leave() {
    // Inside the solid below its top face, rays around -z leave through
    // the side x = 0 when they head +x far enough: the wall fraction again.
    let set = set_of("function color(s) return edgewear(s, 0.5, 32), 0, 0 end").unwrap();
    let (mean, se, worst) = errors(&set, &edge(), 0.5, 400);
    assert!(mean.abs() < 4.0 * se + 1e-3, "mean error {mean} (standard error {se})");
    assert!(worst < 0.1, "largest error {worst}");
    // Far from the edge: no wear at all.
    let c = with_tracer(&edge(), || set.color(0, &point([-0.6, 0.0, 0.0], UP))).unwrap();
    assert_eq!(c[0], 0.0);
}

#[test]
fn bevel_rounds_the_normal_towards_an_edge() {
    let set = set_of("function color(s) return bevel(0.2, 64):unpack() end").unwrap();
    let normal_at = |x: f32| with_tracer(&edge(), || set.color(0, &point([x, 0.3, 0.0], UP))).unwrap();
    // Beyond the radius the face is flat.
    let far = normal_at(-0.5);
    assert!((far[2] - 1.0).abs() < 1e-6 && far[0].abs() < 1e-6, "{far:?}");
    // Towards the edge the normal tilts to the side's, monotonically, to
    // about halfway (45°) at the edge itself; never along y.
    let mut last = 0.0;
    for x in [-0.15, -0.08, -0.03, -0.001] {
        let n = normal_at(x);
        let tilt = n[0].atan2(n[2]).to_degrees();
        assert!(tilt > last && n[1].abs() < 0.05, "x = {x}: {n:?}");
        last = tilt;
    }
    assert!((last - 45.0).abs() < 8.0, "tilt at the edge {last}°");
    // Other objects do not count: the side as another object leaves the
    // top flat.
    let mut two = edge();
    two.rects[1].id = 9;
    let n = with_tracer(&two, || set.color(0, &point([-0.01, 0.3, 0.0], UP))).unwrap();
    assert!((n[2] - 1.0).abs() < 1e-3, "{n:?}");
}

#[test]
fn answers_depend_on_the_point_alone() {
    let wall = Rect { axis: 0, at: 0.0, sign: -1.0, lo: [-BIG, 0.0], hi: [BIG, BIG], id: 5 };
    let scene = Shapes { rects: vec![floor(), wall], spheres: Vec::new() };
    let code = "function color(s) return occlusion(s, 8, 1), edgewear(s, 0.3, 8), bevel(0.2, 4).x end";
    let points: Vec<ShadeInput> =
        (0..64).map(|i| point([-0.01 * i as f32, 0.37 * i as f32, 0.0], UP)).collect();
    let run = |order: Vec<usize>| {
        let set = set_of(code).unwrap();
        let mut out = vec![[0.0; 3]; points.len()];
        with_tracer(&scene, || {
            for i in order {
                out[i] = set.color(0, &points[i]).unwrap();
            }
        });
        out
    };
    let forward = run((0..64).collect());
    let run = &run;
    // In another order, on other threads, with other sets: the same bits.
    let threads: Vec<_> = (0..3)
        .map(|k| {
            let order: Vec<usize> = (0..64).map(|i| (i * 7 + k * 13) % 64).collect();
            std::thread::scope(|s| s.spawn(move || run(order)).join().unwrap())
        })
        .collect();
    for t in threads {
        assert_eq!(t, forward);
    }
    // Different points see different directions: 8 samples cannot give
    // one value for all of them.
    let distinct: std::collections::BTreeSet<u32> = forward.iter().map(|c| c[0].to_bits()).collect();
    assert!(distinct.len() > 3, "{distinct:?}");
}

#[test]
fn normal_is_an_entry_point_returning_a_vector() {
    let set = set_of("function normal(s) return bevel(s, 0.2, 16) end").unwrap();
    assert!(set.has_normal(0) && !set.has_color(0) && !set.has_material(0));
    // Near the edge the normal it gives is the rounded one; with no tracer, s.N.
    let at = point([-0.01, 0.0, 0.0], UP);
    let n = with_tracer(&edge(), || set.normal(0, &at)).unwrap();
    assert!(n[0] > 0.3 && n[2] > 0.3, "{n:?}");
    assert_eq!(set.normal(0, &at).unwrap(), UP);
    let e = set_of("function normal(s) return 1, 0 end").unwrap().normal(0, &at).unwrap_err();
    assert_eq!(e.kind, ShaderErrorKind::BadResult, "{e}");
}
