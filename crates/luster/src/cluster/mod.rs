//! Rendering on many machines: a render split into N parts, each written to
//! part files that `luster merge` joins into the images a single render
//! writes, byte for byte; checkpoints so a killed part resumes; and the
//! Slurm batch scripts that run the parts as a job array.
//!
//! How the work is split (by [`share`]): the images of a job are every camera
//! of every scene on the command line, in order. With at least as many
//! images as parts (an animation), image `i` goes whole to part
//! `i mod N + 1`, so a part loads only the scenes it renders. With fewer
//! images than parts (one long render), every image is split by tiles:
//! part K takes tiles `K-1`, `K-1+N`, `K-1+2N`, ... (row by row, 16 pixels
//! square), which spreads the costly regions of the picture evenly. A pixel's
//! value depends only on the scene, the options and the pixel, so the merged
//! film is the single render's film and the written files are identical.
//!
//! - [`partfile`]: the part file format.
//! - [`part`]: rendering one part of one image, with checkpoints.
//! - [`merge`]: checking a folder's parts and writing the images; progress.
//! - [`slurm`]: the job-array and merge scripts.

pub mod merge;
pub mod part;
pub mod partfile;
pub mod slurm;

use luster_render::render::TileSelection;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// A cluster render failed; the message is one sentence naming the file.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ClusterError(pub String);

/// Part `k` of `n` (`k` from 1, as Slurm's array task ids).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Part {
    /// This part, 1 to `n`.
    pub k: u32,
    /// Number of parts.
    pub n: u32,
}

/// Most parts of one render: far beyond any cluster's array size limit.
pub const MAX_PARTS: u32 = 1 << 20;

/// Most images of one split render (cameras of all its scenes together):
/// a part file claiming more is refused, so no count over a job's images
/// can run to 2^32.
pub const MAX_IMAGES: u32 = 1 << 24;

impl std::str::FromStr for Part {
    type Err = String;
    fn from_str(s: &str) -> Result<Part, String> {
        let (k, n) = s.split_once('/').ok_or_else(|| format!("\"{s}\" is not K/N (e.g. 3/8)"))?;
        let num =
            |t: &str| t.trim().parse::<u32>().map_err(|_| format!("\"{s}\" is not K/N with whole numbers"));
        let (k, n) = (num(k)?, num(n)?);
        if n == 0 || n > MAX_PARTS {
            return Err(format!("{s}: N must be between 1 and {MAX_PARTS}"));
        }
        if k == 0 || k > n {
            return Err(format!("{s}: K must be between 1 and N ({n})"));
        }
        Ok(Part { k, n })
    }
}

/// The tiles of image `image` (of `images`) that part `part` renders, among
/// the image's `tiles` tiles; `None` when the image is another part's. The
/// selection may hold no tile (a tiny image split in many parts): the part
/// then writes a part file with none, so that every expected file exists.
pub fn share(images: u32, part: Part, image: u32, tiles: u32) -> Option<TileSelection> {
    if images >= part.n {
        (image % part.n == part.k - 1).then_some(TileSelection { first: 0, step: 1, end: tiles })
    } else {
        Some(TileSelection { first: part.k - 1, step: part.n, end: tiles })
    }
}

/// The parts that hold some of image `image` (of `images`).
pub fn parts_of(images: u32, n: u32, image: u32) -> std::ops::RangeInclusive<u32> {
    if images >= n {
        let k = image % n + 1;
        k..=k
    } else {
        1..=n
    }
}

/// How many of the `images` images of a split in `n` parts part `k` holds
/// some of, counted without a loop over the images.
pub fn images_of_part(images: u32, n: u32, k: u32) -> u64 {
    if images >= n {
        u64::from(images / n) + u64::from(k - 1 < images % n)
    } else {
        u64::from(images)
    }
}

/// The tiles a selection holds, ascending.
pub fn selected(sel: TileSelection) -> Vec<u32> {
    tiles_of(sel).collect()
}

/// The tiles a selection holds, ascending, without a list.
pub fn tiles_of(sel: TileSelection) -> impl Iterator<Item = u32> {
    (sel.first..sel.end).step_by(sel.step.max(1) as usize)
}

/// What identifies a split render: SHA-256 of the luster version, the
/// number of parts, every scene file's bytes (in order) and the options that
/// change pixels. Files the scenes refer to (meshes, textures) are not
/// hashed: parts of one render must see the same ones.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct JobId(pub [u8; 32]);

