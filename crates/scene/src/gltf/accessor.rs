//! Reading glTF accessors into arrays, with every byte range checked
//! before anything is allocated: an accessor past its buffer view, a view
//! past its buffer, a stride smaller than an element, or a count that the
//! bytes cannot hold is one error naming `accessors[i]` or `bufferViews[i]`.
//!
//! Any component type is read (floats as they are, integers normalized when
//! the accessor says so, as `KHR_mesh_quantization` uses them), and sparse
//! accessors are applied over their base (or zeros).

use super::document::at;
use crate::error::SceneError;
use gltf::accessor::{DataType, Dimensions};
use gltf::Accessor;
use std::cell::Cell;
use std::path::Path;

/// Most elements an accessor without a buffer view (zeros, perhaps with
/// sparse values) may have: nothing in the file backs its size.
const MAX_UNBACKED: usize = 1 << 24;

/// Reads accessors of one file, keeping count of what they unpack to.
pub struct Accessors<'a> {
    /// The file, for errors.
    pub file: &'a Path,
    /// Buffer `i`'s bytes.
    pub buffers: &'a [Vec<u8>],
    /// Bytes that may still be unpacked: accessors shared by many
    /// primitives are read once per primitive, and this keeps a small file
    /// from unpacking into more memory than its buffers by far.
    budget: Cell<u64>,
}

/// Where an accessor's elements are: its bytes from its first element on,
/// and the distance between elements.
struct Span<'b> {
    bytes: &'b [u8],
    stride: usize,
}

