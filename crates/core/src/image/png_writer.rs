//! PNG output for 8-bit RGB images, encoded on two threads: the rows are
//! filtered in bands on the rayon pool while the calling thread compresses
//! the bands already filtered, in order, into the file's one zlib stream.
//!
//! The `png` crate writes the container (signature, `IHDR`, `IDAT`, `IEND`,
//! their CRCs) and `fdeflate` the stream, as the `image` crate's own PNG
//! encoder does at its default (fast) setting; what this module adds is the
//! row filter, PNG's adaptive rule (per row, the one of Sub, Up, Average and
//! Paeth whose bytes, read as signed, have the smallest absolute sum), run
//! beside the compressor instead of before it: the encoder runs after the
//! image is done, with the other cores idle, and `fdeflate` writes one
//! stream that cannot be split, so filtering is the part that can overlap.
//! The bytes do not depend on the number of threads: the bands are
//! compressed in row order whoever filtered them.

use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Mutex;

/// Filtered bytes per band: a few dozen bands for an 800×800 image, each
/// long enough that claiming it costs nothing beside filtering it.
const BAND_BYTES: usize = 64 << 10;

/// Bytes per pixel (RGB, 8 bits a sample): the filters' left neighbour.
const BPP: usize = 3;

/// Writes `rgb` (row-major, top row first, 3 bytes a pixel) to `out` as a
/// PNG image.
pub fn write_rgb8<W: Write>(out: W, width: u32, height: u32, rgb: &[u8]) -> Result<(), String> {
    let stride = width as usize * BPP;
    if width == 0 || height == 0 || rgb.len() != stride * height as usize {
        return Err("the pixel buffer does not match the size".into());
    }
    let zlib = compress(rgb, stride).map_err(|e| e.to_string())?;
    let mut encoder = png::Encoder::new(out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    // A chunk's length is at most 2³¹ − 1 bytes.
    for part in zlib.chunks(1 << 30) {
        writer.write_chunk(png::chunk::IDAT, part).map_err(|e| e.to_string())?;
    }
    writer.finish().map_err(|e| e.to_string())
}

/// The zlib stream of the filtered rows of `rgb` (`stride` bytes a row).
fn compress(rgb: &[u8], stride: usize) -> std::io::Result<Vec<u8>> {
    let line = stride + 1;
    let rows = rgb.len() / stride;
    let band_rows = (BAND_BYTES / line).max(1);
    let mut filtered = vec![0u8; line * rows];
    let bands: Vec<Mutex<&mut [u8]>> = filtered.chunks_mut(band_rows * line).map(Mutex::new).collect();
    let done: Vec<AtomicBool> = bands.iter().map(|_| AtomicBool::new(false)).collect();
    let next = AtomicUsize::new(0);
    // Filters the next unclaimed band; false when none is left.
    let filter_next = || {
        let b = next.fetch_add(1, Ordering::Relaxed);
        let Some(band) = bands.get(b) else { return false };
        let mut band = band.lock().unwrap_or_else(|e| e.into_inner());
        for (i, out) in band.chunks_mut(line).enumerate() {
            let y = b * band_rows + i;
            let prev = if y == 0 { None } else { Some(&rgb[(y - 1) * stride..y * stride]) };
            filter_row(prev, &rgb[y * stride..(y + 1) * stride], out);
        }
        done[b].store(true, Ordering::Release);
        true
    };
    let mut z = fdeflate::Compressor::new(std::io::Cursor::new(Vec::with_capacity(line * rows / 2)))?;
    rayon::scope(|s| -> std::io::Result<()> {
        s.spawn(|_| while filter_next() {});
        for (b, band) in bands.iter().enumerate() {
            let mut spins = 0u32;
            while !done[b].load(Ordering::Acquire) {
                // The band is the other thread's: filter one ahead meanwhile,
                // or wait for it.
                if !filter_next() {
                    spins += 1;
                    if spins < 64 {
                        std::hint::spin_loop();
                    } else {
                        std::thread::yield_now();
                    }
                }
            }
            z.write_data(&band.lock().unwrap_or_else(|e| e.into_inner()))?;
        }
        Ok(())
    })?;
    drop(bands);
    let zlib = z.finish()?.into_inner();
    // Noise compresses badly with fdeflate's fixed code: stored blocks are
    // then smaller (the `png` crate makes the same choice).
    if zlib.len() > fdeflate::StoredOnlyCompressor::<()>::compressed_size(filtered.len()) {
        let mut stored = fdeflate::StoredOnlyCompressor::new(std::io::Cursor::new(Vec::new()))?;
        stored.write_data(&filtered)?;
        return Ok(stored.finish()?.into_inner());
    }
    Ok(zlib)
}

/// The PNG filters the adaptive rule chooses from, by their type byte.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Filter {
    Sub = 1,
    Up = 2,
    Average = 3,
    Paeth = 4,
}

