//! Nanoseconds per call of the noise functions shaders and textures use most.
//!
//! Each iteration evaluates one function at 256 points spread over many
//! lattice cells (so branch predictors and caches see a realistic mix rather
//! than one repeated cell); criterion reports the time per 256 calls, which
//! `Throughput::Elements` turns into calls per second.
//!
//! `cargo bench --bench noise -- --warm-up-time 1 --measurement-time 2`.

use std::hint::black_box;

use criterion::measurement::WallTime;
use criterion::{criterion_group, criterion_main, BenchmarkGroup, Criterion, Throughput};
use luster_shading::noise::{course, fractal, perlin, simplex, voronoi};

/// 256 points from a fixed LCG, over a 64-unit cube.
fn points() -> Vec<[f32; 3]> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (s >> 40) as f32 / (1u64 << 24) as f32 * 64.0 - 32.0
    };
    (0..256).map(|_| [next(), next(), next()]).collect()
}

/// Generic rather than `&dyn Fn`, so each function is inlined into the loop
/// as it would be into a texture, and no indirect call is timed.
fn run(group: &mut BenchmarkGroup<WallTime>, pts: &[[f32; 3]], name: &str, f: impl Fn(f32, f32, f32) -> f32) {
    group.bench_function(name, |b| {
        b.iter(|| pts.iter().map(|p| f(black_box(p[0]), black_box(p[1]), black_box(p[2]))).sum::<f32>())
    });
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let mut group = c.benchmark_group("noise");
    group.throughput(Throughput::Elements(pts.len() as u64));
    let g = &mut group;
    run(g, &pts, "perlin::noise3", perlin::noise3);
    run(g, &pts, "perlin::noise3_grad", |x, y, z| perlin::noise3_grad(x, y, z).1[0]);
    run(g, &pts, "simplex::noise3", simplex::noise3);
    run(g, &pts, "fractal::fbm3 (4 octaves)", |x, y, z| fractal::fbm3(x, y, z, 4, 2.0, 0.5));
    run(g, &pts, "fractal::turbulence3 (4 octaves)", |x, y, z| fractal::turbulence3(x, y, z, 4, 2.0, 0.5));
    run(g, &pts, "voronoi::voronoi3 (Euclidean)", |x, y, z| {
        voronoi::voronoi3(x, y, z, voronoi::Metric::Euclidean, 1.0).f1
    });
    run(g, &pts, "voronoi::voronoi3 (Manhattan)", |x, y, z| {
        voronoi::voronoi3(x, y, z, voronoi::Metric::Manhattan, 1.0).f1
    });
    run(g, &pts, "course::noise", course::noise);
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
