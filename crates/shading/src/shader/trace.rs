//! Rays cast from shaders: the [`Tracer`] a renderer installs for the
//! threads that shade ([`with_tracer`]), and the native halves of the
//! prelude's `trace()`, `occlusion()`, `edgewear()` and `bevel()`
//! (`docs/tracing.md` is the reference for shader authors).
//!
//! The shading crate knows nothing of the scene: the renderer implements
//! [`Tracer`] on its own scene and wraps the work of each render thread in
//! [`with_tracer`]. A script run with no tracer installed (a top level, a
//! probe made while the scene is built) sees every ray miss.
//!
//! Directions are a low-discrepancy set (a Hammersley set of the sample
//! count) rotated per point by a hash of the point's coordinates
//! (Cranley–Patterson rotation): the same point gives the same answer on
//! any thread and in any part of a split render, and neighbouring points
//! decorrelate, so a pixel's samples average the error away.

use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};

use super::ffi::Vec3;

/// The most rays one shader call may cast, all built-ins together: a
/// bound on what one shading point can cost. More is an error naming the
/// script's line. A bump evaluation's three `height` calls share one
/// budget, as they share the time limit.
pub const MAX_RAYS: i32 = 256;

/// A ray a shader casts, in world space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRay {
    /// Where the ray starts.
    pub origin: [f32; 3],
    /// Its unit direction.
    pub dir: [f32; 3],
    /// How far it reaches from `origin`.
    pub max_dist: f32,
    /// The shutter time, 0 to 1 (`s.time`).
    pub time: f32,
    /// The unit geometric normal of the surface `origin` lies on, or zero
    /// when it lies on none: the tracer starts the ray off that surface, on
    /// the side `dir` points to, so that it never finds the surface it
    /// leaves.
    pub ng: [f32; 3],
}

/// The nearest surface a [`TraceRay`] meets.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceHit {
    /// Distance from the ray's origin along its direction.
    pub t: f32,
    /// The point hit, world space.
    pub p: [f32; 3],
    /// The unit shading normal there, on the side of `ng`.
    pub n: [f32; 3],
    /// The unit geometric normal there, facing out of the object (where a
    /// mesh's winding says), whichever side the ray came from.
    pub ng: [f32; 3],
    /// The geometry's object index, as `s.object_id` numbers it.
    pub object_id: u32,
    /// The object's own index, as `s.instance_id` numbers it.
    pub instance_id: u32,
}

/// A scene shaders can cast rays into. The renderer implements it; tests
/// use simple shapes.
pub trait Tracer: Sync {
    /// The nearest surface along `ray` within `ray.max_dist`, or `None`.
    fn trace(&self, ray: &TraceRay) -> Option<TraceHit>;

    /// Whether anything lies along `ray` within `ray.max_dist` (a
    /// renderer may answer faster than [`Tracer::trace`]).
    fn occluded(&self, ray: &TraceRay) -> bool {
        self.trace(ray).is_some()
    }
}

type TracerPtr = *const (dyn Tracer + 'static);

thread_local! {
    /// The tracer installed on this thread, set only by [`with_tracer`]
    /// for the length of its call.
    static TRACER: Cell<Option<TracerPtr>> = const { Cell::new(None) };
}

/// Runs `f` with `tracer` as the scene the shaders this thread calls cast
/// their rays into, then puts back whatever was installed before (also
/// when `f` panics). The renderer calls it around each render thread's
/// work.
pub fn with_tracer<R>(tracer: &dyn Tracer, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<TracerPtr>);
    impl Drop for Restore {
        fn drop(&mut self) {
            let _ = TRACER.try_with(|t| t.set(self.0));
        }
    }
    // SAFETY: only the lifetime is erased. The pointer is read only through
    // `with_current`, on this thread, while `f` runs; `Restore` takes it
    // out again before this function returns or unwinds, so it is never
    // read after `tracer`'s borrow ends.
    let ptr: TracerPtr = unsafe { std::mem::transmute::<*const dyn Tracer, TracerPtr>(tracer) };
    let prev = TRACER.with(|t| t.replace(Some(ptr)));
    let _restore = Restore(prev);
    f()
}

/// Runs `f` with the tracer installed on this thread, if any.
fn with_current<R>(f: impl FnOnce(Option<&dyn Tracer>) -> R) -> R {
    let ptr = TRACER.try_with(Cell::get).ok().flatten();
    // SAFETY: a pointer in TRACER is live while its `with_tracer` call
    // runs, which encloses this one (see there); the reference cannot
    // outlive `f`.
    f(ptr.map(|p| unsafe { &*p }))
}

