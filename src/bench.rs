//! `luster bench`: BVH build time, memory and primary-ray throughput on PLY
//! meshes, with exactly the camera and rays of `shared/bench/embree_rays.py`,
//! so the figures line up against Intel Embree's on the same machine.
//!
//! The rays are made once and not timed, as in the Embree script; what is
//! timed is [`MeshAccel::intersect`] on every ray, split into chunks over a
//! rayon pool of exactly the requested number of threads, with each ray's
//! hit written to an output array (as Embree writes its primID array). The
//! hit fraction printed is the check that both programs shoot the same rays:
//! it must match Embree's to about three decimals.

use std::fs;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use rayon::prelude::*;

use crate::accel::MeshAccel;
use crate::math::{Ray, Vec3};

/// Image size of the benchmark camera.
pub const WIDTH: usize = 1920;
/// Image size of the benchmark camera.
pub const HEIGHT: usize = 1080;
/// Rays per parallel work item: small enough to balance, big enough that
/// scheduling is noise.
const CHUNK: usize = 4096;
/// Builds timed per mesh (the median is reported).
const BUILDS: usize = 3;

/// Runs the benchmark on each mesh and prints a table per mesh.
pub fn run(plys: &[PathBuf], threads: &[usize], reps: usize) -> anyhow::Result<()> {
    let reps = reps.max(1);
    for path in plys {
        let t0 = Instant::now();
        let (positions, triangles) = load_mesh(path)?;
        let t_load = t0.elapsed().as_secs_f64();
        println!(
            "== {}: {} tris, {} verts; ply load {:.3} s",
            path.display(),
            triangles.len(),
            positions.len(),
            t_load
        );

        let mut build_times = Vec::with_capacity(BUILDS);
        let mut accel = None;
        for _ in 0..BUILDS {
            // Drop the previous tree first so peak memory is one tree's worth.
            drop(accel.take());
            let t0 = Instant::now();
            accel = Some(MeshAccel::build(&positions, &triangles));
            build_times.push(t0.elapsed().as_secs_f64());
        }
        let accel = accel.context("no build ran")?;
        let bvh = accel.bvh();
        println!(
            "   BVH build {:.1} ms (median of {BUILDS}; all cores); {} 4-wide nodes, depth {} (binary {}), {} leaves; accel {:.1} MiB",
            median(&mut build_times) * 1e3,
            bvh.node_count(),
            bvh.depth(),
            bvh.binary_depth(),
            bvh.leaf_count(),
            accel.memory_bytes() as f64 / (1 << 20) as f64
        );

        let (eye, target, dirs) = camera_rays(&positions);
        println!("   camera eye {:?} target {:?}; {} rays ({WIDTH}x{HEIGHT})", eye, target, dirs.len());
        let mut out = vec![u32::MAX; dirs.len()];
        trace(&accel, eye, &dirs, &mut out);
        let hits = out.iter().filter(|&&p| p != u32::MAX).count();
        println!("   hit fraction {:.4}", hits as f64 / dirs.len() as f64);

        let mut base = None;
        for &n in threads {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(n.max(1)).build()?;
            let mut times: Vec<f64> = (0..reps)
                .map(|_| {
                    let t0 = Instant::now();
                    pool.install(|| trace(&accel, eye, &dirs, &mut out));
                    t0.elapsed().as_secs_f64()
                })
                .collect();
            let min = times.iter().copied().fold(f64::INFINITY, f64::min);
            let med = median(&mut times);
            let mrays = dirs.len() as f64 / med / 1e6;
            let scale = base.map_or(String::new(), |b: f64| format!("  ({:.2}x of first)", mrays / b));
            base.get_or_insert(mrays);
            println!(
                "   threads={n:<2} closest hit: median {:7.1} ms over {reps} -> {mrays:6.2} Mrays/s (min {:.1} ms){scale}",
                med * 1e3,
                min * 1e3
            );
        }
        if let Some(kib) = peak_rss_kib() {
            println!("   peak RSS so far {:.1} MiB", kib as f64 / 1024.0);
        }
    }
    Ok(())
}

