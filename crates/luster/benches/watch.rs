//! `luster watch`'s save-to-first-pixels latency on the gallery scenes
//! (`examples/scenes/*.xml`): the time from writing the scene file to the
//! first frame of the new render (the 1-spp preview at a quarter of the
//! resolution) being ready to serve, the median of several saves; the goal
//! is under 300 ms. Each save lands while the previous render is still
//! refining, so cancelling it is part of the figure.
//!
//! Beside it, as the reference measured in the same run: loading, building
//! and rendering the same preview directly (no watch, no PNG), whose ratio
//! shows what the watch machinery adds. Run: `cargo bench --bench watch`
//! (`-- --saves N` for more saves, `-- --only NAME` for one scene).
//!
//! `-- --touch WHAT` picks the file saved: `scene` (the default: the scene
//! file), `shader` (the first surface shader script) or `volume` (the first
//! volume script); a save appends a comment to it, which changes the script
//! text, so a volume script's grids must be baked again. Scenes without such a
//! file are left out.

use luster::render::{camera::Camera, render_with, RenderOptions, Scene};
use luster::watch::{Options, Session};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter().position(|a| a == name).and_then(|i| args.get(i + 1)).cloned()
}

/// Copies `from` into `to` recursively (the gallery's relative paths keep working).
fn copy_tree(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("a copy folder");
    for e in std::fs::read_dir(from).expect("the examples folder").flatten() {
        let p = e.path();
        if p.is_dir() {
            copy_tree(&p, &to.join(e.file_name()));
        } else {
            std::fs::copy(&p, to.join(e.file_name())).expect("a copied file");
        }
    }
}

/// Seconds to load, build and render the preview of camera 0 directly.
fn direct_preview(path: &Path) -> f64 {
    let t = Instant::now();
    let desc = luster::scene::load(path).expect("the gallery scene loads");
    let mut scene = Scene::build(&desc).expect("the gallery scene builds");
    let mut small = desc.cameras[0].clone();
    let (w, h) = small.resolution;
    small.resolution = (w.div_ceil(4), h.div_ceil(4));
    scene.cameras[0] = Camera::from_desc(&small);
    let img = render_with(&scene, 0, &RenderOptions { spp: Some(1), ..Default::default() }, &|_| {});
    std::hint::black_box(img.spp);
    t.elapsed().as_secs_f64()
}

/// The file of `scene` that a `touch` save writes to, and the comment syntax.
fn touched(scene: &Path, touch: &str) -> Option<(PathBuf, &'static str)> {
    use luster::scene::description::TextureSource;
    if touch == "scene" {
        return Some((scene.to_path_buf(), "<!-- save {} -->"));
    }
    let desc = luster::scene::load(scene).expect("the gallery scene loads");
    let path = match touch {
        "shader" => desc.texture_maps.iter().find_map(|t| match &t.source {
            TextureSource::Shader { path, .. } => Some(path.clone()),
            _ => None,
        }),
        "volume" => desc.volumes.iter().find_map(|v| v.script.as_ref().map(|s| s.path.clone())),
        other => panic!("--touch takes scene, shader or volume, not {other}"),
    }?;
    Some((path, "-- save {}"))
}

/// Waits for the first frame of `generation`; returns when it was seen, and
/// its size.
fn first_frame(session: &Session, generation: u64) -> (Instant, (u32, u32)) {
    let hub = session.hub();
    let mut seq = 0;
    loop {
        let s =
            hub.wait_newer(seq, Duration::from_secs(120)).expect("the session answers within two minutes");
        assert!(s.error.is_none() || s.generation < generation, "the scene failed: {:?}", s.error);
        if let Some(f) = s.frame.as_ref().filter(|f| f.generation == generation) {
            return (Instant::now(), (f.width, f.height));
        }
        seq = s.seq;
    }
}

fn main() {
    let saves: usize = arg("--saves").and_then(|s| s.parse().ok()).unwrap_or(5).max(1);
    let only = arg("--only");
    let touch = arg("--touch").unwrap_or_else(|| "scene".into());
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let tmp = tempfile::tempdir().expect("a temporary folder");
    copy_tree(&root, tmp.path());
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(tmp.path().join("scenes"))
        .expect("the gallery scenes")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .filter(|p| only.as_ref().is_none_or(|o| p.to_string_lossy().contains(o.as_str())))
        .collect();
    scenes.sort();
    println!(
        "save-to-first-pixels, median of {saves} saves of the {touch} file (preview: 1 spp, a quarter of each side, \
         coarser when the last preview was slow; direct: the quarter-size preview)"
    );
    println!(
        "{:<18} {:>9} {:>10} {:>10} {:>10} {:>7}",
        "scene", "preview", "watch ms", "max ms", "direct ms", "ratio"
    );
    let mut all = Vec::new();
    for path in &scenes {
        let Some((file, comment)) = touched(path, &touch) else { continue };
        let text = std::fs::read_to_string(&file).expect("the saved file's text");
        let opts = Options {
            scene: path.clone(),
            camera: 0,
            render: RenderOptions::default(),
            build: Default::default(),
            view: Default::default(),
            reframe: Box::new(|_| Ok(())),
            threads: None,
            tev: None,
        };
        let session = Session::start(opts, 0).expect("a watch session starts");
        first_frame(&session, 0);
        let mut lat = Vec::new();
        let mut size = (0, 0);
        for i in 1..=saves as u64 {
            // Let the previous render refine a while: the save must cancel it.
            std::thread::sleep(Duration::from_millis(300));
            let t0 = Instant::now();
            let note = comment.replace("{}", &i.to_string());
            std::fs::write(&file, format!("{text}\n{note}\n")).expect("the file is saved");
            let (t1, seen) = first_frame(&session, i);
            lat.push((t1 - t0).as_secs_f64() * 1e3);
            size = seen;
        }
        session.stop();
        std::fs::write(&file, &text).expect("the file is restored");
        let mut direct: Vec<f64> = (0..saves).map(|_| direct_preview(path) * 1e3).collect();
        let (m, d) = (median(&mut lat.clone()), median(&mut direct));
        let max = lat.iter().copied().fold(0.0, f64::max);
        let name = path.file_name().map(|n| n.to_string_lossy().to_string()).unwrap_or_default();
        println!(
            "{name:<18} {:>9} {m:>10.1} {max:>10.1} {d:>10.1} {:>7.2}",
            format!("{}x{}", size.0, size.1),
            m / d
        );
        all.push(m);
    }
    if !all.is_empty() {
        let worst = all.iter().copied().fold(0.0, f64::max);
        println!("worst median: {worst:.1} ms (goal: under 300 ms)");
    }
}
