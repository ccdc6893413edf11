//! Writes a medium's baked density grid as a Mitsuba 3 `gridvolume` file
//! (binary `.vol`: `VOL`, version 3, encoding 1 = float32, x y z
//! resolution, 1 channel, the bounding box, then the samples with x
//! fastest), the grid's values times the volume's `Density`, and prints the
//! box Mitsuba should give it.
//!
//! ```sh
//! cargo run --release --example export_volume -- SCENE.xml VOLUME_ID OUT.vol
//! ```
//!
//! The volume needs a `<Shader>` and a `<GridResolution>`; one without a
//! grid, an unknown id or an unreadable scene exits with status 2 and one
//! sentence.
//!
//! luster's lattice has n points spanning the bound's own box `[a, b]`
//! (spacing `h = (b − a)/(n − 1)`, corners included, interpolated
//! trilinearly between them); Mitsuba puts voxel centres at `(i + 0.5)/n` of
//! its box, so the same samples in Mitsuba span `[a − h/2, b + h/2]` per axis.
//! That box is in the bound's own space: the example maps it to the world by
//! the bound's transform (`Bound::to_world`: the volume's `Transformations`,
//! and an ellipsoid's radii and centre, its own space being the unit ball's)
//! and prints it as a world box when the transform keeps axes aligned (no
//! rotation), and always as `to_world`, the matrix taking Mitsuba's unit
//! cube `[0, 1]³` of the `gridvolume` onto it. The last line printed is that
//! information as JSON, for scripts (tools/volume_crosscheck.py).
//!
//! The header's bounding box is the world box (Mitsuba 3 ignores it unless
//! the volume sets `use_grid_bbox`; give the `gridvolume` the printed
//! `to_world` instead).

use luster::math::Vec3;
use luster::render::Scene;
use luster::volume::Volume;
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Exit status for every error: bad arguments, scene, id or grid.
const USAGE_ERROR: u8 = 2;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("export_volume: {msg}");
            ExitCode::from(USAGE_ERROR)
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene_path, id, out] = &args[..] else {
        return Err("usage: export_volume SCENE.xml VOLUME_ID OUT.vol (three arguments).".into());
    };
    let desc =
        luster::scene::load(Path::new(scene_path)).map_err(|e| format!("cannot read {scene_path}: {e}"))?;
    let scene = Scene::build(&desc).map_err(|e| format!("cannot build {scene_path}: {e}"))?;
    let label = format!("Volume[id={id}]");
    let Some(vol) = scene.volumes.media.iter().find(|v| v.label == label) else {
        let ids: Vec<&str> = scene
            .volumes
            .media
            .iter()
            .map(|v| v.label.trim_start_matches("Volume[id=").trim_end_matches(']'))
            .collect();
        return Err(format!("{scene_path} has no medium with id \"{id}\" (its media: {}).", ids.join(", ")));
    };
    let Some(grid) = vol.density_grid() else {
        return Err(format!(
            "{label} has no density grid: give it a <Shader> and a <GridResolution> to bake one."
        ));
    };
    let dims = grid.dims();
    let scale = vol.density_scale();
    let mut data = Vec::with_capacity(dims[0] * dims[1] * dims[2]);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                // The render clamps negative densities to zero.
                data.push(grid.sample(x, y, z).max(0.0) * scale);
            }
        }
    }
    let lattice = grid.bounds();
    let n = Vec3::new(dims[0] as f32, dims[1] as f32, dims[2] as f32);
    let half = (lattice.max - lattice.min) / (n - 1.0) * 0.5;
    let (lo, hi) = (lattice.min - half, lattice.max + half);
    let frame = MitsubaFrame::new(vol, lo, hi);
    write_vol(Path::new(out), dims, frame.world_box(), &data)
        .map_err(|e| format!("cannot write {out}: {e}"))?;

    let max = data.iter().copied().fold(0.0f32, f32::max);
    let mean = data.iter().map(|&d| d as f64).sum::<f64>() / data.len() as f64;
    println!(
        "wrote {out}: {} x {} x {} samples, density x {scale}, max {max}, mean {mean:.6}",
        dims[0], dims[1], dims[2]
    );
    println!("luster lattice (bound space): {} .. {}", v3(lattice.min), v3(lattice.max));
    println!("mitsuba box (bound space):    {} .. {}", v3(lo), v3(hi));
    match frame.aligned_box() {
        Some((a, b)) if frame.identity => {
            println!("mitsuba box (world, untransformed bound): {} .. {}", v3(a), v3(b))
        }
        Some((a, b)) => {
            println!("mitsuba box (world, through the bound's transform): {} .. {}", v3(a), v3(b))
        }
        None => println!("the bound's transform turns the box: use to_world below, not an axis-aligned box"),
    }
    let m = frame.unit_cube_to_world();
    let rows: Vec<String> = m.iter().map(|r| format!("[{}, {}, {}, {}]", r[0], r[1], r[2], r[3])).collect();
    println!("mitsuba gridvolume to_world ([0,1]^3 -> world): [{}]", rows.join(", "));
    let info = serde_json::json!({
        "file": out,
        "dims": dims,
        "density_scale": scale,
        "max": max,
        "mean": mean,
        "lattice_min": lattice.min.to_array(),
        "lattice_max": lattice.max.to_array(),
        "box_local_min": lo.to_array(),
        "box_local_max": hi.to_array(),
        "transformed": !frame.identity,
        "world_box": frame.aligned_box().map(|(a, b)| serde_json::json!({"min": a.to_array(), "max": b.to_array()})),
        "to_world": m,
    });
    println!("{info}");
    Ok(())
}