/// A ray as the prelude writes it (`luster_ray`): an origin, a direction
/// (for `occlusion` and `bevel`, the axis of their hemisphere), a reach,
/// the shutter time and the geometric normal of the surface it leaves.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RayIn {
    pub o: Vec3,
    pub d: Vec3,
    pub max_dist: f64,
    pub time: f64,
    pub ng: Vec3,
}

/// A hit as the prelude reads it (`luster_hit`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct HitOut {
    pub t: f64,
    pub p: Vec3,
    pub n: Vec3,
    pub ng: Vec3,
    pub object_id: i32,
    pub instance_id: i32,
}

type V = [f64; 3];

fn v(a: Vec3) -> V {
    [a.x, a.y, a.z]
}
fn f32s(a: V) -> [f32; 3] {
    a.map(|x| x as f32)
}
fn f64s(a: [f32; 3]) -> V {
    a.map(f64::from)
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V, k: f64) -> V {
    a.map(|x| x * k)
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalized(a: V) -> Option<V> {
    let l = dot(a, a).sqrt();
    (l > 0.0 && l.is_finite()).then(|| scale(a, 1.0 / l))
}

/// Two unit vectors completing `n` to an orthonormal frame (Duff et al.
/// 2017: no branch on the hot path, no singularity).
fn basis(n: V) -> (V, V) {
    let sign = 1f64.copysign(n[2]);
    let a = -1.0 / (sign + n[2]);
    let b = n[0] * n[1] * a;
    ([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]], [b, sign + n[1] * n[1] * a, -n[1]])
}

/// The rotation of a point's direction set: two numbers in [0, 1) from the
/// bits of its coordinates (as the scene sees them, in `f32`), mixed by
/// SplitMix64's finaliser.
fn rotation(p: V) -> (f64, f64) {
    let mut h = 0x9e37_79b9_7f4a_7c15u64;
    for x in f32s(p) {
        h ^= u64::from(x.to_bits());
        h = h.wrapping_add(0x9e37_79b9_7f4a_7c15);
        h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        h ^= h >> 31;
    }
    let unit = |x: u64| (x >> 11) as f64 / (1u64 << 53) as f64;
    (unit(h), unit(h.rotate_left(32).wrapping_mul(0x2545_f491_4f6c_dd1d)))
}

/// Point `i` of the `n`-point Hammersley set rotated by `r`, in [0, 1)².
fn sample(i: u32, n: u32, r: (f64, f64)) -> (f64, f64) {
    let u = (f64::from(i) + 0.5) / f64::from(n) + r.0;
    let w = f64::from(i.reverse_bits()) / 4_294_967_296.0 + r.1;
    (u.fract(), w.fract())
}

/// `(u, w)` on the unit disc by Shirley and Chiu's concentric map, which
/// keeps the set's stratification.
fn disc(u: f64, w: f64) -> (f64, f64) {
    let (a, b) = (2.0 * u - 1.0, 2.0 * w - 1.0);
    if a == 0.0 && b == 0.0 {
        return (0.0, 0.0);
    }
    let q = std::f64::consts::FRAC_PI_4;
    let (r, phi) = if a.abs() > b.abs() { (a, q * (b / a)) } else { (b, 2.0 * q - q * (a / b)) };
    (r * phi.cos(), r * phi.sin())
}

/// A cosine-weighted direction around the unit `axis` (frame `t`, `b`):
/// a point of the unit disc lifted onto the hemisphere (Malley's method).
fn cosine_dir(axis: V, t: V, b: V, (x, y): (f64, f64)) -> V {
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    add(add(scale(t, x), scale(b, y)), scale(axis, z))
}

/// The fraction of `samples` cosine-weighted directions around `axis` at
/// `p` along which something lies within `max_dist` (`occlusion`; with the
/// axis turned into the surface, `edgewear`). No tracer: 0.
pub(crate) fn occlusion(
    tracer: Option<&dyn Tracer>,
    p: V,
    axis: V,
    ng: V,
    max_dist: f64,
    time: f64,
    samples: u32,
) -> f64 {
    let (Some(tracer), Some(axis), true) = (tracer, normalized(axis), samples > 0) else { return 0.0 };
    let (t, b) = basis(axis);
    let r = rotation(p);
    let mut hits = 0u32;
    for i in 0..samples {
        let d = cosine_dir(axis, t, b, disc_sample(i, samples, r));
        let ray = TraceRay {
            origin: f32s(p),
            dir: f32s(d),
            max_dist: max_dist as f32,
            time: time as f32,
            ng: f32s(ng),
        };
        hits += u32::from(tracer.occluded(&ray));
    }
    f64::from(hits) / f64::from(samples)
}

