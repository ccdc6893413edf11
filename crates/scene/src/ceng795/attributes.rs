//! `<Attribute name="...">`: user data on an object, an instance or a volume
//! that shaders read with `getattribute("name" [, default])` (luster's
//! extension of the CENG795 format; `docs/attributes.md`).
//!
//! ```xml
//! <MeshInstance id="7" baseMeshId="1">
//!     <Material>2</Material>
//!     <Attribute name="tint">0.8 0.2 0.1</Attribute>   <!-- three numbers: a vec3 -->
//!     <Attribute name="wear">0.35</Attribute>          <!-- one number -->
//!     <Attribute name="label">oak</Attribute>          <!-- anything else: text -->
//! </MeshInstance>
//! ```
//!
//! In JSON: `"Attribute": [{"_name": "tint", "_data": "0.8 0.2 0.1"}, ...]`.
//!
//! Values are read as `<Parameter>` values are ([`shader_map::value_of`]).
//! A name may be any text up to 256 bytes without a colon (names with one
//! are luster's, such as `object:name`); an element may have at most 256
//! attributes, each name once.
//!
//! An instance's attributes are its own, then those of the instance it
//! instances (when that is one), then, when a shader looks a name up, those
//! of the mesh drawn. A `Mesh` read from a glTF or OBJ file gives its
//! attributes to every object the file makes, above the glTF file's mesh
//! `extras` and below its node `extras`.

use super::shader_map;
use crate::description::AttributeList;
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_shading::shader::attributes::{check_name, shown_name, MAX_PER_ELEMENT};

/// The child element attributes are given in.
pub const CHILD: &str = "Attribute";

/// The `<Attribute>` children of `el`, in order; an error names the
/// `<Attribute>` at fault.
pub fn read(r: &Reader, el: &Element) -> Result<AttributeList, SceneError> {
    let mut out: AttributeList = Vec::new();
    for a in el.children_named(CHILD) {
        let name = a.attr("name").map(str::trim).unwrap_or("");
        if name.is_empty() {
            return Err(r.err(a, "<Attribute> has no name attribute"));
        }
        check_name(name).map_err(|why| r.err(a, why))?;
        if out.iter().any(|(n, _)| n == name) {
            return Err(r.err(a, format!("attribute {} is given twice on this element", shown_name(name))));
        }
        if out.len() == MAX_PER_ELEMENT {
            return Err(r.err(a, format!("an element may have at most {MAX_PER_ELEMENT} attributes")));
        }
        let value =
            shader_map::value_of("attribute", &shown_name(name), &a.text).map_err(|why| r.err(a, why))?;
        out.push((name.to_string(), value));
    }
    Ok(out)
}

/// `own` followed by those of `base` whose names `own` lacks: an
/// instance's attributes over its base's, the Mesh element's over a file's.
pub fn merged(own: &AttributeList, base: &AttributeList) -> AttributeList {
    let mut out = own.clone();
    out.extend(base.iter().filter(|(n, _)| !own.iter().any(|(o, _)| o == n)).cloned());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::Loc;
    use luster_shading::shader::ParamValue;
    use std::path::Path;

    fn attribute(name: Option<&str>, text: &str) -> Element {
        Element {
            name: CHILD.into(),
            attrs: name.map(|n| vec![("name".to_string(), n.to_string())]).unwrap_or_default(),
            text: text.into(),
            loc: Loc { line: Some(7), path: "Scene/Objects/MeshInstance[id=3]/Attribute".into() },
            ..Default::default()
        }
    }

    fn read_of(children: Vec<Element>) -> Result<AttributeList, SceneError> {
        let el = Element { name: "MeshInstance".into(), children, ..Default::default() };
        read(&Reader { file: Path::new("s.xml") }, &el)
    }

    #[test]
    fn values_are_numbers_vectors_or_text() {
        let got = read_of(vec![
            attribute(Some("wear"), " 0.35 "),
            attribute(Some("tint"), "0.8 0.2 0.1"),
            attribute(Some("label"), "oak plank"),
        ])
        .unwrap();
        assert_eq!(
            got,
            vec![
                ("wear".into(), ParamValue::Number(0.35)),
                ("tint".into(), ParamValue::Vec3([0.8, 0.2, 0.1])),
                ("label".into(), ParamValue::Text("oak plank".into())),
            ]
        );
        assert!(read_of(Vec::new()).unwrap().is_empty());
    }

    #[test]
    fn bad_attributes_name_the_file_and_element() {
        let e = |children| read_of(children).unwrap_err().to_string();
        let twice = e(vec![attribute(Some("tint"), "1"), attribute(Some("tint"), "2")]);
        assert!(twice.starts_with("s.xml: line 7, Scene/Objects/MeshInstance[id=3]/Attribute"), "{twice}");
        assert!(twice.contains("attribute \"tint\" is given twice"), "{twice}");
        assert!(e(vec![attribute(None, "1")]).contains("<Attribute> has no name"));
        assert!(e(vec![attribute(Some("  "), "1")]).contains("<Attribute> has no name"));
        assert!(e(vec![attribute(Some("a:b"), "1")]).contains("reserved"));
        assert!(e(vec![attribute(Some("tint"), "1 2")])
            .contains("attribute \"tint\" has 2 numbers; an attribute"));
        assert!(e(vec![attribute(Some("tint"), "1 nan 2")]).contains("not finite"));
        let many = (0..=MAX_PER_ELEMENT).map(|i| attribute(Some(&format!("a{i}")), "1")).collect();
        assert!(e(many).contains("at most 256 attributes"));
    }

    #[test]
    fn own_attributes_come_first() {
        let own = vec![("tint".to_string(), ParamValue::Number(1.0))];
        let base = vec![
            ("wear".to_string(), ParamValue::Number(2.0)),
            ("tint".to_string(), ParamValue::Number(3.0)),
        ];
        let m = merged(&own, &base);
        assert_eq!(
            m,
            vec![("tint".into(), ParamValue::Number(1.0)), ("wear".into(), ParamValue::Number(2.0))]
        );
    }
}
