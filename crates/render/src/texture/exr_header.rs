//! Checks an OpenEXR file's header before any pixel is decoded.
//!
//! The `image` crate bounds an EXR by its width × height × 4 floats, but the
//! `exr` decoder sizes each compressed block from the header's own channel
//! list and data window: a hostile header (thousands of channels, a window
//! of 2³¹ columns, giant tiles) makes it allocate hundreds of gigabytes for
//! one PIZ block, and the process aborts. So the header is read first with
//! `exr`'s metadata reader, and anything a texture or environment map could
//! not sensibly be is refused with a sentence naming the file.

use std::path::Path;

use exr::meta::{BlockDescription, MetaData};

use super::image::MAX_EDGE;

/// Most channels a texture needs (RGBA, plus a few AOVs some tools write).
const MAX_CHANNELS: usize = 64;
/// Largest layer a texture may declare, in bytes of decoded samples.
const MAX_LAYER_BYTES: u64 = 4 << 30;
/// Most layers (parts) in one file.
const MAX_PARTS: usize = 16;

/// Whether `start` begins with the OpenEXR magic number.
pub fn is_exr(start: &[u8]) -> bool {
    start.starts_with(&[0x76, 0x2f, 0x31, 0x01])
}

/// Reads the header of the EXR at `path` and refuses sizes no texture has.
pub fn check(path: &Path) -> Result<(), String> {
    let bad = |why: String| format!("cannot decode image {}: {why}", path.display());
    let meta =
        MetaData::read_from_file(path, false).map_err(|e| bad(format!("its EXR header is invalid ({e})")))?;
    if meta.headers.len() > MAX_PARTS {
        return Err(bad(format!("it has {} parts; at most {MAX_PARTS} are read", meta.headers.len())));
    }
    for header in &meta.headers {
        if header.deep {
            return Err(bad("it holds deep data, which textures do not use".into()));
        }
        let (w, h) = (header.layer_size.width(), header.layer_size.height());
        if w == 0 || h == 0 || w > MAX_EDGE as usize || h > MAX_EDGE as usize {
            return Err(bad(format!("its data window is {w}×{h}; edges must be 1 to {MAX_EDGE}")));
        }
        let channels = header.channels.list.len();
        if channels > MAX_CHANNELS {
            return Err(bad(format!("it has {channels} channels; at most {MAX_CHANNELS} are read")));
        }
        let bytes = w as u64 * h as u64 * header.channels.bytes_per_pixel as u64;
        if bytes > MAX_LAYER_BYTES {
            return Err(bad(format!("its {w}×{h} layer of {channels} channels needs more than 4 GiB")));
        }
        if let BlockDescription::Tiles(tiles) = &header.blocks {
            let (tw, th) = (tiles.tile_size.width(), tiles.tile_size.height());
            if tw == 0 || th == 0 || tw > MAX_EDGE as usize || th > MAX_EDGE as usize {
                return Err(bad(format!("its tiles are {tw}×{th}; edges must be 1 to {MAX_EDGE}")));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scan-line PIZ EXR header with `channels` float channels over a
    /// `w`×`h` window, one chunk of garbage after it.
    fn exr_bytes(channels: usize, w: i32, h: i32) -> Vec<u8> {
        fn attr(out: &mut Vec<u8>, name: &str, kind: &str, value: &[u8]) {
            out.extend_from_slice(name.as_bytes());
            out.push(0);
            out.extend_from_slice(kind.as_bytes());
            out.push(0);
            out.extend_from_slice(&(value.len() as i32).to_le_bytes());
            out.extend_from_slice(value);
        }
        let mut out = vec![0x76, 0x2f, 0x31, 0x01, 2, 0, 0, 0];
        let mut list = Vec::new();
        for c in 0..channels {
            list.extend_from_slice(format!("c{c:05}").as_bytes());
            list.push(0);
            list.extend_from_slice(&2i32.to_le_bytes());
            list.extend_from_slice(&[0, 0, 0, 0]);
            list.extend_from_slice(&1i32.to_le_bytes());
            list.extend_from_slice(&1i32.to_le_bytes());
        }
        list.push(0);
        attr(&mut out, "channels", "chlist", &list);
        attr(&mut out, "compression", "compression", &[4]);
        let window: Vec<u8> = [0, 0, w - 1, h - 1].iter().flat_map(|v: &i32| v.to_le_bytes()).collect();
        attr(&mut out, "dataWindow", "box2i", &window);
        attr(&mut out, "displayWindow", "box2i", &window);
        attr(&mut out, "lineOrder", "lineOrder", &[0]);
        attr(&mut out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
        attr(&mut out, "screenWindowCenter", "v2f", &[0; 8]);
        attr(&mut out, "screenWindowWidth", "float", &1f32.to_le_bytes());
        out.push(0);
        let chunks = (h as u64).div_ceil(32);
        let table_end = out.len() as u64 + 8 * chunks;
        for i in 0..chunks {
            out.extend_from_slice(&(table_end + i * 40).to_le_bytes());
        }
        for i in 0..chunks {
            out.extend_from_slice(&(i as i32 * 32).to_le_bytes());
            out.extend_from_slice(&32i32.to_le_bytes());
            out.extend_from_slice(&[0xab; 32]);
        }
        out
    }

    fn load(bytes: &[u8]) -> Result<(), String> {
        let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
        let path = dir.path().join("map.exr");
        std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
        crate::texture::image::Image::load(&path).map(|_| ())
    }

    #[test]
    fn hostile_headers_are_refused_before_decoding() {
        // 3000 float channels over 30000×32: one PIZ block would ask for 11 GB.
        let err = load(&exr_bytes(3000, 30000, 32)).unwrap_err();
        assert!(err.contains("3000 channels") && err.contains("map.exr"), "{err}");
        let err = load(&exr_bytes(3, 40000, 32)).unwrap_err();
        assert!(err.contains("40000×32") && err.contains("edges must be"), "{err}");
        let err = load(&exr_bytes(60, 32768, 32768)).unwrap_err();
        assert!(err.contains("4 GiB"), "{err}");
    }

    #[test]
    fn a_plausible_header_passes_to_the_decoder() {
        // The header is fine, so the refusal comes from the decoder's reading
        // of the garbage block, not from this check.
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ok.exr");
        std::fs::write(&path, exr_bytes(3, 64, 32)).unwrap();
        assert!(check(&path).is_ok());
        assert!(crate::texture::image::Image::load(&path).is_err());
    }

    #[test]
    fn magic_number() {
        assert!(is_exr(&[0x76, 0x2f, 0x31, 0x01, 2]));
        assert!(!is_exr(b"\x89PNG"));
        assert!(!is_exr(&[0x76, 0x2f]));
    }
}
