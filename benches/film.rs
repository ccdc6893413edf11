//! What the film's HDR outputs cost: an 800×800 render of
//! `benches/scenes/film.xml` written as the course's 8-bit PNG (A) or as a
//! 32-bit float EXR plus a tone-mapped PNG (B, what an `.exr` `ImageName`
//! writes: hw5's photographic operator with 1% burn-out). The two are run
//! alternately, A B A B ..., on the same machine in the same run, and the
//! medians are compared; the target is B / A ≤ 1.05. Run:
//! `cargo bench --bench film` (`-- --reps N` for more repetitions).

use luster::film::outputs::{plan_outputs, write_outputs};
use luster::film::Display;
use luster::render::{self, Scene};
use std::path::Path;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
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
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/scenes/film.xml");
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
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let (mut a_out, mut b_out) = (Vec::new(), Vec::new());
    for _ in 0..reps {
        for (plan, total, out) in [(&ldr, &mut a, &mut a_out), (&hdr, &mut b, &mut b_out)] {
            let t = Instant::now();
            let img = render::render(&scene, 0, &|_| {});
            let r = t.elapsed().as_secs_f64();
            write_outputs(&img.film, dir.path(), plan).expect("the outputs are written");
            let all = t.elapsed().as_secs_f64();
            total.push(all);
            out.push(all - r);
        }
    }
    // Where the output stage's time goes.
    let img = render::render(&scene, 0, &|_| {});
    let tonemap = luster::film::Tonemap { burn_percent: 1.0, ..luster::film::Tonemap::COURSE_DEFAULT };
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
    let (ma, mb) = (median(&mut a), median(&mut b));
    let (oa, ob) = (median(&mut a_out), median(&mut b_out));
    println!("film bench: 800x800, {reps} alternating repetitions, medians");
    println!("A  render + course PNG            {:8.1} ms  (output stage {:6.1} ms)", ma * 1e3, oa * 1e3);
    println!("B  render + EXR + tone-mapped PNG {:8.1} ms  (output stage {:6.1} ms)", mb * 1e3, ob * 1e3);
    println!(
        "parts of B's output stage (medians): tone mapping {:.1} ms, EXR {:.1} ms, PNG {:.1} ms",
        t_map * 1e3,
        t_exr * 1e3,
        t_png * 1e3
    );
    println!("B / A = {:.3}  (target <= 1.05)", mb / ma);
}
