//! An MTL material's texture statements, as texture maps.
//!
//! | MTL | texture map | notes |
//! |---|---|---|
//! | `map_Kd file` | image, `replace_kd`, bilinear | |
//! | `map_Ks file` | image, `replace_ks`, bilinear | |
//! | `bump file`, `map_bump`, `map_Bump` | image, `bump_normal` | `-bm f` is the `BumpFactor` (default 1); heights follow the course's image-bump convention (8-bit units per texel) |
//! | `norm file` | image, `replace_normal` (tangent space) | |
//! | `texture_shader script` | shader, `replace_kd`: the script's `color` | luster's extension |
//! | `bump_shader script` | shader, `bump_normal`: `height` | `-bm f`: `BumpFactor` |
//! | `reflect_shader script` | shader, `replace_km`: `reflect` | |
//! | `map_Ka`, `map_Ns`, `map_d`, `disp`, `decal`, `refl`, ... | ignored with a warning | |
//!
//! Paths are relative to the MTL file. Options come before the file name, as
//! in the MTL spec: `-bm` is used; `-o`, `-s`, `-t`, `-mm`, `-clamp`,
//! `-blendu`, `-blendv`, `-cc`, `-boost`, `-texres`, `-imfchan` and `-type` are
//! read past with a warning. A shader statement may give its script
//! parameters with `-p NAME VALUE`, where the value is one number, three (a
//! `vec3`) or one word (a string), as a scene's `<Parameter>` elements do:
//!
//! ```text
//! newmtl marble
//! Kd 1 1 1
//! texture_shader -p frequency 2.5 -p vein 0.3 0.2 0.2 shaders/marble.lua
//! bump_shader -bm 0.5 shaders/marble.lua
//! ```
//!
//! A material's maps apply in this order: bump and normal maps first (so the
//! colour shaders see the bumped normal in `s.N`), then `map_Kd`,
//! `texture_shader`, `map_Ks`, `reflect_shader`.

use super::mtl::MtlFile;
use super::PartMap;
use crate::ceng795::shader_map::{param_value, read_script};
use crate::description::{DecalMode, ImageDesc, Interpolation, TextureMapDesc, TextureSource};
use crate::error::{SceneError, Warning};
use luster_shading::shader::ParamValue;
use std::path::{Path, PathBuf};

/// What a texture statement is.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Image,
    Shader,
}

/// Options and the arguments they take: (name, least, most, numeric).
const OPTIONS: [(&str, usize, usize, bool); 13] = [
    ("-bm", 1, 1, true),
    ("-o", 1, 3, true),
    ("-s", 1, 3, true),
    ("-t", 1, 3, true),
    ("-mm", 2, 2, true),
    ("-boost", 1, 1, true),
    ("-texres", 1, 1, true),
    ("-clamp", 1, 1, false),
    ("-blendu", 1, 1, false),
    ("-blendv", 1, 1, false),
    ("-cc", 1, 1, false),
    ("-imfchan", 1, 1, false),
    ("-type", 1, 1, false),
];

/// A texture statement's value taken apart.
#[derive(Debug)]
struct Statement {
    file: String,
    bump: Option<f32>,
    params: Vec<(String, ParamValue)>,
    ignored: Vec<String>,
}

/// Reads material `m`'s texture statements, in the order they apply.
pub fn read(file: &MtlFile, m: usize, warnings: &mut Vec<Warning>) -> Result<Vec<PartMap>, SceneError> {
    let mat = &file.materials[m];
    let unknown = |k: &str| mat.unknown_param.get(k).cloned();
    // (keyword for messages and lines, value, kind, decal)
    let bump_key = ["bump", "map_bump", "map_Bump"].into_iter().find(|k| file.lines[m].contains_key(*k));
    let statements = [
        (bump_key.unwrap_or("bump"), mat.normal_texture.clone(), Kind::Image, DecalMode::BumpNormal),
        ("bump_shader", unknown("bump_shader"), Kind::Shader, DecalMode::BumpNormal),
        ("norm", unknown("norm"), Kind::Image, DecalMode::ReplaceNormal),
        ("map_Kd", mat.diffuse_texture.clone(), Kind::Image, DecalMode::ReplaceKd),
        ("texture_shader", unknown("texture_shader"), Kind::Shader, DecalMode::ReplaceKd),
        ("map_Ks", mat.specular_texture.clone(), Kind::Image, DecalMode::ReplaceKs),
        ("reflect_shader", unknown("reflect_shader"), Kind::Shader, DecalMode::ReplaceKm),
    ];
    for (key, value) in [
        ("map_Ka", &mat.ambient_texture),
        ("map_Ns", &mat.shininess_texture),
        ("map_d", &mat.dissolve_texture),
    ] {
        if value.is_some() {
            warnings.push(Warning {
                loc: file.loc(m, key),
                message: format!("`{key}` is not supported; ignored"),
            });
        }
    }
    let dir = file.path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for (key, value, kind, decal) in statements {
        let Some(value) = value else { continue };
        let st = statement(&value, kind).map_err(|why| file.err(m, key, format!("{key}: {why}")))?;
        for opt in &st.ignored {
            warnings.push(Warning {
                loc: file.loc(m, key),
                message: format!("{key} option {opt} is not supported; ignored"),
            });
        }
        if st.bump.is_some() && decal != DecalMode::BumpNormal {
            warnings.push(Warning {
                loc: file.loc(m, key),
                message: format!("{key} option -bm only applies to bump maps; ignored"),
            });
        }
        let path = resolve(dir, &st.file);
        let loc = file.loc(m, key);
        let id = format!("{}/{key}", mat.name);
        let (source, image) = match kind {
            Kind::Image => {
                luster_core::file::check_regular(&path, luster_core::image::MAX_IMAGE_BYTES).map_err(
                    |why| file.err(m, key, format!("{key}: cannot read image {}: {why}", st.file)),
                )?;
                let source = TextureSource::Image {
                    image: 0,
                    interpolation: Interpolation::Bilinear,
                    normalizer: None,
                };
                (source, Some(ImageDesc::file(id.clone(), path, false, loc.clone())))
            }
            Kind::Shader => {
                let code = read_script(&path).map_err(|why| {
                    file.err(m, key, format!("{key}: cannot read shader script {}: {why}", st.file))
                })?;
                (TextureSource::Shader { path, code, params: st.params }, None)
            }
        };
        let map = TextureMapDesc { id, source, decal, bump_factor: st.bump.unwrap_or(1.0), loc };
        out.push(PartMap { map, image });
    }
    Ok(out)
}

