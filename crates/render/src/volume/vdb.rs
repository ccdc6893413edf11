//! OpenVDB files as a medium's density and emission (`<VdbFile>`): 32-bit
//! float grids read with the `vdb-rs` crate (uncompressed, zip or blosc
//! data) and made dense over the box of their active voxels. Grids saved as
//! 16-bit half floats are refused: `vdb-rs` 0.6 misreads them (it expects a
//! size before every node's values, which OpenVDB omits for a half-float
//! node without active values).
//!
//! A voxel's value sits at its integer index coordinates, which the grid's
//! transform maps into the file's world space (the volume's own space, before
//! its `Transformations`); luster reads uniform and per-axis scale maps with a
//! translation and refuses rotations, shears and frustums. The dense lattice
//! has one sample per voxel plus one voxel of zeros on every side, so the
//! density falls to 0 at the box's faces. Inactive voxels are empty, negative
//! values count as 0, and a value that is not finite is refused.
//!
//! `vdb-rs` panics on some malformed files and on transforms it does not
//! know, so what it would panic on is checked first (the signature, the
//! format version, the grid's type and transform) and the rest runs under
//! `catch_unwind`, so a truncated or foreign file is an error and never a
//! crash. A file corrupted inside can still give `vdb-rs` an absurd length
//! to allocate, which aborts the process: it sizes buffers from the file
//! before reading them.

use super::{Grid, MAX_GRID_BYTES};
use luster_core::math::{Aabb, Quat, Transform, Vec3};
use luster_scene::description::{BoundDesc, VdbDesc};
use std::cell::Cell;
use std::io::Cursor;
use std::ops::RangeInclusive;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;
use vdb_rs::{Map, MetadataValue, ParseError, VdbLevel, VdbReader};

/// Largest VDB file read.
pub const MAX_VDB_BYTES: u64 = 1 << 30;

/// OpenVDB's signature: "VDB " as a little-endian 64-bit number.
const MAGIC: [u8; 8] = [0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0];

/// File format versions read: from the first with a textual UUID (OpenVDB
/// 2.x; older ones `vdb-rs` cannot read) to the latest (OpenVDB 6 and on).
const VERSIONS: RangeInclusive<u32> = 218..=224;

/// OpenVDB's `FloatGrid`, and the same saved as half floats.
const FLOAT_TYPE: &str = "Tree_float_5_4_3";
const HALF_TYPE: &str = "Tree_float_5_4_3_HalfFloat";

/// The transform maps read: each is index × scale (+ translation).
const MAPS: [&str; 3] = ["UniformScaleMap", "UniformScaleTranslateMap", "ScaleTranslateMap"];

/// A VDB file's density grid (and emission grid) as samples on one lattice
/// in the file's world space.
#[derive(Debug)]
pub struct Lattice {
    /// The box the lattice spans: the active voxels' box and one voxel more
    /// on every side.
    pub bounds: Aabb,
    /// Lattice points along x, y and z.
    pub dims: [usize; 3],
    /// A voxel's edges in the file's world space.
    pub voxel: Vec3,
    /// The density, x fastest, negative values as 0.
    pub density: Vec<f32>,
    /// The emission grid's values, on the same lattice.
    pub emission: Option<Vec<f32>>,
}

/// Index space to the file's world space: `index × scale + translation`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Affine {
    scale: [f64; 3],
    translation: [f64; 3],
}

/// A grid as read, with its transform and the box of its active voxels
/// (`None` when it has none), in index space.
struct Read {
    grid: vdb_rs::Grid<f32>,
    xf: Affine,
    active: Option<([i64; 3], [i64; 3])>,
}

