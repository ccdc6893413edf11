//! Shader overhead: nanoseconds per call of Lua shaders through
//! `luster_shading::shader`, beside the same marble computed in Rust, plus the two
//! measurements behind the runtime's design choices (passing the shading point
//! through an FFI record vs `Function::call` with scalars; vec3 cdata vs scalar
//! arithmetic). Run: `cargo bench --bench shader`.
//!
//! The run first prints CPU ns per call (`cpu_table`), the cases alternating
//! round by round, beside a floor measured in the same run: a bare
//! `lua_pcall` of an empty Lua function in a tight C-API loop. CPU time,
//! because load on a shared machine disturbs it far less than wall time.
//! Criterion's benches follow. `-- cpu_only` (a filter no criterion bench
//! matches) prints only the table; `-- profile_empty` runs only the empty
//! call, for `perf record`. The calls go through `ShaderSet::color` and
//! `height`; the renderer's maps take `ShaderSet::call_point`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, Criterion};
use luster_shading::noise::fractal;
use luster_shading::shader::{ShadeInput, ShaderSet, ShaderSource, DEFAULT_TIMEOUT};

const EMPTY: &str = "function color(s) return 0.5, 0.5, 0.5 end";

const MARBLE: &str = "
function color(s)
  local x, y, z = s.P.x * 4, s.P.y * 4, s.P.z * 4
  local t = turbulence(x, y, z, 4, 2, 0.5)
  local v = 0.5 + 0.5 * math.sin(x + 5 * t)
  return 0.9 * v + 0.1, 0.85 * v + 0.1, 0.8 * v + 0.15
end";

const HEIGHT: &str = "function height(s) return 0.05 * perlin3(s.P.x * 8, s.P.y * 8, s.P.z * 8) end";

/// Stripes filtered with a width written by hand (the footprint of `20 x`)…
const STRIPES_GIVEN: &str = "function color(s)
  local v = aastep(0.5, fract(s.P.x * 20), filterwidth(s, 20))
  return v, v, v
end";

/// … and with the width the derivatives find (three runs a call).
const STRIPES_AUTO: &str = "function color(s)
  local v = aastep(0.5, fract(s.P.x * 20))
  return v, v, v
end";

const VEC_METATYPE: &str = "
function color(s)
  local d = normalize(s.P - vec3(0.5, 0.5, 0.5))
  local h = normalize(d + s.N)
  local k = math.max(dot(h, s.N), 0)
  local c = mix(vec3(0.2, 0.3, 0.8), vec3(1, 0.9, 0.7), k)
  return c.x, c.y, c.z
end";

const VEC_SCALAR: &str = "
local sqrt = math.sqrt
local function norm(x, y, z) local l = sqrt(x * x + y * y + z * z) return x / l, y / l, z / l end
function color(s)
  local dx, dy, dz = norm(s.P.x - 0.5, s.P.y - 0.5, s.P.z - 0.5)
  local hx, hy, hz = norm(dx + s.N.x, dy + s.N.y, dz + s.N.z)
  local k = math.max(hx * s.N.x + hy * s.N.y + hz * s.N.z, 0)
  return 0.2 + 0.8 * k, 0.3 + 0.6 * k, 0.8 - 0.1 * k
end";

/// The Lua marble, in Rust.
fn marble_rust(i: &ShadeInput) -> [f32; 3] {
    let (x, y, z) = (i.p[0] * 4.0, i.p[1] * 4.0, i.p[2] * 4.0);
    let t = fractal::turbulence3(x, y, z, 4, 2.0, 0.5);
    let v = 0.5 + 0.5 * (x + 5.0 * t).sin();
    [0.9 * v + 0.1, 0.85 * v + 0.1, 0.8 * v + 0.15]
}

fn points() -> Vec<ShadeInput> {
    (0..1024)
        .map(|i| {
            let f = i as f32;
            let p = [f * 0.0137 % 1.0, f * 0.0291 % 1.0, f * 0.0073 % 1.0];
            ShadeInput { p, pw: p, n: [0.0, 0.6, 0.8], uv: [p[0], p[1]], ..ShadeInput::default() }
        })
        .collect()
}

