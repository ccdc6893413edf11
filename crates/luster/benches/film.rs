//! What the film's HDR outputs cost: an 800×800 render of
//! `benches/scenes/film.xml` written as the course's 8-bit PNG (A) or as a
//! 32-bit float EXR plus a tone-mapped PNG (B, what an `.exr` `ImageName`
//! writes: hw5's photographic operator with 1% burn-out). The two are run
//! alternately, A B A B ..., on the same machine in the same run, and the
//! medians are compared; the target is B / A ≤ 1.05.
//!
//! Each phase is timed twice: wall time, and the whole process's CPU time
//! (`CLOCK_PROCESS_CPUTIME_ID`, every thread of rayon's pool included). On a
//! loaded machine wall time swings with the other jobs while CPU time moves
//! much less, so the CPU ratio is the figure to trust there; on a quiet one
//! the two agree. A second pair of sides writes every file under a new name,
//! to show what replacing the previous images costs (a separate figure, not
//! the target's). Run: `cargo bench --bench film` (`-- --reps N` for more
//! repetitions, `-- --outputs-only` to loop B's output stage for a profiler,
//! `-- --exr-compression` for what each EXR compression costs on this film).

use luster::film::write_outputs;
use luster::image::outputs::plan_outputs;
use luster::render::{self, Scene};
use luster::tonemap::Display;
use std::path::Path;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// CPU seconds used so far by every thread of this process.
fn cpu_now() -> f64 {
    let mut ts = libc::timespec { tv_sec: 0, tv_nsec: 0 };
    // SAFETY: `ts` is a valid, writable timespec for the call's duration.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_PROCESS_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "the process CPU clock is readable");
    ts.tv_sec as f64 + ts.tv_nsec as f64 * 1e-9
}

/// A point in time on both clocks.
#[derive(Clone, Copy)]
struct Stamp {
    wall: Instant,
    cpu: f64,
}

impl Stamp {
    fn now() -> Stamp {
        Stamp { wall: Instant::now(), cpu: cpu_now() }
    }

    /// (wall, CPU) seconds since `self`.
    fn since(self, later: Stamp) -> (f64, f64) {
        (later.wall.duration_since(self.wall).as_secs_f64(), later.cpu - self.cpu)
    }
}

/// Per-repetition figures of one side: totals and output stage, wall and CPU.
#[derive(Default)]
struct Side {
    wall: Vec<f64>,
    cpu: Vec<f64>,
    out_wall: Vec<f64>,
    out_cpu: Vec<f64>,
}