/// Closest hit for every ray, the hit triangle (or `u32::MAX`) into `out`.
fn trace(accel: &MeshAccel, eye: Vec3, dirs: &[Vec3], out: &mut [u32]) {
    out.par_chunks_mut(CHUNK).zip(dirs.par_chunks(CHUNK)).for_each(|(out, dirs)| {
        for (o, &d) in out.iter_mut().zip(dirs) {
            *o = accel.intersect(&Ray::new(eye, d), 0.0, f32::INFINITY).map_or(u32::MAX, |h| h.prim);
        }
    });
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The benchmark camera, replicating `camera_rays` of `embree_rays.py`
/// operation by operation (f32 where numpy works in f32, f64 where it
/// promotes): returns the eye, the bounding-box centre it looks at, and the
/// unit directions in scanline order.
pub fn camera_rays(positions: &[Vec3]) -> (Vec3, Vec3, Vec<Vec3>) {
    let lo = positions.iter().fold(Vec3::INFINITY, |a, &p| a.min(p));
    let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, &p| a.max(p));
    let c = (lo + hi) / 2.0;
    let ext = hi - lo;
    // np.argsort on three elements is an insertion sort: stable.
    let mut ax = [0usize, 1, 2];
    ax.sort_by(|&a, &b| ext[a].total_cmp(&ext[b]));
    let (w_ax, u_ax, v_ax) = (ax[0], ax[2], ax[1]);
    let th = (45.0f64.to_radians() / 2.0).tan();
    let aspect = WIDTH as f64 / HEIGHT as f64;
    let dist = f64::max((ext[u_ax] / 2.0) as f64 / (th * aspect), (ext[v_ax] / 2.0) as f64 / th) * 1.05;
    let mut eye = c;
    eye[w_ax] = (c[w_ax] as f64 + dist) as f32;
    let mut dirs = Vec::with_capacity(WIDTH * HEIGHT);
    for j in 0..HEIGHT {
        let y = (1.0 - (j as f64 + 0.5) / HEIGHT as f64 * 2.0) * th;
        for i in 0..WIDTH {
            let x = ((i as f64 + 0.5) / WIDTH as f64 * 2.0 - 1.0) * th * aspect;
            let mut d = Vec3::ZERO;
            d[u_ax] = x as f32;
            d[v_ax] = y as f32;
            d[w_ax] = -1.0;
            let norm = (d.x * d.x + d.y * d.y + d.z * d.z).sqrt();
            dirs.push(d / norm);
        }
    }
    (eye, c, dirs)
}

/// Peak resident set size of this process (VmHWM), where /proc has it.
pub fn peak_rss_kib() -> Option<u64> {
    let status = fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Reads a mesh's positions and triangles.
///
/// Stand-in for `crate::scene::ply::read_ply` (not on this branch yet): swap
/// the body for `let m = read_ply(path)?; Ok((m.positions, m.triangles))`
/// and delete `stand_in_ply`.
pub fn load_mesh(path: &Path) -> anyhow::Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
    let bytes = fs::read(path).with_context(|| format!("reading {}", path.display()))?;
    stand_in_ply::parse(&bytes).with_context(|| format!("parsing {}", path.display()))
}

/// A minimal PLY reader (ascii and binary, vertex x/y/z and face index lists
/// fanned into triangles), only for the benchmark until the real loader
/// lands.
mod stand_in_ply {
    use anyhow::{bail, Context};

    use crate::math::Vec3;

    #[derive(Clone, Copy, PartialEq)]
    enum Format {
        Ascii,
        Le,
        Be,
    }

    #[derive(Clone, Copy)]
    enum Ty {
        I8,
        U8,
        I16,
        U16,
        I32,
        U32,
        F32,
        F64,
    }