/// Every active value of `grid` as `(index, edge, value)`: a voxel (edge 1)
/// or a constant tile (edge 8 or 128).
fn active(grid: &vdb_rs::Grid<f32>) -> impl Iterator<Item = ([i64; 3], i64, f32)> + '_ {
    grid.iter().map(|(c, value, level)| {
        let edge = match level {
            VdbLevel::Voxel => 1,
            VdbLevel::Node3 => 8,
            VdbLevel::Node4 => 128,
        };
        ([c.x as i64, c.y as i64, c.z as i64], edge, value)
    })
}

/// Refuses a dense grid of `span` points of `per_point` bytes beyond [`MAX_GRID_BYTES`].
fn check_size(span: [u64; 3], per_point: u64) -> Result<(), String> {
    let bytes = span.iter().try_fold(per_point, |n, &s| n.checked_mul(s)).unwrap_or(u64::MAX);
    if bytes > MAX_GRID_BYTES {
        return Err(format!(
            "its active voxels span {}×{}×{} voxels with padding, {:.1} GB as a dense grid, more than the {:.1} GB allowed",
            span[0],
            span[1],
            span[2],
            bytes as f64 / 1e9,
            MAX_GRID_BYTES as f64 / 1e9
        ));
    }
    Ok(())
}

/// Reads `desc`'s density grid (and emission grid) onto one lattice; the
/// error is a sentence naming the file and the grid.
pub fn load(desc: &VdbDesc) -> Result<Lattice, String> {
    let shown = desc.path.display();
    let bytes = luster_core::file::read_bytes(&desc.path, MAX_VDB_BYTES)
        .map_err(|why| format!("cannot read VDB file {shown}: {why}"))?;
    read(&bytes, &desc.density_grid, desc.emission_grid.as_deref())
        .map_err(|why| format!("VDB file {shown}: {why}"))
}

/// [`load`] on the bytes of a file; the error says what is wrong with them.
pub fn read(bytes: &[u8], density: &str, emission: Option<&str>) -> Result<Lattice, String> {
    let version = check_header(bytes)?;
    let mut reader = guarded(|| VdbReader::new(Cursor::new(bytes)).map_err(parse_error))?;
    let d = grid(&mut reader, bytes, version, density)?;
    let e = match emission {
        Some(name) => {
            let e = grid(&mut reader, bytes, version, name)?;
            if e.xf != d.xf {
                return Err(format!(
                    "grids \"{density}\" and \"{name}\" have different transforms; an emission grid must share the density grid's voxels"
                ));
            }
            Some(e)
        }
        None => None,
    };
    let (mut lo, mut hi) = d.active.ok_or_else(|| format!("grid \"{density}\" has no active voxels"))?;
    // An emission grid with no active voxel emits nothing; its voxels widen the box.
    if let Some((elo, ehi)) = e.as_ref().and_then(|e| e.active) {
        for a in 0..3 {
            lo[a] = lo[a].min(elo[a]);
            hi[a] = hi[a].max(ehi[a]);
        }
    }
    // One voxel of zeros beyond the active ones on every side.
    let (lo, hi) = (lo.map(|c| c - 1), hi.map(|c| c + 1));
    let span = [0, 1, 2].map(|a| (hi[a] - lo[a] + 1) as u64);
    // The grids built from the lattice: f32 density, and Vec3 emission.
    check_size(span, if e.is_some() { 16 } else { 4 })?;
    let dims = span.map(|s| s as usize);
    let xf = d.xf;
    let world = |i: [i64; 3]| {
        Vec3::from_array([0, 1, 2].map(|a| (i[a] as f64 * xf.scale[a] + xf.translation[a]) as f32))
    };
    let bounds = Aabb::new(world(lo), world(hi));
    if !bounds.is_finite() || bounds.extent().min_element() <= 0.0 {
        return Err(format!("grid \"{density}\" lies where f32 coordinates cannot place its voxels"));
    }
    Ok(Lattice {
        bounds,
        dims,
        voxel: Vec3::from_array(xf.scale.map(|s| s as f32)),
        density: dense(&d.grid, lo, dims)?,
        emission: match e {
            Some(e) => Some(dense(&e.grid, lo, dims)?),
            None => None,
        },
    })
}