/// Mitsuba's box `[lo, hi]` (bound space) placed in the world by the
/// volume's bound transform.
struct MitsubaFrame {
    /// The box's `lo` corner in the world.
    origin: Vec3,
    /// Its three edges in the world (images of the x, y and z edges).
    edges: [Vec3; 3],
    /// Whether the bound has no transform at all.
    identity: bool,
}

impl MitsubaFrame {
    fn new(vol: &Volume, lo: Vec3, hi: Vec3) -> MitsubaFrame {
        let b = &vol.bound;
        let origin = b.to_world(lo);
        let d = hi - lo;
        let corners =
            [lo + Vec3::new(d.x, 0.0, 0.0), lo + Vec3::new(0.0, d.y, 0.0), lo + Vec3::new(0.0, 0.0, d.z)];
        let edges = corners.map(|c| b.to_world(c) - origin);
        // An affine map that fixes four affinely independent points is the identity.
        let identity = origin == lo && corners.iter().all(|&c| b.to_world(c) == c);
        MitsubaFrame { origin, edges, identity }
    }

    /// The world box, when every edge stays along its axis (within 1e-5
    /// of its length).
    fn aligned_box(&self) -> Option<(Vec3, Vec3)> {
        for (axis, e) in self.edges.iter().enumerate() {
            let len = e.length();
            let off: f32 = (0..3).filter(|&k| k != axis).map(|k| e[k].abs()).sum();
            if off > 1e-5 * len {
                return None;
            }
        }
        let far = self.origin + self.edges[0] + self.edges[1] + self.edges[2];
        Some((self.origin.min(far), self.origin.max(far)))
    }

    /// A world box around the frame (the header's bounding box).
    fn world_box(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::INFINITY;
        let mut hi = Vec3::NEG_INFINITY;
        for i in 0..8 {
            let mut p = self.origin;
            for (k, e) in self.edges.iter().enumerate() {
                if i & (1 << k) != 0 {
                    p += *e;
                }
            }
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    /// Row-major 4×4 matrix taking `[0, 1]³` onto the box in the world.
    fn unit_cube_to_world(&self) -> [[f32; 4]; 4] {
        let [ex, ey, ez] = self.edges;
        let o = self.origin;
        [[ex.x, ey.x, ez.x, o.x], [ex.y, ey.y, ez.y, o.y], [ex.z, ey.z, ez.z, o.z], [0.0, 0.0, 0.0, 1.0]]
    }
}

/// Mitsuba's `.vol`: little-endian header, then float32 samples, x fastest.
fn write_vol(path: &Path, dims: [usize; 3], (lo, hi): (Vec3, Vec3), data: &[f32]) -> std::io::Result<()> {
    let too_big = || std::io::Error::other("the grid has more than 2^31 samples along an axis");
    let mut bytes = Vec::with_capacity(48 + 4 * data.len());
    bytes.extend_from_slice(b"VOL");
    bytes.push(3);
    bytes.extend_from_slice(&1i32.to_le_bytes());
    for d in dims {
        bytes.extend_from_slice(&i32::try_from(d).map_err(|_| too_big())?.to_le_bytes());
    }
    bytes.extend_from_slice(&1i32.to_le_bytes());
    for c in [lo.x, lo.y, lo.z, hi.x, hi.y, hi.z] {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    for d in data {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    let mut f = std::fs::File::create(path)?;
    f.write_all(&bytes)?;
    f.flush()
}

fn v3(v: Vec3) -> String {
    format!("({}, {}, {})", v.x, v.y, v.z)
}