fn disc_sample(i: u32, n: u32, r: (f64, f64)) -> (f64, f64) {
    let (u, w) = sample(i, n, r);
    disc(u, w)
}

/// How many surfaces a `bevel` probe ray follows through: Cycles' bound
/// on the hits of one probe.
const BEVEL_HITS: u32 = 4;

/// The cubic falloff Cycles' bevel weighs points with: a radial density
/// on the disc of radius `radius`, `10 (R − r)³ / (π R⁵)`, which integrates
/// to 1 over the disc.
fn cubic(radius: f64, r: f64) -> f64 {
    if r >= radius {
        return 0.0;
    }
    let f = radius - r;
    10.0 * f * f * f / (std::f64::consts::PI * radius.powi(5))
}

/// A radius drawn from [`cubic`]'s density by its inverse CDF
/// `10x² − 20x³ + 15x⁴ − 4x⁵ = ξ` (Newton's method, as Cycles solves it).
fn cubic_radius(radius: f64, xi: f64) -> f64 {
    let mut x = 0.25f64;
    for _ in 0..10 {
        let (x2, nx) = (x * x, 1.0 - x);
        let f = 10.0 * x2 - 20.0 * x2 * x + 15.0 * x2 * x2 - 4.0 * x2 * x2 * x - xi;
        let df = 20.0 * x * nx * nx * nx;
        if f.abs() < 1e-9 || df == 0.0 {
            break;
        }
        x = (x - f / df).clamp(0.0, 1.0);
    }
    x * radius
}

/// What `bevel` found: the normal and the rays it cast, or that it would
/// have cast more than its budget.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Bevel {
    /// The rounded normal (`n` itself where no probe found the object) and
    /// the rays cast.
    Normal(V, u32),
    /// The budget ran out.
    OverBudget,
}

/// The normal of the surface at `p` (shading normal `n`, geometric `ng`,
/// on object `instance`) rounded over `radius`, as Cycles' Bevel node
/// makes it: `samples` probe rays cross discs of that radius around `p`,
/// each perpendicular to one axis of the frame of `ng` (half of them to
/// `ng` itself), and the normals of the points they find on the same
/// object are averaged, weighted by a cubic falloff with distance and by
/// the multiple-importance weight of the three discs that could have found
/// them. At most `budget` rays.
#[allow(clippy::too_many_arguments)]
pub(crate) fn bevel(
    tracer: Option<&dyn Tracer>,
    p: V,
    n: V,
    ng: V,
    instance: u32,
    radius: f64,
    time: f64,
    samples: u32,
    budget: u32,
) -> Bevel {
    let (Some(tracer), Some(ng), true) = (tracer, normalized(ng), radius > 0.0) else {
        return Bevel::Normal(n, 0);
    };
    let (t, b) = basis(ng);
    let r = rotation(p);
    let mut sum = [0.0; 3];
    let mut rays = 0u32;
    for i in 0..samples {
        let (u, xi) = sample(i, samples, r);
        // The disc's axis: ng with probability 1/2, each tangent with 1/4.
        let (axes, picks, u) = if u < 0.5 {
            ([ng, t, b], [0.5, 0.25, 0.25], u * 2.0)
        } else if u < 0.75 {
            ([t, ng, b], [0.25, 0.5, 0.25], (u - 0.5) * 4.0)
        } else {
            ([b, t, ng], [0.25, 0.25, 0.5], (u - 0.75) * 4.0)
        };
        let [dn, dt, db] = axes;
        let phi = 2.0 * std::f64::consts::PI * u;
        let rd = cubic_radius(radius, xi);
        // The probe crosses the sphere of `radius` around p along -dn.
        let h = (radius * radius - rd * rd).max(0.0).sqrt();
        let on_disc = add(scale(dt, rd * phi.cos()), scale(db, rd * phi.sin()));
        let dir = scale(dn, -1.0);
        let mut origin = add(add(p, scale(dn, h)), on_disc);
        let mut from_ng = [0.0f32; 3];
        let mut left = 2.0 * h;
        for _ in 0..BEVEL_HITS {
            if rays >= budget {
                return Bevel::OverBudget;
            }
            rays += 1;
            let ray = TraceRay {
                origin: f32s(origin),
                dir: f32s(dir),
                max_dist: left as f32,
                time: time as f32,
                ng: from_ng,
            };
            let Some(hit) = tracer.trace(&ray) else { break };
            let hng = f64s(hit.ng);
            if hit.instance_id == instance {
                // Each disc's density of finding this point, its pick
                // probability times the projection of its area; the power
                // heuristic over the three.
                let pdf = [0, 1, 2].map(|k| picks[k] * dot(axes[k], hng).abs());
                let denom = pdf.iter().map(|x| x * x).sum::<f64>();
                if denom > 0.0 {
                    let d = add(f64s(hit.p), scale(p, -1.0));
                    let w = pdf[0] / denom * cubic(radius, dot(d, d).sqrt()) / cubic(radius, rd).max(1e-300);
                    sum = add(sum, scale(f64s(hit.n), w));
                }
            }
            left -= f64::from(hit.t);
            if left.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                break;
            }
            origin = f64s(hit.p);
            from_ng = hit.ng;
        }
    }
    Bevel::Normal(normalized(sum).unwrap_or(n), rays)
}

