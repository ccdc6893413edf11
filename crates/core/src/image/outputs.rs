//! Which files a camera writes: the names and contents an `ImageName` and
//! its `Tonemap`s ask for.
//!
//! | `ImageName` | `Tonemap`s | files |
//! |---|---|---|
//! | `x.png`, `x.jpg` | none | `x.png`: the course's clamp and truncation, no gamma |
//! | `x.png` | one or more | `x.png` tone-mapped by the first; `x_<tmo>.png` by each further one |
//! | `x.exr`, `x.hdr` | none | `x.exr` (32-bit float) and `x.png` tone-mapped by hw5's example operator |
//! | `x.exr`, `x.hdr` | one or more | `x.exr`, `x.png` by the first, `x_<tmo>.png` by each further one |
//!
//! Under a scene's display transform ([`Display`] other than `course`), the
//! rows without a `Tonemap` write their 8-bit image through that transform
//! instead of the course's clamp or hw5's example operator; an explicit
//! `Tonemap` still wins.
//!
//! `<tmo>` is the operator's lower-case name (`photographic`, `aces`,
//! `filmic`); a name used twice gets `_2`, `_3`, ... The course writes
//! `x.exr` beside `x.png` (hw5 `cube_point_hdr`, every hw7 image); its 2025
//! JSON files may list several `Tonemap`s, whose PNG names could not be found
//! in any course file, hence the rule above.

use super::output::{HDR_EXTENSIONS, LDR_EXTENSIONS};
use crate::tonemap::{Display, Tonemap};
use std::path::{Path, PathBuf};

/// What one output file holds.
#[derive(Clone, Debug, PartialEq)]
pub enum OutputKind {
    /// Linear radiance, 32-bit float (`.exr`) or RGBE (`.hdr`).
    Hdr,
    /// 8-bit with the course's clamp and truncation.
    Course,
    /// 8-bit tone-mapped.
    Tonemapped(Tonemap),
    /// 8-bit through the scene's display transform (never `course`).
    Display(Display),
}

/// One file a camera writes.
#[derive(Clone, Debug, PartialEq)]
pub struct Output {
    /// Path relative to the output folder.
    pub name: PathBuf,
    /// What it holds.
    pub kind: OutputKind,
}

/// The files for `image_name` and the camera's `tonemaps` under the scene's
/// `display`, or a sentence saying why the name cannot be written. The names
/// do not depend on `display`.
pub fn plan_outputs(image_name: &str, tonemaps: &[Tonemap], display: Display) -> Result<Vec<Output>, String> {
    let path = Path::new(image_name);
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
    let hdr = HDR_EXTENSIONS.contains(&ext.as_str());
    if !hdr && !LDR_EXTENSIONS.contains(&ext.as_str()) {
        return Err(format!(
            "\"{image_name}\" must end in .{} or .{}, the formats luster writes",
            LDR_EXTENSIONS.join(", ."),
            HDR_EXTENSIONS.join(", .")
        ));
    }
    let mut out = Vec::new();
    let ldr_ext = if hdr { "png" } else { ext.as_str() };
    if hdr {
        out.push(Output { name: path.to_path_buf(), kind: OutputKind::Hdr });
    }
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("image");
    if tonemaps.is_empty() && display.is_linear_workflow() {
        let name = if hdr { path.with_file_name(format!("{stem}.png")) } else { path.to_path_buf() };
        out.push(Output { name, kind: OutputKind::Display(display) });
        return Ok(out);
    }
    let maps: &[Tonemap] = if hdr && tonemaps.is_empty() { &[Tonemap::COURSE_DEFAULT] } else { tonemaps };
    if maps.is_empty() {
        out.push(Output { name: path.to_path_buf(), kind: OutputKind::Course });
    }
    let mut used: Vec<String> = Vec::new();
    for (i, t) in maps.iter().enumerate() {
        let file = if i == 0 {
            format!("{stem}.{ldr_ext}")
        } else {
            let base = format!("{stem}_{}", t.operator.name());
            let mut name = base.clone();
            let mut k = 1;
            while used.contains(&name) {
                k += 1;
                name = format!("{base}_{k}");
            }
            used.push(name.clone());
            format!("{name}.{ldr_ext}")
        };
        out.push(Output { name: path.with_file_name(file), kind: OutputKind::Tonemapped(*t) });
    }
    Ok(out)
}

