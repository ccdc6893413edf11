//! `luster merge`: the part files in a folder become the images a single
//! render writes; and the progress of a split render, from the files on disk.
//!
//! Every part file is read and checked before any image is written: all
//! must be finished parts of one job (same [`super::JobId`] and N), every
//! image of the job must have each of its parts exactly once, and each part
//! must hold exactly its share of the image's tiles ([`super::share`]), so
//! together they cover it exactly. Then each image's film is assembled
//! and written through [`luster_core::image::outputs`], as `luster render` does.
//! The part files stay; a second merge writes the same images.
//!
//! Files are opened only when regular (see [`PartFile::read_with`]): a FIFO
//! or a device named like a part is an error for a merge and a line of the
//! progress report, never a read that blocks. Every count a part file
//! claims (images, parts, tiles) is bounded before anything loops over it.

use super::part::pull_tile;
use super::partfile::{tile_count, tile_rect, PartFile, Pixels};
use super::{images_of_part, parse_part_name, parts_of, share, tiles_of, ClusterError, Part};
use luster_core::image::outputs::{first_clash, plan_outputs, Output};
use luster_core::text::shown;
use luster_render::film::aov::{aov_file_name, write_aov_exr, Aovs, Passes};
use luster_render::film::write_outputs;
use luster_render::film::Film;
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
    /// The render passes, written to [`aov_file_name`] when there are any.
    passes: Passes,
    parts: Vec<PathBuf>,
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
        // The checksum is checked now; the pixels are read when the image is assembled.
        let p = PartFile::read_with(&f.path, Pixels::Check)?;
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
        // Each part holds exactly its share, so the parts of an image cover
        // it exactly once all are there.
        let count = tile_count(p.width, p.height) as u32;
        let share = share(p.images, f.part, p.image, count).map(tiles_of);
        if !share.is_some_and(|s| s.eq(p.tiles.iter().copied())) {
            return Err(ClusterError(format!(
                "{here}: its tiles are not part {} of {}'s share of the image (parts of another split?)",
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
                    passes: p.passes,
                    parts: Vec::new(),
                })
            }
        };
        if plan.passes != p.passes {
            return Err(ClusterError(format!(
                "{here}: another part of image {} holds other render passes",
                p.image + 1
            )));
        }
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
        plan.parts.push(f.path.clone());
    }
    let Some((_, job, n, m)) = first else {
        return Err(ClusterError(format!("{}: there are no part files to merge", outdir.display())));
    };
    // However many images the parts claim, this stops at the first missing
    // part: every lookup before it found a distinct file, so it runs at most
    // once per part file read.
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
    let aov_names: Vec<PathBuf> =
        plans.iter().filter(|p| !p.passes.is_empty()).map(|p| aov_file_name(&p.name)).collect();
    let names = plans.iter().flat_map(|p| p.outputs.iter().map(|o| o.name.as_path()));
    if let Some(clash) = first_clash(names.chain(aov_names.iter().map(PathBuf::as_path))) {
        return Err(ClusterError(format!(
            "{}: two images of the job would be written to {}",
            outdir.display(),
            clash.display()
        )));
    }
    // Everything was checked (checksums included); the films are assembled
    // one at a time, since an animation's films together may not fit in memory.
    let mut written = Vec::new();
    for plan in &plans {
        let (film, aovs) = assemble(plan, job)?;
        written.extend(write_outputs(&film, outdir, &plan.outputs).map_err(|e| ClusterError(e.to_string()))?);
        if let Some(aovs) = aovs {
            let path = outdir.join(aov_file_name(&plan.name));
            write_aov_exr(&path, &film, &aovs).map_err(|e| ClusterError(e.to_string()))?;
            written.push(path);
        }
    }
    Ok(Merged { written, parts: found.len() })
}

/// The film of one image and its passes from its parts (checked by [`merge`]).
fn assemble(plan: &ImagePlan, job: [u8; 32]) -> Result<(Film, Option<Aovs>), ClusterError> {
    let (w, h) = plan.size;
    let mut film = Film::new(w, h);
    let mut aovs = (!plan.passes.is_empty()).then(|| Aovs::new(w, h, plan.passes));
    for path in &plan.parts {
        let p = PartFile::read(path)?;
        let changed = || ClusterError(format!("{}: the file changed during the merge", path.display()));
        if (p.width, p.height) != plan.size || p.job != job || p.passes != plan.passes {
            return Err(changed());
        }
        // The reader checked that the pixels and passes are exactly the
        // listed tiles'.
        let (mut at, mut aov_at) = (0, 0);
        for &t in &p.tiles {
            let rect = tile_rect(t, w, h);
            let len = ((rect.2 - rect.0) * (rect.3 - rect.1)) as usize;
            pull_tile(&mut film, &p.pixels[at..at + len], rect);
            at += len;
            if let Some(a) = &mut aovs {
                aov_at += a.pull_rect(p.aov.get(aov_at..).unwrap_or_default(), rect).ok_or_else(changed)?;
            }
        }
    }
    Ok((film, aovs))
}

/// Most lines about unfinished parts in a progress report; the rest are counted.
const MAX_UNFINISHED_LINES: usize = 32;

/// Progress of a split render, from the files under `outdir`: one line per
/// fact, for `luster slurm status`. Part files are read up to their tile
/// lists (their checksums are `luster merge`'s to check); one that cannot be
/// read is a line saying why. The lines are safe to print: names from the
/// folder have their control characters escaped.
pub fn status(outdir: &Path) -> Result<Vec<String>, ClusterError> {
    let found = find(outdir)?;
    if found.is_empty() {
        return Ok(vec![shown(&format!("{}: no part files yet", outdir.display()), false).into_owned()]);
    }
    let mut lines = Vec::new();
    let mut done: BTreeMap<u32, u64> = BTreeMap::new();
    let mut expected = None;
    for f in &found {
        let p = match PartFile::read_with(&f.path, Pixels::Skip) {
            Ok(p) => p,
            Err(e) => {
                lines.push(format!("unreadable: {e}"));
                continue;
            }
        };
        let count = tile_count(p.width, p.height) as u32;
        let total = share(p.images, f.part, p.image, count).map_or(0, |s| tiles_of(s).count());
        expected = Some((p.images, p.n));
        if f.checkpoint {
            lines.push(format!(
                "part {} of {}: {} in progress, {} of {total} tiles checkpointed",
                f.part.k,
                f.part.n,
                f.image,
                p.tiles.len(),
            ));
        } else {
            *done.entry(f.part.k).or_default() += 1;
        }
    }
    if let Some((m, n)) = expected {
        let finished: u64 = done.values().sum();
        // Every image has one part, or all N of them.
        let all = if m >= n { u64::from(m) } else { u64::from(m) * u64::from(n) };
        lines.insert(0, format!("{finished} of {all} part files finished ({m} images in {n} parts)"));
        let done_of = |k: u32| done.get(&k).copied().unwrap_or(0);
        // Lines are made for the first few only: N may be 2^20.
        let mut unfinished = (1..=n).filter(|&k| done_of(k) < images_of_part(m, n, k));
        lines.extend(unfinished.by_ref().take(MAX_UNFINISHED_LINES).map(|k| {
            format!("part {k} of {n}: {} of {} images finished", done_of(k), images_of_part(m, n, k))
        }));
        let more = unfinished.count();
        if more > 0 {
            lines.push(format!("... and {more} more unfinished parts"));
        }
    }
    Ok(lines.into_iter().map(|l| shown(&l, false).into_owned()).collect())
}
