//! Reading a glTF file into a validated document and its buffers: the JSON
//! of a `.gltf` or the chunks of a `.glb` container, then every buffer from
//! the GLB's BIN chunk, a `data:` URI or a file beside the glTF.
//!
//! Every error names the file and where in it the fault is: the GLB header
//! or chunk, a JSON line and column, or the JSON path the `gltf` crate's
//! validation reports (`accessors[3].bufferView: the index is out of range`).

use crate::error::{shown_token, Loc, SceneError};
use base64::Engine;
use luster_core::file;
use std::path::{Path, PathBuf};

/// Largest glTF or GLB file, and largest buffer file, accepted.
pub const MAX_BYTES: u64 = 1 << 31;

/// A glTF file read: its validated document and its buffers' bytes.
pub struct GltfFile {
    /// The file.
    pub file: PathBuf,
    /// The folder relative URIs resolve against.
    pub base_dir: PathBuf,
    /// The validated document.
    pub doc: gltf::Document,
    /// `buffers[i]` holds buffer `i`'s bytes (at least its `byteLength`).
    pub buffers: Vec<Vec<u8>>,
}

/// An error at a JSON path (or a GLB part) of `file`.
pub fn at(file: &Path, path: impl Into<String>, msg: impl Into<String>) -> SceneError {
    SceneError::at(file, &Loc { line: None, path: path.into() }, msg)
}

/// Reads and validates a `.gltf` or `.glb` file and its buffers.
pub fn open(path: &Path) -> Result<GltfFile, SceneError> {
    let mut bytes = file::read_bytes(path, MAX_BYTES)
        .map_err(|why| SceneError::file(path, format!("cannot read the glTF file: {why}")))?;
    let (json, bin) =
        if bytes.starts_with(b"glTF") { split_glb(path, &bytes)? } else { (0..bytes.len(), None) };
    let root = parse_json(path, &bytes[json])?;
    let doc = gltf::Document::from_json(root).map_err(|e| validation_error(path, e))?;
    // The BIN chunk's bytes become buffer 0 in place: no second copy of a large mesh.
    let blob = bin.map(|r| {
        bytes.truncate(r.end);
        bytes.drain(..r.start);
        bytes
    });
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let buffers = read_buffers(path, &base_dir, &doc, blob)?;
    Ok(GltfFile { file: path.to_path_buf(), base_dir, doc, buffers })
}

/// The byte ranges of a GLB's JSON chunk and BIN chunk (if any).
type Chunks = (std::ops::Range<usize>, Option<std::ops::Range<usize>>);

/// Splits a GLB container (a 12-byte header, then chunks of a length, a
/// type and the data): chunk 0 must be JSON, chunk 1 may be BIN, and
/// chunks of other types are skipped as the specification asks.
fn split_glb(path: &Path, b: &[u8]) -> Result<Chunks, SceneError> {
    let u32_at = |o: usize| u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    if b.len() < 12 {
        return Err(at(path, "GLB header", format!("the header is cut short ({} of 12 bytes)", b.len())));
    }
    let (version, length) = (u32_at(4), u32_at(8) as usize);
    if version != 2 {
        return Err(at(path, "GLB header", format!("GLB version {version} is not supported (only 2)")));
    }
    if length != b.len() {
        return Err(at(
            path,
            "GLB header",
            format!("the header gives a length of {length} bytes but the file has {} (cut short?)", b.len()),
        ));
    }
    let mut pos = 12;
    let mut json = None;
    let mut bin = None;
    let mut chunk = 0;
    while pos < b.len() {
        let name = format!("GLB chunk {chunk}");
        if b.len() - pos < 8 {
            return Err(at(
                path,
                name,
                format!("the chunk header is cut short ({} of 8 bytes)", b.len() - pos),
            ));
        }
        let (len, ty) = (u32_at(pos) as usize, u32_at(pos + 4));
        let start = pos + 8;
        if len > b.len() - start {
            return Err(at(
                path,
                name,
                format!("the chunk claims {len} bytes but only {} follow (cut short?)", b.len() - start),
            ));
        }
        match (chunk, ty) {
            (0, 0x4E4F_534A) => json = Some(start..start + len),
            (0, _) => return Err(at(path, name, "the first chunk must be the JSON chunk")),
            (1, 0x004E_4942) => bin = Some(start..start + len),
            (_, 0x4E4F_534A | 0x004E_4942) => {
                return Err(at(path, name, "only the first chunk may be JSON and only the second BIN"))
            }
            _ => {}
        }
        pos = start + len;
        chunk += 1;
    }
    let json = json.ok_or_else(|| at(path, "GLB chunk 0", "the file has no JSON chunk"))?;
    Ok((json, bin))
}