impl Side {
    fn medians(&mut self) -> [f64; 4] {
        [median(&mut self.wall), median(&mut self.cpu), median(&mut self.out_wall), median(&mut self.out_cpu)]
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let reps = args
        .iter()
        .position(|a| a == "--reps")
        .and_then(|i| args.get(i + 1))
        .and_then(|s| s.parse::<usize>().ok())
        .unwrap_or(7)
        .max(1);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../benches/scenes/film.xml");
    let desc = luster::scene::load(&path).expect("the bench scene loads");
    let scene = Scene::build(&desc).expect("the bench scene builds");
    let cam = &scene.cameras[0];
    let hdr = plan_outputs(&cam.image_name, &cam.tonemaps, cam.display).expect("an .exr plan");
    let ldr = plan_outputs("film.png", &[], Display::Course).expect("a .png plan");
    let dir = tempfile::tempdir().expect("a temporary folder");
    // One render unmeasured, so both sides start warm.
    let warm = render::render(&scene, 0, &|_| {});
    if args.iter().any(|a| a == "--outputs-only") {
        // For a profiler: only B's output stage, over and over.
        for _ in 0..reps {
            write_outputs(&warm.film, dir.path(), &hdr).expect("the outputs are written");
        }
        return;
    }
    if args.iter().any(|a| a == "--exr-compression") {
        exr_compressions(&warm.film, reps);
        return;
    }
    // Both sides write into the same folder every repetition, so from the
    // second on each file replaces the one before, as a user re-rendering a
    // scene under the same name sees it.
    let (mut a, mut b) = alternate(&scene, [&ldr, &hdr], reps, |_| dir.path().to_path_buf());
    // The same with every file under a new name (a folder per repetition,
    // made before the clock starts): what the replacing renames cost.
    let (mut fa, mut fb) = alternate(&scene, [&ldr, &hdr], reps, |i| {
        let d = dir.path().join(format!("fresh{i}"));
        std::fs::create_dir(&d).expect("a fresh folder");
        d
    });
    // Where the output stage's time goes.
    let img = render::render(&scene, 0, &|_| {});
    let tonemap = luster::tonemap::Tonemap { burn_percent: 1.0, ..luster::tonemap::Tonemap::COURSE_DEFAULT };
    let (mut maps, mut exrs, mut pngs) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..reps {
        let t = Instant::now();
        let tm = tonemap.apply(&img.film.pixels);
        maps.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        let exr = dir.path().join("parts.exr");
        luster::image::output::write_rgb32f(&exr, 800, 800, &img.film.pixels).expect("EXR written");
        exrs.push(t.elapsed().as_secs_f64());
        let t = Instant::now();
        luster::image::output::write_rgb8(&dir.path().join("parts.png"), 800, 800, &tm).expect("PNG written");
        pngs.push(t.elapsed().as_secs_f64());
    }
    let (t_map, t_exr, t_png) = (median(&mut maps), median(&mut exrs), median(&mut pngs));
    let [aw, ac, aow, aoc] = a.medians();
    let [bw, bc, bow, boc] = b.medians();
    println!("film bench: 800x800, {reps} alternating repetitions, medians (wall / process CPU)");
    println!(
        "A  render + course PNG            {:7.1} ms / {:7.1} ms CPU  (output stage {:5.1} ms / {:5.1} ms CPU)",
        aw * 1e3,
        ac * 1e3,
        aow * 1e3,
        aoc * 1e3
    );
    println!(
        "B  render + EXR + tone-mapped PNG {:7.1} ms / {:7.1} ms CPU  (output stage {:5.1} ms / {:5.1} ms CPU)",
        bw * 1e3,
        bc * 1e3,
        bow * 1e3,
        boc * 1e3
    );
    println!(
        "parts of B's output stage (wall medians, one at a time): tone mapping {:.1} ms, EXR {:.1} ms, PNG {:.1} ms",
        t_map * 1e3,
        t_exr * 1e3,
        t_png * 1e3
    );
    println!("B / A = {:.3} wall, {:.3} CPU  (target <= 1.05)", bw / aw, bc / ac);
    let [faw, fac, ..] = fa.medians();
    let [fbw, fbc, fbow, fboc] = fb.medians();
    println!(
        "to fresh names (no file replaced; not the target's figure): B / A = {:.3} wall, {:.3} CPU  \
         (B's output stage {:5.1} ms / {:5.1} ms CPU)",
        fbw / faw,
        fbc / fac,
        fbow * 1e3,
        fboc * 1e3
    );
}

/// Renders and writes `plans[0]` (A) then `plans[1]` (B), `reps` times,
/// into the folder `folder(repetition)` gives; the figures of each side.
fn alternate(
    scene: &Scene,
    plans: [&[luster::image::outputs::Output]; 2],
    reps: usize,
    folder: impl Fn(usize) -> std::path::PathBuf,
) -> (Side, Side) {
    let (mut a, mut b) = (Side::default(), Side::default());
    for i in 0..reps {
        let dir = folder(i);
        for (plan, side) in [(plans[0], &mut a), (plans[1], &mut b)] {
            let t0 = Stamp::now();
            let img = render::render(scene, 0, &|_| {});
            let t1 = Stamp::now();
            write_outputs(&img.film, &dir, plan).expect("the outputs are written");
            let t2 = Stamp::now();
            let (w, c) = t0.since(t2);
            let (ow, oc) = t1.since(t2);
            side.wall.push(w);
            side.cpu.push(c);
            side.out_wall.push(ow);
            side.out_cpu.push(oc);
        }
    }
    (a, b)
}

/// The encoding cost (into memory, no file) and size of the film's EXR under
/// each compression the course or the `exr` crate offers, on one thread and
/// on all; the course's own EXRs are 16-bit half PIZ.
fn exr_compressions(film: &luster::film::Film, reps: usize) {
    use exr::prelude::*;
    let (w, h) = (film.width as usize, film.height as usize);
    let px = &film.pixels;
    println!(
        "EXR encoding of the {w}x{h} film into memory, {reps} repetitions, medians (wall / process CPU)"
    );
    let kinds = [
        ("f32 uncompressed", Compression::Uncompressed, false),
        ("f32 RLE", Compression::RLE, false),
        ("f32 ZIP (1 line)", Compression::ZIP1, false),
        ("f32 ZIP (16 lines)", Compression::ZIP16, false),
        ("f32 PIZ", Compression::PIZ, false),
        ("half PIZ (the course's)", Compression::PIZ, true),
    ];
    for (name, compression, half) in kinds {
        let encoding = Encoding { compression, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing };
        for parallel in [false, true] {
            let (mut walls, mut cpus, mut size) = (Vec::new(), Vec::new(), 0);
            for _ in 0..reps {
                let mut out = std::io::Cursor::new(Vec::with_capacity(16 * w * h));
                let t = Stamp::now();
                let result = if half {
                    let ch = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                        let p = px[y * w + x];
                        (f16::from_f32(p.x), f16::from_f32(p.y), f16::from_f32(p.z))
                    });
                    let image =
                        Image::from_layer(Layer::new((w, h), LayerAttributes::default(), encoding, ch));
                    if parallel {
                        image.write().to_buffered(&mut out)
                    } else {
                        image.write().non_parallel().to_buffered(&mut out)
                    }
                } else {
                    let ch = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
                        let p = px[y * w + x];
                        (p.x, p.y, p.z)
                    });
                    let image =
                        Image::from_layer(Layer::new((w, h), LayerAttributes::default(), encoding, ch));
                    if parallel {
                        image.write().to_buffered(&mut out)
                    } else {
                        image.write().non_parallel().to_buffered(&mut out)
                    }
                };
                result.expect("the EXR encodes");
                let (wall, cpu) = t.since(Stamp::now());
                walls.push(wall);
                cpus.push(cpu);
                size = out.into_inner().len();
            }
            println!(
                "{name:24} {:12} {:7.1} ms / {:7.1} ms CPU  {:6.2} MB",
                if parallel { "all threads" } else { "one thread" },
                median(&mut walls) * 1e3,
                median(&mut cpus) * 1e3,
                size as f64 / 1e6
            );
        }
    }
}
