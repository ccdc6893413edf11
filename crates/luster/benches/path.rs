//! What path tracing costs: the hw7 Cornell box `cornellbox_jaroslav_path_diffuse`
//! (512×512, MaxRecursionDepth 3) rendered by luster's MIS path tracer and by
//! the course's NEE + importance-sampling variant, against the recursive ray
//! tracer (direct light only) on the same scene as the reference, alternately
//! in the same run; prints medians of wall and process CPU time (the fair
//! figure on a shared machine), Mrays/s and the CPU ratio of each to the
//! reference. The comparison with Mitsuba 3 at equal samples and
//! depth is `tools/mitsuba_cornell_check.py`. Run:
//! `cargo bench --bench path` (`-- --spp N --reps N`; needs ../shared).

use luster::integrator::Integrator;
use luster::render::{render_with, RenderOptions, Scene};
use std::path::Path;
use std::time::Instant;

fn arg(args: &[String], name: &str, default: usize) -> usize {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
        .max(1)
}

/// CPU seconds used so far by every thread of this process.
fn cpu_now() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec for the call's duration.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "the process CPU clock is readable");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (spp, reps) = (arg(&args, "--spp", 8) as u32, arg(&args, "--reps", 3));
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/scenes/ceng795/hw7/xml/cornellbox_jaroslav_path_diffuse.xml");
    let Ok(desc) = luster::scene::load(&path) else {
        eprintln!("{} is not there: nothing to measure", path.display());
        return;
    };
    let scene = Scene::build(&desc).expect("the bench scene builds");
    let variants: [(&str, Integrator); 3] = [
        ("recursive (direct light)", Integrator::Whitted),
        (
            "path, NEE + cosine",
            Integrator::from_desc(&luster::scene::description::RendererDesc::PathTracing(
                luster::scene::description::PathParamsDesc {
                    next_event: true,
                    importance: true,
                    ..Default::default()
                },
            )),
        ),
        (
            "path, MIS",
            Integrator::from_desc(&luster::scene::description::RendererDesc::PathTracing(
                luster::scene::description::PathParamsDesc { mis: true, ..Default::default() },
            )),
        ),
    ];
    let opts = RenderOptions { spp: Some(spp), ..Default::default() };
    let mut times = vec![Vec::new(); variants.len()];
    let mut cpus = vec![Vec::new(); variants.len()];
    let mut rays = vec![0u64; variants.len()];
    for _ in 0..reps {
        for (k, (_, integrator)) in variants.iter().enumerate() {
            let opts = RenderOptions { integrator: Some(*integrator), ..opts };
            let (t, c) = (Instant::now(), cpu_now());
            let img = render_with(&scene, 0, &opts, &|_| {});
            times[k].push(t.elapsed().as_secs_f64());
            cpus[k].push(cpu_now() - c);
            rays[k] = img.stats.total();
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let reference = median(&mut cpus[0].clone());
    println!("512x512, {spp} spp, {reps} repetitions, medians:");
    for (k, (name, _)) in variants.iter().enumerate() {
        let (t, c) = (median(&mut times[k]), median(&mut cpus[k]));
        println!(
            "  {name:<26} {t:>7.2} s wall {c:>7.2} s CPU  {:>6.2} Mrays/CPU-s  {:>5.2}x the reference's CPU",
            rays[k] as f64 / c / 1e6,
            c / reference
        );
    }
}
