//! Loads one mesh file the way a render does and prints the seconds it
//! took and the process's peak resident memory, for `tools/gltf_load_bench.sh`
//! (one process per measurement, so each peak is its own).
//!
//! ```sh
//! cargo run --release --example load_time -- gltf mesh.glb   # the whole glTF scene description
//! cargo run --release --example load_time -- ply mesh.ply    # the PLY reader a scene build uses
//! ```
//!
//! Prints `seconds peak_rss_kib triangles`.

use std::path::Path;
use std::time::Instant;

fn main() -> std::process::ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (Some(kind), Some(file)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: load_time gltf|ply FILE");
        return std::process::ExitCode::from(2);
    };
    let t = Instant::now();
    let triangles = match kind.as_str() {
        "gltf" => luster::scene::load(Path::new(file))
            .map(|d| {
                d.objects
                    .iter()
                    .map(|o| match &o.shape {
                        luster::scene::description::Shape::Mesh {
                            source: luster::scene::description::MeshSource::Arrays(a),
                            ..
                        } => a.triangles.len(),
                        _ => 0,
                    })
                    .sum::<usize>()
            })
            .map_err(|e| e.to_string()),
        "ply" => luster::scene::ply::read_ply(Path::new(file))
            .map(|m| m.triangles.len())
            .map_err(|e| e.to_string()),
        _ => Err(format!("unknown kind {kind} (gltf or ply)")),
    };
    let secs = t.elapsed().as_secs_f64();
    match triangles {
        Ok(n) => {
            // SAFETY: getrusage only writes the struct it is given.
            let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
            unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
            println!("{secs:.4} {} {n}", usage.ru_maxrss);
            std::process::ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::from(2)
        }
    }
}
