//! MTL material libraries: reading them (through `tobj`, after a line check
//! of our own) and turning each material into a [`MaterialDesc`].
//!
//! | MTL | luster | notes |
//! |---|---|---|
//! | `Kd r g b` | `DiffuseReflectance` | default 0.8 grey |
//! | `Ka r g b` | `AmbientReflectance` | default: `Kd` (ambient light lights the surface's own colour) |
//! | `Ks r g b` | `SpecularReflectance` | default 0; 0 under `illum` 0 and 1 |
//! | `Ns e` | `PhongExponent` | at least 1; default 10 |
//! | `illum 3`, `5`, `8` | `type="mirror"`, `MirrorReflectance` = `Ks` | |
//! | `illum 4`, `6`, `7`, `9` | `type="dielectric"`, `RefractionIndex` = `Ni` | `Ni` default 1.5 |
//! | `d` < 1 (or `Tr` > 0) with `Ni` | `type="dielectric"` | without `Ni`: opaque, with a warning (no partial transparency) |
//! | `illum 0` | no ambient, no highlight | `illum 1`: no highlight |
//! | `Ke`, `Tf`, `illum 10`, PBR statements | ignored with a warning | |
//!
//! A colour may be one number (`Kd 0.5` is grey, as the MTL spec says) or
//! three; `spectral` and `xyz` colours are refused. Texture statements are
//! [`super::maps`]'s.
//!
//! Colours keep the MTL's 0–1 scale: like the course's reflectances they
//! multiply light intensities, which carry the 0–255 output scale.

use super::{at, PartMap};
use crate::description::{MaterialDesc, MaterialKind};
use crate::error::{shown_token, Loc, SceneError, Warning};
use luster_core::math::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Largest MTL file accepted.
const MAX_MTL_BYTES: u64 = 64 << 20;

/// An MTL file read: `tobj`'s materials and the line of each statement.
#[derive(Debug)]
pub struct MtlFile {
    /// The file.
    pub path: PathBuf,
    /// Its materials in file order.
    pub materials: Vec<tobj::Material>,
    /// For each material, the line of each of its statements by keyword
    /// (the last, when one is repeated), and of its `newmtl`.
    pub lines: Vec<HashMap<String, u32>>,
    /// What was accepted but ignored.
    pub warnings: Vec<Warning>,
}

impl MtlFile {
    /// The line of material `m`'s statement `key`, or of its `newmtl`.
    pub fn line(&self, m: usize, key: &str) -> u32 {
        let l = &self.lines[m];
        l.get(key).or_else(|| l.get("newmtl")).copied().unwrap_or(0)
    }

    /// Where material `m`'s statement `key` is, for messages.
    pub fn loc(&self, m: usize, key: &str) -> Loc {
        at(&self.path, self.line(m, key))
    }

    /// An error at material `m`'s statement `key`.
    pub fn err(&self, m: usize, key: &str, msg: impl Into<String>) -> SceneError {
        let line = self.line(m, key);
        SceneError::file(&self.path, format!("line {line}: {}", msg.into()))
    }
}

/// Colour statements: one number (grey) or three.
const COLORS: [&str; 5] = ["Ka", "Kd", "Ks", "Ke", "Tf"];
/// Statements of one number.
const SCALARS: [&str; 4] = ["Ns", "Ni", "d", "Tr"];

/// Reads an MTL file.
pub fn read(path: &Path) -> Result<MtlFile, SceneError> {
    let text = read_text(path, MAX_MTL_BYTES)
        .map_err(|why| SceneError::file(path, format!("cannot read the material library: {why}")))?;
    let (normalized, lines, mut warnings) = check(path, &text)?;
    let mut reader = super::CountingReader::new(normalized.as_bytes());
    let (materials, _) = tobj::load_mtl_buf(&mut reader)
        .map_err(|e| SceneError::file(path, format!("line {}: {e}", reader.line())))?;
    if materials.len() != lines.len() {
        return Err(SceneError::file(path, "internal error: materials miscounted"));
    }
    let mut seen: HashMap<&str, u32> = HashMap::new();
    for (m, l) in materials.iter().zip(&lines) {
        let line = l.get("newmtl").copied().unwrap_or(0);
        if let Some(first) = seen.insert(&m.name, line) {
            warnings.push(Warning {
                loc: at(path, line),
                message: format!(
                    "material \"{}\" is defined again (first on line {first}); the last one is used",
                    m.name
                ),
            });
        }
    }
    Ok(MtlFile { path: path.to_path_buf(), materials, lines, warnings })
}

/// A text file's contents, or why it cannot be read.
pub fn read_text(path: &Path, max: u64) -> Result<String, String> {
    luster_core::file::read_text(path, max)
}

type Checked = (String, Vec<HashMap<String, u32>>, Vec<Warning>);

