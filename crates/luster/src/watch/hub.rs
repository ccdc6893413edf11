//! What a watch session shows right now: the newest frame (a PNG, display
//! transformed as `luster render` writes it), the pass and samples in it, and
//! the error of the newest change, if any. The driver publishes into it; the
//! page's event streams wait on it and always send the newest state, so a
//! slow browser skips frames instead of queueing them.

use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::{Duration, Instant};

/// A rendered image ready to serve.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Frame number, from 1; every published image gets the next.
    pub number: u64,
    /// The change it renders (see [`State::generation`]).
    pub generation: u64,
    /// The PNG file's bytes.
    pub png: Arc<Vec<u8>>,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Samples per pixel in it.
    pub spp: u32,
    /// Samples per pixel the render is heading for.
    pub target_spp: u32,
    /// Pass number within its render, from 1 (the preview is pass 1).
    pub pass: u32,
    /// Whether it is the quick low-resolution first look.
    pub preview: bool,
    /// Width the page shows it at (the full image's, also for a preview).
    pub display_width: u32,
    /// Milliseconds from the change (or the start) to this frame.
    pub ms: u64,
}

/// The state the page mirrors.
#[derive(Clone, Debug, Default)]
pub struct State {
    /// Bumped on every change of the state.
    pub seq: u64,
    /// Changes seen (0: the first load).
    pub generation: u64,
    /// The last good image.
    pub frame: Option<Frame>,
    /// The newest change's error, one sentence as `luster render` prints it;
    /// the last good image stays.
    pub error: Option<String>,
    /// Whether a load or render is under way.
    pub busy: bool,
    /// The scene file.
    pub scene: String,
    /// The shader file and line the error points at, when it names one of
    /// the files the editor lists (the name the editor lists it under).
    pub error_at: Option<(String, u32)>,
    /// The editor's [`seq`](super::editor::Editor::seq): the page asks for
    /// `/shaders` again when it changes.
    pub editor: u64,
}

impl State {
    /// The state as the JSON of a page event (without the PNG).
    pub fn to_json(&self) -> String {
        let f = self.frame.as_ref();
        serde_json::json!({
            "seq": self.seq,
            "generation": self.generation,
            "scene": self.scene,
            "busy": self.busy,
            "error": self.error,
            "frame": f.map(|f| f.number),
            "width": f.map(|f| f.width),
            "height": f.map(|f| f.height),
            "spp": f.map(|f| f.spp),
            "target_spp": f.map(|f| f.target_spp),
            "pass": f.map(|f| f.pass),
            "preview": f.map(|f| f.preview),
            "display_width": f.map(|f| f.display_width),
            "ms": f.map(|f| f.ms),
            "error_at": self.error_at.as_ref().map(|(file, line)| serde_json::json!({ "file": file, "line": line })),
            "editor": self.editor,
        })
        .to_string()
    }
}

/// The shared state and a condition variable that wakes its readers.
#[derive(Default)]
pub struct Hub {
    state: Mutex<State>,
    changed: Condvar,
    /// Set when the session ends: streams close.
    closed: Mutex<bool>,
}

impl Hub {
    /// A hub for the scene named `scene`.
    pub fn new(scene: String) -> Arc<Hub> {
        Arc::new(Hub { state: Mutex::new(State { scene, ..State::default() }), ..Hub::default() })
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        // A panic while holding the lock left plain data behind: keep using it.
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// A copy of the current state.
    pub fn snapshot(&self) -> State {
        self.lock().clone()
    }

    /// Changes the state with `f` and wakes every reader.
    pub fn update(&self, f: impl FnOnce(&mut State)) {
        let mut s = self.lock();
        f(&mut s);
        s.seq += 1;
        drop(s);
        self.changed.notify_all();
    }

    /// Waits until the state is newer than `seq` (or `timeout` passes, or
    /// the hub closes) and returns it; `None` on a timeout or once closed.
    pub fn wait_newer(&self, seq: u64, timeout: Duration) -> Option<State> {
        let end = Instant::now() + timeout;
        let mut s = self.lock();
        loop {
            if self.is_closed() {
                return None;
            }
            if s.seq > seq {
                return Some(s.clone());
            }
            let left = end.checked_duration_since(Instant::now())?;
            s = self.changed.wait_timeout(s, left).map(|(g, _)| g).unwrap_or_else(|p| p.into_inner().0);
        }
    }

    /// Ends every wait.
    pub fn close(&self) {
        // Under the state's lock, so no reader sits between its check and its wait.
        let _s = self.lock();
        *self.closed.lock().unwrap_or_else(|p| p.into_inner()) = true;
        self.changed.notify_all();
    }

    /// Whether [`Hub::close`] was called.
    pub fn is_closed(&self) -> bool {
        *self.closed.lock().unwrap_or_else(|p| p.into_inner())
    }
}