/// Bytes summed in 16 bits: 256 of at most 128 each.
const RUN: usize = 256;

/// Writes row `cur` (below `prev`, `None` for the top row) filtered into
/// `out`: the filter's type byte, then the row. Of equal sums the later
/// filter in the order Up, Sub, Average, Paeth is taken, as libpng and the
/// `png` crate do.
fn filter_row(prev: Option<&[u8]>, cur: &[u8], out: &mut [u8]) {
    let zeros;
    let prev = match prev {
        Some(p) => p,
        None => {
            zeros = vec![0u8; cur.len()];
            &zeros
        }
    };
    let [sub, up, average, paeth] = costs(prev, cur);
    let mut best = (up, Filter::Up);
    for (sum, f) in [(sub, Filter::Sub), (average, Filter::Average), (paeth, Filter::Paeth)] {
        if sum <= best.0 {
            best = (sum, f);
        }
    }
    out[0] = best.1 as u8;
    write(best.1, prev, cur, &mut out[1..]);
}

/// The filters' costs (Sub, Up, Average, Paeth): the sums of their bytes'
/// magnitudes, read as signed. One pass computes all four, 16-bit sums over
/// runs short enough not to overflow, so that it runs as vector code.
fn costs(prev: &[u8], cur: &[u8]) -> [u64; 4] {
    let n = cur.len().min(prev.len());
    let mut total = [0u64; 4];
    let mag = |v: u8| u16::from((v as i8).unsigned_abs());
    // The first pixel has no left neighbour: its `a` and `c` are 0.
    for j in 0..BPP.min(n) {
        for (t, f) in total.iter_mut().zip([Filter::Sub, Filter::Up, Filter::Average, Filter::Paeth]) {
            *t += u64::from(mag(cur[j].wrapping_sub(predict(f, 0, prev[j], 0))));
        }
    }
    let mut start = BPP.min(n);
    while start < n {
        let end = (start + RUN).min(n);
        let m = end - start;
        let (x, b) = (&cur[start..end], &prev[start..end]);
        let (a, c) = (&cur[start - BPP..end - BPP], &prev[start - BPP..end - BPP]);
        let mut s = [0u16; 4];
        for k in 0..m {
            let (x, a, b, c) = (x[k], a[k], b[k], c[k]);
            s[0] += mag(x.wrapping_sub(a));
            s[1] += mag(x.wrapping_sub(b));
            s[2] += mag(x.wrapping_sub(average(a, b)));
            s[3] += mag(x.wrapping_sub(paeth(a, b, c)));
        }
        for (t, v) in total.iter_mut().zip(s) {
            *t += u64::from(v);
        }
        start = end;
    }
    total
}

/// Writes row `cur` below `prev` filtered by `f` into `out`.
fn write(f: Filter, prev: &[u8], cur: &[u8], out: &mut [u8]) {
    let n = cur.len().min(prev.len()).min(out.len());
    let h = BPP.min(n);
    for j in 0..h {
        out[j] = cur[j].wrapping_sub(predict(f, 0, prev[j], 0));
    }
    let (o, x, b) = (&mut out[h..n], &cur[h..n], &prev[h..n]);
    let (a, c) = (&cur[..n - h], &prev[..n - h]);
    let m = o.len();
    let (x, a, b, c) = (&x[..m], &a[..m], &b[..m], &c[..m]);
    match f {
        Filter::Sub => (0..m).for_each(|k| o[k] = x[k].wrapping_sub(a[k])),
        Filter::Up => (0..m).for_each(|k| o[k] = x[k].wrapping_sub(b[k])),
        Filter::Average => (0..m).for_each(|k| o[k] = x[k].wrapping_sub(average(a[k], b[k]))),
        Filter::Paeth => (0..m).for_each(|k| o[k] = x[k].wrapping_sub(paeth(a[k], b[k], c[k]))),
    }
}

