//! The render loop of a watch session: load and build the scene, render a
//! quick preview and then refining passes, publish each as a frame, and
//! start over when a file of the scene changes, cancelling the render in
//! flight.
//!
//! A burst of file events (an editor's write-then-rename, a flood of saves)
//! is one change: the render stops at the first event, and the reload waits
//! until the files have been quiet for [`QUIET`].
//!
//! Volume grids are the slow part of a build (a shader call per cell), so
//! the session keeps them across reloads ([`GridCache`]): a save that leaves
//! a volume's inputs alone reuses its grids. Where a grid must be baked, the
//! preview gets a coarse one and the refining passes the full one, and a
//! save abandons a bake in flight.

use super::files::{scene_files, FileWatch};
use super::hub::{Frame, Hub};
use super::Options;
use luster_core::image::outputs::{first_ldr, OutputKind};
use luster_render::film::rgb8;
use luster_render::film::Film;
use luster_render::render::camera::Camera;
use luster_render::render::{render_progressive, Progress, RenderOptions, Scene};
use luster_render::volume::{Baking, GridCache};
use luster_scene::Description;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the files must be quiet before a reload: longer than an
/// editor's write-rename dance, short enough to start within 100 ms.
pub const QUIET: Duration = Duration::from_millis(20);

/// Images with more pixels than this get a preview first.
const PREVIEW_ABOVE: u32 = 160 * 160;

/// Density grids of the preview have at most this many cells per edge.
const PREVIEW_GRID: u32 = 32;

/// `desc` with its volumes' density grids capped at [`PREVIEW_GRID`], if any is finer.
fn coarse_grids(desc: &Description) -> Option<Description> {
    let fine = |g: Option<u32>| g.is_some_and(|g| g > PREVIEW_GRID);
    if !desc.volumes.iter().any(|v| fine(v.grid)) {
        return None;
    }
    let mut coarse = desc.clone();
    for v in &mut coarse.volumes {
        v.grid = v.grid.map(|g| g.min(PREVIEW_GRID));
    }
    Some(coarse)
}

/// What the preview pass may cost, going by the last one's time per pixel.
const PREVIEW_BUDGET: f64 = 0.12;

/// The preview's size: a quarter of each side, or an eighth or a sixteenth
/// when the last preview's `cost` per pixel (seconds; 0 when unknown) says a
/// quarter would take longer than [`PREVIEW_BUDGET`], as viewport renderers
/// start coarser on heavy scenes; at least one pixel.
fn preview_size(w: u32, h: u32, cost: f64) -> (u32, u32) {
    let at = |d: u32| (w.div_ceil(d).max(1), h.div_ceil(d).max(1));
    let mut d = 4;
    while d < 16 && cost * f64::from(at(d).0) * f64::from(at(d).1) > PREVIEW_BUDGET {
        d *= 2;
    }
    at(d)
}

/// The driver's side of a session.
pub struct Driver {
    /// What to render.
    pub opts: Options,
    /// Where frames and errors go.
    pub hub: Arc<Hub>,
    /// Set by the file watcher at a change; stops the render.
    pub cancel: Arc<AtomicBool>,
    /// One message per file event (the time it was seen).
    pub changes: Receiver<Instant>,
    /// The watch over the scene's files (reset at every load).
    pub files: FileWatch,
    /// Seconds per pixel of the last whole preview pass (f64 bits; 0 at first).
    pub preview_cost: AtomicU64,
    /// Volume grids baked by earlier loads.
    pub grids: GridCache,
    /// The tev viewer the passes go to as well.
    pub tev: std::sync::Mutex<Option<super::tev::Tev>>,
    /// The page's shader editor: its files, parameters and overrides.
    pub editor: Arc<super::editor::Editor>,
}

