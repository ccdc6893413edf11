//! What a shader's ray costs beyond the renderer's traversal: 64 rays a
//! call, cast by `occlusion()` in one native call or by `trace()` in a Lua
//! loop over the same cosine-weighted directions, into a scene of one plane
//! whose own test costs next to nothing. Run: `cargo bench --bench trace`.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use luster_shading::shader::{
    with_tracer, ShadeInput, ShaderSet, ShaderSource, TraceHit, TraceRay, Tracer, DEFAULT_TIMEOUT,
};

/// The plane `z = 1`, facing down.
struct Ceiling;

impl Tracer for Ceiling {
    fn trace(&self, r: &TraceRay) -> Option<TraceHit> {
        let t = (1.0 - r.origin[2]) / r.dir[2];
        (t > 0.0 && t <= r.max_dist).then(|| TraceHit {
            t,
            p: [r.origin[0] + t * r.dir[0], r.origin[1] + t * r.dir[1], 1.0],
            n: [0.0, 0.0, -1.0],
            ng: [0.0, 0.0, -1.0],
            object_id: 0,
            instance_id: 0,
        })
    }
}

const NATIVE: &str = "function color(s) return occlusion(s, 64), 0, 0 end";

const LUA: &str = "
local sqrt, cos, sin, pi = math.sqrt, math.cos, math.sin, math.pi
function color(s)
  local hits = 0
  for i = 0, 63 do
    local u, w = (i + 0.5) / 64, hash(i, 7)
    local r, phi = sqrt(u), 2 * pi * w
    if trace(s.Pw, vec3(r * cos(phi), r * sin(phi), sqrt(1 - u))) then hits = hits + 1 end
  end
  return hits / 64, 0, 0
end";

fn bench(c: &mut Criterion) {
    let set = |code: &str| {
        ShaderSet::new(vec![ShaderSource::new("b", "b.lua", code)], DEFAULT_TIMEOUT).expect("compiles")
    };
    let (native, lua) = (set(NATIVE), set(LUA));
    let mut input = ShadeInput { n: [0.0, 0.0, 1.0], ng: [0.0, 0.0, 1.0], ..ShadeInput::default() };
    let mut group = c.benchmark_group("64 rays");
    for (name, s) in [("occlusion", &native), ("trace loop", &lua)] {
        group.bench_function(name, |b| {
            with_tracer(&Ceiling, || {
                b.iter(|| {
                    // A new point each call, as in a render.
                    input.pw[0] += 1e-3;
                    black_box(s.color(0, black_box(&input)).expect("runs"))
                })
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