/// The first 8-bit output of a camera: the image a person (or the
/// conformance suite, against the course's `.png`) looks at. `None` when the
/// name cannot be written.
pub fn first_ldr(image_name: &str, tonemaps: &[Tonemap], display: Display) -> Option<Output> {
    plan_outputs(image_name, tonemaps, display).ok()?.into_iter().find(|o| o.kind != OutputKind::Hdr)
}

/// The first file name that two outputs (of one camera or of several) share,
/// compared after joining to the output folder. Case and Unicode
/// normalisation are not folded: on such file systems two names may still
/// meet.
pub fn first_clash<'a>(names: impl IntoIterator<Item = &'a Path>) -> Option<PathBuf> {
    let mut seen = std::collections::HashSet::new();
    names.into_iter().find(|n| !seen.insert(file_key(n))).map(Path::to_path_buf)
}

/// The form of an output name that two names of one file share (`./a.png`
/// and `a.png`, `x//a.png` and `x/a.png`).
pub fn file_key(name: &Path) -> PathBuf {
    name.components().filter(|c| !matches!(c, std::path::Component::CurDir)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tonemap::{Gamma, Operator};

    fn names(o: &[Output]) -> Vec<String> {
        o.iter().map(|o| o.name.display().to_string()).collect()
    }

    #[test]
    fn exr_writes_itself_and_a_png_beside_it() {
        let o = plan_outputs("sub/cube_point_hdr.exr", &[], Display::Course).unwrap();
        assert_eq!(names(&o), ["sub/cube_point_hdr.exr", "sub/cube_point_hdr.png"]);
        assert_eq!(o[0].kind, OutputKind::Hdr);
        assert_eq!(o[1].kind, OutputKind::Tonemapped(Tonemap::COURSE_DEFAULT));
    }

    #[test]
    fn several_tonemaps_get_their_operator_in_the_name() {
        let t = |operator| Tonemap { operator, ..Tonemap::COURSE_DEFAULT };
        let maps = [t(Operator::Photographic), t(Operator::Aces), t(Operator::Filmic), t(Operator::Aces)];
        let o = plan_outputs("a.hdr", &maps, Display::Course).unwrap();
        assert_eq!(names(&o), ["a.hdr", "a.png", "a_aces.png", "a_filmic.png", "a_aces_2.png"]);
    }

    #[test]
    fn png_without_tonemap_keeps_the_course_clamp() {
        assert_eq!(plan_outputs("x.PNG", &[], Display::Course).unwrap()[0].kind, OutputKind::Course);
        let srgb = Tonemap { gamma: Gamma::Srgb, ..Tonemap::DISPLAY };
        let o = plan_outputs("x.jpg", &[srgb], Display::Aces).unwrap();
        assert_eq!(names(&o), ["x.jpg"]);
        assert_eq!(o[0].kind, OutputKind::Tonemapped(srgb));
    }

    #[test]
    fn a_display_transform_replaces_the_clamp_and_hw5s_default_only() {
        let o = plan_outputs("x.png", &[], Display::Srgb).unwrap();
        assert_eq!(names(&o), ["x.png"]);
        assert_eq!(o[0].kind, OutputKind::Display(Display::Srgb));
        let o = plan_outputs("d/x.exr", &[], Display::Filmic).unwrap();
        assert_eq!(names(&o), ["d/x.exr", "d/x.png"]);
        assert_eq!(o[1].kind, OutputKind::Display(Display::Filmic));
        let o = plan_outputs("x.exr", &[Tonemap::DISPLAY], Display::Filmic).unwrap();
        assert_eq!(o[1].kind, OutputKind::Tonemapped(Tonemap::DISPLAY), "an explicit Tonemap wins");
    }

    #[test]
    fn other_extensions_are_refused() {
        let e = plan_outputs("x.bmp", &[], Display::Srgb).unwrap_err();
        assert!(e.contains("x.bmp") && e.contains(".exr"), "{e}");
        assert!(plan_outputs("noext", &[], Display::Course).is_err());
    }

    #[test]
    fn clashes_are_found_after_normalising() {
        let a = plan_outputs("a.exr", &[], Display::Course).unwrap();
        let b = plan_outputs("./a.png", &[], Display::Course).unwrap();
        let all: Vec<&Path> = a.iter().chain(&b).map(|o| o.name.as_path()).collect();
        assert_eq!(first_clash(all), Some(PathBuf::from("./a.png")));
        assert_eq!(first_clash([Path::new("a.png"), Path::new("b.png")]), None);
    }
}