/// The JSON root; a syntax error names its line and column, never the text.
fn parse_json(path: &Path, json: &[u8]) -> Result<gltf::json::Root, SceneError> {
    gltf::json::Root::from_slice(json).map_err(|e| {
        use serde_json::error::Category;
        let what = match e.classify() {
            Category::Eof => "the JSON ends early",
            Category::Syntax => "the JSON is malformed",
            Category::Data => "a value does not have the type glTF gives it",
            Category::Io => "the JSON cannot be read",
        };
        SceneError::file(path, format!("line {}, column {}: {what}", e.line(), e.column()))
    })
}

/// The first of the crate's validation errors as one sentence at its JSON
/// path, with the number of others.
fn validation_error(path: &Path, e: gltf::Error) -> SceneError {
    let gltf::Error::Validation(errors) = e else {
        return SceneError::file(path, "the glTF document is invalid");
    };
    let Some((json_path, first)) = errors.first() else {
        return SceneError::file(path, "the glTF document is invalid");
    };
    use gltf::json::validation::Error as V;
    let what = match first {
        V::IndexOutOfBounds => "the index is out of range",
        V::Invalid => "the value is invalid",
        V::Missing => "a required value is missing",
        V::Oversize => "the size is beyond what can be held in memory",
        V::Unsupported => "the file requires an extension luster does not support",
    };
    let more = match errors.len() {
        1 => String::new(),
        2 => " (and 1 more problem)".to_string(),
        n => format!(" (and {} more problems)", n - 1),
    };
    at(path, luster_core::text::shown(&json_path.to_string(), false).into_owned(), format!("{what}{more}"))
}

/// Every buffer's bytes: the GLB's BIN chunk for the buffer without a URI,
/// a base64 `data:` URI decoded, or a file relative to the glTF.
fn read_buffers(
    path: &Path,
    base_dir: &Path,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let mut out = Vec::with_capacity(doc.buffers().len());
    for buffer in doc.buffers() {
        let i = buffer.index();
        let name = format!("buffers[{i}]");
        let bytes = match buffer.source() {
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                at(path, &name, "the buffer has no uri and the file has no (other unused) GLB BIN chunk")
            })?,
            gltf::buffer::Source::Uri(uri) => read_uri(path, base_dir, uri, &format!("{name}.uri"))?,
        };
        if bytes.len() < buffer.length() {
            return Err(at(
                path,
                &name,
                format!("byteLength is {} but the buffer holds only {} bytes", buffer.length(), bytes.len()),
            ));
        }
        out.push(bytes);
    }
    Ok(out)
}

/// The bytes a URI names: a base64 `data:` URI, or a relative file path
/// (percent-encoded as URIs are). Other schemes are refused: luster reads
/// no network.
pub fn read_uri(path: &Path, base_dir: &Path, uri: &str, json_path: &str) -> Result<Vec<u8>, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((header, data)) = rest.split_once(',') else {
            return Err(at(path, json_path, "the data URI has no comma before its data"));
        };
        if !header.ends_with(";base64") {
            return Err(at(path, json_path, "the data URI is not base64-encoded (no ;base64)"));
        }
        if data.len() as u64 / 4 * 3 > MAX_BYTES {
            return Err(at(
                path,
                json_path,
                format!("the data URI is larger than the {MAX_BYTES} bytes accepted"),
            ));
        }
        return base64::engine::general_purpose::STANDARD
            .decode(data.trim_end())
            .map_err(|_| at(path, json_path, "the data URI's base64 is invalid"));
    }
    let rel = file_uri(path, uri, json_path)?;
    file::read_bytes(&base_dir.join(&rel), MAX_BYTES).map_err(|why| {
        at(path, json_path, format!("cannot read {}: {why}", shown_token(&rel.to_string_lossy())))
    })
}