/// The samples of `grid` on the lattice of `dims` points from index `lo`,
/// x fastest, negative values as 0.
fn dense(grid: &vdb_rs::Grid<f32>, lo: [i64; 3], dims: [usize; 3]) -> Result<Vec<f32>, String> {
    let mut data = vec![0.0f32; dims[0] * dims[1] * dims[2]];
    guarded(|| {
        for (c, edge, value) in active(grid) {
            // Every active voxel lies inside the lattice, which was sized from them.
            let o = [0, 1, 2].map(|a| (c[a] - lo[a]) as usize);
            let edge = edge as usize;
            for z in o[2]..o[2] + edge {
                for y in o[1]..o[1] + edge {
                    let row = (z * dims[1] + y) * dims[0];
                    data[row + o[0]..row + o[0] + edge].fill(value.max(0.0));
                }
            }
        }
        Ok(())
    })?;
    Ok(data)
}

/// The file's format version, after checking what `vdb-rs` would otherwise
/// panic on or misread: the signature, the version, and grid offsets.
fn check_header(bytes: &[u8]) -> Result<u32, String> {
    if bytes.len() < MAGIC.len() || bytes[..MAGIC.len()] != MAGIC {
        return Err("it is not an OpenVDB file (it does not start with the VDB signature)".to_string());
    }
    let version = u32_at(bytes, 8).ok_or_else(truncated)?;
    if !VERSIONS.contains(&version) {
        return Err(format!(
            "it is in OpenVDB file format {version}; formats {} to {} are read",
            VERSIONS.start(),
            VERSIONS.end()
        ));
    }
    // After the version, the library's major and minor version; then whether
    // grids can be found by offset, which `vdb-rs` requires.
    if bytes.get(20).ok_or_else(truncated)? != &1 {
        return Err("it does not record where its grids start, which OpenVDB files since 2.0 do".to_string());
    }
    Ok(version)
}

/// The float grid `name`, its type, transform, size and values checked.
fn grid(
    reader: &mut VdbReader<Cursor<&[u8]>>,
    bytes: &[u8],
    version: u32,
    name: &str,
) -> Result<Read, String> {
    let gd = reader.grid_descriptors.get(name).ok_or_else(|| format!("it has no grid named \"{name}\""))?;
    if gd.grid_type == HALF_TYPE || gd.meta_data.is_half_float() {
        return Err(format!(
            "grid \"{name}\" is saved as 16-bit half floats, which cannot be read yet; save it with 32-bit floats"
        ));
    }
    if gd.grid_type != FLOAT_TYPE {
        return Err(format!("grid \"{name}\" is not a float grid"));
    }
    if !gd.instance_parent.is_empty() {
        return Err(format!(
            "grid \"{name}\" shares another grid's voxels (an instanced grid), which is not read"
        ));
    }
    let map = map_name(bytes, gd.grid_pos, version).ok_or_else(truncated)?;
    if !MAPS.iter().any(|m| m.as_bytes() == map) {
        return Err(format!(
            "grid \"{name}\" has a transform other than a scale and a translation (a rotation, shear or frustum), which is not supported"
        ));
    }
    // The box OpenVDB records refuses a huge grid before it is decompressed;
    // the box of the voxels read decides.
    let recorded = |key: &str| match gd.meta_data.0.get(key) {
        Some(MetadataValue::Vec3i(v)) => Some([v.x, v.y, v.z].map(i64::from)),
        _ => None,
    };
    if let (Some(lo), Some(hi)) = (recorded("file_bbox_min"), recorded("file_bbox_max")) {
        if (0..3).all(|a| lo[a] <= hi[a]) {
            check_size([0, 1, 2].map(|a| (hi[a] - lo[a] + 3) as u64), 4)?;
        }
    }
    guarded(|| {
        let grid = reader.read_grid::<f32>(name).map_err(parse_error)?;
        let (scale, translation) = match grid.transform {
            Map::UniformScaleMap { scale_values, .. } => (scale_values, Default::default()),
            Map::ScaleTranslateMap { scale_values, translation, .. } => (scale_values, translation),
        };
        let xf = Affine {
            scale: [scale.x, scale.y, scale.z],
            translation: [translation.x, translation.y, translation.z],
        };
        if !xf.scale.iter().all(|s| *s > 0.0 && s.is_finite())
            || !xf.translation.iter().all(|t| t.is_finite())
        {
            return Err(format!("grid \"{name}\" has a voxel size that is not positive and finite"));
        }
        let mut bounds: Option<([i64; 3], [i64; 3])> = None;
        for (c, edge, value) in active(&grid) {
            if !value.is_finite() {
                return Err(format!("grid \"{name}\" holds a value that is not finite"));
            }
            let top = c.map(|i| i + edge - 1);
            bounds = Some(match bounds {
                Some((lo, hi)) => ([0, 1, 2].map(|a| lo[a].min(c[a])), [0, 1, 2].map(|a| hi[a].max(top[a]))),
                None => (c, top),
            });
        }
        Ok(Read { grid, xf, active: bounds })
    })
}