/// [`points`] with a pixel footprint, as the renderer gives them (the
/// derivatives of a point without one cost a single run).
fn points_with_footprint() -> Vec<ShadeInput> {
    points()
        .into_iter()
        .map(|p| ShadeInput {
            dpdx: [0.002, 0.0, 0.001],
            dpdy: [0.0, 0.002, 0.0005],
            dpwdx: [0.002, 0.0, 0.001],
            dpwdy: [0.0, 0.002, 0.0005],
            dpcdx: [0.002, 0.0, 0.0],
            dpcdy: [0.0, -0.002, 0.0],
            duvdx: [0.002, 0.0],
            duvdy: [0.0, 0.002],
            filterwidth: 0.002,
            ..p
        })
        .collect()
}

fn set(code: &str) -> ShaderSet {
    match ShaderSet::new(vec![ShaderSource::new("bench", "bench.lua", code)], DEFAULT_TIMEOUT) {
        Ok(s) => s,
        Err(e) => panic!("{e}"),
    }
}

fn bench_shaders(c: &mut Criterion) {
    let pts = points();
    let mut g = c.benchmark_group("shader");
    for (name, code) in [
        ("empty_color", EMPTY),
        ("marble_lua", MARBLE),
        ("vec3_metatype", VEC_METATYPE),
        ("vec3_scalar", VEC_SCALAR),
    ] {
        let s = set(code);
        let mut k = 0;
        g.bench_function(name, |b| {
            b.iter(|| {
                k = (k + 1) & 1023;
                s.color(0, black_box(&pts[k])).ok()
            })
        });
    }
    let mut k = 0;
    g.bench_function("marble_rust", |b| {
        b.iter(|| {
            k = (k + 1) & 1023;
            marble_rust(black_box(&pts[k]))
        })
    });
    let s = set(HEIGHT);
    let mut k = 0;
    g.bench_function("height", |b| {
        b.iter(|| {
            k = (k + 1) & 1023;
            s.height(0, black_box(&pts[k])).ok()
        })
    });
    g.finish();
}

/// The alternative to the FFI record: the twelve inputs as arguments, three
/// results as return values, through mlua's conversions.
fn bench_call_scalars(c: &mut Criterion) {
    let pts = points();
    let lua = mlua::Lua::new();
    let f: mlua::Function = match lua
        .load("return function(px, py, pz, wx, wy, wz, nx, ny, nz, u, v, t) return 0.5, 0.5, 0.5 end")
        .eval()
    {
        Ok(f) => f,
        Err(e) => panic!("{e}"),
    };
    let mut k = 0;
    c.bench_function("boundary/call_scalars", |b| {
        b.iter(|| {
            k = (k + 1) & 1023;
            let i = black_box(&pts[k]);
            f.call::<(f64, f64, f64)>((
                i.p[0], i.p[1], i.p[2], i.pw[0], i.pw[1], i.pw[2], i.n[0], i.n[1], i.n[2], i.uv[0], i.uv[1],
                i.time,
            ))
            .ok()
        })
    });
}

fn config() -> Criterion {
    Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(30)
}

/// CPU time of this thread, in nanoseconds (load on a shared machine
/// disturbs it far less than wall time).
fn thread_cpu_ns() -> f64 {
    let mut t = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    t.tv_sec as f64 * 1e9 + t.tv_nsec as f64
}

/// CPU nanoseconds per call of `f`, over `n` calls.
fn cpu_per_call<R>(n: usize, mut f: impl FnMut(usize) -> R) -> f64 {
    let t0 = thread_cpu_ns();
    for k in 0..n {
        black_box(f(k));
    }
    (thread_cpu_ns() - t0) / n as f64
}

