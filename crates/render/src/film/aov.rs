//! Render passes (AOVs): what the first surface a camera sample meets is,
//! recorded beside the beauty image for a compositor and a denoiser, and
//! written as layers of one multi-layer OpenEXR file.
//!
//! | pass (`--aov`) | EXR channels | per pixel |
//! |---|---|---|
//! | `albedo` | `albedo.R/G/B` | reflectance of the first non-specular surface: through perfect mirrors and smooth glass as Cycles' denoising albedo, times their tint; 0 where the path leaves the scene |
//! | `normal` | `normal.X/Y/Z` | world-space shading normal of the first hit, facing the camera; 0 on the background; averaged, not renormalized |
//! | `emission` | `emission.R/G/B` | light emitted by the first hit towards the camera (lights, shader emission, unlit maps), film units |
//! | `depth` | `depth.Z` | distance from the camera (lens point) to the first hit; [`BACKGROUND_DEPTH`] where nothing is hit |
//! | `position` | `position.X/Y/Z` | world-space position of the first hit; 0 on the background |
//! | `object_id` | `object_id.X` | 1 + the index of the object hit (the scene's object order, instances their own), 0 on the background |
//! | `samples` | `samples.X` | samples taken: the heat map of adaptive sampling |
//!
//! `albedo`, `normal` and `emission` are filtered like the beauty image
//! (the reconstruction filter's weighted mean of the pixel's samples);
//! `depth`, `position` and `object_id` come from one sample, the one
//! nearest the pixel's centre (the first of those nearest), so that an edge
//! pixel holds a depth and an id that exist in the scene, not a blend of
//! two objects (Cycles takes its first sample for the same reason).
//!
//! The AOV file of an image `name.ext` is `name.aov.exr` beside it
//! ([`aov_file_name`]): one part, 32-bit float channels, ZIP compressed, the
//! beauty as the unnamed layer (`R`, `G`, `B`) so that a plain viewer shows
//! it, each pass as a layer `pass.channel`, the naming Blender's and Nuke's
//! readers split into layers.
//!
//! Other code reads the passes of a finished render from
//! [`RenderedImage::aovs`](crate::render::RenderedImage::aovs): for a
//! denoiser, [`Aovs::albedo`] and [`Aovs::normal`], linear, row-major, top
//! row first, like [`Film::pixels`].

use super::{Film, Filter, Tile};
use luster_core::image::output::{write_atomic, WriteError};
use luster_core::math::Vec3;
use std::path::{Path, PathBuf};

/// The depth written where a pixel's sample hits nothing (as Cycles' Z pass:
/// a far, finite value that every reader handles).
pub const BACKGROUND_DEPTH: f32 = 1e10;

/// One render pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Pass {
    /// Reflectance of the first non-specular surface.
    Albedo,
    /// First-hit shading normal.
    Normal,
    /// Emission seen directly.
    Emission,
    /// Distance to the first hit.
    Depth,
    /// Position of the first hit.
    Position,
    /// The object hit.
    ObjectId,
    /// Samples taken.
    Samples,
}

impl Pass {
    /// Every pass, in the order they are stored and written.
    pub const ALL: [Pass; 7] = [
        Pass::Albedo,
        Pass::Normal,
        Pass::Emission,
        Pass::Depth,
        Pass::Position,
        Pass::ObjectId,
        Pass::Samples,
    ];

    /// Its name on the command line and as the EXR layer.
    pub fn name(self) -> &'static str {
        match self {
            Pass::Albedo => "albedo",
            Pass::Normal => "normal",
            Pass::Emission => "emission",
            Pass::Depth => "depth",
            Pass::Position => "position",
            Pass::ObjectId => "object_id",
            Pass::Samples => "samples",
        }
    }

    /// Its channels' names within the layer.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Pass::Albedo | Pass::Emission => &["R", "G", "B"],
            Pass::Normal | Pass::Position => &["X", "Y", "Z"],
            Pass::Depth => &["Z"],
            Pass::ObjectId | Pass::Samples => &["X"],
        }
    }

    fn bit(self) -> u8 {
        1 << Pass::ALL.iter().position(|&p| p == self).unwrap_or(0)
    }
}

