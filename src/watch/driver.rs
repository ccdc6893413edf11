//! The render loop of a watch session: load and build the scene, render a
//! quick preview and then refining passes, publish each as a frame, and
//! start over when a file of the scene changes, cancelling the render in
//! flight.
//!
//! A burst of file events (an editor's write-then-rename, a flood of saves)
//! is one change: the render stops at the first event, and the reload waits
//! until the files have been quiet for [`QUIET`].

use super::files::{scene_files, FileWatch};
use super::hub::{Frame, Hub};
use super::Options;
use crate::film::outputs::{first_ldr, rgb8, OutputKind};
use crate::film::Film;
use crate::render::camera::Camera;
use crate::render::{render_progressive, Progress, RenderOptions, Scene};
use crate::scene::Description;
use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, RecvTimeoutError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// How long the files must be quiet before a reload: longer than an
/// editor's write-rename dance, short enough to start within 100 ms.
pub const QUIET: Duration = Duration::from_millis(30);

/// Images with more pixels than this get a preview first.
const PREVIEW_ABOVE: u32 = 160 * 160;

/// The preview's size: a quarter of each side, at least one pixel.
fn preview_size(w: u32, h: u32) -> (u32, u32) {
    (w.div_ceil(4).max(1), h.div_ceil(4).max(1))
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
                Err(_) => Some(format!("{}: luster failed unexpectedly (a bug); save again to retry", self.name())),
            };
            if let Some(e) = &error {
                eprintln!("error: {e}");
            }
            self.hub.update(|s| {
                s.busy = false;
                if error.is_some() {
                    s.error = error;
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
    fn generation(&mut self, known: &mut BTreeSet<PathBuf>, since: Instant, generation: u64) -> Result<(), String> {
        let loaded = self.load();
        // Keep watching what the last good load read, so fixing any of it counts.
        match &loaded {
            Ok((d, _)) => {
                *known = scene_files(d);
                self.files.set_files(known, false);
            }
            Err((d, _)) => {
                let mut files = known.clone();
                files.insert(super::files::watched_name(&self.opts.scene));
                if let Some(d) = d {
                    files.extend(scene_files(d));
                }
                self.files.set_files(&files, true);
            }
        }
        let (desc, mut scene) = loaded.map_err(|(_, e)| e)?;
        self.render(&desc, &mut scene, since, generation)
    }

    /// The scene's description and render scene, or the error (with the
    /// description when only the build failed).
    #[allow(clippy::type_complexity)] // one-off: the two halves of a load
    fn load(&self) -> Result<(Description, Scene), (Option<Description>, String)> {
        let path = &self.opts.scene;
        let mut desc = crate::scene::load_viewed(path, &self.opts.view)
            .map_err(|e| (None, format!("{:#}", anyhow::Error::from(e))))?;
        if let Err(e) = (self.opts.reframe)(&mut desc) {
            return Err((Some(desc), format!("{}: {e}", path.display())));
        }
        for w in &desc.warnings {
            eprintln!("warning: {}: {w}", path.display());
        }
        let scene = match Scene::build_with(&desc, &self.opts.build) {
            Ok(s) => s,
            Err(e) => return Err((Some(desc), format!("{:#}", anyhow::Error::from(e)))),
        };
        let n = scene.cameras.len();
        if self.opts.camera >= n {
            let msg = format!(
                "{}: there is no camera {} (the scene has {n}; cameras are numbered from 0)",
                path.display(),
                self.opts.camera
            );
            return Err((Some(desc), msg));
        }
        Ok((desc, scene))
    }

    /// The preview, then the refining passes, each published as a frame.
    fn render(
        &mut self,
        desc: &Description,
        scene: &mut Scene,
        since: Instant,
        generation: u64,
    ) -> Result<(), String> {
        let cam = self.opts.camera;
        let full = scene.cameras[cam].clone();
        let target = self.opts.render.spp.unwrap_or(full.num_samples).max(1);
        let kind = first_ldr(&full.image_name, &full.tonemaps).map_or(OutputKind::Course, |o| o.kind);
        let mut labels = Labels { kind, target, preview: true, since, display_width: full.width, pass: 0, generation };
        let path = self.opts.scene.clone();
        let fail = |e: Box<crate::shader::ShaderError>| format!("{}: {e}", path.display());
        if full.width * full.height > PREVIEW_ABOVE {
            let mut small = desc.cameras[cam].clone();
            small.resolution = preview_size(full.width, full.height);
            scene.cameras[cam] = Camera::from_desc(&small);
            let opts = RenderOptions { spp: Some(1), ..self.opts.render };
            let r = self.progressive(scene, &opts, &mut labels);
            scene.cameras[cam] = full;
            r.map_err(fail)?;
        }
        if self.cancel.load(Ordering::SeqCst) {
            return Ok(());
        }
        labels.preview = false;
        let opts = RenderOptions { spp: Some(target), ..self.opts.render };
        self.progressive(scene, &opts, &mut labels).map_err(fail)
    }

    /// One progressive render of the session's camera, every pass published.
    fn progressive(
        &self,
        scene: &Scene,
        opts: &RenderOptions,
        labels: &mut Labels,
    ) -> Result<(), Box<crate::shader::ShaderError>> {
        let hub = &self.hub;
        let mut on_pass = |film: &Film, spp: u32| {
            labels.pass += 1;
            let Some(png) = encode(film, &labels.kind) else { return };
            let ms = labels.since.elapsed().as_millis() as u64;
            let (width, height) = (film.width, film.height);
            let Labels { target, preview, display_width, pass, generation, .. } = *labels;
            hub.update(|s| {
                let number = s.frame.as_ref().map_or(1, |f| f.number + 1);
                let png = Arc::new(png);
                let target_spp = target;
                let f = Frame { number, generation, png, width, height, spp, target_spp, pass, preview, ms, display_width };
                s.frame = Some(f);
                s.error = None;
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
