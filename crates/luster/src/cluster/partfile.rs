//! The part file: the finished tiles of one image rendered by one part of a
//! split render, in linear film values, with what `luster merge` needs to
//! check that the parts in a folder belong together.
//!
//! All numbers little-endian; `u32` unless said otherwise:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | magic `LUSTPART` |
//! | 4 | format version (2) |
//! | 4 | state: 1 a finished part, 0 a checkpoint of an unfinished one |
//! | 32 | job id: SHA-256 of the luster version, the scene files' bytes and the options that change pixels ([`super::JobId`]) |
//! | 4 + 4 | N, K: this is part K of N |
//! | 4 + 4 | M, i: this image is image i (from 0) of the M images of the job |
//! | 4 + 4 | width, height in pixels |
//! | 4 | tile edge in pixels (16) |
//! | 4 + L | L, then the image's `ImageName` (UTF-8) |
//! | 4 + 18·t | t, then the camera's tone mappings: operator (u8: 0 photographic, 1 ACES, 2 filmic), key, burn-out, saturation (f32), gamma (u8: 0 power, 1 sRGB; f32 exponent) |
//! | 1 | the scene's display transform (u8: 0 course, 1 sRGB, 2 ACES, 3 filmic) |
//! | 4 + 4·T | T, then the indices of the tiles held, ascending (tiles are numbered row by row) |
//! | 12·P | the tiles' pixels, tile after tile, each row by row: linear RGB as three f32 |
//! | 4 | CRC-32 (IEEE) of every byte before it |
//!
//! P is the number of pixels in the listed tiles (edge tiles are cut at the
//! image border).

use super::ClusterError;
use luster_core::math::Vec3;
use luster_core::tonemap::{Display, Gamma, Operator, Tonemap};
use luster_render::render::{tile_origins, TILE};
use luster_scene::ceng795::camera::{MAX_PIXELS, MAX_SIDE};
use std::path::Path;

const MAGIC: &[u8; 8] = b"LUSTPART";
const VERSION: u32 = 2;

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
    /// Their pixels, tile after tile.
    pub pixels: Vec<Vec3>,
}

/// The pixel rectangle of tile `i` of a `w`×`h` image.
pub fn tile_rect(origins: &[(u32, u32)], i: u32, w: u32, h: u32) -> (u32, u32, u32, u32) {
    let (x0, y0) = origins[i as usize];
    (x0, y0, (x0 + TILE).min(w), (y0 + TILE).min(h))
}

