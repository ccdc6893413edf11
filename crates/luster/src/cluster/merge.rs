//! `luster merge`: the part files in a folder become the images a single
//! render writes; and the progress of a split render, from the files on disk.
//!
//! Every part file is read and checked before any image is written: all
//! must be finished parts of one job (same [`super::JobId`] and N), every
//! image of the job must have each of its parts exactly once, and their
//! tiles must cover the image exactly. Then each image's film is assembled
//! and written through [`luster_core::image::outputs`], as `luster render` does.
//! The part files stay; a second merge writes the same images.

use super::part::pull_tile;
use super::partfile::{tile_rect, PartFile};
use super::{parse_part_name, parts_of, ClusterError, Part};
use luster_core::image::outputs::{first_clash, plan_outputs, Output};
use luster_render::film::write_outputs;
use luster_render::film::Film;
use luster_render::render::tile_origins;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A part file or checkpoint found in the folder.
struct Found {
    path: PathBuf,
    /// Its name relative to the folder, `/`-separated.
    image: String,
    part: Part,
    checkpoint: bool,
}

/// Every `*.part-K-of-N` (and checkpoint) under `outdir`, in name order.
fn find(outdir: &Path) -> Result<Vec<Found>, ClusterError> {
    let mut out = Vec::new();
    let mut stack = vec![(outdir.to_path_buf(), String::new())];
    while let Some((dir, prefix)) = stack.pop() {
        let entries = std::fs::read_dir(&dir).map_err(|e| {
            ClusterError(format!(
                "{}: cannot read the folder: {}",
                dir.display(),
                luster_core::file::io_reason(&e)
            ))
        })?;
        for e in entries.flatten() {
            let Ok(name) = e.file_name().into_string() else { continue };
            let rel = format!("{prefix}{name}");
            let Ok(ft) = e.file_type() else { continue };
            if ft.is_dir() {
                stack.push((e.path(), format!("{rel}/")));
            } else if let Some((image, part, checkpoint)) = parse_part_name(&rel) {
                out.push(Found { path: e.path(), image: image.to_string(), part, checkpoint });
            }
        }
    }
    out.sort_by(|a, b| a.path.cmp(&b.path));
    Ok(out)
}

/// One image of the job, as its parts describe it.
struct ImagePlan {
    name: String,
    size: (u32, u32),
    outputs: Vec<Output>,
    parts: Vec<PathBuf>,
    covered: Vec<bool>,
}

/// What a merge did.
#[derive(Debug)]
pub struct Merged {
    /// Files written.
    pub written: Vec<PathBuf>,
    /// Part files read.
    pub parts: usize,
}

/// Checks the parts under `outdir` and writes every image; on any error no
/// image is written.
pub fn merge(outdir: &Path) -> Result<Merged, ClusterError> {
    let found: Vec<Found> = find(outdir)?.into_iter().filter(|f| !f.checkpoint).collect();
    if found.is_empty() {
        return Err(ClusterError(format!(
            "{}: there are no part files (*.part-K-of-N) to merge",
            outdir.display()
        )));
    }
    let mut first: Option<(PathBuf, [u8; 32], u32, u32)> = None;
    let mut images: BTreeMap<u32, ImagePlan> = BTreeMap::new();
    let mut seen: BTreeMap<(u32, u32), PathBuf> = BTreeMap::new();
    for f in &found {
        let mut p = PartFile::read(&f.path)?;
        p.pixels = Vec::new();
        let here = f.path.display();
        if !p.finished || p.k != f.part.k || p.n != f.part.n || p.image_name != f.image {
            return Err(ClusterError(format!(
                "{here}: its contents are not what its name says (a renamed or unfinished part file)"
            )));
        }
        match &first {
            None => first = Some((f.path.clone(), p.job, p.n, p.images)),
            Some((other, job, n, m)) => {
                if *job != p.job || *n != p.n || *m != p.images {
                    return Err(ClusterError(format!(
                        "{here} and {} come from different renders (another scene, other options or another number of parts); merge one render's parts at a time",
                        other.display()
                    )));
                }
            }
        }
        if let Some(other) = seen.insert((p.image, p.k), f.path.clone()) {
            return Err(ClusterError(format!(
                "{here} and {} are the same part of the same image (duplicated)",
                other.display()
            )));
        }
        if !parts_of(p.images, p.n, p.image).contains(&p.k) {
            return Err(ClusterError(format!(
                "{here}: part {} of {} holds no share of this image",
                p.k, p.n
            )));
        }
        let plan = match images.get_mut(&p.image) {
            Some(plan) => plan,
            None => {
                let outputs = plan_outputs(&p.image_name, &p.tonemaps, p.display)
                    .map_err(|e| ClusterError(format!("{here}: {e}")))?;
                images.entry(p.image).or_insert(ImagePlan {
                    name: p.image_name.clone(),
                    size: (p.width, p.height),
                    outputs,
                    parts: Vec::new(),
                    covered: vec![false; tile_origins(p.width, p.height).len()],
                })
            }
        };
        if plan.name != p.image_name || plan.size != (p.width, p.height) {
            return Err(ClusterError(format!(
                "{here}: another part says image {} of the job is {} ({}x{}), this one says {} ({}x{})",
                p.image + 1,
                plan.name,
                plan.size.0,
                plan.size.1,
                p.image_name,
                p.width,
                p.height
            )));
        }
        for &t in &p.tiles {
            if std::mem::replace(&mut plan.covered[t as usize], true) {
                return Err(ClusterError(format!("{here}: tile {t} is also in another part")));
            }
        }
        plan.parts.push(f.path.clone());
    }
    let Some((_, _, n, m)) = first else {
        return Err(ClusterError(format!("{}: there are no part files to merge", outdir.display())));
    };
    for i in 0..m {
        for k in parts_of(m, n, i) {
            if !seen.contains_key(&(i, k)) {
                return Err(ClusterError(match images.get(&i) {
                    Some(plan) => format!("{}.part-{k}-of-{n} is missing", outdir.join(&plan.name).display()),
                    None => format!(
                        "{}: part {k} of {n} is missing (image {} of the render's {m} has no part file)",
                        outdir.display(),
                        i + 1
                    ),
                }));
            }
        }
    }
    let plans: Vec<ImagePlan> = images.into_values().collect();
    if let Some(clash) = first_clash(plans.iter().flat_map(|p| p.outputs.iter().map(|o| o.name.as_path()))) {
        return Err(ClusterError(format!(
            "{}: two images of the job would be written to {}",
            outdir.display(),
            clash.display()
        )));
    }
    if let Some(plan) = plans.iter().find(|p| p.covered.contains(&false)) {
        let t = plan.covered.iter().position(|c| !c).unwrap_or(0);
        return Err(ClusterError(format!(
            "{}: no part holds tile {t} of {} (parts of another split?)",
            plan.parts[0].display(),
            plan.name
        )));
    }
    // Everything was checked (checksums included); the films are assembled
    // one at a time, since an animation's films together may not fit in memory.
    let mut written = Vec::new();
    for plan in &plans {
        let film = assemble(plan)?;
        written.extend(write_outputs(&film, outdir, &plan.outputs).map_err(|e| ClusterError(e.to_string()))?);
    }
    Ok(Merged { written, parts: found.len() })
}

