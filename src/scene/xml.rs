//! The XML encoding of the CENG795 format, read with roxmltree into the
//! format-neutral [`Element`] tree. Line numbers come along so every later
//! error can say where.

use super::element::Element;
use super::error::{Loc, SceneError};
use std::path::Path;

/// Parses XML text into an element tree rooted at the document element.
pub fn parse(file: &Path, text: &str) -> Result<Element, SceneError> {
    let doc = roxmltree::Document::parse(text).map_err(|e| {
        let pos = e.pos();
        // roxmltree ends its message with the position, which `loc` already gives.
        let msg = e.to_string();
        let msg = msg.strip_suffix(&format!(" at {}:{}", pos.row, pos.col)).unwrap_or(&msg);
        SceneError {
            file: file.to_path_buf(),
            loc: Some(Loc { line: Some(pos.row), path: format!("column {}", pos.col) }),
            message: format!("malformed XML: {msg}"),
        }
    })?;
    Ok(convert(&doc, doc.root_element(), String::new(), None))
}

fn convert(
    doc: &roxmltree::Document,
    node: roxmltree::Node,
    parent: String,
    index: Option<usize>,
) -> Element {
    let name = node.tag_name().name().to_string();
    let attrs: Vec<(String, String)> =
        node.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect();
    let seg = Element::segment(&name, &attrs, index);
    let path = if parent.is_empty() { seg } else { format!("{parent}/{seg}") };
    let mut text = String::new();
    for c in node.children().filter(|c| c.is_text()) {
        text.push_str(c.text().unwrap_or(""));
        text.push(' ');
    }
    let elems: Vec<roxmltree::Node> = node.children().filter(|c| c.is_element()).collect();
    let children = elems
        .iter()
        .map(|c| {
            let same = elems.iter().filter(|o| o.tag_name() == c.tag_name()).count();
            let idx = (same > 1).then(|| {
                elems.iter().take_while(|o| o.id() != c.id()).filter(|o| o.tag_name() == c.tag_name()).count()
            });
            convert(doc, *c, path.clone(), idx)
        })
        .collect();
    let line = doc.text_pos_at(node.range().start).row;
    Element { name, attrs, text: text.trim().to_string(), children, loc: Loc { line: Some(line), path } }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_lines_attributes_and_paths() {
        let x = "<Scene>\n  <Objects>\n    <Mesh id=\"3\">\n      <Faces plyFile=\"a.ply\"/>\n    </Mesh>\n  </Objects>\n</Scene>";
        let root = parse(Path::new("s.xml"), x).unwrap();
        let mesh = root.child("Objects").unwrap().child("Mesh").unwrap();
        let faces = mesh.child("Faces").unwrap();
        assert_eq!(faces.attr("plyFile"), Some("a.ply"));
        assert_eq!(faces.loc.line, Some(4));
        assert_eq!(faces.loc.path, "Scene/Objects/Mesh[id=3]/Faces");
    }

    #[test]
    fn malformed_xml_names_line() {
        let e = parse(Path::new("bad.xml"), "<Scene>\n<Cameras>\n</Scene>").unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("bad.xml: line 3"), "{s}");
        assert!(s.contains("malformed XML"), "{s}");
    }
}