/// Pixels in the listed tiles of a `w`×`h` image.
pub fn pixels_in(tiles: &[u32], w: u32, h: u32) -> usize {
    let origins = tile_origins(w, h);
    tiles
        .iter()
        .map(|&i| {
            let (x0, y0, x1, y1) = tile_rect(&origins, i, w, h);
            ((x1 - x0) * (y1 - y0)) as usize
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
        for v in [self.n, self.k, self.images, self.image, self.width, self.height, TILE] {
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
        u(&mut b, self.tiles.len() as u32);
        for &t in &self.tiles {
            u(&mut b, t);
        }
        for p in &self.pixels {
            for c in p.to_array() {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        let crc = crc32fast::hash(&b);
        u(&mut b, crc);
        b
    }

    /// Reads a part file; `what` names it in errors.
    pub fn decode(bytes: &[u8], what: &Path) -> Result<PartFile, ClusterError> {
        let bad = |why: &str| ClusterError(format!("{}: not a usable part file ({why})", what.display()));
        if bytes.len() < 8 || &bytes[..8] != MAGIC {
            return Err(bad("it does not start with LUSTPART"));
        }
        if bytes.len() < 16 {
            return Err(bad("it is truncated"));
        }
        let (body, tail) = bytes.split_at(bytes.len() - 4);
        let mut r = Cursor { b: body, at: 8 };
        let version = r.u32().ok_or_else(|| bad("it is truncated"))?;
        if version != VERSION {
            return Err(bad(&format!("format version {version}, this luster reads {VERSION}")));
        }
        let stored = u32::from_le_bytes([tail[0], tail[1], tail[2], tail[3]]);
        if crc32fast::hash(body) != stored {
            return Err(bad("its checksum does not match: truncated or corrupt"));
        }
        let parsed = (|| {
            let finished = r.u32()? == 1;
            let job: [u8; 32] = r.take(32)?.try_into().ok()?;
            let [n, k, images, image, width, height, tile] = [(); 7].map(|_| r.u32());
            let (n, k, images, image, width, height, tile) =
                (n?, k?, images?, image?, width?, height?, tile?);
            // The scene reader's size limits bound what a header may claim, so a
            // forged one cannot make the reader build a huge tile list.
            let too_big =
                width > MAX_SIDE || height > MAX_SIDE || u64::from(width) * u64::from(height) > MAX_PIXELS;
            if tile != TILE
                || n == 0
                || k == 0
                || k > n
                || image >= images
                || width == 0
                || height == 0
                || too_big
            {
                return None;
            }
            let len = r.u32()? as usize;
            let image_name = String::from_utf8(r.take(len)?.to_vec()).ok()?;
            let nt = r.u32()? as usize;
            let mut tonemaps = Vec::with_capacity(nt.min(64));
            for _ in 0..nt {
                let operator = match r.u8()? {
                    0 => Operator::Photographic,
                    1 => Operator::Aces,
                    2 => Operator::Filmic,
                    _ => return None,
                };
                let (key, burn_percent, saturation) = (r.f32()?, r.f32()?, r.f32()?);
                let gamma = match (r.u8()?, r.f32()?) {
                    (0, g) => Gamma::Power(g),
                    (1, _) => Gamma::Srgb,
                    _ => return None,
                };
                tonemaps.push(Tonemap { operator, key, burn_percent, saturation, gamma });
            }
            let display = match r.u8()? {
                0 => Display::Course,
                1 => Display::Srgb,
                2 => Display::Aces,
                3 => Display::Filmic,
                _ => return None,
            };
            let count = tile_origins(width, height).len();
            let t = r.u32()? as usize;
            if t > count {
                return None;
            }
            let tiles: Vec<u32> = (0..t).map(|_| r.u32()).collect::<Option<_>>()?;
            if tiles.windows(2).any(|w| w[0] >= w[1]) || tiles.last().is_some_and(|&l| l as usize >= count) {
                return None;
            }
            let p = pixels_in(&tiles, width, height);
            let raw = r.take(p.checked_mul(12)?)?;
            if r.at != body.len() {
                return None;
            }
            let pixels = raw
                .chunks_exact(12)
                .map(|c| {
                    let f = |i: usize| f32::from_le_bytes([c[i], c[i + 1], c[i + 2], c[i + 3]]);
                    Vec3::new(f(0), f(4), f(8))
                })
                .collect();
            Some(PartFile {
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
            })
        })();
        parsed.ok_or_else(|| bad("its header or tile list is inconsistent"))
    }

    /// Reads and decodes `path`.
    pub fn read(path: &Path) -> Result<PartFile, ClusterError> {
        let bytes = std::fs::read(path).map_err(|e| {
            ClusterError(format!(
                "{}: cannot read the part file: {}",
                path.display(),
                luster_core::file::io_reason(&e)
            ))
        })?;
        PartFile::decode(&bytes, path)
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

struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let end = self.at.checked_add(n)?;
        let s = self.b.get(self.at..end)?;
        self.at = end;
        Some(s)
    }
    fn u8(&mut self) -> Option<u8> {
        Some(self.take(1)?[0])
    }
    fn u32(&mut self) -> Option<u32> {
        Some(u32::from_le_bytes(self.take(4)?.try_into().ok()?))
    }
    fn f32(&mut self) -> Option<f32> {
        Some(f32::from_bits(self.u32()?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> PartFile {
        let (width, height) = (40, 20);
        let tiles = vec![0, 2, 5];
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
        }
    }

    #[test]
    fn round_trips_and_edge_tiles_are_cut() {
        let f = sample();
        // Tiles 0 and 2 are 16×16 and 8×16 (the right edge); tile 5 is 8×4.
        assert_eq!(f.pixels.len(), 256 + 128 + 32);
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
}
