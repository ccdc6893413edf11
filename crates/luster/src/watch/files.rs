//! Which files a scene is made of, and noticing when one of them is saved.
//!
//! The files come from the loaded [`Description`]: the scene (or OBJ model)
//! itself, PLY meshes, images of texture maps (an OBJ's MTL textures
//! included), shader scripts of texture maps and volumes, and volumes' VDB
//! files. Their folders are watched rather than the files, because editors
//! save by writing a new file and renaming it over the old one, which ends a
//! watch on the file itself.
//! Reads are not changes (the loader's own reads would loop forever), nor are
//! metadata-only events.

use luster_scene::description::{MeshSource, Shape, TextureSource};
use luster_scene::Description;
use notify::{EventKind, RecommendedWatcher, RecursiveMode, Watcher};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The files `desc` was read from, each once, in their watched spelling.
pub fn scene_files(desc: &Description) -> BTreeSet<PathBuf> {
    let mut files = BTreeSet::new();
    files.insert(watched_name(&desc.file));
    for o in &desc.objects {
        if let Shape::Mesh { source: MeshSource::Ply(p), .. } = &o.shape {
            files.insert(watched_name(p));
        }
    }
    for i in &desc.images {
        files.insert(watched_name(&i.path));
    }
    for t in &desc.texture_maps {
        if let TextureSource::Shader { path, .. } = &t.source {
            files.insert(watched_name(path));
        }
    }
    for v in &desc.volumes {
        if let Some(s) = &v.script {
            files.insert(watched_name(&s.path));
        }
        if let Some(f) = &v.vdb {
            files.insert(watched_name(&f.path));
        }
    }
    files
}

/// `path` as the folder watcher reports it: the canonical folder joined with
/// the file name (the file itself may be missing for a moment during a save).
pub fn watched_name(path: &Path) -> PathBuf {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let dir = dir.canonicalize().unwrap_or(dir);
    match path.file_name() {
        Some(name) => dir.join(name),
        None => dir,
    }
}

/// What counts as a change.
#[derive(Default)]
struct Interest {
    files: BTreeSet<PathBuf>,
    /// After a failed load the file list may be short of the file that is
    /// missing: then a file appearing in a watched folder counts too.
    loose: bool,
}

/// Watches a scene's files and calls back on every change to one of them.
pub struct FileWatch {
    watcher: RecommendedWatcher,
    dirs: BTreeSet<PathBuf>,
    interest: Arc<Mutex<Interest>>,
}

impl FileWatch {
    /// A watch calling `on_change` (on the watcher's thread) for every
    /// change to a file of [`FileWatch::set_files`].
    pub fn new(on_change: impl Fn() + Send + 'static) -> notify::Result<FileWatch> {
        let interest = Arc::new(Mutex::new(Interest::default()));
        let seen = Arc::clone(&interest);
        let watcher = notify::recommended_watcher(move |ev: notify::Result<notify::Event>| {
            let Ok(ev) = ev else { return };
            let counts = match ev.kind {
                EventKind::Access(_) | EventKind::Modify(notify::event::ModifyKind::Metadata(_)) => false,
                EventKind::Create(_) | EventKind::Modify(_) | EventKind::Remove(_) | EventKind::Any => true,
                EventKind::Other => false,
            };
            if !counts {
                return;
            }
            let appeared = matches!(
                ev.kind,
                EventKind::Create(_) | EventKind::Modify(notify::event::ModifyKind::Name(_))
            );
            let hit = {
                let i = seen.lock().unwrap_or_else(|p| p.into_inner());
                (i.loose && appeared) || ev.paths.iter().any(|p| i.files.contains(p))
            };
            if hit {
                on_change();
            }
        })?;
        Ok(FileWatch { watcher, dirs: BTreeSet::new(), interest })
    }

    /// Watches `files` (in [`watched_name`] spelling) from now on; `loose`:
    /// a file created in their folders counts too. A folder that cannot be watched
    /// (deleted, unreadable) is skipped, and tried again on the next call.
    pub fn set_files(&mut self, files: &BTreeSet<PathBuf>, loose: bool) {
        let dirs: BTreeSet<PathBuf> =
            files.iter().filter_map(|f| f.parent().map(Path::to_path_buf)).collect();
        for gone in self.dirs.difference(&dirs) {
            let _ = self.watcher.unwatch(gone);
        }
        let mut watched = BTreeSet::new();
        for d in &dirs {
            if self.dirs.contains(d) || self.watcher.watch(d, RecursiveMode::NonRecursive).is_ok() {
                watched.insert(d.clone());
            }
        }
        self.dirs = watched;
        let mut i = self.interest.lock().unwrap_or_else(|p| p.into_inner());
        i.files = files.clone();
        i.loose = loose;
    }
}