/// Checks every line, writing one-number colours out as three (`tobj` reads
/// only three) and `d -halo f` as `d f`, and records where each statement is.
/// The text keeps its lines, so `tobj`'s own errors keep their numbers.
fn check(path: &Path, text: &str) -> Result<Checked, SceneError> {
    let mut out = String::with_capacity(text.len() + 64);
    let mut lines: Vec<HashMap<String, u32>> = Vec::new();
    let mut warnings = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i as u32 + 1;
        let err = |msg: String| SceneError::file(path, format!("line {line}: {msg}"));
        let mut words = raw.split_whitespace();
        let key = match words.next() {
            Some(k) if !k.starts_with('#') => k,
            _ => {
                out.push('\n');
                continue;
            }
        };
        let args: Vec<&str> = words.collect();
        if key == "newmtl" {
            if args.is_empty() {
                return Err(err("newmtl names no material".to_string()));
            }
            lines.push(HashMap::from([("newmtl".to_string(), line)]));
        } else if let Some(current) = lines.last_mut() {
            current.insert(key.to_string(), line);
        } else {
            return Err(err(format!("{} before any newmtl", shown_token(key))));
        }
        let rewritten = if COLORS.contains(&key) {
            if matches!(args.first(), Some(&"spectral") | Some(&"xyz")) {
                return Err(err(format!("{key} {} colours are not supported; give r g b", args[0])));
            }
            let v = floats(&args)
                .map_err(|w| err(format!("{key} has {}, which is not a number", shown_token(&w))))?;
            match v[..] {
                [g] if g >= 0.0 => Some(format!("{key} {g} {g} {g}")),
                [r, g, b] if r >= 0.0 && g >= 0.0 && b >= 0.0 => None,
                [_] | [_, _, _] => return Err(err(format!("{key} must not be negative"))),
                _ => return Err(err(format!("{key} needs 1 or 3 numbers, found {}", v.len()))),
            }
        } else if SCALARS.contains(&key) {
            let args = if key == "d" && args.first() == Some(&"-halo") {
                warnings.push(Warning {
                    loc: at(path, line),
                    message: "d -halo is not supported; plain d used".into(),
                });
                &args[1..]
            } else {
                &args[..]
            };
            let v = floats(args)
                .map_err(|w| err(format!("{key} has {}, which is not a number", shown_token(&w))))?;
            if v.len() != 1 {
                return Err(err(format!("{key} needs 1 number, found {}", v.len())));
            }
            Some(format!("{key} {}", v[0]))
        } else if key == "illum" {
            match args[..] {
                [n] if n.parse::<u8>().is_ok_and(|n| n <= 10) => None,
                _ => {
                    return Err(err(format!(
                        "illum needs a model number 0 to 10, found {}",
                        shown_token(&args.join(" "))
                    )))
                }
            }
        } else {
            None
        };
        out.push_str(rewritten.as_deref().unwrap_or(raw));
        out.push('\n');
    }
    Ok((out, lines, warnings))
}

/// Parses every word as a finite number, or returns the first that is not.
fn floats(words: &[&str]) -> Result<Vec<f32>, String> {
    words
        .iter()
        .map(|w| w.parse::<f32>().ok().filter(|x| x.is_finite()).ok_or_else(|| w.to_string()))
        .collect()
}

/// MTL statements mapped here or in [`super::maps`]; any other that `tobj`
/// kept in `unknown_param` gets a warning.
pub const HANDLED: [&str; 5] = ["norm", "Tr", "texture_shader", "bump_shader", "reflect_shader"];