/// A set of passes (`--aov albedo,normal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Passes(u8);

impl Passes {
    /// No pass: the render costs nothing beyond the beauty image.
    pub const NONE: Passes = Passes(0);

    /// The names a list may hold, for messages.
    pub const NAMES: &'static str = "albedo, normal, emission, depth, position, object_id, samples, or all";

    /// Parses a comma-separated list of pass names (`all`: every pass).
    pub fn parse(list: &str) -> Result<Passes, String> {
        let mut set = Passes::NONE;
        for word in list.split(',').map(str::trim) {
            if word == "all" {
                set = Pass::ALL.iter().fold(set, |s, &p| s.with(p));
                continue;
            }
            match Pass::ALL.iter().find(|p| p.name() == word) {
                Some(&p) => set = set.with(p),
                None => {
                    let shown = luster_core::text::shown(word, false);
                    return Err(format!("\"{shown}\" is not a render pass (expected {})", Passes::NAMES));
                }
            }
        }
        Ok(set)
    }

    /// This set and `p`.
    pub fn with(self, p: Pass) -> Passes {
        Passes(self.0 | p.bit())
    }

    /// Whether `p` is in the set.
    pub fn has(self, p: Pass) -> bool {
        self.0 & p.bit() != 0
    }

    /// Whether the set is empty.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// The passes, in [`Pass::ALL`]'s order.
    pub fn iter(self) -> impl Iterator<Item = Pass> {
        Pass::ALL.into_iter().filter(move |&p| self.has(p))
    }

    /// The set as a byte (for part files).
    pub fn bits(self) -> u8 {
        self.0
    }

    /// The set a byte from [`bits`](Self::bits) stands for; `None` for bits
    /// no pass has.
    pub fn from_bits(b: u8) -> Option<Passes> {
        (u32::from(b) < 1 << Pass::ALL.len()).then_some(Passes(b))
    }

    /// Output channels per pixel.
    pub fn channels(self) -> usize {
        self.iter().map(|p| p.channels().len()).sum()
    }

    /// The names, comma-separated (for the job id of a split render).
    pub fn names(self) -> String {
        self.iter().map(Pass::name).collect::<Vec<_>>().join(",")
    }

    /// Bytes per pixel a render with these passes needs beyond the beauty
    /// image's: the accumulators, the finished passes and the EXR encoder's
    /// copy of them.
    pub fn bytes_per_pixel(self) -> u64 {
        if self.is_empty() {
            return 0;
        }
        4 * (Layout::of(self).stride + 2 * self.channels()) as u64
    }
}

/// Where each pass sits in a pixel's accumulator, in `f32`s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Layout {
    albedo: Option<usize>,
    normal: Option<usize>,
    emission: Option<usize>,
    /// The nearest-to-centre sample: its key (2 − squared distance from the
    /// centre; 0: none yet), depth, position and object.
    nearest: Option<usize>,
    samples: Option<usize>,
    /// Floats per pixel.
    pub stride: usize,
}

impl Layout {
    pub(crate) fn of(p: Passes) -> Layout {
        let mut at = 0;
        let mut slot = |on: bool, n: usize| {
            on.then(|| {
                at += n;
                at - n
            })
        };
        let albedo = slot(p.has(Pass::Albedo), 3);
        let normal = slot(p.has(Pass::Normal), 3);
        let emission = slot(p.has(Pass::Emission), 3);
        let nearest = slot(p.has(Pass::Depth) || p.has(Pass::Position) || p.has(Pass::ObjectId), 6);
        let samples = slot(p.has(Pass::Samples), 1);
        Layout { albedo, normal, emission, nearest, samples, stride: at }
    }
}

