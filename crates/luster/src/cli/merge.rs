//! `luster merge OUTDIR`: the part files of a split render become its images
//! (see `luster::cluster::merge`).

use luster_core::text::shown;
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

/// Merges, printing what was written and how long it took.
pub fn run(outdir: &Path) -> ExitCode {
    let t = Instant::now();
    match luster::cluster::merge::merge(outdir) {
        Ok(m) => {
            for p in &m.written {
                say!("{}", shown(&p.display().to_string(), false));
            }
            say!(
                "merged {} part files into {} files in {:.3} s",
                m.parts,
                m.written.len(),
                t.elapsed().as_secs_f64()
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            super::report("error", &e);
            ExitCode::from(2)
        }
    }
}