thread_local! {
    /// Whether this thread is inside [`guarded`], whose panics are reported as errors.
    static QUIET: Cell<bool> = const { Cell::new(false) };
}

/// Runs `f`, turning a panic inside `vdb-rs` into an error. The panic hook
/// stays silent for it, so the user sees the error alone.
fn guarded<T>(f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    static HOOK: Once = Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(Cell::get) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let result = catch_unwind(AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    result.unwrap_or_else(|_| {
        Err("it is corrupt, or uses a part of the format that cannot be read".to_string())
    })
}

fn truncated() -> String {
    "it ends early (the file is truncated or corrupt)".to_string()
}

/// A `vdb-rs` error as a sentence fragment that quotes nothing from the file.
fn parse_error(e: ParseError) -> String {
    match e {
        ParseError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => truncated(),
        ParseError::IoError(e) => format!("it cannot be read ({e})"),
        ParseError::UnsupportedVersion(_) | ParseError::UnsupportedBloscFormat => {
            "it uses a part of the format that cannot be read".to_string()
        }
        _ => "it is corrupt".to_string(),
    }
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(bytes.get(at..at.checked_add(4)?)?.try_into().ok()?))
}

/// The name of the transform map of the grid stored at `pos`, peeked before
/// `vdb-rs` reads the grid (it panics on a map it does not know). A grid
/// starts with its compression flags (from format 222), its metadata
/// (a count, then name, type name and value, each a length and bytes), and
/// then the map's name.
fn map_name(bytes: &[u8], pos: u64, version: u32) -> Option<&[u8]> {
    let mut at = usize::try_from(pos).ok()?;
    if version >= 222 {
        at = at.checked_add(4)?;
    }
    let field = |at: &mut usize| -> Option<&[u8]> {
        let len = u32_at(bytes, *at)? as usize;
        let start = *at + 4;
        let s = bytes.get(start..start.checked_add(len)?)?;
        *at = start + len;
        Some(s)
    };
    let count = u32_at(bytes, at)?;
    at += 4;
    // Each entry takes at least 12 bytes, so a corrupt count soon runs out of file.
    for _ in 0..count {
        for _ in 0..3 {
            field(&mut at)?;
        }
    }
    field(&mut at)
}

impl Lattice {
    /// The lattice's box as a bound, for a volume that gives none.
    pub fn bound(&self) -> BoundDesc {
        BoundDesc::Box { min: self.bounds.min, max: self.bounds.max }
    }