/// What one camera sample records for the passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AovSample {
    /// See [`Pass::Albedo`].
    pub albedo: Vec3,
    /// See [`Pass::Normal`].
    pub normal: Vec3,
    /// See [`Pass::Emission`].
    pub emission: Vec3,
    /// See [`Pass::Depth`].
    pub depth: f32,
    /// See [`Pass::Position`].
    pub position: Vec3,
    /// See [`Pass::ObjectId`].
    pub object: u32,
}

impl AovSample {
    /// A sample that hit nothing.
    pub const BACKGROUND: AovSample = AovSample {
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        emission: Vec3::ZERO,
        depth: BACKGROUND_DEPTH,
        position: Vec3::ZERO,
        object: 0,
    };
}

/// The pass accumulators of a rectangle of the film, beside its [`Tile`].
pub struct AovTile<'a> {
    x0: u32,
    y0: u32,
    width: u32,
    acc: &'a mut [f32],
    layout: Layout,
    filter: Filter,
}

impl<'a> AovTile<'a> {
    /// Empty accumulators for `passes` covering `rects` (as
    /// [`Tile::all_in`]) in consecutive parts of `store`, replaced by a
    /// zeroed buffer unless it has their size.
    pub fn all_in(
        store: &'a mut Vec<f32>,
        rects: &[(u32, u32, u32, u32)],
        filter: Filter,
        passes: Passes,
    ) -> Vec<AovTile<'a>> {
        let layout = Layout::of(passes);
        let area = |&(x0, y0, x1, y1): &(u32, u32, u32, u32)| (x1 - x0) as usize * (y1 - y0) as usize;
        let n = rects.iter().map(area).sum::<usize>() * layout.stride;
        if store.len() != n {
            *store = vec![0.0; n];
        }
        let mut rest = store.as_mut_slice();
        let mut tiles = Vec::with_capacity(rects.len());
        for r @ &(x0, y0, x1, _) in rects {
            let (acc, tail) = std::mem::take(&mut rest).split_at_mut(area(r) * layout.stride);
            rest = tail;
            tiles.push(AovTile { x0, y0, width: x1 - x0, acc, layout, filter });
        }
        tiles
    }

    /// Forgets its samples (see [`Tile::clear`]).
    pub fn clear(&mut self) {
        self.acc.fill(0.0);
    }

    /// Adds sample `a`, taken at `(jx, jy)` inside pixel `(x, y)`.
    #[inline]
    pub fn add(&mut self, x: u32, y: u32, jx: f32, jy: f32, a: &AovSample) {
        let (dx, dy) = (jx - 0.5, jy - 0.5);
        let w = self.filter.weight(dx, dy);
        let l = self.layout;
        let i = ((y - self.y0) * self.width + (x - self.x0)) as usize * l.stride;
        let px = &mut self.acc[i..i + l.stride];
        let mut add3 = |at: Option<usize>, v: Vec3| {
            if let Some(k) = at {
                px[k] += v.x * w;
                px[k + 1] += v.y * w;
                px[k + 2] += v.z * w;
            }
        };
        add3(l.albedo, a.albedo);
        add3(l.normal, a.normal);
        add3(l.emission, a.emission);
        if let Some(k) = l.nearest {
            // Strictly nearer only: of samples at one distance the first
            // counts, whatever the passes (the order of samples is fixed).
            let key = 2.0 - (dx * dx + dy * dy);
            if key > px[k] {
                px[k] = key;
                px[k + 1] = a.depth;
                px[k + 2] = a.position.x;
                px[k + 3] = a.position.y;
                px[k + 4] = a.position.z;
                px[k + 5] = a.object as f32;
            }
        }
        if let Some(k) = l.samples {
            px[k] += 1.0;
        }
    }

    /// Writes the finished passes into `out`, the filtered ones divided by
    /// the weights `beauty` (this rectangle's [`Tile`]) summed.
    pub fn write(&self, beauty: &Tile, out: &mut Aovs) {
        let l = self.layout;
        let (w, tw) = (out.width as usize, self.width as usize);
        if tw == 0 || l.stride == 0 {
            return;
        }
        for (j, (px, sum)) in self.acc.chunks_exact(l.stride).zip(beauty.sums()).enumerate() {
            let (x, y) = (self.x0 as usize + j % tw, self.y0 as usize + j / tw);
            let at = y * w + x;
            let wt = sum[3];
            let mean =
                |k: usize| if wt > 0.0 { Vec3::new(px[k], px[k + 1], px[k + 2]) / wt } else { Vec3::ZERO };
            for (pass, plane) in &mut out.planes {
                match (pass, plane) {
                    (Pass::Albedo, Plane::Colour(v)) => v[at] = l.albedo.map_or(Vec3::ZERO, mean),
                    (Pass::Normal, Plane::Colour(v)) => v[at] = l.normal.map_or(Vec3::ZERO, mean),
                    (Pass::Emission, Plane::Colour(v)) => v[at] = l.emission.map_or(Vec3::ZERO, mean),
                    (Pass::Position, Plane::Colour(v)) => {
                        v[at] = l.nearest.map_or(Vec3::ZERO, |k| Vec3::new(px[k + 2], px[k + 3], px[k + 4]))
                    }
                    (Pass::Depth, Plane::Scalar(v)) => {
                        v[at] = match l.nearest {
                            Some(k) if px[k] > 0.0 => px[k + 1],
                            _ => BACKGROUND_DEPTH,
                        }
                    }
                    (Pass::ObjectId, Plane::Scalar(v)) => v[at] = l.nearest.map_or(0.0, |k| px[k + 5]),
                    (Pass::Samples, Plane::Scalar(v)) => v[at] = l.samples.map_or(0.0, |k| px[k]),
                    _ => {}
                }
            }
        }
    }
}

