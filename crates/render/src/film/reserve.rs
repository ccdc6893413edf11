//! Film memory written ahead of a render by a worker that would otherwise
//! wait.
//!
//! A render writes two buffers as large as its image: the tiles'
//! accumulators (16 bytes a pixel) and the film (12). Fresh from the
//! allocator their pages are not mapped yet, and the first write to each
//! faults, in the render's workers or, for the film, after the render.
//! Before the render, while the scene loads, one worker often idles: hw4
//! brickwall decodes a 350×350 PNG on one worker and a 1024×1024 JPEG (in
//! one piece: the file has no restart markers) on the other.
//! [`FilmReserve::start`] gives such a
//! worker the first camera's buffers to write; the render takes them as they
//! are when it starts: each buffer the worker finished (one it did not is
//! dropped, and the render allocates its own as it would have). On one
//! thread nothing is started: there is no idle worker to give the work to.
//! A render with passes ([`super::aov`]) has a third buffer, their
//! accumulators, written after the other two ([`FilmReserve::start_with`]).

use super::aov::{Layout, Passes};
use luster_core::math::Vec3;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// The buffers a render of `n` pixels writes, zeroed, where written.
#[derive(Default)]
pub(crate) struct FilmMemory {
    /// The tiles' accumulators, `[r, g, b, weight]` a pixel.
    pub store: Option<Vec<[f32; 4]>>,
    /// The film's pixels.
    pub pixels: Option<Vec<Vec3>>,
    /// The passes' accumulators (see [`super::aov::AovTile`]).
    pub aov: Option<Vec<f32>>,
}

/// The memory of a render of `width`×`height` pixels, being written by a
/// rayon worker (see the module's documentation).
pub struct FilmReserve {
    width: u32,
    height: u32,
    passes: Passes,
    shared: Arc<Shared>,
}

struct Shared {
    /// Held by the worker while it writes; what it wrote when it is done.
    memory: Mutex<Option<FilmMemory>>,
    /// Set when the render wants the memory: the worker stops within a page.
    stop: AtomicBool,
}

/// Bytes written at a time between two looks at the stop flag.
const PAGE: usize = 4096;

impl FilmReserve {
    /// Starts writing the memory of a `width`×`height` render on a worker of
    /// the current rayon pool, if it has more than one thread.
    pub fn start(width: u32, height: u32) -> FilmReserve {
        FilmReserve::start_with(width, height, Passes::NONE)
    }

    /// [`start`](Self::start) for a render with `passes`: their
    /// accumulators are written too.
    pub fn start_with(width: u32, height: u32, passes: Passes) -> FilmReserve {
        let shared = Arc::new(Shared { memory: Mutex::new(None), stop: AtomicBool::new(false) });
        let n = width as usize * height as usize;
        let aov = n * Layout::of(passes).stride;
        if rayon::current_num_threads() > 1 && n > 0 {
            let s = Arc::clone(&shared);
            rayon::spawn(move || s.write(n, aov));
        }
        FilmReserve { width, height, passes, shared }
    }

    /// Stops the worker and takes the memory it wrote, if the render is of
    /// the size reserved: each buffer the worker finished, zeroed (`None` for
    /// one it did not: completing it here would fault its pages on one
    /// thread, where the render's workers share them).
    pub(crate) fn take(&self, width: u32, height: u32, passes: Passes) -> FilmMemory {
        self.shared.stop.store(true, Ordering::Relaxed);
        let n = width as usize * height as usize;
        // The worker, if it is writing, holds the lock for at most a page more.
        let memory = self.shared.memory.lock().ok().and_then(|mut m| m.take());
        match memory {
            Some(m) if (width, height) == (self.width, self.height) => FilmMemory {
                store: m.store.filter(|s| s.len() == n),
                pixels: m.pixels.filter(|p| p.len() == n),
                aov: m.aov.filter(|a| passes == self.passes && a.len() == n * Layout::of(passes).stride),
            },
            _ => FilmMemory::default(),
        }
    }
}

impl Drop for FilmReserve {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
    }
}

