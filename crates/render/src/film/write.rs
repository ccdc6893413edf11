//! Writing a [`Film`]'s outputs: the 8-bit image each output asks for, and
//! every file of a camera written in parallel, each one whole or not at all.

use super::Film;
use luster_core::image::output::{write_rgb32f, write_rgb8, WriteError};
use luster_core::image::outputs::{Output, OutputKind};
use std::path::{Path, PathBuf};

/// The 8-bit image `kind` asks for (`None` for [`OutputKind::Hdr`]).
pub fn rgb8(film: &Film, kind: &OutputKind) -> Option<Vec<u8>> {
    match kind {
        OutputKind::Hdr => None,
        OutputKind::Course => Some(film.to_rgb8()),
        OutputKind::Tonemapped(t) => Some(t.apply(&film.pixels)),
        OutputKind::Display(d) => Some(d.apply(&film.pixels)),
    }
}

/// Writes every output of `film` under `outdir`; returns the paths written,
/// in the order of `outputs`. Each file appears whole or not at all, but a
/// failure to write one does not stop the others.
///
/// The HDR files are encoded and written on threads of their own while the
/// 8-bit ones are tone-mapped and encoded on rayon's pool. An HDR writer
/// spends most of its time in the kernel, copying 12 bytes a pixel into
/// the page cache. When the rename replaces an older image, the file system
/// frees that image's blocks (slowly on ext4 mounted with `discard`, with
/// no CPU used) when its last handle closes, which
/// [`write_atomic`](luster_core::image::output) leaves to a thread of its own.
pub fn write_outputs(film: &Film, outdir: &Path, outputs: &[Output]) -> Result<Vec<PathBuf>, WriteError> {
    use rayon::prelude::*;
    let write = |o: &Output| -> Result<PathBuf, WriteError> {
        let path = outdir.join(&o.name);
        match rgb8(film, &o.kind) {
            None => write_rgb32f(&path, film.width, film.height, &film.pixels)?,
            Some(rgb) => write_rgb8(&path, film.width, film.height, &rgb)?,
        }
        Ok(path)
    };
    let is_hdr = |o: &&Output| o.kind == OutputKind::Hdr;
    let (hdr, ldr): (Vec<&Output>, Vec<&Output>) = outputs.iter().partition(is_hdr);
    let (hdr_results, ldr_results) = std::thread::scope(|s| {
        let writers: Vec<_> = hdr.iter().map(|o| s.spawn(|| write(o))).collect();
        let ldr_results: Vec<Result<PathBuf, WriteError>> = ldr.par_iter().map(|o| write(o)).collect();
        let hdr_results: Vec<Result<PathBuf, WriteError>> = writers
            .into_iter()
            .map(|w| w.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic)))
            .collect();
        (hdr_results, ldr_results)
    });
    // Back into the order of `outputs`.
    let (mut hdr_results, mut ldr_results) = (hdr_results.into_iter(), ldr_results.into_iter());
    outputs
        .iter()
        .map(|o| {
            let next = if is_hdr(&o) { hdr_results.next() } else { ldr_results.next() };
            next.unwrap_or_else(|| unreachable!("one result per output"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster_core::image::outputs::plan_outputs;
    use luster_core::tonemap::{Display, Operator, Tonemap};

    #[test]
    fn every_output_is_written_and_reported_in_plan_order() {
        let dir = tempfile::tempdir().unwrap();
        let mut film = Film::new(7, 3);
        for (i, p) in film.pixels.iter_mut().enumerate() {
            *p = luster_core::math::Vec3::new(i as f32 * 40.0, 300.0 - i as f32, (i % 4) as f32 * 90.0);
        }
        let t = |operator| Tonemap { operator, ..Tonemap::COURSE_DEFAULT };
        let maps = [t(Operator::Photographic), t(Operator::Aces)];
        // The HDR files come first and last, so their results must be put
        // back in place around the 8-bit ones.
        let mut plan = plan_outputs("a.exr", &maps, Display::Course).unwrap();
        plan.extend(plan_outputs("b.hdr", &[], Display::Course).unwrap().into_iter().rev());
        let paths = write_outputs(&film, dir.path(), &plan).unwrap();
        let want: Vec<PathBuf> = plan.iter().map(|o| dir.path().join(&o.name)).collect();
        assert_eq!(paths, want);
        for (o, path) in plan.iter().zip(&paths) {
            let back = image::open(path).unwrap();
            match rgb8(&film, &o.kind) {
                Some(rgb) => assert!(back.to_rgb8().into_raw() == rgb, "{}", path.display()),
                None => assert_eq!(back.to_rgb32f().dimensions(), (7, 3), "{}", path.display()),
            }
        }
        let exr = image::open(&paths[0]).unwrap().to_rgb32f().into_raw();
        assert!(exr == film.pixels.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>());
    }

    #[test]
    fn a_failed_hdr_write_is_the_error() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("sub"), b"a file, not a folder").unwrap();
        let plan = [
            Output { name: PathBuf::from("ok.png"), kind: OutputKind::Course },
            Output { name: PathBuf::from("sub/x.exr"), kind: OutputKind::Hdr },
        ];
        let e = write_outputs(&Film::new(2, 2), dir.path(), &plan).unwrap_err();
        assert!(e.path.ends_with("sub/x.exr"), "{e}");
        assert!(dir.path().join("ok.png").is_file(), "the other output is still written");
    }
}