/// Checks that a URI that is not a `data:` URI names a readable regular
/// file beside the glTF (images are decoded later, when the scene is
/// built; a missing one is reported now, at its JSON path).
pub fn check_uri(path: &Path, base_dir: &Path, uri: &str, json_path: &str) -> Result<(), SceneError> {
    if uri.starts_with("data:") {
        return Ok(());
    }
    let rel = file_uri(path, uri, json_path)?;
    file::check_regular(&base_dir.join(&rel), MAX_BYTES).map(|_| ()).map_err(|why| {
        at(path, json_path, format!("cannot read {}: {why}", shown_token(&rel.to_string_lossy())))
    })
}

/// The relative path a file URI names; URLs (a scheme) are refused.
fn file_uri(path: &Path, uri: &str, json_path: &str) -> Result<PathBuf, SceneError> {
    let scheme = uri.split_once(':').is_some_and(|(s, _)| {
        s.len() > 1 && s.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if scheme {
        return Err(at(path, json_path, "only relative file paths and data URIs are read, not URLs"));
    }
    luster_core::uri::percent_decode(uri)
        .map(PathBuf::from)
        .ok_or_else(|| at(path, json_path, "the URI's percent-encoding is invalid"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend(0u32.to_le_bytes());
        out.extend((json.len() as u32).to_le_bytes());
        out.extend(b"JSON");
        out.extend(json);
        if let Some(bin) = bin {
            out.extend((bin.len() as u32).to_le_bytes());
            out.extend(b"BIN\0");
            out.extend(bin);
        }
        let n = out.len() as u32;
        out[8..12].copy_from_slice(&n.to_le_bytes());
        out
    }

    #[test]
    fn glb_chunks_are_found_and_lies_refused() {
        let p = Path::new("m.glb");
        let b = glb(b"{}  ", Some(b"abcd"));
        let (json, bin) = split_glb(p, &b).expect("a valid GLB");
        assert_eq!((&b[json], bin.map(|r| &b[r])), (&b"{}  "[..], Some(&b"abcd"[..])));
        let mut lying = b.clone();
        lying[12..16].copy_from_slice(&100u32.to_le_bytes());
        let e = split_glb(p, &lying).unwrap_err().to_string();
        assert!(e.contains("GLB chunk 0: the chunk claims 100 bytes"), "{e}");
        let e = split_glb(p, &b[..10]).unwrap_err().to_string();
        assert!(e.contains("GLB header: the header is cut short (10 of 12 bytes)"), "{e}");
        let e = split_glb(p, &b[..b.len() - 2]).unwrap_err().to_string();
        assert!(e.contains("GLB header") && e.contains("cut short"), "{e}");
    }

    #[test]
    fn data_uris_decode_and_urls_are_refused() {
        let (p, d) = (Path::new("m.gltf"), Path::new("."));
        assert_eq!(read_uri(p, d, "data:application/octet-stream;base64,AAEC", "b").unwrap(), [0, 1, 2]);
        let e = read_uri(p, d, "data:application/octet-stream,abc", "buffers[0].uri").unwrap_err();
        assert!(e.to_string().contains("buffers[0].uri: the data URI is not base64"), "{e}");
        let e = read_uri(p, d, "data:application/octet-stream;base64,@@", "b").unwrap_err();
        assert!(e.to_string().contains("base64 is invalid"), "{e}");
        let e = read_uri(p, d, "https://example.com/a.bin", "b").unwrap_err();
        assert!(e.to_string().contains("not URLs"), "{e}");
    }
}
