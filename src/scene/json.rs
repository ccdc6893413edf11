//! The 2025 JSON encoding of the CENG795 format, mapped onto the same
//! [`Element`] tree as the XML: a key starting with `_` is an attribute
//! (`_data` is the element's text), an array is a repeated element, a string
//! is an element's text and `null` an empty element. Numbers and booleans are
//! accepted where the course writes strings.
//!
//! serde_json does not keep positions of values, so JSON errors locate an
//! element by its path (`Scene/Objects/Mesh[id=3]/Faces`); syntax errors carry
//! the line and column from the parser.

use super::element::Element;
use super::error::{Loc, SceneError};
use serde_json::Value;
use std::path::Path;

/// Parses JSON text into an element tree rooted at the `Scene` element.
pub fn parse(file: &Path, text: &str) -> Result<Element, SceneError> {
    let v: Value = serde_json::from_str(text).map_err(|e| {
        // serde_json ends its message with the position, which `loc` already gives.
        let msg = e.to_string();
        let msg = msg.strip_suffix(&format!(" at line {} column {}", e.line(), e.column())).unwrap_or(&msg);
        SceneError {
            file: file.to_path_buf(),
            loc: Some(Loc { line: Some(e.line() as u32), path: format!("column {}", e.column()) }),
            message: format!("malformed JSON: {msg}"),
        }
    })?;
    let Value::Object(top) = &v else {
        return Err(SceneError::file(
            file,
            "the top level of a scene must be an object with a \"Scene\" key",
        ));
    };
    let (name, body) = match top.iter().next() {
        Some((k, body)) if top.len() == 1 => (k.as_str(), body),
        _ => {
            return Err(SceneError::file(
                file,
                "the top level of a scene must be an object with a single \"Scene\" key",
            ))
        }
    };
    convert(file, name, body, "", None)
}

fn convert(
    file: &Path,
    name: &str,
    v: &Value,
    parent: &str,
    index: Option<usize>,
) -> Result<Element, SceneError> {
    let mut el = Element { name: name.to_string(), ..Default::default() };
    let mut kids: Vec<(&str, &Value)> = Vec::new();
    match v {
        Value::Null => {}
        Value::String(s) => el.text = s.trim().to_string(),
        Value::Number(n) => el.text = n.to_string(),
        Value::Bool(b) => el.text = b.to_string(),
        Value::Array(_) => {
            return Err(SceneError::at(
                file,
                &Loc { line: None, path: format!("{parent}/{name}") },
                "nested arrays are not part of the format",
            ))
        }
        Value::Object(map) => {
            for (k, val) in map {
                if k == "_data" {
                    el.text = scalar(val).trim().to_string();
                } else if let Some(attr) = k.strip_prefix('_') {
                    el.attrs.push((attr.to_string(), scalar(val)));
                } else {
                    kids.push((k, val));
                }
            }
        }
    }
    let seg = Element::segment(name, &el.attrs, index);
    el.loc = Loc { line: None, path: if parent.is_empty() { seg } else { format!("{parent}/{seg}") } };
    for (k, val) in kids {
        match val {
            Value::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let idx = (items.len() > 1).then_some(i);
                    el.children.push(convert(file, k, item, &el.loc.path, idx)?);
                }
            }
            _ => el.children.push(convert(file, k, val, &el.loc.path, None)?),
        }
    }
    Ok(el)
}

fn scalar(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => String::new(),
        other => other.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_attributes_data_and_arrays() {
        let j = r#"{"Scene": {"Objects": {"Mesh": [
            {"_id": "1", "Material": "2", "Faces": {"_data": "1 2 3", "_type": "triangle"}},
            {"_id": "2", "Material": "1", "Faces": {"_plyFile": "a.ply"}}]},
            "VertexData": null}}"#;
        let root = parse(Path::new("s.json"), j).unwrap();
        let meshes: Vec<_> = root.child("Objects").unwrap().children_named("Mesh").collect();
        assert_eq!(meshes.len(), 2);
        assert_eq!(meshes[0].child("Faces").unwrap().text, "1 2 3");
        assert_eq!(meshes[0].child("Faces").unwrap().attr("type"), Some("triangle"));
        assert_eq!(meshes[1].child("Faces").unwrap().attr("plyFile"), Some("a.ply"));
        assert_eq!(meshes[1].child("Material").unwrap().loc.path, "Scene/Objects/Mesh[id=2]/Material");
        assert_eq!(root.child("VertexData").unwrap().text, "");
    }

    #[test]
    fn syntax_error_has_line() {
        let e = parse(Path::new("bad.json"), "{\n\"Scene\": {\n\"A\": }\n}").unwrap_err();
        assert!(e.to_string().starts_with("bad.json: line 3"), "{e}");
    }
}
