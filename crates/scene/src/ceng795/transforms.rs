//! `Transformations`: named transforms, and the reference lists that compose them.
//!
//! | element | numbers | reference |
//! |---|---|---|
//! | `Translation id="N"` | dx dy dz | `tN` |
//! | `Scaling id="N"` | sx sy sz | `sN` |
//! | `Rotation id="N"` | angle (degrees, counter-clockwise) x y z | `rN` |
//! | `Composite id="N"` | 16 numbers, a 4×4 matrix row by row | `cN` |
//!
//! An object's `<Transformations>r1 t1 s2</Transformations>` applies them in
//! the listed order: the matrix is `S2 T1 R1` (hw2 spec, eq. 1).

use super::Warnings;
use crate::element::{Element, Reader};
use crate::error::SceneError;
use luster_core::math::{Transform, Vec3};
use std::collections::HashMap;

/// Reads the named transforms, keyed by their reference (`t1`, `s2`, ...).
pub fn read_all(
    r: &Reader,
    ts: &Element,
    w: &mut Warnings,
) -> Result<HashMap<String, Transform>, SceneError> {
    w.unknown_children(ts, &["Translation", "Scaling", "Rotation", "Composite"]);
    let mut map = HashMap::new();
    for el in &ts.children {
        let (prefix, t) = match el.name.as_str() {
            "Translation" => ("t", Transform::translation(r.vec3(el)?)),
            "Scaling" => {
                let s = r.vec3(el)?;
                ("s", Transform::scaling(s).ok_or_else(|| r.err(el, "<Scaling> has a zero factor"))?)
            }
            "Rotation" => {
                let v = r.floats_n(el, 4)?;
                let t = Transform::rotation(v[0], Vec3::new(v[1], v[2], v[3]))
                    .ok_or_else(|| r.err(el, "<Rotation> has a zero axis"))?;
                ("r", t)
            }
            "Composite" => {
                let v = r.floats_n(el, 16)?;
                let mut rows = [0.0; 16];
                rows.copy_from_slice(&v);
                let t = Transform::from_rows(rows)
                    .ok_or_else(|| r.err(el, "<Composite> is not an invertible affine matrix"))?;
                ("c", t)
            }
            _ => continue,
        };
        let id = el.attr("id").map(str::trim).unwrap_or("");
        if id.is_empty() {
            return Err(r.err(el, format!("<{}> has no id", el.name)));
        }
        let key = format!("{prefix}{id}");
        if map.insert(key.clone(), t).is_some() {
            w.at(el, format!("transformation {key} is defined twice; the last definition is used"));
        }
    }
    Ok(map)
}

/// Composes an object's `<Transformations>` list in the listed order.
pub fn compose(r: &Reader, el: &Element, map: &HashMap<String, Transform>) -> Result<Transform, SceneError> {
    let mut t = Transform::IDENTITY;
    for tok in el.text.split_ascii_whitespace() {
        let next = map.get(tok).ok_or_else(|| {
            r.err(el, format!("transformation \"{tok}\" is not defined in <Transformations>"))
        })?;
        t = t.then(next);
    }
    Ok(t)
}