/// The floor: a bare `lua_pcall` of an empty Lua function, in a tight loop
/// on the C API (no shading point, no result, no Rust around it). CPU ns
/// per call.
fn bare_pcall_ns(n: usize) -> f64 {
    let lua = mlua::Lua::new();
    let f: mlua::Function = match lua.load("return function() end").eval() {
        Ok(f) => f,
        Err(e) => panic!("{e}"),
    };
    let mut ns = 0.0;
    // SAFETY: exec_raw pushes `f` and runs the closure on a protected state
    // with `f` on top; each pcall consumes the copy pushed before it.
    let r = unsafe {
        lua.exec_raw::<()>(f, |l| {
            ns = cpu_per_call(n, |_| {
                mlua::ffi::lua_pushvalue(l, -1);
                mlua::ffi::lua_pcall(l, 0, 0, 0);
            });
        })
    };
    if let Err(e) = r {
        panic!("{e}");
    }
    ns
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Per-call CPU time of the floor, the empty shader, `height`, the bump
/// path (`heights3`, per point), the marble, and stripes filtered with a
/// width by hand and with the automatic one, alternating the cases
/// round by round (A B C … A B C …) and quoting medians.
fn cpu_table() {
    const N: usize = 400_000;
    const ROUNDS: usize = 7;
    let pts = points();
    let empty = set(EMPTY);
    let height = set(HEIGHT);
    let height_empty = set("function height(s) return 0.5 end");
    let marble = set(MARBLE);
    let footprint = points_with_footprint();
    let (stripes_given, stripes_auto) = (set(STRIPES_GIVEN), set(STRIPES_AUTO));
    let triples: Vec<[ShadeInput; 3]> =
        (0..1024).map(|k| [pts[k], pts[(k + 1) & 1023], pts[(k + 2) & 1023]]).collect();
    type Case<'a> = (&'a str, Box<dyn Fn() -> f64 + 'a>);
    let cases: Vec<Case> = vec![
        ("floor: bare lua_pcall of an empty Lua function", Box::new(|| bare_pcall_ns(N))),
        (
            "empty color(s) through ShaderSet::color",
            Box::new(|| cpu_per_call(N, |k| empty.color(0, black_box(&pts[k & 1023])).ok())),
        ),
        (
            "height(s) = 0.5 through ShaderSet::height",
            Box::new(|| cpu_per_call(N, |k| height_empty.height(0, black_box(&pts[k & 1023])).ok())),
        ),
        (
            "height(s) = 0.5, per point of heights3 (batched: 3 a call)",
            Box::new(|| {
                cpu_per_call(N / 3, |k| height_empty.heights3(0, black_box(&triples[k & 1023])).ok()) / 3.0
            }),
        ),
        (
            "height: scaled perlin3",
            Box::new(|| cpu_per_call(N, |k| height.height(0, black_box(&pts[k & 1023])).ok())),
        ),
        (
            "marble in Lua",
            Box::new(|| cpu_per_call(N / 4, |k| marble.color(0, black_box(&pts[k & 1023])).ok())),
        ),
        ("marble in Rust", Box::new(|| cpu_per_call(N / 4, |k| marble_rust(black_box(&pts[k & 1023]))))),
        (
            "stripes, aastep with a width by hand",
            Box::new(|| cpu_per_call(N, |k| stripes_given.color(0, black_box(&footprint[k & 1023])).ok())),
        ),
        (
            "stripes, aastep with the automatic width (3 runs)",
            Box::new(|| cpu_per_call(N, |k| stripes_auto.color(0, black_box(&footprint[k & 1023])).ok())),
        ),
    ];
    let mut times = vec![Vec::new(); cases.len()];
    for _ in 0..ROUNDS {
        for (t, (_, run)) in times.iter_mut().zip(&cases) {
            t.push(run());
        }
    }
    println!("shader call, CPU ns per call (median of {ROUNDS} alternating rounds):");
    let floor = median(times[0].clone());
    for ((name, _), t) in cases.iter().zip(times) {
        let (m, lo, hi) = (
            median(t.clone()),
            t.iter().copied().fold(f64::MAX, f64::min),
            t.iter().copied().fold(0.0, f64::max),
        );
        println!("  {m:8.1} ns  ({lo:.1}-{hi:.1}, {:.2}x floor)  {name}", m / floor);
    }
}

criterion_group! { name = benches; config = config(); targets = bench_shaders, bench_call_scalars }

/// `-- profile_empty`: only the empty colour call, for about two seconds,
/// so `perf record` sees that path alone.
fn profile_empty() {
    let pts = points();
    let empty = set(EMPTY);
    let ns = cpu_per_call(60_000_000, |k| empty.color(0, black_box(&pts[k & 1023])).ok());
    println!("empty color(s): {ns:.1} CPU ns per call");
}

fn main() {
    if std::env::args().any(|a| a == "profile_empty") {
        profile_empty();
        return;
    }
    cpu_table();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
