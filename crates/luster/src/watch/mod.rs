//! `luster watch`: a live preview of a scene in the browser while its files
//! are edited.
//!
//! A session renders one camera of the scene progressively — a 1-spp pass at
//! a quarter of the resolution first, then passes of 1, 1, 2, 4, ... samples
//! per pixel at full resolution up to the camera's `NumSamples` (or `--spp`)
//! — and publishes every pass as a PNG frame, display transformed as `luster
//! render` writes the camera's first 8-bit image. When the scene file, a PLY
//! mesh, an image or a shader it reads is saved ([`files`]), the render in
//! flight is cancelled and the scene reloads ([`driver`]). A page on
//! 127.0.0.1 ([`server`]) shows the frames as they come, the pass and spp,
//! and the newest error (the sentence `luster render` prints, with the
//! shader's `file:line`) over the last good image ([`hub`]). The page's
//! editor opens and saves the scene's shader scripts and sets their
//! `params{}` values for the session ([`editor`]).
//!
//! Reads the scene as `luster render` does, plus each camera's
//! `ImageResolution`, `NumSamples`, `ImageName` and `Tonemap` for the frames.

mod conns;
pub mod driver;
pub mod editor;
pub mod files;
pub mod hub;
pub mod request;
pub mod server;
pub mod tev;

use hub::Hub;
use luster_render::render::{BuildOptions, RenderOptions};
use luster_scene::obj::ModelView;
use luster_scene::Description;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Instant;

/// A change to a loaded description before it is built (`--env`, `--size`,
/// `--scale`, `--crop`); its error is one sentence.
pub type Reframe = Box<dyn Fn(&mut Description) -> Result<(), String> + Send>;

/// What a session renders and how.
pub struct Options {
    /// The scene (or OBJ model).
    pub scene: PathBuf,
    /// Which camera, from 0.
    pub camera: usize,
    /// Samples per pixel (`spp`: instead of the camera's), seed and filter.
    pub render: RenderOptions,
    /// Shader limits.
    pub build: BuildOptions,
    /// How an OBJ model is seen.
    pub view: ModelView,
    /// Applied to every load.
    pub reframe: Reframe,
    /// Render threads (`None`: all cores).
    pub threads: Option<usize>,
    /// A tev viewer (`HOST:PORT`) that every pass is streamed to as well.
    pub tev: Option<String>,
}

/// A running session: its render loop, file watch and page server.
pub struct Session {
    hub: Arc<Hub>,
    addr: SocketAddr,
    server: Arc<server::Server>,
    cancel: Arc<AtomicBool>,
    threads: Vec<JoinHandle<()>>,
}

impl Session {
    /// Starts a session serving on 127.0.0.1:`port` (0: any free port). A
    /// scene that fails to load still starts one, showing the error.
    pub fn start(opts: Options, port: u16) -> Result<Session, String> {
        let tev = opts.tev.as_deref().map(tev::Tev::connect).transpose()?;
        let server = Arc::new(server::bind(port)?);
        let addr = server.addr();
        let hub = Hub::new(opts.scene.display().to_string());
        let cancel = Arc::new(AtomicBool::new(false));
        let (tx, changes) = std::sync::mpsc::channel::<Instant>();
        let (stop, poke) = (Arc::clone(&cancel), tx.clone());
        let editor = Arc::new(editor::Editor::new(move || {
            stop.store(true, Ordering::SeqCst);
            let _ = poke.send(Instant::now());
        }));
        let stop = Arc::clone(&cancel);
        let files = files::FileWatch::new(move || {
            stop.store(true, Ordering::SeqCst);
            let _ = tx.send(Instant::now());
        })
        .map_err(|e| format!("cannot watch files: {e}"))?;
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(opts.threads.unwrap_or(0))
            .thread_name(|i| format!("watch-render-{i}"))
            .stack_size(luster_shading::shader::STACK_SIZE)
            .build()
            .map_err(|e| format!("cannot start worker threads: {e}"))?;
        let driver = driver::Driver {
            opts,
            hub: Arc::clone(&hub),
            cancel: Arc::clone(&cancel),
            changes,
            files,
            preview_cost: std::sync::atomic::AtomicU64::new(0),
            grids: Default::default(),
            tev: std::sync::Mutex::new(tev),
            editor: Arc::clone(&editor),
        };
        let spawn = |name: &str, f: Box<dyn FnOnce() + Send>| {
            std::thread::Builder::new()
                .name(name.into())
                .stack_size(luster_shading::shader::STACK_SIZE)
                .spawn(f)
                .map_err(|e| format!("cannot start a thread: {e}"))
        };
        let render = spawn("watch-driver", Box::new(move || driver.run(&pool)))?;
        let (s, h) = (Arc::clone(&server), Arc::clone(&hub));
        let serve = spawn("watch-server", Box::new(move || s.serve(h, editor)))?;
        Ok(Session { hub, addr, server, cancel, threads: vec![render, serve] })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://{}/", self.addr)
    }

    /// The state the page shows.
    pub fn hub(&self) -> &Arc<Hub> {
        &self.hub
    }

    /// Stops the render, the watch and the server, and waits for their threads.
    pub fn stop(self) {
        self.hub.close();
        self.cancel.store(true, Ordering::SeqCst);
        self.server.unblock();
        for t in self.threads {
            let _ = t.join();
        }
    }

    /// Blocks for as long as the session runs (until the process is ended).
    pub fn wait(self) {
        for t in self.threads {
            let _ = t.join();
        }
    }
}
