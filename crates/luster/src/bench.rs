//! `luster bench`: BVH build time, memory and primary-ray throughput on PLY
//! meshes, with exactly the camera and rays of `shared/bench/embree_rays.py`,
//! so the figures line up against Intel Embree's on the same machine.
//!
//! The rays are made once and not timed, as in the Embree script; what is
//! timed is [`MeshAccel::intersect`] on every ray, split into chunks over a
//! rayon pool of exactly the requested number of threads, with each ray's
//! hit written to an output array (as Embree writes its primID array). The
//! hit fraction printed is the check that both programs shoot the same rays:
//! it must match Embree's to about three decimals.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use rayon::prelude::*;

use luster_core::math::{Ray, Vec3};
use luster_render::accel::MeshAccel;

/// Image size of the benchmark camera.
pub const WIDTH: usize = 1920;
/// Image size of the benchmark camera.
pub const HEIGHT: usize = 1080;
/// Rays per parallel work item: small enough to balance, big enough that
/// scheduling is noise.
const CHUNK: usize = 4096;
/// Builds timed per mesh (the median is reported).
const BUILDS: usize = 3;

/// Runs the benchmark on each mesh and prints a table per mesh.
pub fn run(plys: &[PathBuf], threads: &[usize], reps: usize) -> anyhow::Result<()> {
    let reps = reps.max(1);
    for path in plys {
        let t0 = Instant::now();
        let (positions, triangles) = load_mesh(path)?;
        let t_load = t0.elapsed().as_secs_f64();
        println!(
            "== {}: {} tris, {} verts; ply load {:.3} s",
            path.display(),
            triangles.len(),
            positions.len(),
            t_load
        );

        let (mut build_times, mut build_cpu) = (Vec::with_capacity(BUILDS), Vec::with_capacity(BUILDS));
        let mut accel = None;
        for _ in 0..BUILDS {
            // Drop the previous tree first so peak memory is one tree's worth.
            drop(accel.take());
            let (t0, c0) = (Instant::now(), cpu_seconds());
            accel = Some(MeshAccel::build(&positions, &triangles));
            build_times.push(t0.elapsed().as_secs_f64());
            build_cpu.push(cpu_seconds().zip(c0).map_or(f64::NAN, |(c1, c0)| c1 - c0));
        }
        let accel = accel.context("no build ran")?;
        let rss_build = peak_rss_kib();
        let bvh = accel.bvh();
        println!(
            "   BVH build {:.1} ms (median of {BUILDS}; all cores; CPU {:.1} ms); {} wide nodes, depth {} (binary {}), {} leaves, {} 4-triangle blocks; accel {:.1} MiB",
            median(&mut build_times) * 1e3,
            median(&mut build_cpu) * 1e3,
            bvh.node_count(),
            bvh.depth(),
            bvh.binary_depth(),
            bvh.leaf_count(),
            accel.block_count(),
            accel.memory_bytes() as f64 / (1 << 20) as f64
        );

        let (eye, target, dirs) = camera_rays(&positions);
        println!("   camera eye {:?} target {:?}; {} rays ({WIDTH}x{HEIGHT})", eye, target, dirs.len());
        let mut out = vec![u32::MAX; dirs.len()];
        trace(&accel, eye, &dirs, &mut out);
        let hits = out.iter().filter(|&&p| p != u32::MAX).count();
        // FNV-1a over every ray's hit triangle: equal between two builds
        // exactly when they find the same triangles.
        let sum = out
            .iter()
            .fold(0xcbf2_9ce4_8422_2325u64, |h, &p| (h ^ u64::from(p)).wrapping_mul(0x100_0000_01b3));
        println!(
            "   hit fraction {:.4}; hit checksum {sum:016x}; node test {}",
            hits as f64 / dirs.len() as f64,
            luster_render::accel::bvh::node_test_isa()
        );

        let mut base = None;
        for &n in threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build()?;
            let mut cpu = Vec::with_capacity(reps);
            let mut times: Vec<f64> = (0..reps)
                .map(|_| {
                    let c0 = cpu_seconds();
                    let t0 = Instant::now();
                    pool.install(|| trace(&accel, eye, &dirs, &mut out));
                    let t = t0.elapsed().as_secs_f64();
                    cpu.push(cpu_seconds().zip(c0).map_or(f64::NAN, |(c1, c0)| c1 - c0));
                    t
                })
                .collect();
            let min = times.iter().copied().fold(f64::INFINITY, f64::min);
            let med = median(&mut times);
            let mrays = dirs.len() as f64 / med / 1e6;
            let scale = base.map_or(String::new(), |b: f64| format!("  ({:.2}x of first)", mrays / b));
            base.get_or_insert(mrays);
            let cpu = median(&mut cpu);
            println!(
                "   threads={n:<2} closest hit: median {:7.1} ms over {reps} -> {mrays:6.2} Mrays/s (min {:.1} ms); CPU {:.1} ms -> {:.2} Mrays per CPU-second{scale}",
                med * 1e3,
                min * 1e3,
                cpu * 1e3,
                dirs.len() as f64 / cpu / 1e6
            );
        }
        if let Some(kib) = peak_rss_kib() {
            let mib = |k: u64| k as f64 / 1024.0;
            println!(
                "   peak RSS so far {:.1} MiB (after the builds {:.1} MiB)",
                mib(kib),
                rss_build.map_or(f64::NAN, mib)
            );
        }
    }
    Ok(())
}