/// `trace(origin, dir, maxdist)` for the prelude: 1 with the hit written
/// into `out`, 0 for a miss (or no tracer), -1 after a panic.
pub(crate) extern "C" fn trace_ffi(ray: *const RayIn, out: *mut HitOut) -> i32 {
    if ray.is_null() || out.is_null() {
        return -1;
    }
    // SAFETY: both are the prelude's scratch records (`ffi.new`), alive
    // for the call and not aliased during it.
    let (ray, out) = unsafe { (*ray, &mut *out) };
    let r = TraceRay {
        origin: f32s(v(ray.o)),
        dir: f32s(v(ray.d)),
        max_dist: ray.max_dist as f32,
        time: ray.time as f32,
        ng: f32s(v(ray.ng)),
    };
    let found = catch_unwind(AssertUnwindSafe(|| with_current(|t| t.and_then(|t| t.trace(&r)))));
    match found {
        Ok(Some(h)) => {
            let vec = |a: [f32; 3]| Vec3 { x: a[0].into(), y: a[1].into(), z: a[2].into() };
            *out = HitOut {
                t: h.t.into(),
                p: vec(h.p),
                n: vec(h.n),
                ng: vec(h.ng),
                object_id: h.object_id as i32,
                instance_id: h.instance_id as i32,
            };
            1
        }
        Ok(None) => 0,
        Err(_) => -1,
    }
}

/// `occlusion` and `edgewear` for the prelude: the fraction of `samples`
/// directions around `ray.d` that are blocked within `ray.max_dist`; NaN
/// after a panic.
pub(crate) extern "C" fn occlusion_ffi(ray: *const RayIn, samples: i32) -> f64 {
    if ray.is_null() {
        return f64::NAN;
    }
    // SAFETY: the prelude's scratch record, alive for the call.
    let ray = unsafe { *ray };
    let samples = u32::try_from(samples).unwrap_or(0);
    catch_unwind(AssertUnwindSafe(|| {
        with_current(|t| occlusion(t, v(ray.o), v(ray.d), v(ray.ng), ray.max_dist, ray.time, samples))
    }))
    .unwrap_or(f64::NAN)
}

/// `bevel` for the prelude, at `ray.o` with shading normal `ray.d`,
/// geometric normal `ray.ng` and radius `ray.max_dist`: the rays cast,
/// with the normal in `out`; -1 when more than `budget` rays would be
/// needed, -2 after a panic.
pub(crate) extern "C" fn bevel_ffi(
    ray: *const RayIn,
    instance: u32,
    samples: i32,
    budget: i32,
    out: *mut Vec3,
) -> i32 {
    if ray.is_null() || out.is_null() {
        return -2;
    }
    // SAFETY: the prelude's scratch records, alive for the call and not
    // aliased during it.
    let (ray, out) = unsafe { (*ray, &mut *out) };
    let (samples, budget) = (u32::try_from(samples).unwrap_or(0), u32::try_from(budget).unwrap_or(0));
    let found = catch_unwind(AssertUnwindSafe(|| {
        with_current(|t| {
            bevel(t, v(ray.o), v(ray.d), v(ray.ng), instance, ray.max_dist, ray.time, samples, budget)
        })
    }));
    match found {
        Ok(Bevel::Normal(n, rays)) => {
            *out = Vec3 { x: n[0], y: n[1], z: n[2] };
            rays as i32
        }
        Ok(Bevel::OverBudget) => -1,
        Err(_) => -2,
    }
}
