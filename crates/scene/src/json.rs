//! The 2025 JSON encoding of the CENG795 format, mapped onto the same
//! [`Element`] tree as the XML: a key starting with `_` is an attribute
//! (`_data` is the element's text), an array is a repeated element, a string
//! is an element's text and `null` an empty element. Numbers and booleans are
//! accepted where the course writes strings.
//!
//! serde_json does not keep positions of values, so JSON errors locate an
//! element by its path (`Scene/Objects/Mesh[id=3]/Faces`); syntax errors carry
//! the line and column from the parser.
//!
//! Two things JSON allows are refused: a key given twice in one object (the
//! file is read into `Json`, which keeps every key, and the second one is
//! an error with its line instead of silently replacing the first), and
//! `null` for an element that is always an object ([`OBJECT_ELEMENTS`]).
//! Nesting deeper than serde_json's limit of 128 is an error, never a stack
//! overflow.

use super::element::Element;
use super::error::{Loc, SceneError};
use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use std::path::Path;

/// Elements that are always objects in the format: `null` for one of them is
/// a mistake (an empty camera, an empty mesh), not an empty element.
pub const OBJECT_ELEMENTS: &[&str] = &[
    "Scene",
    "Cameras",
    "Camera",
    "Lights",
    "PointLight",
    "AreaLight",
    "DirectionalLight",
    "SpotLight",
    "SphericalDirectionalLight",
    "Materials",
    "Material",
    "Transformations",
    "Textures",
    "Images",
    "TextureMap",
    "Objects",
    "Mesh",
    "MeshInstance",
    "Triangle",
    "Sphere",
    "Plane",
    "Ellipsoid",
    "Volumes",
    "Volume",
];

/// A JSON value that keeps its object's keys in order and refuses duplicates.
enum Value {
    Null,
    Bool(bool),
    Number(serde_json::Number),
    String(String),
    Array(Vec<Value>),
    Object(Vec<(String, Value)>),
}

impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Value, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

struct ValueVisitor;

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }
    fn visit_unit<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_none<E>(self) -> Result<Value, E> {
        Ok(Value::Null)
    }
    fn visit_bool<E>(self, b: bool) -> Result<Value, E> {
        Ok(Value::Bool(b))
    }
    fn visit_i64<E>(self, n: i64) -> Result<Value, E> {
        Ok(Value::Number(n.into()))
    }
    fn visit_u64<E>(self, n: u64) -> Result<Value, E> {
        Ok(Value::Number(n.into()))
    }
    fn visit_f64<E: de::Error>(self, n: f64) -> Result<Value, E> {
        serde_json::Number::from_f64(n).map(Value::Number).ok_or_else(|| E::custom("a number is not finite"))
    }
    fn visit_str<E>(self, s: &str) -> Result<Value, E> {
        Ok(Value::String(s.to_string()))
    }
    fn visit_string<E>(self, s: String) -> Result<Value, E> {
        Ok(Value::String(s))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Value, A::Error> {
        let mut items = Vec::new();
        while let Some(v) = seq.next_element()? {
            items.push(v);
        }
        Ok(Value::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Value, A::Error> {
        let mut entries: Vec<(String, Value)> = Vec::new();
        let mut seen = std::collections::HashSet::new();
        while let Some(key) = map.next_key::<String>()? {
            if !seen.insert(key.clone()) {
                return Err(de::Error::custom(format!(
                    "the key {} is given twice in one object",
                    super::error::shown_token(&key)
                )));
            }
            let v = map.next_value()?;
            entries.push((key, v));
        }
        Ok(Value::Object(entries))
    }
}

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
    let (name, body) = match top.first() {
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
        Value::Null if OBJECT_ELEMENTS.contains(&name) => {
            let path = if parent.is_empty() { name.to_string() } else { format!("{parent}/{name}") };
            return Err(SceneError::at(
                file,
                &Loc { line: None, path },
                format!("<{name}> is null; it must be an object"),
            ));
        }
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
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => n.to_string(),
        Value::Array(_) | Value::Object(_) => String::new(),
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
    fn duplicate_keys_null_objects_and_deep_nesting_are_refused() {
        let dup = "{\"Scene\": {\n\"Cameras\": {},\n\"Cameras\": {}}}";
        let e = parse(Path::new("d.json"), dup).unwrap_err().to_string();
        assert!(e.starts_with("d.json: line 3") && e.contains("\"Cameras\" is given twice"), "{e}");
        let e = parse(Path::new("n.json"), r#"{"Scene": {"Cameras": {"Camera": null}}}"#).unwrap_err();
        assert_eq!(e.to_string(), "n.json: Scene/Cameras/Camera: <Camera> is null; it must be an object");
        let deep = format!("{{\"Scene\": {}{}}}", "[".repeat(100_000), "]".repeat(100_000));
        let e = parse(Path::new("deep.json"), &deep).unwrap_err().to_string();
        assert!(e.contains("recursion limit"), "{e}");
    }

    #[test]
    fn syntax_error_has_line() {
        let e = parse(Path::new("bad.json"), "{\n\"Scene\": {\n\"A\": }\n}").unwrap_err();
        assert!(e.to_string().starts_with("bad.json: line 3"), "{e}");
    }
}