/// One finished pass over the image.
#[derive(Clone, Debug, PartialEq)]
pub enum Plane {
    /// Three channels a pixel.
    Colour(Vec<Vec3>),
    /// One channel a pixel.
    Scalar(Vec<f32>),
}

/// The finished passes of an image, each row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Aovs {
    /// Width.
    pub width: u32,
    /// Height.
    pub height: u32,
    planes: Vec<(Pass, Plane)>,
}

impl Aovs {
    /// Passes of a `width`×`height` image with nothing rendered: zero, and
    /// [`BACKGROUND_DEPTH`] for depth.
    pub fn new(width: u32, height: u32, passes: Passes) -> Aovs {
        let n = width as usize * height as usize;
        let planes = passes
            .iter()
            .map(|p| {
                let plane = match p.channels().len() {
                    3 => Plane::Colour(vec![Vec3::ZERO; n]),
                    _ if p == Pass::Depth => Plane::Scalar(vec![BACKGROUND_DEPTH; n]),
                    _ => Plane::Scalar(vec![0.0; n]),
                };
                (p, plane)
            })
            .collect();
        Aovs { width, height, planes }
    }

    /// The passes held.
    pub fn passes(&self) -> Passes {
        self.planes.iter().fold(Passes::NONE, |s, (p, _)| s.with(*p))
    }

    /// Pass `p`, if held.
    pub fn plane(&self, p: Pass) -> Option<&Plane> {
        self.planes.iter().find(|(q, _)| *q == p).map(|(_, v)| v)
    }

    fn colour(&self, p: Pass) -> Option<&[Vec3]> {
        match self.plane(p)? {
            Plane::Colour(v) => Some(v),
            Plane::Scalar(_) => None,
        }
    }

    fn scalar(&self, p: Pass) -> Option<&[f32]> {
        match self.plane(p)? {
            Plane::Scalar(v) => Some(v),
            Plane::Colour(_) => None,
        }
    }

    /// The albedo pass (a denoiser's first feature).
    pub fn albedo(&self) -> Option<&[Vec3]> {
        self.colour(Pass::Albedo)
    }

