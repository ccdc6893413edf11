//! `<TextureMap type="shader">`: luster's extension of the CENG795 format that
//! attaches a Lua shader script (see `docs/shaders.md`) to objects.
//!
//! ```xml
//! <TextureMap id="5" type="shader">
//!     <Shader>shaders/marble.lua</Shader>
//!     <DecalMode>replace_kd</DecalMode>
//!     <Parameter name="frequency">4</Parameter>
//!     <Parameter name="vein">0.3 0.2 0.2</Parameter>
//! </TextureMap>
//! ```
//!
//! | element | reads | default |
//! |---|---|---|
//! | `Shader` | the script's path, relative to the scene file | required |
//! | `Parameter name` | one number (a Lua number), three (a `vec3`), or text (a string) | none |
//! | `DecalMode`, `BumpFactor` | as for every map; which entry point each mode calls is checked when the scene is built | |
//!
//! In JSON: `"Shader": "shaders/marble.lua"` and
//! `"Parameter": [{"_name": "frequency", "_data": "4"}, ...]`.
//!
//! The script is read here, so a missing file is reported with the element
//! that names it; it is compiled when the render scene is built
//! (`render::Scene::build_with`), where syntax errors and missing entry points
//! are reported against the `TextureMap`.

use crate::description::{ScriptDesc, TextureSource};
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_shading::shader::ParamValue;
use std::path::Path;

/// Largest script accepted: real shaders are a few kilobytes, and a huge
/// file would be compiled once per worker thread.
pub const MAX_SCRIPT_BYTES: u64 = 4 << 20;

/// Children a shader map may have besides `DecalMode` and `BumpFactor`.
pub const CHILDREN: [&str; 2] = ["Shader", "Parameter"];

/// Reads the source of a shader map: the script and its parameters.
pub fn read(r: &Reader, el: &Element, base_dir: &Path) -> Result<TextureSource, SceneError> {
    let ScriptDesc { path, code, params } = script(r, el, base_dir)?;
    Ok(TextureSource::Shader { path, code, params })
}

/// Reads `el`'s `Shader` (required) and `Parameter` children: the script's
/// text and its parameters. Volumes name their scripts the same way.
pub fn script(r: &Reader, el: &Element, base_dir: &Path) -> Result<ScriptDesc, SceneError> {
    let shader = r.required(el, "Shader")?;
    let rel = shader.text.trim();
    if rel.is_empty() {
        return Err(r.err(shader, "<Shader> names no script file"));
    }
    let path = base_dir.join(rel);
    let code =
        read_script(&path).map_err(|why| r.err(shader, format!("cannot read shader script {rel}: {why}")))?;
    let mut params: Vec<(String, ParamValue)> = Vec::new();
    for p in el.children_named("Parameter") {
        let (name, value) = parameter(r, p)?;
        if params.iter().any(|(n, _)| *n == name) {
            return Err(r.err(p, format!("parameter \"{name}\" is given twice")));
        }
        params.push((name, value));
    }
    Ok(ScriptDesc { path, code, params })
}

/// A shader script's text, or why it cannot be read (a sentence fragment:
/// "no such file", "it is a folder", ...).
pub fn read_script(path: &Path) -> Result<String, String> {
    luster_core::file::read_text(path, MAX_SCRIPT_BYTES).map_err(|why| {
        if why.starts_with("it is not UTF-8") {
            "it is not UTF-8 text".to_string()
        } else {
            why
        }
    })
}

/// One `<Parameter name="...">value</Parameter>`.
fn parameter(r: &Reader, el: &Element) -> Result<(String, ParamValue), SceneError> {
    let name = el.attr("name").map(str::trim).unwrap_or("");
    if name.is_empty() {
        return Err(r.err(el, "<Parameter> has no name attribute"));
    }
    let value = param_value(name, &el.text).map_err(|why| r.err(el, why))?;
    Ok((name.to_string(), value))
}

/// A shader parameter's value from its text, whatever file it came from (a
/// scene's `Parameter`, an MTL file's `-p`): one number is a Lua number,
/// three a `vec3`, anything that is not only numbers a string.
///
/// A value made only of numbers must be one number or three: two or four
/// numbers are almost certainly a typo for a vector, and passing them on as a
/// string would only fail later, inside the script, far from the mistake.
/// The name must be a Lua name, since the script reads it as `param.NAME`.
pub fn param_value(name: &str, text: &str) -> Result<ParamValue, String> {
    if !is_identifier(name) {
        return Err(format!(
            "parameter name \"{name}\" is not a Lua name (letters, digits and _, not starting with a digit)"
        ));
    }
    value_of("parameter", &format!("\"{name}\""), text)
}

/// A value as [`param_value`] reads it, for a `what` (`parameter`,
/// `attribute`) named `shown` in messages.
pub fn value_of(what: &str, shown: &str, text: &str) -> Result<ParamValue, String> {
    let text = text.trim();
    let numbers: Option<Vec<f64>> = text.split_ascii_whitespace().map(|t| t.parse::<f64>().ok()).collect();
    match numbers {
        Some(v) if !v.is_empty() => {
            if let Some(bad) = v.iter().find(|x| !x.is_finite()) {
                return Err(format!("{what} {shown} is not finite ({bad})"));
            }
            match v[..] {
                [x] => Ok(ParamValue::Number(x)),
                [x, y, z] => Ok(ParamValue::Vec3([x, y, z])),
                _ => Err(format!(
                    "{what} {shown} has {} numbers; a{} {what} is one number, three (a vec3) or text",
                    v.len(),
                    if what.starts_with(['a', 'e', 'i', 'o', 'u']) { "n" } else { "" }
                )),
            }
        }
        _ => Ok(ParamValue::Text(text.to_string())),
    }
}

fn is_identifier(s: &str) -> bool {
    let mut chars = s.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn param(attrs: &[(&str, &str)], text: &str) -> Result<(String, ParamValue), SceneError> {
        let el = Element {
            name: "Parameter".into(),
            attrs: attrs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect(),
            text: text.into(),
            ..Default::default()
        };
        parameter(&Reader { file: Path::new("s.xml") }, &el)
    }

    #[test]
    fn parameters_are_numbers_vectors_or_text() {
        assert_eq!(param(&[("name", "f")], " 4 ").unwrap(), ("f".into(), ParamValue::Number(4.0)));
        assert_eq!(param(&[("name", "c")], "1 0.5 -2").unwrap().1, ParamValue::Vec3([1.0, 0.5, -2.0]));
        assert_eq!(param(&[("name", "m")], "euclidean").unwrap().1, ParamValue::Text("euclidean".into()));
        assert_eq!(param(&[("name", "m")], "").unwrap().1, ParamValue::Text(String::new()));
        assert_eq!(param(&[("name", "m")], "3 apples").unwrap().1, ParamValue::Text("3 apples".into()));
    }

    #[test]
    fn bad_parameters_are_refused() {
        let two = param(&[("name", "c")], "1 2").unwrap_err().to_string();
        assert!(two.contains("has 2 numbers"), "{two}");
        assert!(param(&[], "1").unwrap_err().to_string().contains("no name"));
        assert!(param(&[("name", "2x")], "1").unwrap_err().to_string().contains("not a Lua name"));
        assert!(param(&[("name", "x")], "inf").unwrap_err().to_string().contains("not finite"));
    }
}
