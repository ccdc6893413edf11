//! The XML encoding of the CENG795 format, read with roxmltree into the
//! format-neutral [`Element`] tree. Line numbers come along so every later
//! error can say where.
//!
//! Conversion is linear in the file's size: line numbers come from one
//! cursor that moves forward through the text (roxmltree's `text_pos_at`
//! counts from the start on every call), and sibling indices from running
//! counts. Elements nested deeper than [`MAX_DEPTH`] are refused before the
//! (recursive) conversion starts, so no file can overflow the stack.

use super::element::Element;
use super::error::{shown_token, Loc, SceneError};
use std::collections::HashMap;
use std::path::Path;

/// Deepest element nesting accepted; course scenes nest five or six levels.
pub const MAX_DEPTH: usize = 64;

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
            message: format!("malformed XML: {}", unquote(msg)),
        }
    })?;
    let mut lines = LineCursor { text, pos: 0, line: 1 };
    check_depth(file, &doc, &mut lines)?;
    let mut lines = LineCursor { text, pos: 0, line: 1 };
    Ok(convert(&doc.root_element(), String::new(), None, &mut lines))
}

/// Refuses nesting deeper than [`MAX_DEPTH`], without recursion: nodes come
/// in document order, so a node's parent always has its depth already.
fn check_depth(file: &Path, doc: &roxmltree::Document, lines: &mut LineCursor) -> Result<(), SceneError> {
    let mut depth: HashMap<roxmltree::NodeId, usize> = HashMap::new();
    for node in doc.root().descendants().filter(|n| n.is_element()) {
        let d = node.parent().and_then(|p| depth.get(&p.id())).copied().unwrap_or(0) + 1;
        if d > MAX_DEPTH {
            let line = lines.line_at(node.range().start);
            return Err(SceneError {
                file: file.to_path_buf(),
                loc: Some(Loc { line: Some(line), path: format!("<{}>", node.tag_name().name()) }),
                message: format!("elements are nested more than {MAX_DEPTH} deep"),
            });
        }
        depth.insert(node.id(), d);
    }
    Ok(())
}

/// A parser message with anything quoted that is not a plain name or number
/// left out, so a file that is not XML at all is never shown back.
fn unquote(msg: &str) -> String {
    let parts: Vec<&str> = msg.split('\'').collect();
    if parts.len() < 3 {
        return msg.to_string();
    }
    let mut out = String::new();
    for (i, part) in parts.iter().enumerate() {
        if i % 2 == 1 && i + 1 < parts.len() {
            let shown = shown_token(part);
            out.push_str(
                shown
                    .strip_prefix('"')
                    .and_then(|s| s.strip_suffix('"'))
                    .map_or("…".to_string(), |s| format!("'{s}'"))
                    .as_str(),
            );
        } else {
            out.push_str(part);
        }
    }
    out
}

/// Line numbers of byte offsets asked for in increasing order.
struct LineCursor<'a> {
    text: &'a str,
    pos: usize,
    line: u32,
}

impl LineCursor<'_> {
    fn line_at(&mut self, pos: usize) -> u32 {
        if pos < self.pos {
            self.pos = 0;
            self.line = 1;
        }
        let pos = pos.min(self.text.len());
        self.line += self.text.as_bytes()[self.pos..pos].iter().filter(|&&b| b == b'\n').count() as u32;
        self.pos = pos;
        self.line
    }
}

fn convert(node: &roxmltree::Node, parent: String, index: Option<usize>, lines: &mut LineCursor) -> Element {
    let name = node.tag_name().name().to_string();
    let attrs: Vec<(String, String)> =
        node.attributes().map(|a| (a.name().to_string(), a.value().to_string())).collect();
    let seg = Element::segment(&name, &attrs, index);
    let path = if parent.is_empty() { seg } else { format!("{parent}/{seg}") };
    let line = lines.line_at(node.range().start);
    let mut text = String::new();
    for c in node.children().filter(|c| c.is_text()) {
        text.push_str(c.text().unwrap_or(""));
        text.push(' ');
    }
    let elems: Vec<roxmltree::Node> = node.children().filter(|c| c.is_element()).collect();
    let mut total: HashMap<&str, usize> = HashMap::new();
    for c in &elems {
        *total.entry(c.tag_name().name()).or_default() += 1;
    }
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let children = elems
        .iter()
        .map(|c| {
            let tag = c.tag_name().name();
            let k = seen.entry(tag).or_default();
            let idx = (total[tag] > 1).then_some(*k);
            *k += 1;
            convert(c, path.clone(), idx, lines)
        })
        .collect();
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
    fn deep_nesting_is_an_error_and_wide_files_load_in_linear_time() {
        let deep = format!("<Scene>{}{}</Scene>", "<a>".repeat(100_000), "</a>".repeat(100_000));
        let e = parse(Path::new("deep.xml"), &deep).unwrap_err().to_string();
        assert!(e.contains("nested more than 64 deep"), "{e}");
        // 100,000 siblings, one per line: a conversion quadratic in the
        // file's size would not finish.
        let wide = format!("<Scene>\n{}</Scene>", "<Sphere><Radius>1</Radius></Sphere>\n".repeat(100_000));
        let root = parse(Path::new("wide.xml"), &wide).unwrap();
        assert_eq!(root.children.len(), 100_000);
        assert_eq!(root.children[99_999].loc.line, Some(100_001));
        assert_eq!(root.children[99_999].loc.path, "Scene/Sphere[99999]");
        assert_eq!(root.children[5].child("Radius").unwrap().loc.path, "Scene/Sphere[5]/Radius");
    }

    #[test]
    fn parser_messages_do_not_show_what_is_not_a_name() {
        assert_eq!(unquote("expected 'Camera' tag, not 'Cameras'"), "expected 'Camera' tag, not 'Cameras'");
        assert_eq!(unquote("unknown token 'root:x:0:0'"), "unknown token …");
    }

    #[test]
    fn malformed_xml_names_line() {
        let e = parse(Path::new("bad.xml"), "<Scene>\n<Cameras>\n</Scene>").unwrap_err();
        let s = e.to_string();
        assert!(s.starts_with("bad.xml: line 3"), "{s}");
        assert!(s.contains("malformed XML"), "{s}");
    }
}