impl JobId {
    /// Hashes the scene files (read here) and `options`, a canonical text of
    /// the options.
    pub fn new(n: u32, scenes: &[PathBuf], options: &str) -> Result<JobId, ClusterError> {
        let mut h = Sha256::new();
        h.update(b"luster ");
        h.update(env!("CARGO_PKG_VERSION").as_bytes());
        h.update(n.to_le_bytes());
        // The scene and OBJ readers' own cap: a bigger file fails to load anyway.
        const MAX_SCENE: u64 = 1 << 30;
        for s in scenes {
            let bytes = luster_core::file::read_bytes(s, MAX_SCENE)
                .map_err(|why| ClusterError(format!("{}: cannot read the scene: {why}", s.display())))?;
            h.update((bytes.len() as u64).to_le_bytes());
            h.update(&bytes);
        }
        h.update(options.as_bytes());
        Ok(JobId(h.finalize().into()))
    }
}

/// Where part `part` of an image named `image_name` goes under `outdir`.
pub fn part_path(outdir: &Path, image_name: &str, part: Part) -> PathBuf {
    outdir.join(format!("{image_name}.part-{}-of-{}", part.k, part.n))
}

/// Where the checkpoint of that part goes.
pub fn checkpoint_path(outdir: &Path, image_name: &str, part: Part) -> PathBuf {
    outdir.join(format!("{image_name}.part-{}-of-{}.checkpoint", part.k, part.n))
}

/// Splits a file name `<image>.part-K-of-N` (or its `.checkpoint`) into the
/// image name, the part and whether it is a checkpoint.
pub fn parse_part_name(name: &str) -> Option<(&str, Part, bool)> {
    let (name, checkpoint) = match name.strip_suffix(".checkpoint") {
        Some(n) => (n, true),
        None => (name, false),
    };
    let (image, rest) = name.rsplit_once(".part-")?;
    let (k, n) = rest.split_once("-of-")?;
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    if image.is_empty() || !digits(k) || !digits(n) {
        return None;
    }
    let part: Part = format!("{k}/{n}").parse().ok()?;
    Some((image, part, checkpoint))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn part_numbers_are_checked() {
        assert_eq!("3/8".parse::<Part>(), Ok(Part { k: 3, n: 8 }));
        for bad in ["5/4", "0/0", "0/4", "1/0", "x/2", "2", "-1/3"] {
            assert!(bad.parse::<Part>().is_err(), "{bad}");
        }
    }

    #[test]
    fn every_tile_of_every_image_is_in_exactly_one_part() {
        for (images, n, tiles) in [(8, 4, 10), (2, 4, 9), (1, 3, 1), (5, 5, 3), (3, 7, 20)] {
            for image in 0..images {
                let mut seen = vec![0; tiles as usize];
                for k in 1..=n {
                    let part = Part { k, n };
                    let sel = share(images, part, image, tiles);
                    assert_eq!(sel.is_some(), parts_of(images, n, image).contains(&k));
                    for t in sel.map(selected).unwrap_or_default() {
                        seen[t as usize] += 1;
                    }
                }
                assert!(seen.iter().all(|&c| c == 1), "{images} images, {n} parts: {seen:?}");
            }
            for k in 1..=n {
                let holding = (0..images).filter(|&i| parts_of(images, n, i).contains(&k)).count();
                assert_eq!(images_of_part(images, n, k), holding as u64, "{images} images, part {k} of {n}");
            }
        }
    }

    #[test]
    fn part_names_round_trip() {
        let p = Part { k: 2, n: 12 };
        let path = part_path(Path::new("o"), "sub/a.png", p);
        assert_eq!(path, Path::new("o/sub/a.png.part-2-of-12"));
        assert_eq!(parse_part_name("sub/a.png.part-2-of-12"), Some(("sub/a.png", p, false)));
        assert_eq!(parse_part_name("a.png.part-2-of-12.checkpoint"), Some(("a.png", p, true)));
        for bad in ["a.png", "a.png.part-3-of-2", "a.png.part-x-of-2", ".part-1-of-2", "a.part-1-of-"] {
            assert_eq!(parse_part_name(bad), None, "{bad}");
        }
    }
}
