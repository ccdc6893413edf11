//! The part file: the finished tiles of one image rendered by one part of a
//! split render, in linear film values, with what `luster merge` needs to
//! check that the parts in a folder belong together.
//!
//! All numbers little-endian; `u32` unless said otherwise:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `LUSTPART` |
//! | 4 | format version (3) |
//! | 4 | state: 1 a finished part, 0 a checkpoint of an unfinished one |
//! | 32 | job id: SHA-256 of the luster version, the scene files' bytes and the options that change pixels ([`super::JobId`]) |
//! | 4 + 4 | N, K: this is part K of N |
//! | 4 + 4 | M, i: this image is image i (from 0) of the M images of the job |
//! | 4 + 4 | width, height in pixels |
//! | 4 | tile edge in pixels (16) |
//! | 4 + L | L, then the image's `ImageName` (UTF-8) |
//! | 4 + 18·t | t, then the camera's tone mappings: operator (u8: 0 photographic, 1 ACES, 2 filmic), key, burn-out, saturation (f32), gamma (u8: 0 power, 1 sRGB; f32 exponent) |
//! | 1 | the scene's display transform (u8: 0 course, 1 sRGB, 2 ACES, 3 filmic) |
//! | 1 | the render passes held (u8: a bit per pass of [`Pass::ALL`](luster_render::film::aov::Pass::ALL), from the lowest) |
//! | 4 + 4·T | T, then the indices of the tiles held, ascending (tiles are numbered row by row) |
//! | 12·P | the tiles' pixels, tile after tile, each row by row: linear RGB as three f32 |
//! | 4·C·P | the tiles' passes, tile after tile, each pass after pass, row by row, a pixel's channels together (f32; [`Aovs::push_rect`](luster_render::film::aov::Aovs::push_rect)) |
//! | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! P is the number of pixels in the listed tiles (edge tiles are cut at the
//! image border), C the passes' channels per pixel.
//!
//! A file named like a part may be anything (a FIFO, a link to a device, a
//! sparse file of gigabytes, a forged header with a right checksum), so
//! [`PartFile::read_with`] opens regular files only, reads the header first,
//! bounds every count in it by a limit ([`MAX_NAME`], [`MAX_TONEMAPS`],
//! [`super::MAX_PARTS`], [`super::MAX_IMAGES`], the scene reader's image
//! size) and by the bytes the file has left before allocating or looping,
//! and requires the file's size to be exactly what the header implies
//! before it reads a pixel.

use super::{ClusterError, MAX_IMAGES, MAX_PARTS};
use luster_core::math::Vec3;
use luster_core::tonemap::{Display, Gamma, Operator, Tonemap};
use luster_render::film::aov::Passes;
use luster_render::render::tile_size;
use luster_scene::ceng795::camera::{MAX_PIXELS, MAX_SIDE};
use std::io::Read;
use std::path::Path;

const MAGIC: &[u8; 8] = b"LUSTPART";
const VERSION: u32 = 3;

/// Longest `ImageName` a part file may hold, in bytes (a path's limit on Linux).
pub const MAX_NAME: u32 = 4096;
/// Most tone mappings a part file may hold.
pub const MAX_TONEMAPS: u32 = 4096;
/// Bytes of the fields of fixed size: magic to tile edge, the three counts
/// (L, t, T), the display and passes bytes and the checksum.
const FIXED: u64 = 8 + 4 + 4 + 32 + 7 * 4 + 4 + 4 + 1 + 1 + 4 + 4;
/// Most pass channels a pixel may have (every pass).
const MAX_CHANNELS: u64 = 15;
/// Bytes of one tone mapping.
const TONEMAP_BYTES: u64 = 18;
/// The largest part file: the header at its longest, then every tile of the
/// largest image (a tile holds at least one pixel) with its pixels. Larger
/// files are refused before a byte is read.
pub const MAX_FILE: u64 =
    FIXED + MAX_NAME as u64 + TONEMAP_BYTES * MAX_TONEMAPS as u64 + (4 + 12 + 4 * MAX_CHANNELS) * MAX_PIXELS;