/// The film of one image from its parts (checked by [`merge`]).
fn assemble(plan: &ImagePlan) -> Result<Film, ClusterError> {
    let (w, h) = plan.size;
    let origins = tile_origins(w, h);
    let mut film = Film::new(w, h);
    for path in &plan.parts {
        let p = PartFile::read(path)?;
        if (p.width, p.height) != plan.size {
            return Err(ClusterError(format!("{}: the file changed during the merge", path.display())));
        }
        let mut at = 0;
        for &t in &p.tiles {
            let rect = tile_rect(&origins, t, w, h);
            let len = ((rect.2 - rect.0) * (rect.3 - rect.1)) as usize;
            pull_tile(&mut film, &p.pixels[at..at + len], rect);
            at += len;
        }
    }
    Ok(film)
}

/// Progress of a split render, from the files under `outdir`: one line per
/// fact, for `luster slurm status`.
pub fn status(outdir: &Path) -> Result<Vec<String>, ClusterError> {
    let found = find(outdir)?;
    if found.is_empty() {
        return Ok(vec![format!("{}: no part files yet", outdir.display())]);
    }
    let mut lines = Vec::new();
    let mut done: BTreeMap<u32, usize> = BTreeMap::new();
    let mut expected = None;
    for f in &found {
        let p = match PartFile::read(&f.path) {
            Ok(p) => p,
            Err(e) => {
                lines.push(format!("unreadable: {e}"));
                continue;
            }
        };
        let total =
            super::share(p.images, f.part, p.image, origins_len(&p)).map(|s| super::selected(s).len());
        expected = Some((p.images, p.n));
        if f.checkpoint {
            lines.push(format!(
                "part {} of {}: {} in progress, {} of {} tiles checkpointed",
                f.part.k,
                f.part.n,
                f.image,
                p.tiles.len(),
                total.unwrap_or(0)
            ));
        } else {
            *done.entry(f.part.k).or_default() += 1;
        }
    }
    if let Some((m, n)) = expected {
        let per_part = |k: u32| (0..m).filter(|&i| parts_of(m, n, i).contains(&k)).count();
        let finished: usize = done.values().sum();
        let all: usize = (1..=n).map(per_part).sum();
        lines.insert(0, format!("{finished} of {all} part files finished ({m} images in {n} parts)"));
        for k in 1..=n {
            let d = done.get(&k).copied().unwrap_or(0);
            if d < per_part(k) {
                lines.push(format!("part {k} of {n}: {d} of {} images finished", per_part(k)));
            }
        }
    }
    Ok(lines)
}

fn origins_len(p: &PartFile) -> u32 {
    tile_origins(p.width, p.height).len() as u32
}