impl Driver {
    /// Runs until the hub closes.
    pub fn run(mut self, pool: &rayon::ThreadPool) {
        let mut known: BTreeSet<PathBuf> = BTreeSet::new();
        let mut since = Instant::now();
        let mut generation = 0;
        while !self.hub.is_closed() {
            self.hub.update(|s| {
                s.busy = true;
                s.generation = generation;
            });
            let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                pool.install(|| self.generation(&mut known, since, generation))
            }));
            let error = match outcome {
                Ok(r) => r.err(),
                Err(_) => {
                    Some(format!("{}: luster failed unexpectedly (a bug); save again to retry", self.name()))
                }
            };
            if let Some(e) = &error {
                eprintln!("error: {}", luster_core::text::shown(e, false));
            }
            let at = error.as_deref().and_then(|e| self.editor.locate(e));
            let editor = self.editor.seq();
            self.hub.update(|s| {
                s.busy = false;
                s.editor = editor;
                if error.is_some() {
                    s.error = error;
                    s.error_at = at;
                }
            });
            match self.next_change() {
                Some(t) => since = t,
                None => return,
            }
            generation += 1;
        }
    }

    fn name(&self) -> String {
        self.opts.scene.display().to_string()
    }

    /// Waits for a change and for the files to be quiet after it; returns
    /// when the first event of the burst was seen, `None` when the session ends.
    fn next_change(&self) -> Option<Instant> {
        let first = loop {
            match self.changes.recv_timeout(Duration::from_millis(250)) {
                Ok(t) => break t,
                Err(RecvTimeoutError::Timeout) if !self.hub.is_closed() => {}
                Err(_) => return None,
            }
        };
        loop {
            // Cleared before the quiet wait: an event from now on cancels the coming render.
            self.cancel.store(false, Ordering::SeqCst);
            match self.changes.recv_timeout(QUIET) {
                Ok(_) => {}
                Err(RecvTimeoutError::Timeout) => break,
                Err(RecvTimeoutError::Disconnected) => return None,
            }
        }
        (!self.hub.is_closed()).then_some(first)
    }

    /// Loads, builds and renders once; the error, as `luster render` words it.
    fn generation(
        &mut self,
        known: &mut BTreeSet<PathBuf>,
        since: Instant,
        generation: u64,
    ) -> Result<(), String> {
        let desc = self.load();
        // Until a load succeeds, keep watching what the last good one read,
        // so fixing any of it counts.
        let mut loose = known.clone();
        loose.insert(super::files::watched_name(&self.opts.scene));
        let mut desc = match desc {
            Ok(d) => d,
            Err(e) => {
                self.files.set_files(&loose, true);
                return Err(e);
            }
        };
        self.editor.publish(&desc, &loose, self.opts.build.shader_timeout);
        self.editor.apply(&mut desc);
        let editor = self.editor.seq();
        self.hub.update(|s| s.editor = editor);
        loose.extend(scene_files(&desc));
        // Watched before the build, which may take seconds: a save during it counts.
        self.files.set_files(&loose, true);
        let full = desc.cameras.get(self.opts.camera).cloned();
        let mut labels = Labels {
            kind: OutputKind::Course,
            target: 1,
            preview: true,
            since,
            display_width: full.as_ref().map_or(1, |c| c.resolution.0),
            pass: 0,
            generation,
        };
        // A density grid costs one shader call per cell: unless the full ones
        // are kept from an earlier load, the preview gets coarse ones.
        let coarse = if self.grids.covers(&desc) { None } else { coarse_grids(&desc) };
        let mut built = None;
        if full.is_some_and(|c| c.resolution.0 * c.resolution.1 > PREVIEW_ABOVE) {
            let mut scene = match self.build(coarse.as_ref().unwrap_or(&desc)) {
                Ok(s) => s,
                // A save abandoned the bake: the next load follows at once.
                Err(_) if self.cancel.load(Ordering::SeqCst) => return Ok(()),
                Err(e) => {
                    self.files.set_files(&loose, true);
                    return Err(e);
                }
            };
            let previewed = self.preview(&desc, &mut scene, &mut labels);
            // Modules are required as shaders first run: watch those the preview met.
            loose.extend(scene.textures.shader_modules());
            loose.extend(scene.volumes.shader_modules());
            self.files.set_files(&loose, true);
            self.editor.modules(&loose);
            previewed?;
            if coarse.is_none() {
                built = Some(scene);
            }
            if self.cancel.load(Ordering::SeqCst) {
                return Ok(());
            }
        }
        let mut scene = match built.map_or_else(|| self.build(&desc), Ok) {
            Ok(s) => s,
            Err(_) if self.cancel.load(Ordering::SeqCst) => return Ok(()),
            Err(e) => {
                self.files.set_files(&loose, true);
                return Err(e);
            }
        };
        *known = scene_files(&desc);
        known.extend(loose.iter().filter(|p| is_module(p)).cloned());
        self.files.set_files(known, false);
        labels.preview = false;
        let refined = self.refine(&mut scene, &mut labels);
        known.extend(scene.textures.shader_modules());
        known.extend(scene.volumes.shader_modules());
        self.files.set_files(known, false);
        self.editor.modules(known);
        refined
    }

    /// The scene's description after `--size`, `--scale` and `--crop`.
    fn load(&self) -> Result<Description, String> {
        let path = &self.opts.scene;
        let mut desc = luster_scene::load_viewed(path, &self.opts.view)
            .map_err(|e| format!("{:#}", anyhow::Error::from(e)))?;
        (self.opts.reframe)(&mut desc).map_err(|e| format!("{}: {e}", path.display()))?;
        for w in &desc.warnings {
            eprintln!("warning: {}", luster_core::text::shown(&format!("{}: {w}", path.display()), false));
        }
        let camera = desc.cameras.get(self.opts.camera).map(|c| c.resolution);
        luster_render::film::check_memory(camera).map_err(|e| format!("{}: {e}", path.display()))?;
        Ok(desc)
    }

    /// The render scene of `desc`, which has the session's camera.
    fn build(&self, desc: &Description) -> Result<Scene, String> {
        let path = &self.opts.scene;
        let baking = Baking { cache: Some(&self.grids), cancel: Some(&self.cancel) };
        let scene = Scene::build_baking(desc, &self.opts.build, &baking)
            .map_err(|e| format!("{:#}", anyhow::Error::from(e)))?;
        let n = scene.cameras.len();
        if self.opts.camera >= n {
            let cam = self.opts.camera;
            return Err(format!(
                "{}: there is no camera {cam} (the scene has {n}; cameras are numbered from 0)",
                path.display()
            ));
        }
        Ok(scene)
    }

    fn fail(&self, e: Box<luster_shading::shader::ShaderError>) -> String {
        format!("{}: {e}", self.opts.scene.display())
    }

    /// The 1-spp preview at a quarter of each side, published as a frame.
    fn preview(&self, desc: &Description, scene: &mut Scene, labels: &mut Labels) -> Result<(), String> {
        let cam = self.opts.camera;
        let full = scene.cameras[cam].clone();
        labels.target = self.opts.render.spp.unwrap_or(full.num_samples).max(1);
        labels.kind =
            first_ldr(&full.image_name, &full.tonemaps, full.display).map_or(OutputKind::Course, |o| o.kind);
        let mut small = desc.cameras[cam].clone();
        let cost = f64::from_bits(self.preview_cost.load(Ordering::Relaxed));
        small.resolution = preview_size(full.width, full.height, cost);
        scene.cameras[cam] = Camera::from_desc(&small);
        let opts = RenderOptions { spp: Some(1), ..self.opts.render };
        let start = Instant::now();
        let r = self.progressive(scene, &opts, labels);
        if r.is_ok() && !self.cancel.load(Ordering::SeqCst) {
            let pixels = f64::from(small.resolution.0) * f64::from(small.resolution.1);
            self.preview_cost.store((start.elapsed().as_secs_f64() / pixels).to_bits(), Ordering::Relaxed);
        }
        scene.cameras[cam] = full;
        r.map_err(|e| self.fail(e))
    }

    /// The full-resolution passes up to the target sample count.
    fn refine(&self, scene: &mut Scene, labels: &mut Labels) -> Result<(), String> {
        let full = &scene.cameras[self.opts.camera];
        labels.target = self.opts.render.spp.unwrap_or(full.num_samples).max(1);
        labels.kind =
            first_ldr(&full.image_name, &full.tonemaps, full.display).map_or(OutputKind::Course, |o| o.kind);
        let opts = RenderOptions { spp: Some(labels.target), ..self.opts.render };
        self.progressive(scene, &opts, labels).map_err(|e| self.fail(e))
    }

    /// One progressive render of the session's camera, every pass published.
    fn progressive(
        &self,
        scene: &Scene,
        opts: &RenderOptions,
        labels: &mut Labels,
    ) -> Result<(), Box<luster_shading::shader::ShaderError>> {
        let (hub, editor) = (&self.hub, &self.editor);
        let image_name = scene.cameras[self.opts.camera].image_name.clone();
        let mut on_pass = |film: &Film, spp: u32| {
            labels.pass += 1;
            if let Some(tev) = self.tev.lock().unwrap_or_else(|p| p.into_inner()).as_mut() {
                tev.show(&image_name, film);
            }
            let Some(png) = encode(film, &labels.kind) else { return };
            let ms = labels.since.elapsed().as_millis() as u64;
            let (width, height) = (film.width, film.height);
            let Labels { target, preview, display_width, pass, generation, .. } = *labels;
            hub.update(|s| {
                let number = s.frame.as_ref().map_or(1, |f| f.number + 1);
                let png = Arc::new(png);
                let target_spp = target;
                let f = Frame {
                    number,
                    generation,
                    png,
                    width,
                    height,
                    spp,
                    target_spp,
                    pass,
                    preview,
                    ms,
                    display_width,
                };
                s.frame = Some(f);
                s.error = None;
                s.error_at = None;
                s.editor = editor.seq();
            });
        };
        let progress = Progress { cancel: &self.cancel, on_pass: &mut on_pass };
        render_progressive(scene, self.opts.camera, opts, progress).map(|_| ())
    }
}