    /// The normal pass (a denoiser's second feature).
    pub fn normal(&self) -> Option<&[Vec3]> {
        self.colour(Pass::Normal)
    }

    /// The emission pass.
    pub fn emission(&self) -> Option<&[Vec3]> {
        self.colour(Pass::Emission)
    }

    /// The position pass.
    pub fn position(&self) -> Option<&[Vec3]> {
        self.colour(Pass::Position)
    }

    /// The depth pass.
    pub fn depth(&self) -> Option<&[f32]> {
        self.scalar(Pass::Depth)
    }

    /// The object-id pass.
    pub fn object_id(&self) -> Option<&[f32]> {
        self.scalar(Pass::ObjectId)
    }

    /// The samples pass.
    pub fn samples(&self) -> Option<&[f32]> {
        self.scalar(Pass::Samples)
    }

    /// Appends the passes of rectangle `(x0, y0, x1, y1)`: pass after pass
    /// (in [`Pass::ALL`]'s order), each row by row, a pixel's channels
    /// together (for part files).
    pub fn push_rect(&self, out: &mut Vec<f32>, (x0, y0, x1, y1): (u32, u32, u32, u32)) {
        let w = self.width as usize;
        for (_, plane) in &self.planes {
            for y in y0..y1 {
                let row = y as usize * w;
                let span = row + x0 as usize..row + x1 as usize;
                match plane {
                    Plane::Colour(v) => out.extend(v[span].iter().flat_map(|p| p.to_array())),
                    Plane::Scalar(v) => out.extend_from_slice(&v[span]),
                }
            }
        }
    }

    /// Writes values taken by [`push_rect`](Self::push_rect) back; returns
    /// how many it read, or `None` when `data` is too short.
    pub fn pull_rect(&mut self, data: &[f32], (x0, y0, x1, y1): (u32, u32, u32, u32)) -> Option<usize> {
        let w = self.width as usize;
        let tw = (x1 - x0) as usize;
        let mut at = 0;
        for (_, plane) in &mut self.planes {
            for y in y0..y1 {
                let row = y as usize * w + x0 as usize;
                match plane {
                    Plane::Colour(v) => {
                        let src = data.get(at..at + 3 * tw)?;
                        for (p, c) in v[row..row + tw].iter_mut().zip(src.chunks_exact(3)) {
                            *p = Vec3::new(c[0], c[1], c[2]);
                        }
                        at += 3 * tw;
                    }
                    Plane::Scalar(v) => {
                        v[row..row + tw].copy_from_slice(data.get(at..at + tw)?);
                        at += tw;
                    }
                }
            }
        }
        Some(at)
    }
}

/// The AOV file of the image `image_name`: `<stem>.aov.exr` beside it.
pub fn aov_file_name(image_name: &str) -> PathBuf {
    let p = Path::new(image_name);
    let stem = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    p.with_file_name(format!("{stem}.aov.exr"))
}

