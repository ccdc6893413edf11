//! Per-thread Lua states. A Lua state is not thread-safe, so every thread that
//! shades (each rayon worker) gets its own state per [`ShaderSet`](super::ShaderSet),
//! created on first use and kept in a thread-local list.
//!
//! Several sets can live in one process (tests render many scenes), so each
//! entry is keyed by its set's unique id and holds a weak reference to it. A
//! thread cannot reach another thread's locals, so states are freed lazily:
//! dropping a set frees the dropping thread's state at once, and any thread
//! sweeps out states of dropped sets whenever it creates a new one. A thread
//! also keeps at most [`MAX_SETS_PER_THREAD`] states, evicting the least
//! recently created one, so memory stays bounded even while many sets are alive.

use std::cell::RefCell;
use std::sync::{Arc, Weak};

use super::error::{ShaderError, ShaderErrorKind};
use super::state::ThreadState;
use super::Shared;

/// How many sets' states one thread keeps.
pub(crate) const MAX_SETS_PER_THREAD: usize = 8;

struct Slot {
    id: u64,
    owner: Weak<Shared>,
    state: ThreadState,
}

thread_local! {
    static SLOTS: RefCell<Vec<Slot>> = const { RefCell::new(Vec::new()) };
}

#[cold]
fn internal(shared: &Shared, what: &str) -> ShaderError {
    let name = shared.sources.first().map_or("(none)", |s| s.name.as_str());
    ShaderError::new(ShaderErrorKind::Internal, name, format!("shader runtime: {what}"))
}

/// Runs `f` on this thread's state for `shared`, creating it if needed.
#[inline]
pub(crate) fn with_state<R>(
    shared: &Arc<Shared>,
    f: impl FnOnce(&ThreadState) -> Result<R, ShaderError>,
) -> Result<R, ShaderError> {
    SLOTS
        .try_with(|cell| {
            // A borrow can only fail if shading re-entered itself from Lua,
            // which no built-in does; report it rather than panic.
            let mut slots =
                cell.try_borrow_mut().map_err(|_| internal(shared, "shader called re-entrantly"))?;
            let index = match slots.iter().position(|s| s.id == shared.id) {
                Some(i) => i,
                None => create(&mut slots, shared)?,
            };
            f(&slots[index].state)
        })
        .unwrap_or_else(|_| Err(internal(shared, "thread is shutting down")))
}

/// What [`with_state_fast`] returns when it did not run `f`: this thread has
/// no state for the set yet, or the thread is shutting down, or shading
/// re-entered itself. The caller then goes through [`with_state`], which
/// builds the state or reports the problem.
pub(crate) const MISS: u32 = u32::MAX;

/// Runs `f` on this thread's state for `shared` if it exists and is free;
/// [`MISS`] otherwise. The hot path of a shader call: it returns a bare code
/// in a register, because the `Result` of [`with_state`] (about 80 bytes
/// with its error) is copied out of the thread-local access in chunks that
/// its own stores cannot forward to, a stall on every call.
#[inline]
pub(crate) fn with_state_fast(shared: &Shared, f: impl FnOnce(&ThreadState) -> u32) -> u32 {
    SLOTS
        .try_with(|cell| {
            let Ok(slots) = cell.try_borrow_mut() else { return MISS };
            match slots.iter().find(|s| s.id == shared.id) {
                Some(slot) => f(&slot.state),
                None => MISS,
            }
        })
        .unwrap_or(MISS)
}

/// Builds this thread's state for `shared`, making room for it; its index.
#[cold]
#[inline(never)]
fn create(slots: &mut Vec<Slot>, shared: &Arc<Shared>) -> Result<usize, ShaderError> {
    slots.retain(|s| s.owner.strong_count() > 0);
    if slots.len() >= MAX_SETS_PER_THREAD {
        slots.remove(0);
    }
    let state = ThreadState::new(shared)?;
    slots.push(Slot { id: shared.id, owner: Arc::downgrade(shared), state });
    Ok(slots.len() - 1)
}

/// Stores a state this thread already built (the one [`ShaderSet::new`]
/// validated the scripts with), so the first call need not build another.
///
/// [`ShaderSet::new`]: super::ShaderSet::new
pub(crate) fn adopt(shared: &Arc<Shared>, state: ThreadState) {
    let _ = SLOTS.try_with(|cell| {
        if let Ok(mut slots) = cell.try_borrow_mut() {
            slots.retain(|s| s.owner.strong_count() > 0 && s.id != shared.id);
            if slots.len() >= MAX_SETS_PER_THREAD {
                slots.remove(0);
            }
            slots.push(Slot { id: shared.id, owner: Arc::downgrade(shared), state });
        }
    });
}

/// Frees this thread's state for set `id` (called when the set drops).
pub(crate) fn release(id: u64) {
    let _ = SLOTS.try_with(|cell| {
        if let Ok(mut slots) = cell.try_borrow_mut() {
            slots.retain(|s| s.id != id);
        }
    });
}

/// How many states this thread holds (for tests).
#[cfg(test)]
pub(crate) fn count() -> usize {
    SLOTS.with(|cell| cell.borrow().len())
}