/// How the frames of one render are labelled.
struct Labels {
    /// The display transform.
    kind: OutputKind,
    /// Samples per pixel aimed at.
    target: u32,
    /// Whether the frames are the preview's.
    preview: bool,
    /// The change the render answers.
    since: Instant,
    /// The full image's width.
    display_width: u32,
    /// Passes published so far.
    pass: u32,
    /// The change rendered.
    generation: u64,
}

/// The film as the PNG `luster render` would write for the camera
/// (display transformed by `kind`), compressed for speed.
fn encode(film: &Film, kind: &OutputKind) -> Option<Vec<u8>> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    use image::ImageEncoder;
    let rgb = rgb8(film, kind).unwrap_or_else(|| film.to_rgb8());
    let mut png = Vec::new();
    PngEncoder::new_with_quality(&mut png, CompressionType::Fast, FilterType::Adaptive)
        .write_image(&rgb, film.width, film.height, image::ExtendedColorType::Rgb8)
        .ok()?;
    Some(png)
}

/// Whether `path` is a Lua module (kept watched across reloads, since the
/// scene description does not name what its shaders `require`).
fn is_module(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e == "lua")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_preview_gets_coarser_when_the_last_one_was_slow() {
        assert_eq!(preview_size(800, 600, 0.0), (200, 150), "a quarter when the cost is unknown");
        // 1 µs a pixel: 30,000 pixels cost 30 ms, within the budget.
        assert_eq!(preview_size(800, 600, 1e-6), (200, 150));
        // 10 µs a pixel: a quarter would take 0.3 s, an eighth 75 ms.
        assert_eq!(preview_size(800, 600, 1e-5), (100, 75));
        // Never below a sixteenth, however slow.
        assert_eq!(preview_size(800, 600, 1.0), (50, 38));
        assert_eq!(preview_size(3, 2, 1.0), (1, 1));
    }
}