/// A path from an MTL file: relative to its folder, with Windows separators
/// accepted when the file is not found as written.
fn resolve(dir: &Path, name: &str) -> PathBuf {
    let p = dir.join(name);
    if !p.exists() && name.contains('\\') {
        let q = dir.join(name.replace('\\', "/"));
        if q.exists() {
            return q;
        }
    }
    p
}

/// Splits `[options] file` into its parts.
fn statement(value: &str, kind: Kind) -> Result<Statement, String> {
    let words: Vec<&str> = value.split_whitespace().collect();
    let mut st = Statement { file: String::new(), bump: None, params: Vec::new(), ignored: Vec::new() };
    let mut i = 0;
    while i < words.len() && words[i].starts_with('-') && words[i].len() > 1 {
        let opt = words[i];
        i += 1;
        if opt == "-p" && kind == Kind::Shader {
            let name = *words.get(i).ok_or("option -p needs a name and a value")?;
            i += 1;
            let numeric = words[i..].iter().take(3).take_while(|w| w.parse::<f64>().is_ok()).count();
            let take = numeric.max(1);
            if i + take > words.len() {
                return Err(format!("option -p {name} needs a value"));
            }
            let value = param_value(name, &words[i..i + take].join(" "))?;
            i += take;
            if st.params.iter().any(|(n, _)| n == name) {
                return Err(format!("parameter \"{name}\" is given twice"));
            }
            st.params.push((name.to_string(), value));
            continue;
        }
        let Some(&(_, least, most, numeric)) = OPTIONS.iter().find(|o| o.0 == opt) else {
            return Err(format!("option {opt} is unknown"));
        };
        let n = if numeric {
            words[i..].iter().take(most).take_while(|w| w.parse::<f32>().is_ok_and(f32::is_finite)).count()
        } else {
            most.min(words.len() - i)
        };
        if n < least {
            return Err(format!("option {opt} needs {least} value(s)"));
        }
        if opt == "-bm" {
            st.bump = words[i].parse::<f32>().ok();
        } else {
            st.ignored.push(opt.to_string());
        }
        i += n;
    }
    st.file = words[i..].join(" ");
    if st.file.is_empty() {
        return Err("names no file".to_string());
    }
    Ok(st)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_come_before_the_file() {
        let s = statement("-bm 0.5 -o 0.1 0.2 bumps/a b.png", Kind::Image).unwrap();
        assert_eq!(
            (s.file.as_str(), s.bump, s.ignored),
            ("bumps/a b.png", Some(0.5), vec!["-o".to_string()])
        );
        let s = statement("-p f 2.5 -p c 1 0 0 -p mode euclidean x.lua", Kind::Shader).unwrap();
        assert_eq!(s.file, "x.lua");
        assert_eq!(s.params[0], ("f".to_string(), ParamValue::Number(2.5)));
        assert_eq!(s.params[1].1, ParamValue::Vec3([1.0, 0.0, 0.0]));
        assert_eq!(s.params[2].1, ParamValue::Text("euclidean".into()));
    }

    #[test]
    fn bad_statements_are_refused() {
        assert!(statement("-bm", Kind::Image).unwrap_err().contains("-bm needs 1"));
        assert!(statement("-zz 1 a.png", Kind::Image).unwrap_err().contains("-zz is unknown"));
        assert!(statement("-bm 2", Kind::Image).unwrap_err().contains("names no file"));
        assert!(statement("-p 2x 1 a.lua", Kind::Shader).unwrap_err().contains("not a Lua name"));
        assert!(statement("-p a 1 2 a.lua", Kind::Shader).unwrap_err().contains("2 numbers"));
    }
}
