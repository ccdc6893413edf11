//! A glTF file's images as image descriptions: files named by relative URIs
//! (percent-decoded, against the glTF's folder), `data:` URIs (base64) and
//! buffer views of a `.glb`. Each is checked when the file loads (it exists,
//! it is a PNG or JPEG, its header decodes), so a bad image is an error
//! naming `images[i]` before anything renders; its texels are decoded when
//! the scene is built.

use crate::description::{ImageDesc, ImageEncoding};
use crate::error::{Loc, SceneError};
use base64::Engine;
use luster_core::text::shown;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Where an image's encoded bytes are, found once per image.
#[derive(Clone)]
struct Source {
    /// The file, or the name an in-memory image goes by in messages.
    path: PathBuf,
    /// The bytes of an image inside the glTF (a buffer view or a data URI).
    bytes: Option<Arc<[u8]>>,
    /// Width and height, from the header.
    size: (u32, u32),
}

/// The images of one glTF file, resolved on first use.
pub(super) struct Images<'a> {
    doc: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    base_dir: &'a Path,
    file: &'a Path,
    resolved: Vec<Option<Source>>,
}

impl<'a> Images<'a> {
    pub(super) fn new(
        doc: &'a gltf::Document,
        buffers: &'a [Vec<u8>],
        base_dir: &'a Path,
        file: &'a Path,
    ) -> Self {
        Images { doc, buffers, base_dir, file, resolved: vec![None; doc.images().len()] }
    }

    /// Image `i` read as `encoding` says, and its size in texels. Its id,
    /// `FILE#images[i]/ENCODING`, is the name the material shader samples it by.
    pub(super) fn get(
        &mut self,
        i: usize,
        encoding: ImageEncoding,
    ) -> Result<(ImageDesc, (u32, u32)), SceneError> {
        let src = match self.resolved.get(i) {
            Some(Some(s)) => s.clone(),
            Some(None) => {
                let s = self.resolve(i)?;
                self.resolved[i] = Some(s.clone());
                s
            }
            None => return Err(self.err(i, "", "there is no such image")),
        };
        let role = match encoding {
            ImageEncoding::Srgb => "srgb",
            ImageEncoding::Linear => "linear",
            ImageEncoding::Alpha => "alpha",
            ImageEncoding::GlNormal { .. } => "normal",
            ImageEncoding::Scene => "scene",
        };
        let desc = ImageDesc {
            id: format!("{}#images[{i}]/{role}", self.file.display()),
            path: src.path,
            degamma: false,
            loc: Loc { line: None, path: format!("images[{i}]") },
            bytes: src.bytes,
            encoding,
        };
        Ok((desc, src.size))
    }

    fn err(&self, i: usize, field: &str, msg: impl std::fmt::Display) -> SceneError {
        SceneError::at(self.file, &Loc { line: None, path: format!("images[{i}]{field}") }, msg.to_string())
    }

    fn resolve(&self, i: usize) -> Result<Source, SceneError> {
        let Some(json) = self.doc.as_json().images.get(i) else {
            return Err(self.err(i, "", "there is no such image"));
        };
        let (path, bytes) = match (&json.uri, &json.buffer_view) {
            (Some(uri), _) if uri.starts_with("data:") => {
                let bytes = data_uri(uri).map_err(|why| self.err(i, ".uri", why))?;
                (self.label(i), Some(bytes))
            }
            (Some(uri), _) => {
                let path = self.file_of(uri).map_err(|why| self.err(i, ".uri", why))?;
                luster_core::file::check_regular(&path, luster_core::image::MAX_IMAGE_BYTES).map_err(
                    |why| self.err(i, ".uri", format!("cannot read image {}: {why}", shown(uri, false))),
                )?;
                (path, None)
            }
            (None, Some(view)) => {
                let bytes = self.view_bytes(view.value()).map_err(|why| self.err(i, ".bufferView", why))?;
                (self.label(i), Some(bytes))
            }
            (None, None) => return Err(self.err(i, "", "the image has neither a uri nor a bufferView")),
        };
        let size = header_size(&path, bytes.as_deref()).map_err(|why| self.err(i, "", why))?;
        Ok(Source { path, bytes, size })
    }

