//! Baked volume grids kept from one scene build to the next, as an
//! interactive renderer keeps them: `luster watch` rebuilds the whole scene
//! at every save, and a 128³ grid costs two million shader calls, so a save
//! that does not touch a volume must not bake it again.
//!
//! An entry is found by everything the bake read: the volume's place in the
//! scene (its index, which scripts see as `s.object_id`), its script's path,
//! text and parameters, its bound and transform, the grid resolution, the
//! module search path and the scene's images (path, size and modification
//! time, as `texture()` may sample them). The modules the scripts required
//! are not known before the scripts run, so an entry also records the text of
//! each module file as the bake saw it, and a module saved since makes the
//! entry stale. Least recently used entries go once the grids held pass
//! [`CACHE_BYTES`].
//!
//! A [`Baking`] also carries a flag that abandons a bake in flight: the
//! watch sets it at a save, so a stale build does not hold up the new one.

use super::Grid;
use luster_core::math::Vec3;
use luster_scene::description::{Description, VolumeDesc};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// Most bytes of grids a cache keeps.
pub const CACHE_BYTES: usize = 768 << 20;

/// A volume's baked grids: density, and emission when the script has one.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The density grid.
    pub density: Arc<Grid<f32>>,
    /// The emission grid.
    pub emission: Option<Arc<Grid<Vec3>>>,
}

impl Baked {
    fn bytes(&self) -> usize {
        self.density.bytes() + self.emission.as_ref().map_or(0, |g| g.bytes())
    }
}

struct Entry {
    key: String,
    /// Each required module file and its text when baked (`None`: unreadable).
    modules: Vec<(PathBuf, Option<Vec<u8>>)>,
    grids: Baked,
    used: u64,
}

/// Baked grids kept across builds. `Sync`: builds may share one.
#[derive(Default)]
pub struct GridCache {
    entries: Mutex<(Vec<Entry>, u64)>,
}

impl std::fmt::Debug for GridCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "GridCache({} entries)", self.lock().0.len())
    }
}

/// How a build bakes its volumes' grids: where it keeps them, and when to give up.
#[derive(Clone, Copy, Debug, Default)]
pub struct Baking<'a> {
    /// Grids kept from earlier builds (`None`: bake every grid).
    pub cache: Option<&'a GridCache>,
    /// Set to abandon the bake (the build then fails with [`CANCELLED`]).
    pub cancel: Option<&'a AtomicBool>,
}

/// The error of a bake abandoned through [`Baking::cancel`].
pub const CANCELLED: &str = "the grid bake was cancelled";

impl Baking<'_> {
    /// Whether the bake should stop.
    #[inline]
    pub fn cancelled(&self) -> bool {
        self.cancel.is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// The cache key of volume `index` of `desc` baked at `n` cells per edge.
pub fn key(desc: &Description, index: usize, n: u32) -> Option<String> {
    let v: &VolumeDesc = desc.volumes.get(index)?;
    let s = v.script.as_ref()?;
    let images: Vec<_> = desc
        .images
        .iter()
        .map(|i| {
            let meta = std::fs::metadata(&i.path).ok();
            (&i.id, &i.path, meta.as_ref().map(|m| m.len()), meta.and_then(|m| m.modified().ok()))
        })
        .collect();
    // Debug output of floats round-trips, so equal text means equal inputs.
    Some(format!(
        "{index}|{n}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{}",
        s.path,
        s.params,
        v.bound,
        v.transform.matrix(),
        desc.module_search_path(),
        images,
        s.code
    ))
}

impl GridCache {
    fn lock(&self) -> std::sync::MutexGuard<'_, (Vec<Entry>, u64)> {
        self.entries.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// The grids baked under `key`, if their modules are unchanged.
    pub fn get(&self, key: &str) -> Option<Baked> {
        let mut guard = self.lock();
        let (entries, clock) = &mut *guard;
        let at = entries.iter().position(|e| e.key == key)?;
        let fresh = entries[at].modules.iter().all(|(p, text)| std::fs::read(p).ok() == *text);
        if !fresh {
            entries.swap_remove(at);
            return None;
        }
        *clock += 1;
        entries[at].used = *clock;
        Some(entries[at].grids.clone())
    }

    /// Keeps `grids` under `key`, with the module files the bake read.
    pub fn put(&self, key: String, modules: &[PathBuf], grids: Baked) {
        let modules = modules.iter().map(|p| (p.clone(), std::fs::read(p).ok())).collect();
        let mut guard = self.lock();
        let (entries, clock) = &mut *guard;
        *clock += 1;
        entries.retain(|e| e.key != key);
        entries.push(Entry { key, modules, grids, used: *clock });
        // Drop the least recently used until the rest fit (the newest always stays).
        let mut total: usize = entries.iter().map(|e| e.grids.bytes()).sum();
        while total > CACHE_BYTES && entries.len() > 1 {
            let Some(old) = entries.iter().enumerate().min_by_key(|(_, e)| e.used).map(|(i, _)| i) else {
                break;
            };
            total -= entries[old].grids.bytes();
            entries.swap_remove(old);
        }
    }

    /// Whether every gridded volume of `desc` has its grids here at full resolution.
    pub fn covers(&self, desc: &Description) -> bool {
        desc.volumes.iter().enumerate().all(|(i, v)| match (v.grid, &v.script) {
            (Some(n), Some(_)) => key(desc, i, n).is_some_and(|k| self.get(&k).is_some()),
            _ => true,
        })
    }

    /// How many volumes' grids are kept.
    pub fn len(&self) -> usize {
        self.lock().0.len()
    }

    /// Whether none are.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