/// Writes `film` and its passes as one multi-layer EXR at `path` (see the
/// module's documentation), atomically. The bytes depend only on the
/// values: blocks are compressed and written in order on this thread.
pub fn write_aov_exr(path: &Path, film: &Film, aovs: &Aovs) -> Result<(), WriteError> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Compression, Encoding, FlatSamples, Image, Layer, LayerAttributes,
        LineOrder, SmallVec, WritableImage,
    };
    let (w, h) = (film.width as usize, film.height as usize);
    if (aovs.width, aovs.height) != (film.width, film.height) || w == 0 || h == 0 {
        return Err(WriteError {
            path: path.to_path_buf(),
            reason: "the passes do not match the image's size".into(),
        });
    }
    // Neither a NaN nor an infinity is written (readers and compositors
    // choke on them): they become 0.
    let clean = |c: f32| if c.is_finite() { c } else { 0.0 };
    let mut channels = Vec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let plane = film.pixels.iter().map(|p| clean(p[c])).collect();
        channels.push(AnyChannel::new(name, FlatSamples::F32(plane)));
    }
    for (pass, plane) in &aovs.planes {
        for (c, ch) in pass.channels().iter().enumerate() {
            let values = match plane {
                Plane::Colour(v) => v.iter().map(|p| clean(p[c])).collect(),
                Plane::Scalar(v) => v.iter().map(|&s| clean(s)).collect(),
            };
            channels
                .push(AnyChannel::new(format!("{}.{ch}", pass.name()).as_str(), FlatSamples::F32(values)));
        }
    }
    let encoding = Encoding {
        compression: Compression::ZIP16,
        line_order: LineOrder::Increasing,
        ..Encoding::FAST_LOSSLESS
    };
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        encoding,
        AnyChannels::sort(SmallVec::from_vec(channels)),
    );
    write_atomic(path, |out| {
        Image::from_layer(layer).write().non_parallel().to_buffered(out).map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_to_sets_and_unknown_names_are_refused() {
        let s = Passes::parse("albedo, normal,depth").unwrap();
        assert!(s.has(Pass::Albedo) && s.has(Pass::Normal) && s.has(Pass::Depth) && !s.has(Pass::Samples));
        assert_eq!(s.channels(), 7);
        assert_eq!(Passes::parse("all").unwrap().channels(), 15);
        assert_eq!(Passes::from_bits(s.bits()), Some(s));
        assert_eq!(Passes::from_bits(0x80), None);
        let e = Passes::parse("albedo,zdepth").unwrap_err();
        assert!(e.contains("\"zdepth\" is not a render pass"), "{e}");
        assert_eq!(aov_file_name("out/a.png"), PathBuf::from("out/a.aov.exr"));
        assert_eq!(aov_file_name("b.exr"), PathBuf::from("b.aov.exr"));
    }

    #[test]
    fn filtered_passes_average_and_the_nearest_sample_gives_depth_and_id() {
        let rects = [(0, 0, 2, 1)];
        let passes = Passes::parse("all").unwrap();
        let (mut bs, mut astore) = (Vec::new(), Vec::new());
        let mut beauty = Tile::all_in(&mut bs, &rects, Filter::Box).remove(0);
        let mut aov = AovTile::all_in(&mut astore, &rects, Filter::Box, passes).remove(0);
        let s = |albedo: f32, depth: f32, object: u32| AovSample {
            albedo: Vec3::splat(albedo),
            normal: Vec3::Z,
            emission: Vec3::ZERO,
            depth,
            position: Vec3::splat(depth),
            object,
        };
        for (jx, a) in [(0.9, s(0.2, 5.0, 3)), (0.45, s(0.6, 7.0, 4)), (0.55, s(0.4, 9.0, 5))] {
            beauty.add_sample(1, 0, jx, 0.5, Vec3::ONE);
            aov.add(1, 0, jx, 0.5, &a);
        }
        let mut out = Aovs::new(2, 1, passes);
        aov.write(&beauty, &mut out);
        assert!((out.albedo().unwrap()[1] - Vec3::splat(0.4)).abs().max_element() < 1e-6);
        // 0.45 and 0.55 are equally near the centre: the first counts.
        assert_eq!(out.depth().unwrap()[1], 7.0);
        assert_eq!(out.object_id().unwrap()[1], 4.0);
        assert_eq!(out.samples().unwrap()[1], 3.0);
        assert_eq!(out.depth().unwrap()[0], BACKGROUND_DEPTH, "no sample: the background");
        let mut flat = Vec::new();
        out.push_rect(&mut flat, (0, 0, 2, 1));
        assert_eq!(flat.len(), 2 * 15);
        let mut back = Aovs::new(2, 1, passes);
        assert_eq!(back.pull_rect(&flat, (0, 0, 2, 1)), Some(30));
        assert_eq!(back, out);
        assert_eq!(back.pull_rect(&flat[1..], (0, 0, 2, 1)), None);
    }
}