    /// The march step a voxel suggests: its shortest edge after `transform`
    /// (the volume's, to the world).
    pub fn world_step(&self, transform: &Transform) -> f32 {
        [Vec3::X, Vec3::Y, Vec3::Z]
            .iter()
            .map(|&e| transform.vector(e * self.voxel).length())
            .fold(f32::INFINITY, f32::min)
    }

    /// The density grid, and the emission grid times `colour`, in the space
    /// a volume bounded by `bound` looks them up in: the file's world space,
    /// except inside an ellipsoid, whose space is its unit ball's.
    pub fn grids(
        self,
        bound: Option<&BoundDesc>,
        colour: Vec3,
    ) -> Result<(Grid<f32>, Option<Grid<Vec3>>), String> {
        let invalid = || "the grid's lattice is degenerate".to_string();
        let glow = |e: Vec<f32>| -> Vec<Vec3> { e.into_iter().map(|v| colour * v).collect() };
        let ellipsoid = match bound {
            Some(&BoundDesc::Ellipsoid { center, radii, rotation }) => Some((center, radii, rotation)),
            _ => None,
        };
        let unturned = |r: Quat| (r.w.abs() - 1.0).abs() < 1e-6;
        let b = match ellipsoid {
            // Unturned, the unit ball's space is the file's moved and scaled
            // along the axes: the lattice holds and only its box moves.
            Some((center, radii, rotation)) if unturned(rotation) => {
                Aabb::new((self.bounds.min - center) / radii, (self.bounds.max - center) / radii)
            }
            _ => self.bounds,
        };
        let density = Grid::from_samples(b, self.dims, self.density).ok_or_else(invalid)?;
        let emission = match self.emission {
            Some(e) => Some(Grid::from_samples(b, self.dims, glow(e)).ok_or_else(invalid)?),
            None => None,
        };
        let Some((center, radii, rotation)) = ellipsoid.filter(|e| !unturned(e.2)) else {
            return Ok((density, emission));
        };
        // Turned: resample on the unit ball's box, a cell no longer than the
        // shortest voxel edge along any of the ellipsoid's axes.
        let edge = self.voxel.min_element();
        let dims = [0, 1, 2].map(|a| ((2.0 * radii[a] / edge).ceil() as usize + 1).clamp(2, 1 << 20));
        let points = dims.iter().try_fold(1u64, |n, &d| n.checked_mul(d as u64)).unwrap_or(u64::MAX);
        let bytes = points.saturating_mul(if emission.is_some() { 16 } else { 4 });
        if bytes > MAX_GRID_BYTES {
            return Err(format!(
                "resampled into the turned <Ellipsoid>, the grid takes {:.1} GB, more than the {:.1} GB allowed",
                bytes as f64 / 1e9,
                MAX_GRID_BYTES as f64 / 1e9
            ));
        }
        let unit = Aabb::new(Vec3::splat(-1.0), Vec3::ONE);
        let cell =
            unit.extent() / Vec3::new(dims[0] as f32 - 1.0, dims[1] as f32 - 1.0, dims[2] as f32 - 1.0);
        // Lattice point i of the unit ball's box, in the file's space.
        let at = |i: usize| {
            let q = unit.min
                + cell
                    * Vec3::new(
                        (i % dims[0]) as f32,
                        ((i / dims[0]) % dims[1]) as f32,
                        (i / (dims[0] * dims[1])) as f32,
                    );
            center + rotation * (q * radii)
        };
        let n = dims[0] * dims[1] * dims[2];
        let resampled = Grid::from_samples(unit, dims, (0..n).map(|i| density.at(at(i))).collect())
            .ok_or_else(invalid)?;
        let emission = match emission {
            Some(g) => Some(
                Grid::from_samples(unit, dims, (0..n).map(|i| g.at(at(i))).collect()).ok_or_else(invalid)?,
            ),
            None => None,
        };
        Ok((resampled, emission))
    }
}

#[cfg(test)]
#[path = "tests_vdb.rs"]
mod tests;