    impl Ty {
        fn parse(s: &str) -> anyhow::Result<Ty> {
            Ok(match s {
                "char" | "int8" => Ty::I8,
                "uchar" | "uint8" => Ty::U8,
                "short" | "int16" => Ty::I16,
                "ushort" | "uint16" => Ty::U16,
                "int" | "int32" => Ty::I32,
                "uint" | "uint32" => Ty::U32,
                "float" | "float32" => Ty::F32,
                "double" | "float64" => Ty::F64,
                _ => bail!("unknown PLY type {s}"),
            })
        }
        fn size(self) -> usize {
            match self {
                Ty::I8 | Ty::U8 => 1,
                Ty::I16 | Ty::U16 => 2,
                Ty::I32 | Ty::U32 | Ty::F32 => 4,
                Ty::F64 => 8,
            }
        }
    }

    enum Prop {
        Scalar(Ty, String),
        List(Ty, Ty, String),
    }

    struct Element {
        name: String,
        count: usize,
        props: Vec<Prop>,
    }

    /// Reads values one at a time from the body, whatever the encoding.
    struct Reader<'a> {
        fmt: Format,
        body: &'a [u8],
        pos: usize,
        tokens: std::str::SplitAsciiWhitespace<'a>,
    }

    impl Reader<'_> {
        fn value(&mut self, ty: Ty) -> anyhow::Result<f64> {
            if self.fmt == Format::Ascii {
                let tok = self.tokens.next().context("unexpected end of PLY data")?;
                return tok.parse::<f64>().with_context(|| format!("bad PLY number {tok:?}"));
            }
            let n = ty.size();
            let b = self.body.get(self.pos..self.pos + n).context("unexpected end of PLY data")?;
            self.pos += n;
            let mut a = [0u8; 8];
            a[..n].copy_from_slice(b);
            if self.fmt == Format::Be {
                a[..n].reverse();
            }
            Ok(match ty {
                Ty::I8 => a[0] as i8 as f64,
                Ty::U8 => a[0] as f64,
                Ty::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                Ty::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                Ty::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Ty::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Ty::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                Ty::F64 => f64::from_le_bytes(a),
            })
        }
    }

    pub(super) fn parse(bytes: &[u8]) -> anyhow::Result<(Vec<Vec3>, Vec<[u32; 3]>)> {
        let marker = b"end_header";
        let end = bytes.windows(marker.len()).position(|w| w == marker).context("no end_header")?;
        let mut body_start = end + marker.len();
        // The header line ends in \n or \r\n.
        while body_start < bytes.len() && bytes[body_start] != b'\n' {
            body_start += 1;
        }
        body_start += 1;
        let header = std::str::from_utf8(&bytes[..end]).context("PLY header is not text")?;
        let mut fmt = None;
        let mut elements: Vec<Element> = Vec::new();
        for line in header.lines() {
            let t: Vec<&str> = line.split_whitespace().collect();
            match t.as_slice() {
                ["format", f, ..] => {
                    fmt = Some(match *f {
                        "ascii" => Format::Ascii,
                        "binary_little_endian" => Format::Le,
                        "binary_big_endian" => Format::Be,
                        _ => bail!("unknown PLY format {f}"),
                    })
                }
                ["element", name, count] => elements.push(Element {
                    name: name.to_string(),
                    count: count.parse().context("bad element count")?,
                    props: Vec::new(),
                }),
                ["property", "list", ct, it, name] => elements
                    .last_mut()
                    .context("property before element")?
                    .props
                    .push(Prop::List(Ty::parse(ct)?, Ty::parse(it)?, name.to_string())),
                ["property", ty, name] => elements
                    .last_mut()
                    .context("property before element")?
                    .props
                    .push(Prop::Scalar(Ty::parse(ty)?, name.to_string())),
                _ => {}
            }
        }
        let fmt = fmt.context("PLY header has no format")?;
        let body = bytes.get(body_start..).unwrap_or_default();
        let text = if fmt == Format::Ascii {
            std::str::from_utf8(body).context("ascii PLY is not text")?
        } else {
            ""
        };
        let mut r = Reader { fmt, body, pos: 0, tokens: text.split_ascii_whitespace() };
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        let mut row = Vec::new();
        for e in &elements {
            let is_vertex = e.name == "vertex";
            let is_face = e.name == "face";
            let xyz: Vec<Option<usize>> = e
                .props
                .iter()
                .map(|p| match p {
                    Prop::Scalar(_, n) => ["x", "y", "z"].iter().position(|a| a == n),
                    Prop::List(..) => None,
                })
                .collect();
            if is_vertex {
                // The header's count is untrusted: never reserve more than
                // the file could hold.
                positions.reserve(e.count.min(bytes.len() / 3));
            }
            for _ in 0..e.count {
                let mut p = [0.0f32; 3];
                for (prop, slot) in e.props.iter().zip(&xyz) {
                    match prop {
                        Prop::Scalar(ty, _) => {
                            let v = r.value(*ty)?;
                            if let Some(k) = slot {
                                p[*k] = v as f32;
                            }
                        }
                        Prop::List(ct, it, name) => {
                            let n = r.value(*ct)? as usize;
                            row.clear();
                            for _ in 0..n {
                                row.push(r.value(*it)?);
                            }
                            if is_face && (name == "vertex_indices" || name == "vertex_index") {
                                for k in 1..n.saturating_sub(1) {
                                    triangles.push([row[0] as u32, row[k] as u32, row[k + 1] as u32]);
                                }
                            }
                        }
                    }
                }
                if is_vertex {
                    positions.push(Vec3::from(p));
                }
            }
        }
        Ok((positions, triangles))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stand_in_reader_reads_ascii_and_binary() {
        let ascii = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let (p, t) = stand_in_ply::parse(ascii).unwrap();
        assert_eq!(p.len(), 4);
        assert_eq!(p[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(t, vec![[0, 1, 2], [0, 2, 3]]);

        let mut bin = b"ply\r\nformat binary_little_endian 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n\
property float z\r\nproperty float u\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\nend_header\r\n"
            .to_vec();
        for v in [[0.0f32, 0.0, 0.0, 9.0], [2.0, 0.0, 0.0, 9.0], [0.0, 2.0, 5.0, 9.0]] {
            v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
        }
        bin.push(3);
        [0i32, 1, 2].iter().for_each(|i| bin.extend(i.to_le_bytes()));
        let (p, t) = stand_in_ply::parse(&bin).unwrap();
        assert_eq!(p[2], Vec3::new(0.0, 2.0, 5.0));
        assert_eq!(t, vec![[0, 1, 2]]);
        assert!(stand_in_ply::parse(&bin[..bin.len() - 2]).is_err(), "truncated data is an error");
    }

    #[test]
    fn camera_frames_the_box_along_its_thinnest_axis() {
        // A box thin in z, wide in x: the camera looks down -z, x is horizontal.
        let pts = [Vec3::new(-2.0, -1.0, -0.1), Vec3::new(2.0, 1.0, 0.1)];
        let (eye, target, dirs) = camera_rays(&pts);
        assert_eq!(target, Vec3::ZERO);
        assert!(eye.x == 0.0 && eye.y == 0.0 && eye.z > 0.0);
        assert_eq!(dirs.len(), WIDTH * HEIGHT);
        let first = dirs[0];
        assert!(first.x < 0.0 && first.y > 0.0 && first.z < 0.0, "top-left pixel first: {first}");
        assert!(dirs.iter().all(|d| (d.length() - 1.0).abs() < 1e-6));
        // The frame's half-width at the box centre is 1.05 times the box's.
        let right = dirs[WIDTH - 1];
        let x_at_center = right.x / -right.z * eye.z;
        assert!((x_at_center - 2.0 * 1.05).abs() < 0.01, "{x_at_center}");
    }
}