/// Maps material `m` of `file` to a [`MaterialDesc`] and its texture maps;
/// warnings for what it ignores go to `warnings`.
pub fn material(
    file: &MtlFile,
    m: usize,
    warnings: &mut Vec<Warning>,
) -> Result<(MaterialDesc, Vec<PartMap>), SceneError> {
    let mat = &file.materials[m];
    let mut warn = |key: &str, msg: String| warnings.push(Warning { loc: file.loc(m, key), message: msg });
    let v3 = |c: Option<[f32; 3]>| c.map(Vec3::from_array);
    let diffuse = v3(mat.diffuse).unwrap_or(Vec3::splat(0.8));
    let illum = mat.illumination_model.unwrap_or(2);
    let mut ambient = v3(mat.ambient).unwrap_or(diffuse);
    let mut specular = v3(mat.specular).unwrap_or(Vec3::ZERO);
    if illum <= 1 {
        specular = Vec3::ZERO;
        if illum == 0 {
            ambient = Vec3::ZERO;
        }
    }
    let tr = match mat.unknown_param.get("Tr").map(|t| t.parse::<f32>()) {
        Some(Ok(t)) => Some(t),
        Some(Err(_)) => return Err(file.err(m, "Tr", "Tr is not a number")),
        None => None,
    };
    let opacity = mat.dissolve.or(tr.map(|t| 1.0 - t)).unwrap_or(1.0);
    let kind = match illum {
        3 | 5 | 8 => MaterialKind::Mirror,
        4 | 6 | 7 | 9 => MaterialKind::Dielectric,
        _ if opacity < 1.0 && mat.optical_density.is_some() => MaterialKind::Dielectric,
        _ => {
            if opacity < 1.0 {
                let key = if mat.dissolve.is_some() { "d" } else { "Tr" };
                warn(key, format!("a transparency without Ni cannot be rendered (no partial transparency); material \"{}\" is opaque", mat.name));
            }
            if illum == 10 {
                warn("illum", "illum 10 (shadow matte) is not supported; rendered as illum 2".to_string());
            }
            MaterialKind::Plain
        }
    };
    if v3(mat.emissive).is_some_and(|e| e != Vec3::ZERO) {
        warn("Ke", format!("emission (Ke) is not supported; material \"{}\" does not glow", mat.name));
    }
    let mut unknown: Vec<&String> =
        mat.unknown_param.keys().filter(|k| !HANDLED.contains(&k.as_str())).collect();
    unknown.sort();
    for k in unknown {
        if k == "Tf" {
            continue; // A transmission filter only matters to glass, which has no tint here.
        }
        warn(k, format!("`{k}` is not supported; ignored"));
    }
    let refraction_index = match mat.optical_density {
        Some(n) if n > 0.0 => n,
        Some(n) => return Err(file.err(m, "Ni", format!("Ni must be positive, found {n}"))),
        None => 1.5,
    };
    let desc = MaterialDesc {
        id: mat.name.clone(),
        kind,
        ambient,
        diffuse,
        specular,
        mirror: if kind == MaterialKind::Mirror { specular } else { Vec3::ZERO },
        phong_exponent: mat.shininess.unwrap_or(10.0).max(1.0),
        refraction_index,
        absorption_coefficient: Vec3::ZERO,
        absorption_index: 0.0,
        roughness: 0.0,
        brdf: None,
        loc: file.loc(m, "newmtl"),
    };
    let maps = super::maps::read(file, m, warnings)?;
    Ok((desc, maps))
}

/// The material of faces that name none: a light grey, no highlight.
pub fn default_material(loc: Loc) -> MaterialDesc {
    MaterialDesc {
        id: "(none)".to_string(),
        kind: MaterialKind::Plain,
        ambient: Vec3::splat(0.8),
        diffuse: Vec3::splat(0.8),
        specular: Vec3::ZERO,
        mirror: Vec3::ZERO,
        phong_exponent: 10.0,
        refraction_index: 1.5,
        absorption_coefficient: Vec3::ZERO,
        absorption_index: 0.0,
        roughness: 0.0,
        brdf: None,
        loc,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mtl(text: &str) -> Result<MtlFile, SceneError> {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("m.mtl");
        std::fs::write(&p, text).unwrap();
        read(&p)
    }

    #[test]
    fn statements_map_onto_materials() {
        let f = mtl("newmtl a\nKd 0.5\nKs 0.1 0.2 0.3\nNs 0\nillum 3\nnewmtl glass\nillum 4\nNi 1.3\nnewmtl b\nd 0.5\nNi 1.2\n").unwrap();
        let mut w = Vec::new();
        let (a, _) = material(&f, 0, &mut w).unwrap();
        assert_eq!((a.diffuse, a.ambient), (Vec3::splat(0.5), Vec3::splat(0.5)));
        assert_eq!(
            (a.kind, a.mirror, a.phong_exponent),
            (MaterialKind::Mirror, Vec3::new(0.1, 0.2, 0.3), 1.0)
        );
        let (g, _) = material(&f, 1, &mut w).unwrap();
        assert_eq!((g.kind, g.refraction_index), (MaterialKind::Dielectric, 1.3));
        let (b, _) = material(&f, 2, &mut w).unwrap();
        assert_eq!(b.kind, MaterialKind::Dielectric);
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(f.line(1, "Ni"), 8);
    }

    #[test]
    fn bad_statements_name_their_line() {
        let e = |t: &str| mtl(t).unwrap_err().to_string();
        assert!(e("newmtl a\nKd 1 1\n").contains("line 2: Kd needs 1 or 3 numbers, found 2"));
        assert!(e("Kd 1 1 1\n").contains("line 1: \"Kd\" before any newmtl"));
        assert!(e("newmtl a\nNs shiny\n").contains("line 2: Ns has \"shiny\""));
        assert!(e("newmtl a\nillum 12\n").contains("illum needs"));
        assert!(e("newmtl a\nKd spectral x.rfl\n").contains("not supported"));
    }

    #[test]
    fn ignored_statements_warn() {
        let f = mtl("newmtl a\nKe 1 0 0\nPr 0.5\nd 0.5\n").unwrap();
        let mut w = Vec::new();
        material(&f, 0, &mut w).unwrap();
        let text: Vec<String> = w.iter().map(|w| w.to_string()).collect();
        assert_eq!(w.len(), 3, "{text:?}");
        assert!(text[0].contains("line 4") && text[0].contains("opaque"), "{text:?}");
    }
}
