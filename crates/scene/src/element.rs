//! A format-neutral element tree: what both encodings of the CENG795 format
//! (XML and the 2025 JSON) parse into before anything is interpreted.
//!
//! An element has a name, attributes, text and children, and remembers where it
//! came from. The JSON encoding maps onto it mechanically (keys starting with
//! `_` are attributes, `_data` is the text, arrays are repeated children), so
//! everything after this point is written once for both encodings.

use super::error::{shown_token, Loc, SceneError};
use glam::Vec3;
use std::path::Path;

/// One element of a scene file.
#[derive(Clone, Debug, Default)]
pub struct Element {
    /// Tag name.
    pub name: String,
    /// Attributes in file order.
    pub attrs: Vec<(String, String)>,
    /// Text content, trimmed.
    pub text: String,
    /// Child elements in file order.
    pub children: Vec<Element>,
    /// Where it is.
    pub loc: Loc,
}

impl Element {
    /// The first child named `name`.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    /// All children named `name`.
    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }

    /// An attribute's value.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == name).map(|(_, v)| v.as_str())
    }

    /// The path segment naming this element, with its id when it has one.
    pub fn segment(name: &str, attrs: &[(String, String)], index: Option<usize>) -> String {
        match (attrs.iter().find(|(k, _)| k == "id"), index) {
            (Some((_, id)), _) => format!("{name}[id={id}]"),
            (None, Some(i)) => format!("{name}[{i}]"),
            (None, None) => name.to_string(),
        }
    }
}

/// Reads typed values out of elements, turning every failure into a
/// [`SceneError`] that names the file and the element.
#[derive(Clone, Copy)]
pub struct Reader<'a> {
    /// The scene file, for error messages.
    pub file: &'a Path,
}

impl<'a> Reader<'a> {
    /// An error at `el`.
    pub fn err(&self, el: &Element, msg: impl Into<String>) -> SceneError {
        SceneError::at(self.file, &el.loc, msg)
    }

    /// All whitespace-separated numbers of the element's text.
    pub fn floats(&self, el: &Element) -> Result<Vec<f32>, SceneError> {
        el.text
            .split_ascii_whitespace()
            .map(|tok| {
                let v: f32 = tok.parse().map_err(|_| {
                    self.err(el, format!("<{}> has {}, which is not a number", el.name, shown_token(tok)))
                })?;
                if v.is_finite() {
                    Ok(v)
                } else {
                    Err(self.err(el, format!("<{}> has a non-finite number {}", el.name, shown_token(tok))))
                }
            })
            .collect()
    }

    /// Exactly `n` numbers.
    pub fn floats_n(&self, el: &Element, n: usize) -> Result<Vec<f32>, SceneError> {
        let v = self.floats(el)?;
        if v.len() != n {
            return Err(self.err(el, format!("<{}> needs {n} numbers, found {}", el.name, v.len())));
        }
        Ok(v)
    }

    /// A single number.
    pub fn float(&self, el: &Element) -> Result<f32, SceneError> {
        Ok(self.floats_n(el, 1)?[0])
    }

    /// Three numbers.
    pub fn vec3(&self, el: &Element) -> Result<Vec3, SceneError> {
        let v = self.floats_n(el, 3)?;
        Ok(Vec3::new(v[0], v[1], v[2]))
    }

    /// All whitespace-separated non-negative integers.
    pub fn uints(&self, el: &Element) -> Result<Vec<u32>, SceneError> {
        el.text
            .split_ascii_whitespace()
            .map(|tok| {
                tok.parse::<u32>().map_err(|_| {
                    self.err(
                        el,
                        format!(
                            "<{}> has {}, which is not a non-negative integer",
                            el.name,
                            shown_token(tok)
                        ),
                    )
                })
            })
            .collect()
    }

    /// A single non-negative integer.
    pub fn uint(&self, el: &Element) -> Result<u32, SceneError> {
        let v = self.uints(el)?;
        if v.len() != 1 {
            return Err(self.err(el, format!("<{}> needs one integer, found {}", el.name, v.len())));
        }
        Ok(v[0])
    }

    /// The named child, which must exist.
    pub fn required<'e>(&self, parent: &'e Element, name: &str) -> Result<&'e Element, SceneError> {
        parent
            .child(name)
            .ok_or_else(|| self.err(parent, format!("<{}> is missing its <{name}>", parent.name)))
    }

    /// The named child's three numbers, or a default when absent.
    pub fn vec3_or(&self, parent: &Element, name: &str, default: Vec3) -> Result<Vec3, SceneError> {
        parent.child(name).map_or(Ok(default), |c| self.vec3(c))
    }

    /// The named child's number, or a default when absent.
    pub fn float_or(&self, parent: &Element, name: &str, default: f32) -> Result<f32, SceneError> {
        parent.child(name).map_or(Ok(default), |c| self.float(c))
    }

    /// A boolean attribute (`true`/`false`, `1`/`0`), or a default when absent.
    pub fn bool_attr(&self, el: &Element, name: &str, default: bool) -> Result<bool, SceneError> {
        match el.attr(name).map(|s| s.trim().to_ascii_lowercase()) {
            None => Ok(default),
            Some(s) if s == "true" || s == "1" => Ok(true),
            Some(s) if s == "false" || s == "0" => Ok(false),
            Some(s) => Err(self.err(el, format!("attribute {name}=\"{s}\" must be true or false"))),
        }
    }
}