/// Closest hit for every ray, the hit triangle (or `u32::MAX`) into `out`.
fn trace(accel: &MeshAccel, eye: Vec3, dirs: &[Vec3], out: &mut [u32]) {
    out.par_chunks_mut(CHUNK).zip(dirs.par_chunks(CHUNK)).for_each(|(out, dirs)| {
        for (o, &d) in out.iter_mut().zip(dirs) {
            *o = accel.intersect(&Ray::new(eye, d), 0.0, f32::INFINITY).map_or(u32::MAX, |h| h.prim);
        }
    });
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The benchmark camera, replicating `camera_rays` of `embree_rays.py`
/// operation by operation (f32 where numpy works in f32, f64 where it
/// promotes): returns the eye, the bounding-box centre it looks at, and the
/// unit directions in scanline order.
pub fn camera_rays(positions: &[Vec3]) -> (Vec3, Vec3, Vec<Vec3>) {
    let lo = positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
    let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
    let c = (lo + hi) / 2.0;
    let ext = hi - lo;
    // np.argsort on three elements is an insertion sort: stable.
    let mut ax = [0usize, 1, 2];
    ax.sort_by(|&a, &b| ext[a].total_cmp(&ext[b]));
    let (w_ax, u_ax, v_ax) = (ax[0], ax[2], ax[1]);
    let th = (45.0f64.to_radians() / 2.0).tan();
    let aspect = WIDTH as f64 / HEIGHT as f64;
    let dist = f64::max((ext[u_ax] / 2.0) as f64 / (th * aspect), (ext[v_ax] / 2.0) as f64 / th) * 1.05;
    let mut eye = c;
    eye[w_ax] = (c[w_ax] as f64 + dist) as f32;
    let mut dirs = Vec::with_capacity(WIDTH * HEIGHT);
    for j in 0..HEIGHT {
        let y = (1.0 - (j as f64 + 0.5) / HEIGHT as f64 * 2.0) * th;
        for i in 0..WIDTH {
            let x = ((i as f64 + 0.5) / WIDTH as f64 * 2.0 - 1.0) * th * aspect;
            let mut d = Vec3::ZERO;
            d[u_ax] = x as f32;
            d[v_ax] = y as f32;
            d[w_ax] = -1.0;
            let norm = (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
            dirs.push(d / norm);
        }
    }
    (eye, c, dirs)
}

/// CPU time of all this process's threads so far, in seconds, from the
/// scheduler's nanosecond counters (`/proc/self/task/*/schedstat`). On a
/// machine shared with other jobs the wall time of a run measures the
/// neighbours as much as the code; its CPU time far less so.
pub fn cpu_seconds() -> Option<f64> {
    let mut ns = 0u64;
    for task in fs::read_dir("/proc/self/task").ok()? {
        let stat = fs::read_to_string(task.ok()?.path().join("schedstat")).ok()?;
        ns += stat.split_whitespace().next()?.parse::<u64>().ok()?;
    }
    Some(ns as f64 * 1e-9)
}

/// Peak resident set size of this process (VmHWM), where /proc has it.
pub fn peak_rss_kib() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Loads a PLY mesh with the renderer's own loader.
pub fn load_mesh(path: &Path) -> anyhow::Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let m = luster_scene::ply::read_ply(path)?;
    Ok((m.positions, m.triangles))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_frames_the_box_along_its_thinnest_axis() {
        // A box thin in z, wide in x: the camera looks down -z, x is horizontal.
        let pts = [Vec3::new(-2.0, -1.0, -0.1), Vec3::new(2.0, 1.0, 0.1)];
        let (eye, target, dirs) = camera_rays(&pts);
        assert_eq!(target, Vec3::ZERO);
        assert!(eye.x == 0.0 && eye.y == 0.0 && eye.z > 0.0);
        assert_eq!(dirs.len(), WIDTH * HEIGHT);
        let first = dirs[0];
        assert!(first.x < 0.0 && first.y > 0.0 && first.z < 0.0, "top-left pixel first: {first}");
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-6));
        // The frame's half-width at the box centre is 1.05 times the box's.
        let right = dirs[WIDTH - 1];
        let x_at_center = right.x / -right.z * eye.z;
        assert!((x_at_center - 2.0 * 1.05).abs() < 0.01, "{x_at_center}");
    }
}