impl<'a> Accessors<'a> {
    /// A reader of `buffers`, allowed to unpack 16 times their size plus 256 MiB.
    pub fn new(file: &'a Path, buffers: &'a [Vec<u8>]) -> Accessors<'a> {
        let total: u64 = buffers.iter().map(|b| b.len() as u64).sum();
        Accessors { file, buffers, budget: Cell::new(total.saturating_mul(16).saturating_add(256 << 20)) }
    }

    fn name(acc: &Accessor) -> String {
        format!("accessors[{}]", acc.index())
    }

    /// Takes `bytes` from the unpacking budget.
    fn spend(&self, acc: &Accessor, bytes: u64) -> Result<(), SceneError> {
        let left = self.budget.get();
        if bytes > left {
            return Err(at(
                self.file,
                Self::name(acc),
                "the file's accessors unpack to far more memory than its buffers hold (one accessor shared by \
                 very many meshes?)",
            ));
        }
        self.budget.set(left - bytes);
        Ok(())
    }

    /// The bytes of a buffer view, checked against its buffer.
    fn view_bytes(&self, view: &gltf::buffer::View) -> Result<&'a [u8], SceneError> {
        let buffer = &self.buffers[view.buffer().index()];
        let (off, len) = (view.offset(), view.length());
        match off.checked_add(len) {
            Some(end) if end <= buffer.len() => Ok(&buffer[off..end]),
            _ => Err(at(
                self.file,
                format!("bufferViews[{}]", view.index()),
                format!(
                    "bytes {off} to {} lie past the end of buffers[{}] ({} bytes)",
                    off as u128 + len as u128,
                    view.buffer().index(),
                    buffer.len()
                ),
            )),
        }
    }

    /// Where the accessor's elements lie, after checking that all `count`
    /// of them fit in its view; `None` when it has no view (zeros).
    fn span(&self, acc: &Accessor) -> Result<Option<Span<'a>>, SceneError> {
        let Some(view) = acc.view() else {
            if acc.count() > MAX_UNBACKED {
                return Err(at(
                    self.file,
                    Self::name(acc),
                    format!(
                        "{} elements without a buffer view are more than the {MAX_UNBACKED} accepted",
                        acc.count()
                    ),
                ));
            }
            return Ok(None);
        };
        let bytes = self.view_bytes(&view)?;
        let size = acc.size();
        let stride = view.stride().unwrap_or(size);
        if stride < size {
            return Err(at(
                self.file,
                format!("bufferViews[{}].byteStride", view.index()),
                format!(
                    "a stride of {stride} bytes is less than the {size} bytes of an element of {}",
                    Self::name(acc)
                ),
            ));
        }
        let count = acc.count() as u128;
        let need =
            acc.offset() as u128 + if count == 0 { 0 } else { (count - 1) * stride as u128 + size as u128 };
        if need > bytes.len() as u128 {
            return Err(at(
                self.file,
                Self::name(acc),
                format!(
                    "{} elements from byte {} need {need} bytes, past the end of bufferViews[{}] ({} bytes)",
                    acc.count(),
                    acc.offset(),
                    view.index(),
                    bytes.len()
                ),
            ));
        }
        Ok(Some(Span { bytes: &bytes[acc.offset()..], stride }))
    }

    /// The accessor as `N`-component vectors of floats (integers converted,
    /// normalized ones to [0, 1] or [−1, 1]); `what` names the attribute.
    pub fn floats<const N: usize>(&self, acc: &Accessor, what: &str) -> Result<Vec<[f32; N]>, SceneError> {
        if acc.dimensions().multiplicity() != N || matches!(acc.dimensions(), Dimensions::Mat2) {
            return Err(at(
                self.file,
                Self::name(acc),
                format!("{what} needs {N} components per element, the accessor has {:?}", acc.dimensions()),
            ));
        }
        let (ty, norm) = (acc.data_type(), acc.normalized());
        if ty == DataType::U32 {
            return Err(at(self.file, Self::name(acc), format!("{what} cannot be unsigned 32-bit integers")));
        }
        let span = self.span(acc)?;
        self.spend(acc, acc.count() as u64 * N as u64 * 4)?;
        let mut out = Vec::with_capacity(acc.count());
        match span {
            None => out.resize(acc.count(), [0.0; N]),
            Some(Span { bytes, stride }) if ty == DataType::F32 => {
                out.extend((0..acc.count()).map(|i| {
                    let e = &bytes[i * stride..i * stride + 4 * N];
                    std::array::from_fn(|k| {
                        f32::from_le_bytes([e[4 * k], e[4 * k + 1], e[4 * k + 2], e[4 * k + 3]])
                    })
                }));
            }
            Some(Span { bytes, stride }) => {
                let c = ty.size();
                out.extend(
                    (0..acc.count())
                        .map(|i| std::array::from_fn(|k| component(&bytes[i * stride + k * c..], ty, norm))),
                );
            }
        }
        if let Some(sparse) = acc.sparse() {
            let idx = self.sparse_indices(acc, &sparse, acc.count())?;
            let values = sparse.values();
            let bytes = self.view_bytes(&values.view())?;
            let size = acc.size();
            let need = values.offset() as u128 + idx.len() as u128 * size as u128;
            if need > bytes.len() as u128 {
                return Err(at(
                    self.file,
                    format!("{}.sparse.values", Self::name(acc)),
                    format!(
                        "{} values need {need} bytes, more than bufferViews[{}] holds",
                        idx.len(),
                        values.view().index()
                    ),
                ));
            }
            let bytes = &bytes[values.offset()..];
            let c = ty.size();
            for (j, &i) in idx.iter().enumerate() {
                out[i as usize] = std::array::from_fn(|k| component(&bytes[j * size + k * c..], ty, norm));
            }
        }
        Ok(out)
    }

    /// The accessor as vertex indices (unsigned integers, scalar).
    pub fn indices(&self, acc: &Accessor) -> Result<Vec<u32>, SceneError> {
        let ty = acc.data_type();
        if acc.dimensions() != Dimensions::Scalar
            || !matches!(ty, DataType::U8 | DataType::U16 | DataType::U32)
        {
            return Err(at(self.file, Self::name(acc), "indices must be unsigned integer scalars"));
        }
        let span = self.span(acc)?;
        self.spend(acc, acc.count() as u64 * 4)?;
        let mut out = Vec::with_capacity(acc.count());
        match span {
            None => out.resize(acc.count(), 0),
            Some(Span { bytes, stride }) => {
                out.extend((0..acc.count()).map(|i| uint(&bytes[i * stride..], ty)))
            }
        }
        if let Some(sparse) = acc.sparse() {
            let idx = self.sparse_indices(acc, &sparse, acc.count())?;
            let values = sparse.values();
            let bytes = self.view_bytes(&values.view())?;
            let need = values.offset() as u128 + idx.len() as u128 * ty.size() as u128;
            if need > bytes.len() as u128 {
                return Err(at(
                    self.file,
                    format!("{}.sparse.values", Self::name(acc)),
                    format!("{} values need {need} bytes, more than its buffer view holds", idx.len()),
                ));
            }
            let bytes = &bytes[values.offset()..];
            for (j, &i) in idx.iter().enumerate() {
                out[i as usize] = uint(&bytes[j * ty.size()..], ty);
            }
        }
        Ok(out)
    }

    /// A sparse accessor's element indices, each checked against `count`.
    fn sparse_indices(
        &self,
        acc: &Accessor,
        sparse: &gltf::accessor::sparse::Sparse,
        count: usize,
    ) -> Result<Vec<u32>, SceneError> {
        let name = format!("{}.sparse", Self::name(acc));
        let n = sparse.count();
        if n > count {
            return Err(at(self.file, name, format!("{n} sparse values for {count} elements")));
        }
        let ind = sparse.indices();
        let ty = match ind.index_type() {
            gltf::accessor::sparse::IndexType::U8 => DataType::U8,
            gltf::accessor::sparse::IndexType::U16 => DataType::U16,
            gltf::accessor::sparse::IndexType::U32 => DataType::U32,
        };
        let bytes = self.view_bytes(&ind.view())?;
        let need = ind.offset() as u128 + n as u128 * ty.size() as u128;
        if need > bytes.len() as u128 {
            return Err(at(
                self.file,
                format!("{name}.indices"),
                format!("{n} indices need {need} bytes, more than bufferViews[{}] holds", ind.view().index()),
            ));
        }
        let bytes = &bytes[ind.offset()..];
        let idx: Vec<u32> = (0..n).map(|j| uint(&bytes[j * ty.size()..], ty)).collect();
        if let Some(bad) = idx.iter().find(|&&i| i as usize >= count) {
            return Err(at(
                self.file,
                format!("{name}.indices"),
                format!("index {bad} is out of range of the {count} elements"),
            ));
        }
        Ok(idx)
    }
}

