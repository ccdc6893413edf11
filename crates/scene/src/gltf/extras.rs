//! glTF `extras` as attributes that shaders read with `getattribute`: a
//! node's are its objects' own, a mesh's are its geometry's (what every node
//! drawing it shares). Blender exports an object's custom properties as its
//! node's `extras` and a mesh's as the mesh's.
//!
//! | JSON value | attribute |
//! |---|---|
//! | a number | a number |
//! | `true`, `false` | 1, 0 |
//! | a string | text |
//! | an array of three numbers | a `vec3` |
//!
//! Anything else (objects, other arrays, `null`), a name with a colon or
//! a control character, a name over 256 bytes, and the attributes past 256
//! on one element are skipped, with one warning per file naming the first
//! such value's JSON path (`nodes[2].extras.foo`). `extras` that are not a
//! JSON object are skipped the same way.

use super::Notes;
use crate::description::AttributeList;
use luster_shading::shader::attributes::{check_name, MAX_PER_ELEMENT};
use luster_shading::shader::ParamValue;
use serde_json::Value;

/// The attributes of one `extras` (`at` is its owner's JSON path, such as
/// `nodes[2]`), warning through `notes` about what is skipped.
pub fn attributes(extras: &gltf::json::Extras, at: &str, notes: &mut Notes) -> AttributeList {
    let Some(raw) = extras else { return Vec::new() };
    let map = match serde_json::from_str::<Value>(raw.get()) {
        Ok(Value::Object(map)) => map,
        _ => {
            notes.once(
                &format!("{at}.extras"),
                "extras that are not a JSON object are not read as attributes",
            );
            return Vec::new();
        }
    };
    let mut out = Vec::new();
    for (name, value) in &map {
        let path = || format!("{at}.extras{}", key_path(name));
        let Some(value) = value_of(value) else {
            notes.once(
                &path(),
                "extras values other than numbers, booleans, strings and arrays of three numbers are not \
                 attributes; skipped",
            );
            continue;
        };
        if check_name(name).is_err() {
            notes.once(
                &path(),
                "extras names with a colon or a control character, or longer than 256 bytes, are not \
                 attributes; skipped",
            );
            continue;
        }
        if out.len() == MAX_PER_ELEMENT {
            notes
                .once(&path(), &format!("extras past the first {MAX_PER_ELEMENT} of an element are skipped"));
            break;
        }
        out.push((name.clone(), value));
    }
    out
}

/// A JSON value as an attribute's, if it is one (JSON numbers are finite).
fn value_of(v: &Value) -> Option<ParamValue> {
    Some(match v {
        Value::Number(n) => ParamValue::Number(n.as_f64()?),
        Value::Bool(b) => ParamValue::Number(f64::from(u8::from(*b))),
        Value::String(s) => ParamValue::Text(s.clone()),
        Value::Array(a) => match &a[..] {
            [Value::Number(x), Value::Number(y), Value::Number(z)] => {
                ParamValue::Vec3([x.as_f64()?, y.as_f64()?, z.as_f64()?])
            }
            _ => return None,
        },
        Value::Null | Value::Object(_) => return None,
    })
}

/// `.name` for a short identifier, else `["(n characters)"]`: a warning does
/// not quote the file at length.
fn key_path(name: &str) -> String {
    if !name.is_empty() && name.len() <= 64 && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        format!(".{name}")
    } else {
        format!("[a key of {} characters]", name.chars().count())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::value::RawValue;

    fn read(json: &str) -> (AttributeList, Vec<String>) {
        let extras: gltf::json::Extras = Some(RawValue::from_string(json.to_string()).unwrap());
        let mut notes = Notes::default();
        let got = attributes(&extras, "nodes[2]", &mut notes);
        (got, notes.warnings.iter().map(|w| format!("{}: {}", w.loc.path, w.message)).collect())
    }

    #[test]
    fn json_values_map_to_attribute_kinds() {
        let (got, warnings) = read(
            r#"{"wear": 0.25, "broken": true, "clean": false, "label": "oak", "tint": [0.8, 0.2, 0.1]}"#,
        );
        assert!(warnings.is_empty(), "{warnings:?}");
        let find = |n: &str| got.iter().find(|(k, _)| k == n).map(|(_, v)| v.clone());
        assert_eq!(find("wear"), Some(ParamValue::Number(0.25)));
        assert_eq!(find("broken"), Some(ParamValue::Number(1.0)));
        assert_eq!(find("clean"), Some(ParamValue::Number(0.0)));
        assert_eq!(find("label"), Some(ParamValue::Text("oak".into())));
        assert_eq!(find("tint"), Some(ParamValue::Vec3([0.8, 0.2, 0.1])));
        assert_eq!(got.len(), 5);
    }

    #[test]
    fn other_values_are_skipped_with_one_warning() {
        let (got, warnings) =
            read(r#"{"a": {"x": 1}, "b": [1, 2], "c": null, "d": [1, "2", 3], "e": 4, "f:g": 1}"#);
        assert_eq!(got, vec![("e".to_string(), ParamValue::Number(4.0))]);
        assert_eq!(warnings.len(), 2, "{warnings:?}");
        assert!(
            warnings[0].starts_with("nodes[2].extras.a: extras values other than numbers"),
            "{warnings:?}"
        );
        assert!(warnings[0].ends_with("(said once per file)"), "{warnings:?}");
        assert!(warnings[1].starts_with("nodes[2].extras[a key of 3 characters]: extras names with a colon"));
        let (got, warnings) = read("[1, 2, 3]");
        assert!(got.is_empty());
        assert_eq!(warnings, vec!["nodes[2].extras: extras that are not a JSON object are not read as attributes (said once per file)"]);
    }

    #[test]
    fn no_element_gets_more_than_the_cap() {
        let body: Vec<String> = (0..300).map(|i| format!("\"a{i:03}\": {i}")).collect();
        let (got, warnings) = read(&format!("{{{}}}", body.join(",")));
        assert_eq!(got.len(), MAX_PER_ELEMENT);
        assert_eq!(warnings.len(), 1, "{warnings:?}");
        assert!(warnings[0].contains("past the first 256"), "{warnings:?}");
    }
}