/// Filter `f`'s prediction of a byte from the bytes left of it (`a`),
/// above it (`b`) and above-left (`c`). The vector loops of [`costs`] and
/// [`write`] spell it out per filter; the first pixel's few bytes use it.
#[inline(always)]
fn predict(f: Filter, a: u8, b: u8, c: u8) -> u8 {
    match f {
        Filter::Sub => a,
        Filter::Up => b,
        Filter::Average => average(a, b),
        Filter::Paeth => paeth(a, b, c),
    }
}

/// The Average filter's predictor: the mean of the left and upper bytes,
/// rounded down.
#[inline(always)]
fn average(a: u8, b: u8) -> u8 {
    ((u16::from(a) + u16::from(b)) / 2) as u8
}

/// The Paeth predictor: of the left, upper and upper-left bytes `a`, `b`,
/// `c`, the one nearest to `p = a + b − c`, ties going to `a`, then `b`.
/// Branch-free, in the form of stb_image's decoder: `c` is taken when `p`
/// lies outside `[min(a, b), max(a, b)]` by less than it lies from `c`,
/// which comparing `3c − (a + b)` with the two decides.
#[inline(always)]
fn paeth(a: u8, b: u8, c: u8) -> u8 {
    let (a, b, c) = (i16::from(a), i16::from(b), i16::from(c));
    let thresh = 3 * c - (a + b);
    let (lo, hi) = (a.min(b), a.max(b));
    let t0 = if hi <= thresh { lo } else { c };
    (if thresh <= lo { hi } else { t0 }) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    fn encode(width: u32, height: u32, rgb: &[u8]) -> Vec<u8> {
        let mut out = Vec::new();
        write_rgb8(&mut out, width, height, rgb).unwrap();
        out
    }

    fn decode(png: &[u8]) -> (u32, u32, Vec<u8>) {
        let img = image::load_from_memory_with_format(png, image::ImageFormat::Png).unwrap();
        assert_eq!(img.color(), image::ColorType::Rgb8);
        let img = img.into_rgb8();
        (img.width(), img.height(), img.into_raw())
    }

    /// Deterministic bytes: xorshift noise, or a smooth pattern with edges
    /// (which every filter wins somewhere).
    fn pixels(width: u32, height: u32, noise: bool) -> Vec<u8> {
        let mut s = 0x9e37_79b9_u32 ^ width.wrapping_mul(31) ^ height;
        (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .flat_map(|(x, y)| {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                if noise {
                    s.to_le_bytes()[..3].try_into().unwrap_or([0; 3])
                } else {
                    let band = if (x / 7 + y / 5) % 3 == 0 { 90 } else { 0 };
                    [(x * 3 + band) as u8, (y * 2 + x / 2) as u8, ((x ^ y) + (s % 3)) as u8]
                }
            })
            .collect()
    }

    #[test]
    fn images_of_every_shape_decode_to_their_pixels() {
        for (w, h) in [(1, 1), (1, 9), (9, 1), (2, 3), (37, 11), (300, 120), (700, 300)] {
            for noise in [false, true] {
                let rgb = pixels(w, h, noise);
                assert_eq!(decode(&encode(w, h, &rgb)), (w, h, rgb), "{w}×{h}, noise {noise}");
            }
        }
    }

    #[test]
    fn smooth_images_compress_and_noise_falls_back_to_stored_blocks() {
        let (w, h) = (300, 120);
        let raw = (w * h * 3) as usize;
        assert!(encode(w, h, &pixels(w, h, false)).len() < raw / 2);
        let noisy = encode(w, h, &pixels(w, h, true)).len();
        // Stored blocks: the raw bytes, a type byte a row and 5 bytes a block.
        assert!(noisy > raw && noisy < raw + h as usize + raw / 1000 + 100, "{noisy} bytes for {raw}");
    }

    #[test]
    fn the_bytes_do_not_depend_on_the_threads() {
        let (w, h) = (700, 300);
        let rgb = pixels(w, h, false);
        let on = |n| {
            rayon::ThreadPoolBuilder::new().num_threads(n).build().unwrap().install(|| encode(w, h, &rgb))
        };
        let one = on(1);
        assert_eq!(on(2), one);
        assert_eq!(on(3), one);
    }

    #[test]
    fn each_filter_is_chosen_for_the_row_it_predicts_exactly() {
        let stride = 50 * BPP;
        let prev = pixels(50, 1, true);
        // Row `j`'s byte from the bytes left, above and above-left of it.
        let made = |rule: &dyn Fn(u8, u8, u8) -> u8| {
            let mut row = vec![0u8; stride];
            for j in 0..stride {
                let (a, c) = if j >= BPP { (row[j - BPP], prev[j - BPP]) } else { (0, 0) };
                row[j] = rule(a, prev[j], c);
            }
            row
        };
        let ramp: Vec<u8> = (0..stride).map(|j| (j * 5) as u8).collect();
        let cases = [
            (Filter::Sub, ramp.clone()),
            (Filter::Average, made(&|a, b, _| average(a, b))),
            (Filter::Paeth, made(&|a, b, c| paeth(a, b, c))),
        ];
        let mut out = vec![0u8; stride + 1];
        for (want, row) in cases {
            filter_row(Some(&prev), &row, &mut out);
            assert_eq!(out[0], want as u8, "{want:?}");
            if want != Filter::Sub {
                assert!(out[1..].iter().all(|&v| v == 0), "{want:?} leaves a residue");
            }
        }
        // A flat image costs nothing under every filter: the tie goes to Paeth.
        let flat = vec![7u8; stride];
        filter_row(Some(&flat), &flat, &mut out);
        assert_eq!(out[0], Filter::Paeth as u8);
        // The top row is filtered against zeros, where Paeth predicts what
        // Sub does (the left byte) and wins the tie.
        filter_row(None, &ramp, &mut out);
        assert_eq!(out[0], Filter::Paeth as u8);
        assert_eq!(&out[1..4], &ramp[..3]);
        assert!(out[4..].iter().all(|&v| v == 15));
    }

    /// The rule from the specification, byte by byte: every filter's row, the
    /// cheapest (later ones winning ties) chosen and written.
    #[test]
    fn rows_are_filtered_as_the_rule_says() {
        let (w, h) = (61, 12);
        for noise in [false, true] {
            let rgb = pixels(w, h, noise);
            let stride = w as usize * BPP;
            let mut out = vec![0u8; stride + 1];
            for y in 0..h as usize {
                let cur = &rgb[y * stride..(y + 1) * stride];
                let prev = if y == 0 { vec![0; stride] } else { rgb[(y - 1) * stride..y * stride].to_vec() };
                let mut best: Option<(u64, u8, Vec<u8>)> = None;
                for f in 1..=4u8 {
                    let row: Vec<u8> = (0..stride)
                        .map(|j| {
                            let (a, c) = if j >= BPP { (cur[j - BPP], prev[j - BPP]) } else { (0, 0) };
                            let b = prev[j];
                            let p = match f {
                                1 => a,
                                2 => b,
                                3 => ((u16::from(a) + u16::from(b)) / 2) as u8,
                                _ => paeth(a, b, c),
                            };
                            cur[j].wrapping_sub(p)
                        })
                        .collect();
                    let cost = row.iter().map(|&v| u64::from((v as i8).unsigned_abs())).sum();
                    // Up is tried first, then Sub, Average, Paeth.
                    let order = [0, 2, 1, 3, 4][f as usize];
                    if best.as_ref().is_none_or(|(c, o, _)| cost < *c || (cost == *c && order > *o)) {
                        best = Some((cost, order, row));
                    }
                }
                let (_, order, row) = best.unwrap();
                filter_row((y > 0).then_some(&prev[..]), cur, &mut out);
                assert_eq!(out[0], [0, 2, 1, 3, 4][order as usize], "row {y}, noise {noise}");
                assert_eq!(&out[1..], &row[..], "row {y}, noise {noise}");
            }
        }
    }

    #[test]
    fn the_branch_free_paeth_predictor_is_the_specifications() {
        let spec = |a: u8, b: u8, c: u8| {
            let p = i16::from(a) + i16::from(b) - i16::from(c);
            let (pa, pb, pc) = ((p - i16::from(a)).abs(), (p - i16::from(b)).abs(), (p - i16::from(c)).abs());
            if pa <= pb && pa <= pc {
                a
            } else if pb <= pc {
                b
            } else {
                c
            }
        };
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                for c in 0..=255u8 {
                    assert_eq!(paeth(a, b, c), spec(a, b, c), "a {a}, b {b}, c {c}");
                }
            }
        }
    }

    #[test]
    fn a_buffer_of_the_wrong_size_is_refused() {
        let e = write_rgb8(Vec::new(), 2, 2, &[0; 11]).unwrap_err();
        assert!(e.contains("does not match"), "{e}");
        assert!(write_rgb8(Vec::new(), 0, 2, &[]).is_err());
    }
}