/// The contents of a part file (or of a checkpoint).
#[derive(Clone, Debug, PartialEq)]
pub struct PartFile {
    /// Finished (`true`) or a checkpoint.
    pub finished: bool,
    /// The job it belongs to.
    pub job: [u8; 32],
    /// Number of parts.
    pub n: u32,
    /// This part, from 1.
    pub k: u32,
    /// Images of the job.
    pub images: u32,
    /// This image's number among them, from 0.
    pub image: u32,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The camera's `ImageName`.
    pub image_name: String,
    /// The camera's tone mappings.
    pub tonemaps: Vec<Tonemap>,
    /// The scene's display transform.
    pub display: Display,
    /// The tiles held, ascending.
    pub tiles: Vec<u32>,
    /// Their pixels, tile after tile (empty when read with [`Pixels::Skip`]
    /// or [`Pixels::Check`]).
    pub pixels: Vec<Vec3>,
    /// The render passes held.
    pub passes: Passes,
    /// Their values, tile after tile
    /// ([`Aovs::push_rect`](luster_render::film::aov::Aovs::push_rect); empty as
    /// `pixels` is).
    pub aov: Vec<f32>,
}

/// What [`PartFile::read_with`] does with the pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pixels {
    /// Read them and check the checksum.
    Keep,
    /// Read them to check the checksum, and drop them.
    Check,
    /// Leave them unread: the header and the file's size are checked, the
    /// checksum is not (for progress reports).
    Skip,
}

/// Tiles of a `w`×`h` image (numbered row by row, as
/// [`luster_render::render::tile_origins`] lists them).
pub fn tile_count(w: u32, h: u32) -> u64 {
    let t = tile_size(w, h);
    u64::from(w.div_ceil(t)) * u64::from(h.div_ceil(t))
}

/// The pixel rectangle `(x0, y0, x1, y1)` of tile `i` of a `w`×`h` image.
pub fn tile_rect(i: u32, w: u32, h: u32) -> (u32, u32, u32, u32) {
    let t = tile_size(w, h);
    let cols = w.div_ceil(t).max(1);
    luster_render::render::tile_rect(w, h, ((i % cols) * t, (i / cols) * t))
}

/// Pixels in the listed tiles of a `w`×`h` image.
pub fn pixels_in(tiles: &[u32], w: u32, h: u32) -> u64 {
    tiles
        .iter()
        .map(|&i| {
            let (x0, y0, x1, y1) = tile_rect(i, w, h);
            u64::from(x1 - x0) * u64::from(y1 - y0)
        })
        .sum()
}