/// An unsigned integer component at the start of `b` (which holds it).
fn uint(b: &[u8], ty: DataType) -> u32 {
    match ty {
        DataType::U8 => u32::from(b[0]),
        DataType::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
        _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
    }
}

/// A component at the start of `b` as a float: normalized integers as the
/// glTF specification maps them (`max(c / 127, −1)` for signed bytes,
/// `c / 255` for unsigned, alike for shorts).
fn component(b: &[u8], ty: DataType, normalized: bool) -> f32 {
    match ty {
        DataType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        DataType::I8 => {
            let v = f32::from(b[0] as i8);
            if normalized {
                (v / 127.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U8 => {
            let v = f32::from(b[0]);
            if normalized {
                v / 255.0
            } else {
                v
            }
        }
        DataType::I16 => {
            let v = f32::from(i16::from_le_bytes([b[0], b[1]]));
            if normalized {
                (v / 32767.0).max(-1.0)
            } else {
                v
            }
        }
        DataType::U16 => {
            let v = f32::from(u16::from_le_bytes([b[0], b[1]]));
            if normalized {
                v / 65535.0
            } else {
                v
            }
        }
        DataType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normalized_integers_map_as_the_specification_says() {
        assert_eq!(component(&[255], DataType::U8, true), 1.0);
        assert_eq!(component(&[0x80], DataType::I8, true), -1.0);
        assert_eq!(component(&[0x81], DataType::I8, true), -1.0);
        assert_eq!(component(&[0xff, 0x7f], DataType::I16, true), 1.0);
        assert_eq!(component(&[0xff, 0xff], DataType::U16, true), 1.0);
        assert_eq!(component(&[7], DataType::U8, false), 7.0);
        assert_eq!(uint(&[1, 2, 0, 0], DataType::U16), 0x201);
    }
}
