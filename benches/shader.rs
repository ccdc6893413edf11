//! Shader overhead: nanoseconds per call of Lua shaders through
//! `luster::shader`, beside the same marble computed in Rust, plus the two
//! measurements behind the runtime's design choices (passing the shading point
//! through an FFI record vs `Function::call` with scalars; vec3 cdata vs scalar
//! arithmetic). Run: `cargo bench --bench shader`.
//!
//! On the project's 2-core machine: empty color 86 ns (again 86–106 ns on
//! 2026-11-23 with the shading point written in place: no measurable change); FFI record 2.4× faster
//! than `Function::call` with scalars (209 ns); Lua marble 379 ns vs Rust 193 ns
//! (1.96×); height 166 ns; vec3 155 ns vs scalars 134 ns. `docs/shaders.md`
//! has the table. Session 9 (bare `lua_pcall` from a call thread, octave
//! lanes in the fractal noise), load 5: empty color 71 ns, marble 254 ns,
//! height 97 ns.

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use luster::noise::fractal;
use luster::shader::{ShadeInput, ShaderSet, ShaderSource, DEFAULT_TIMEOUT};

const EMPTY: &str = "function color(s) return 0.5, 0.5, 0.5 end";

const MARBLE: &str = "
function color(s)
  local x, y, z = s.P.x * 4, s.P.y * 4, s.P.z * 4
  local t = turbulence(x, y, z, 4, 2, 0.5)
  local v = 0.5 + 0.5 * math.sin(x + 5 * t)
  return 0.9 * v + 0.1, 0.85 * v + 0.1, 0.8 * v + 0.15
end";

const HEIGHT: &str = "function height(s) return 0.05 * perlin3(s.P.x * 8, s.P.y * 8, s.P.z * 8) end";

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

criterion_group! { name = benches; config = config(); targets = bench_shaders, bench_call_scalars }
criterion_main!(benches);