impl PartFile {
    /// The file's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(128 + self.tiles.len() * 4 + self.pixels.len() * 12);
        let u = |b: &mut Vec<u8>, v: u32| b.extend_from_slice(&v.to_le_bytes());
        b.extend_from_slice(MAGIC);
        u(&mut b, VERSION);
        u(&mut b, u32::from(self.finished));
        b.extend_from_slice(&self.job);
        for v in [
            self.n,
            self.k,
            self.images,
            self.image,
            self.width,
            self.height,
            tile_size(self.width, self.height),
        ] {
            u(&mut b, v);
        }
        u(&mut b, self.image_name.len() as u32);
        b.extend_from_slice(self.image_name.as_bytes());
        u(&mut b, self.tonemaps.len() as u32);
        for t in &self.tonemaps {
            b.push(match t.operator {
                Operator::Photographic => 0,
                Operator::Aces => 1,
                Operator::Filmic => 2,
            });
            for f in [t.key, t.burn_percent, t.saturation] {
                b.extend_from_slice(&f.to_le_bytes());
            }
            let (tag, g) = match t.gamma {
                Gamma::Power(g) => (0, g),
                Gamma::Srgb => (1, 0.0),
            };
            b.push(tag);
            b.extend_from_slice(&g.to_le_bytes());
        }
        b.push(match self.display {
            Display::Course => 0,
            Display::Srgb => 1,
            Display::Aces => 2,
            Display::Filmic => 3,
        });
        b.push(self.passes.bits());
        u(&mut b, self.tiles.len() as u32);
        for &t in &self.tiles {
            u(&mut b, t);
        }
        for p in &self.pixels {
            for c in p.to_array() {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        for v in &self.aov {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let crc = crc32fast::hash(&b);
        u(&mut b, crc);
        b
    }

    /// Reads a part file from memory; `what` names it in errors.
    pub fn decode(bytes: &[u8], what: &Path) -> Result<PartFile, ClusterError> {
        parse(bytes, bytes.len() as u64, what, Pixels::Keep)
    }

    /// Reads and checks `path` with its pixels.
    pub fn read(path: &Path) -> Result<PartFile, ClusterError> {
        PartFile::read_with(path, Pixels::Keep)
    }

    /// Reads and checks `path`: only a regular file of at most [`MAX_FILE`]
    /// bytes is opened (a FIFO, a device or a folder is refused unopened),
    /// and its size must be exactly what its header implies before a pixel
    /// is read.
    pub fn read_with(path: &Path, pixels: Pixels) -> Result<PartFile, ClusterError> {
        let cannot =
            |why: String| ClusterError(format!("{}: cannot read the part file: {why}", path.display()));
        let (file, len) = luster_core::file::open_regular(path, MAX_FILE).map_err(cannot)?;
        parse(std::io::BufReader::with_capacity(64 << 10, file), len, path, pixels)
    }

    /// Writes to `path` atomically (a temporary renamed into place), so a
    /// render killed while writing leaves the previous file whole.
    pub fn write(&self, path: &Path) -> Result<(), ClusterError> {
        let bytes = self.encode();
        luster_core::image::output::write_atomic(path, |w| {
            std::io::Write::write_all(w, &bytes).map_err(|e| luster_core::file::io_reason(&e))
        })
        .map_err(|e| ClusterError(e.to_string()))
    }
}

/// Feeds `data` to the part-file reader as a file on disk reaches it: written
/// as `f.png.part-1-of-1` into a scratch folder (one per thread), read in
/// each [`Pixels`] mode, then given to `luster merge` and `luster slurm
/// status` ([`super::merge`]). The entry point of the fuzz target `partfile`
/// and of the fuzz smoke test; an error is the expected answer to garbage,
/// the contract is to return.
pub fn fuzz(data: &[u8]) {
    thread_local! {
        static SCRATCH: tempfile::TempDir =
            tempfile::tempdir().unwrap_or_else(|e| panic!("no scratch folder for fuzzing: {e}"));
    }
    SCRATCH.with(|dir| {
        let path = dir.path().join("f.png.part-1-of-1");
        std::fs::write(&path, data).unwrap_or_else(|e| panic!("cannot write {}: {e}", path.display()));
        for mode in [Pixels::Keep, Pixels::Check, Pixels::Skip] {
            let _ = PartFile::read_with(&path, mode);
        }
        let _ = super::merge::status(dir.path());
        let _ = super::merge::merge(dir.path());
    });
}

/// Why a part file was refused, before the file's name is put in front.
enum Fail {
    /// Reading failed.
    Io(String),
    /// The contents are not a usable part file.
    Bad(String),
}

impl Fail {
    fn bad(why: &str) -> Fail {
        Fail::Bad(why.to_string())
    }
}

/// The part file's bytes in order: every read is checked against the bytes
/// the file has left first, so no count read from it can make the reader
/// allocate or loop beyond the file's size; the checksum runs along.
struct Reader<R> {
    src: R,
    /// The file's length.
    len: u64,
    /// Bytes not read yet.
    left: u64,
    crc: crc32fast::Hasher,
}

impl<R: Read> Reader<R> {
    fn fill(&mut self, buf: &mut [u8]) -> Result<(), Fail> {
        if buf.len() as u64 > self.left {
            return Err(Fail::bad("it is truncated or corrupt"));
        }
        self.src.read_exact(buf).map_err(|e| match e.kind() {
            // The file shrank since its size was read.
            std::io::ErrorKind::UnexpectedEof => Fail::bad("it is truncated or corrupt"),
            _ => Fail::Io(luster_core::file::io_reason(&e)),
        })?;
        self.left -= buf.len() as u64;
        self.crc.update(buf);
        Ok(())
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], Fail> {
        let mut b = [0; N];
        self.fill(&mut b)?;
        Ok(b)
    }
    fn u8(&mut self) -> Result<u8, Fail> {
        Ok(self.array::<1>()?[0])
    }
    fn u32(&mut self) -> Result<u32, Fail> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    fn f32(&mut self) -> Result<f32, Fail> {
        Ok(f32::from_bits(self.u32()?))
    }
    /// Checks that `count` items of `size` bytes, plus `after` bytes, fit in
    /// what is left.
    fn fits(&self, count: u64, size: u64, after: u64) -> Result<(), Fail> {
        match count.checked_mul(size).and_then(|b| b.checked_add(after)) {
            Some(b) if b <= self.left => Ok(()),
            _ => Err(Fail::bad("its header claims more than the file holds: truncated or corrupt")),
        }
    }
}

/// Reads a part file of `len` bytes from `src`.
fn parse(src: impl Read, len: u64, what: &Path, pixels: Pixels) -> Result<PartFile, ClusterError> {
    let mut r = Reader { src, len, left: len, crc: crc32fast::Hasher::new() };
    fields(&mut r, pixels).map_err(|f| match f {
        Fail::Io(why) => ClusterError(format!("{}: cannot read the part file: {why}", what.display())),
        Fail::Bad(why) => ClusterError(format!("{}: not a usable part file ({why})", what.display())),
    })
}

fn fields<R: Read>(r: &mut Reader<R>, pixels: Pixels) -> Result<PartFile, Fail> {
    let inconsistent = || Fail::bad("its header or tile list is inconsistent");
    let mut magic = [0u8; 8];
    let head = r.left.min(8) as usize;
    r.fill(&mut magic[..head])?;
    if head < 8 || &magic != MAGIC {
        return Err(Fail::bad("it does not start with LUSTPART"));
    }
    if r.left < FIXED - 8 {
        return Err(Fail::bad("it is truncated"));
    }
    let version = r.u32()?;
    if version != VERSION {
        return Err(Fail::Bad(format!("format version {version}, this luster reads {VERSION}")));
    }
    let finished = match r.u32()? {
        0 => false,
        1 => true,
        _ => return Err(inconsistent()),
    };
    let job: [u8; 32] = r.array()?;
    let [n, k, images, image, width, height, tile] = [(); 7].map(|_| r.u32());
    let (n, k, images, image, width, height, tile) = (n?, k?, images?, image?, width?, height?, tile?);
    // The scene reader's size limits and the split's bound what a header may
    // claim, so a forged one cannot make the reader or a merge build a huge
    // tile list or count to 2^32.
    let too_big = width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_PIXELS;
    if tile != tile_size(width, height)
        || n == 0
        || n > MAX_PARTS
        || k == 0
        || k > n
        || images > MAX_IMAGES
        || image >= images
        || width == 0
        || height == 0
        || too_big
    {
        return Err(inconsistent());
    }
    // What follows the name: t, the display and passes bytes, T and the checksum.
    let rest = 4 + 1 + 1 + 4 + 4;
    let len = r.u32()?;
    if len > MAX_NAME {
        return Err(Fail::bad("its image name is longer than any file name"));
    }
    r.fits(u64::from(len), 1, rest)?;
    let mut name = vec![0; len as usize];
    r.fill(&mut name)?;
    let image_name = String::from_utf8(name).map_err(|_| Fail::bad("its image name is not UTF-8"))?;
    if luster_core::text::file_name_problem(&image_name).is_some() {
        return Err(Fail::bad("its image name is not a file name luster writes"));
    }
    let nt = r.u32()?;
    if nt > MAX_TONEMAPS {
        return Err(inconsistent());
    }
    r.fits(u64::from(nt), TONEMAP_BYTES, rest - 4)?;
    let mut tonemaps = Vec::with_capacity(nt as usize);
    for _ in 0..nt {
        let operator = match r.u8()? {
            0 => Operator::Photographic,
            1 => Operator::Aces,
            2 => Operator::Filmic,
            _ => return Err(inconsistent()),
        };
        let (key, burn_percent, saturation) = (r.f32()?, r.f32()?, r.f32()?);
        let gamma = match (r.u8()?, r.f32()?) {
            (0, g) => Gamma::Power(g),
            (1, _) => Gamma::Srgb,
            _ => return Err(inconsistent()),
        };
        tonemaps.push(Tonemap { operator, key, burn_percent, saturation, gamma });
    }
    let display = match r.u8()? {
        0 => Display::Course,
        1 => Display::Srgb,
        2 => Display::Aces,
        3 => Display::Filmic,
        _ => return Err(inconsistent()),
    };
    let passes = Passes::from_bits(r.u8()?).ok_or_else(inconsistent)?;
    let count = tile_count(width, height);
    let t = r.u32()?;
    if u64::from(t) > count {
        return Err(inconsistent());
    }
    r.fits(u64::from(t), 4, 4)?;
    let mut tiles = Vec::with_capacity(t as usize);
    for _ in 0..t {
        tiles.push(r.u32()?);
    }
    if tiles.windows(2).any(|w| w[0] >= w[1]) || tiles.last().is_some_and(|&l| u64::from(l) >= count) {
        return Err(inconsistent());
    }
    // The size the header implies, checked before a pixel is read: a huge
    // or sparse file behind a small header is refused here.
    let p = pixels_in(&tiles, width, height);
    let channels = passes.channels() as u64;
    let expected = p * (12 + 4 * channels) + 4;
    if r.left != expected {
        let at = r.len - r.left;
        return Err(Fail::Bad(format!(
            "its header implies {} bytes, the file has {}: truncated or corrupt",
            at + expected,
            r.len
        )));
    }
    let (pixels, aov) = match pixels {
        Pixels::Skip => (Vec::new(), Vec::new()),
        _ => read_pixels(r, p, channels, pixels == Pixels::Keep)?,
    };
    Ok(PartFile {
        finished,
        job,
        n,
        k,
        images,
        image,
        width,
        height,
        image_name,
        tonemaps,
        display,
        tiles,
        pixels,
        passes,
        aov,
    })
}

/// Reads `p` pixels and their `channels` pass values each (kept when
/// `keep`) and checks the checksum that ends the file.
fn read_pixels<R: Read>(
    r: &mut Reader<R>,
    p: u64,
    channels: u64,
    keep: bool,
) -> Result<(Vec<Vec3>, Vec<f32>), Fail> {
    // The caller checked that the file holds exactly these bytes.
    let mut out = Vec::with_capacity(if keep { p as usize } else { 0 });
    // In chunks of whole pixels, so a large part never needs its bytes and
    // its pixels in memory at once.
    const CHUNK: u64 = 12 * 8192;
    let mut buf = vec![0u8; CHUNK as usize];
    let mut todo = p * 12;
    while todo > 0 {
        let chunk = &mut buf[..todo.min(CHUNK) as usize];
        r.fill(chunk)?;
        todo -= chunk.len() as u64;
        if keep {
            out.extend(chunk.chunks_exact(12).map(|c| {
                let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                Vec3::new(f(0), f(4), f(8))
            }));
        }
    }
    let mut aov = Vec::with_capacity(if keep { (p * channels) as usize } else { 0 });
    let mut todo = p * channels * 4;
    while todo > 0 {
        let chunk = &mut buf[..todo.min(CHUNK) as usize];
        r.fill(chunk)?;
        todo -= chunk.len() as u64;
        if keep {
            aov.extend(chunk.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])));
        }
    }
    let computed = r.crc.clone().finalize();
    if u32::from_le_bytes(r.array()?) != computed {
        return Err(Fail::bad("its checksum does not match: truncated or corrupt"));
    }
    Ok((out, aov))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PartFile {
        let (width, height) = (36, 20);
        let tiles = vec![0, 4, 14];
        let p = pixels_in(&tiles, width, height);
        PartFile {
            finished: true,
            job: [7; 32],
            n: 3,
            k: 1,
            images: 2,
            image: 1,
            width,
            height,
            image_name: "sub/a.exr".into(),
            tonemaps: vec![Tonemap::COURSE_DEFAULT, Tonemap::DISPLAY],
            display: Display::Filmic,
            tiles,
            pixels: (0..p).map(|i| Vec3::new(i as f32, 0.5, -1.0)).collect(),
            passes: Passes::parse("albedo,depth").unwrap(),
            aov: (0..p * 4).map(|i| i as f32 * 0.25).collect(),
        }
    }

    #[test]
    fn round_trips_and_edge_tiles_are_cut() {
        let f = sample();
        // A small image's tiles are 8×8: tile 0 is whole, tile 4 is 4×8
        // (the right edge), tile 14 is 4×4 (the corner).
        assert_eq!(f.pixels.len(), 64 + 32 + 16);
        assert_eq!(PartFile::decode(&f.encode(), Path::new("x")).unwrap(), f);
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_refused() {
        let bytes = sample().encode();
        for cut in [0, 7, 8, 15, 40, bytes.len() / 2, bytes.len() - 1] {
            let e = PartFile::decode(&bytes[..cut], Path::new("p")).unwrap_err().0;
            assert!(e.starts_with("p: not a usable part file"), "{e}");
        }
        for at in (0..bytes.len()).step_by(37) {
            let mut b = bytes.clone();
            b[at] ^= 0x10;
            assert!(PartFile::decode(&b, Path::new("p")).is_err(), "a flip at byte {at} went unnoticed");
        }
    }

    #[test]
    fn tiles_are_numbered_as_the_renderer_numbers_them() {
        for (w, h) in [(1, 1), (16, 16), (17, 5), (40, 20), (33, 70), (256, 256), (300, 257)] {
            let origins = luster_render::render::tile_origins(w, h);
            assert_eq!(tile_count(w, h), origins.len() as u64);
            for (i, &(x0, y0)) in origins.iter().enumerate() {
                let (a, b, x1, y1) = tile_rect(i as u32, w, h);
                assert_eq!((a, b), (x0, y0));
                let t = tile_size(w, h);
                assert_eq!((x1, y1), ((x0 + t).min(w), (y0 + t).min(h)));
            }
        }
    }

    /// Re-encodes `bytes` with the u32 at `at` set to `v` and a matching checksum.
    fn forged(bytes: &[u8], at: usize, v: u32) -> Vec<u8> {
        let mut b = bytes[..bytes.len() - 4].to_vec();
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        let crc = crc32fast::hash(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    #[test]
    fn counts_in_a_checksum_valid_header_are_bounded_by_the_file() {
        let f = sample();
        let bytes = f.encode();
        let name_at = 8 + 4 + 4 + 32 + 7 * 4;
        let tonemaps_at = name_at + 4 + f.image_name.len();
        let tiles_at = tonemaps_at + 4 + 18 * f.tonemaps.len() + 2;
        let images_at = 8 + 4 + 4 + 32 + 8;
        for (what, at, v) in [
            ("a 4 GiB name", name_at, u32::MAX),
            ("a name longer than the file", name_at, 4000),
            ("2^32-1 tone mappings", tonemaps_at, u32::MAX),
            ("more tone mappings than the file holds", tonemaps_at, 1000),
            ("2^32-1 tiles", tiles_at, u32::MAX),
            ("2^32-1 images", images_at, u32::MAX),
            ("2^32-1 parts", 8 + 4 + 4 + 32, u32::MAX),
        ] {
            let e = PartFile::decode(&forged(&bytes, at, v), Path::new("p")).unwrap_err().0;
            assert!(e.starts_with("p: not a usable part file"), "{what}: {e}");
        }
    }

    #[test]
    fn the_size_is_checked_against_the_header_before_the_pixels() {
        let mut bytes = sample().encode();
        bytes.extend_from_slice(&[0; 12]);
        for mode in [Pixels::Keep, Pixels::Skip] {
            let e = parse(&bytes[..], bytes.len() as u64, Path::new("p"), mode).unwrap_err().0;
            assert!(e.contains("its header implies") && e.contains("truncated or corrupt"), "{e}");
        }
        // Headers alone do not check the checksum; the pixels are not read.
        let f = sample();
        let mut flipped = f.encode();
        let last = flipped.len() - 1;
        flipped[last] ^= 1;
        let head = parse(&flipped[..], flipped.len() as u64, Path::new("p"), Pixels::Skip).unwrap();
        assert!(head.pixels.is_empty() && head.aov.is_empty() && head.tiles == f.tiles);
        assert_eq!(head.passes, f.passes);
        assert!(parse(&flipped[..], flipped.len() as u64, Path::new("p"), Pixels::Check).is_err());
    }

    #[test]
    fn names_a_terminal_or_a_shell_would_act_on_are_refused() {
        let mut f = sample();
        f.image_name = "a\u{1b}[2J.png".into();
        let e = PartFile::decode(&f.encode(), Path::new("p")).unwrap_err().0;
        assert!(e.contains("not a file name luster writes") && !e.contains('\u{1b}'), "{e}");
    }

    #[test]
    fn special_files_are_refused_unopened() {
        let e = PartFile::read(Path::new("/dev/zero")).unwrap_err().0;
        assert_eq!(e, "/dev/zero: cannot read the part file: it is a device, not a regular file");
    }
}