impl Shared {
    /// Writes zeros into the two buffers of `n` pixels a page at a time
    /// until done or stopped, then leaves them for [`FilmReserve::take`].
    fn write(&self, n: usize, aov_len: usize) {
        let Ok(mut slot) = self.memory.lock() else { return };
        if self.stop.load(Ordering::Relaxed) {
            return;
        }
        // Memory written ahead is a gain, not a need: when it cannot be had,
        // the render allocates (or reports) it itself.
        let mut store = Vec::new();
        let mut pixels = Vec::new();
        let mut aov = Vec::new();
        if store.try_reserve_exact(n).is_ok()
            && fill(&mut store, n, [0.0; 4], &self.stop)
            && pixels.try_reserve_exact(n).is_ok()
            && fill(&mut pixels, n, Vec3::ZERO, &self.stop)
            && aov_len > 0
            && aov.try_reserve_exact(aov_len).is_ok()
        {
            fill(&mut aov, aov_len, 0.0, &self.stop);
        }
        *slot = Some(FilmMemory { store: Some(store), pixels: Some(pixels), aov: Some(aov) });
    }
}

/// Pushes `zero` into `buf` up to `n` elements, a page at a time, unless
/// `stop` is set; whether it got to `n`.
fn fill<T: Copy>(buf: &mut Vec<T>, n: usize, zero: T, stop: &AtomicBool) -> bool {
    let per_page = (PAGE / std::mem::size_of::<T>()).max(1);
    while buf.len() < n {
        if stop.load(Ordering::Relaxed) {
            return false;
        }
        let k = per_page.min(n - buf.len());
        buf.extend(std::iter::repeat_n(zero, k));
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap()
    }

    #[test]
    fn each_buffer_comes_whole_and_zeroed_or_not_at_all() {
        pool(2).install(|| {
            for wait in [0, 1, 50] {
                let r = FilmReserve::start(300, 200);
                std::thread::sleep(std::time::Duration::from_millis(wait));
                let m = r.take(300, 200, Passes::NONE);
                for len in
                    [m.store.as_ref().map(Vec::len), m.pixels.as_ref().map(Vec::len)].into_iter().flatten()
                {
                    assert_eq!(len, 60_000);
                }
                assert!(m.store.iter().flatten().all(|p| *p == [0.0; 4]));
                assert!(m.pixels.iter().flatten().all(|p| *p == Vec3::ZERO));
                if wait == 50 {
                    assert!(m.store.is_some() && m.pixels.is_some(), "a worker had 50 ms for 1.7 MB");
                }
                let again = r.take(300, 200, Passes::NONE);
                assert!(again.store.is_none() && again.pixels.is_none(), "taken once");
            }
        });
    }

    #[test]
    fn the_passes_accumulators_come_for_the_passes_reserved_only() {
        pool(2).install(|| {
            let passes = Passes::parse("albedo,depth").unwrap();
            let r = FilmReserve::start_with(40, 30, passes);
            std::thread::sleep(std::time::Duration::from_millis(50));
            let m = r.take(40, 30, passes);
            let aov = m.aov.expect("a worker had 50 ms for 100 kB");
            assert_eq!(aov.len(), 40 * 30 * Layout::of(passes).stride);
            assert!(aov.iter().all(|&v| v == 0.0));
            let r = FilmReserve::start_with(40, 30, passes);
            std::thread::sleep(std::time::Duration::from_millis(50));
            assert!(r.take(40, 30, Passes::NONE).aov.is_none(), "other passes");
        });
    }

    #[test]
    fn another_size_or_one_thread_gets_nothing() {
        pool(2).install(|| {
            let r = FilmReserve::start(64, 64);
            std::thread::sleep(std::time::Duration::from_millis(20));
            let m = r.take(64, 65, Passes::NONE);
            assert!(m.store.is_none() && m.pixels.is_none());
        });
        pool(1).install(|| {
            let m = FilmReserve::start(64, 64).take(64, 64, Passes::NONE);
            assert!(m.store.is_none() && m.pixels.is_none());
        });
    }

    #[test]
    fn a_reserve_dropped_unused_stops_its_worker() {
        pool(2).install(|| {
            let r = FilmReserve::start(2000, 2000);
            let shared = Arc::clone(&r.shared);
            drop(r);
            // The worker stops within a page; its lock is then free.
            let t = std::time::Instant::now();
            while shared.memory.try_lock().is_err() {
                assert!(t.elapsed().as_secs() < 10, "the worker did not stop");
                std::thread::yield_now();
            }
            assert!(shared.stop.load(Ordering::Relaxed));
        });
    }
}