    /// The name an image inside the glTF goes by in messages.
    fn label(&self, i: usize) -> PathBuf {
        PathBuf::from(format!("{}#images[{i}]", self.file.display()))
    }

    /// The file a relative URI names.
    fn file_of(&self, uri: &str) -> Result<PathBuf, String> {
        let scheme = uri.split_once(':').map(|(s, _)| s);
        if scheme
            .is_some_and(|s| s.len() > 1 && s.chars().all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c)))
        {
            return Err(format!(
                "{} is not a relative file name or a data: URI (luster reads no other URIs)",
                shown(uri, false)
            ));
        }
        let name = luster_core::uri::percent_decode(uri)
            .ok_or_else(|| format!("{} is not a valid URI", shown(uri, false)))?;
        Ok(self.base_dir.join(name))
    }

    /// The bytes of buffer view `v`, checked against its buffer.
    fn view_bytes(&self, v: usize) -> Result<Arc<[u8]>, String> {
        let view = self.doc.views().nth(v).ok_or_else(|| format!("buffer view {v} does not exist"))?;
        let b = view.buffer().index();
        let buffer = self.buffers.get(b).ok_or_else(|| format!("buffer {b} was not loaded"))?;
        let (start, len) = (view.offset(), view.length());
        match start.checked_add(len) {
            Some(end) if end <= buffer.len() => Ok(Arc::from(&buffer[start..end])),
            _ => Err(format!(
                "buffer view {v} (bytes {start} to {start}+{len}) runs past the end of buffer {b} ({} bytes)",
                buffer.len()
            )),
        }
    }
}

/// The bytes of a base64 `data:` URI.
fn data_uri(uri: &str) -> Result<Arc<[u8]>, String> {
    let Some((head, data)) = uri.split_once(',') else {
        return Err("the data URI has no ',' before its data".to_string());
    };
    if !head.ends_with(";base64") {
        return Err("the data URI is not base64 (luster reads only ;base64 data URIs)".to_string());
    }
    let bytes = base64::engine::general_purpose::STANDARD
        .decode(data.trim_end())
        .map_err(|_| "the data URI's data is not valid base64".to_string())?;
    Ok(Arc::from(bytes))
}

/// The size an image's header gives, when it is a PNG or JPEG whose header decodes.
fn header_size(path: &Path, bytes: Option<&[u8]>) -> Result<(u32, u32), String> {
    fn check<R: std::io::BufRead + std::io::Seek>(r: image::ImageReader<R>) -> Result<(u32, u32), String> {
        let r = r.with_guessed_format().map_err(|e| format!("cannot read the image: {e}"))?;
        if !matches!(r.format(), Some(image::ImageFormat::Png | image::ImageFormat::Jpeg)) {
            return Err("the image is not a PNG or JPEG file".to_string());
        }
        r.into_dimensions()
            .map_err(|e| format!("the image does not decode: {}", shown(&e.to_string(), false)))
    }
    match bytes {
        Some(b) => check(image::ImageReader::new(std::io::Cursor::new(b))),
        None => {
            let (f, _) = luster_core::file::open_regular(path, luster_core::image::MAX_IMAGE_BYTES)
                .map_err(|why| format!("cannot open the image: {why}"))?;
            check(image::ImageReader::new(std::io::BufReader::new(f)))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_uris_must_be_base64() {
        assert_eq!(&*data_uri("data:image/png;base64,AAEC").unwrap(), &[0, 1, 2]);
        assert!(data_uri("data:image/png,abc").unwrap_err().contains("not base64"));
        assert!(data_uri("data:image/png;base64,@@@").unwrap_err().contains("not valid base64"));
        assert!(data_uri("data:image/png;base64").unwrap_err().contains("no ','"));
    }
}
