//! A line-by-line check of an OBJ file before `tobj` reads it.
//!
//! `tobj` reports errors without a line, reads a face index of 0 as "no
//! index", ignores statements it does not know and drops `usemtl` names that
//! no material library defines. This pass catches those with the line they are
//! on, and collects what the loader needs first: the `mtllib` statements (the
//! MTL files are read before the geometry, so a material's name can be
//! checked) and the `usemtl` names.
//!
//! | statement | checked |
//! |---|---|
//! | `v x y z [w]` or `v x y z r g b` | at least 3 finite numbers |
//! | `vt u v [w]` | at least 2 finite numbers |
//! | `vn x y z` | 3 finite numbers |
//! | `f a b c ...` | at least 3 corners, each `v`, `v/vt`, `v//vn` or `v/vt/vn`; no index 0; negative indices count back from the last one defined so far; positive ones must exist by the end of the file |
//! | `mtllib`, `usemtl` | a name is given |
//! | `o`, `g`, `s`, `mg` | accepted (objects and groups only name parts; smoothing groups are left to the normals) |
//! | `l`, `p`, free-form geometry, display attributes | ignored with one warning per statement |
//! | anything else | an error: the file is not what it claims to be |

use crate::error::shown_token;

/// One `mtllib` or `usemtl` statement: its line and its argument.
#[derive(Clone, Debug)]
pub struct Named {
    /// 1-based line.
    pub line: u32,
    /// The text after the keyword, trimmed.
    pub name: String,
}

/// What the scan found in a well-formed file.
#[derive(Debug, Default)]
pub struct Scan {
    /// `mtllib` statements in order.
    pub mtllibs: Vec<Named>,
    /// `usemtl` statements in order.
    pub usemtls: Vec<Named>,
    /// Faces (polygons, before triangulation).
    pub faces: usize,
    /// (line, message) of what is ignored, one per kind of statement.
    pub warnings: Vec<(u32, String)>,
}

/// Statements that describe curves, surfaces or display settings, which a
/// ray tracer of polygons has no use for: accepted and ignored.
const IGNORED: &[&str] = &[
    "l",
    "p",
    "vp",
    "cstype",
    "deg",
    "bmat",
    "step",
    "curv",
    "curv2",
    "surf",
    "parm",
    "trim",
    "hole",
    "scrv",
    "sp",
    "end",
    "con",
    "bevel",
    "c_interp",
    "d_interp",
    "lod",
    "usemap",
    "maplib",
    "shadow_obj",
    "trace_obj",
    "ctech",
    "stech",
];

/// A problem on a line: (line, message).
pub type LineError = (u32, String);

/// Checks every line of an OBJ file's text.
pub fn scan(text: &str) -> Result<Scan, LineError> {
    let mut out = Scan::default();
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    // The largest positive index of each kind and the first line using it:
    // OBJ files may refer forwards, so these are checked at the end.
    let mut max_ref: [(usize, u32); 3] = [(0, 0); 3];
    let mut warned: Vec<&str> = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i as u32 + 1;
        let mut words = raw.split_whitespace();
        let Some(key) = words.next() else { continue };
        if key.starts_with('#') {
            continue;
        }
        let rest = raw.trim_start()[key.len()..].trim();
        let err = |msg: String| Err((line, msg));
        match key {
            "v" => {
                let n = numbers(line, key, rest)?;
                if n < 3 {
                    return err(format!("v needs x y z, found {n} number(s)"));
                }
                nv += 1;
            }
            "vt" => {
                let n = numbers(line, key, rest)?;
                if n < 2 {
                    return err(format!("vt needs u v, found {n} number(s)"));
                }
                nvt += 1;
            }
            "vn" => {
                let n = numbers(line, key, rest)?;
                if n != 3 {
                    return err(format!("vn needs x y z, found {n} number(s)"));
                }
                nvn += 1;
            }
            "f" => {
                let corners: Vec<&str> = rest.split_whitespace().collect();
                if corners.len() < 3 {
                    return err(format!("a face needs at least 3 corners, found {}", corners.len()));
                }
                for c in corners {
                    corner(line, c, [nv, nvt, nvn], &mut max_ref)?;
                }
                out.faces += 1;
            }
            "mtllib" | "usemtl" => {
                if rest.is_empty() {
                    return err(format!(
                        "{key} names no {}",
                        if key == "mtllib" { "file" } else { "material" }
                    ));
                }
                let n = Named { line, name: rest.to_string() };
                if key == "mtllib" {
                    out.mtllibs.push(n)
                } else {
                    out.usemtls.push(n)
                }
            }
            "o" | "g" | "s" | "mg" => {}
            k if IGNORED.contains(&k) => {
                if !warned.contains(&k) {
                    warned.push(k);
                    out.warnings.push((line, format!("`{k}` statements are not supported; ignored")));
                }
            }
            other => {
                return err(format!("{} is not an OBJ statement", shown_token(other)));
            }
        }
    }
    for (k, (name, count)) in
        [("vertex", nv), ("texture coordinate", nvt), ("normal", nvn)].iter().enumerate()
    {
        let (max, line) = max_ref[k];
        if max > *count {
            return Err((line, format!("face refers to {name} {max}, but the file defines {count}")));
        }
    }
    if out.faces == 0 {
        return Err((0, "the file has no faces".to_string()));
    }
    Ok(out)
}

/// Counts the numbers after a `v`, `vt` or `vn`, refusing anything else.
fn numbers(line: u32, key: &str, rest: &str) -> Result<usize, LineError> {
    let mut n = 0;
    for w in rest.split_whitespace() {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => n += 1,
            Ok(_) => return Err((line, format!("{key} has a non-finite number {}", shown_token(w)))),
            Err(_) => return Err((line, format!("{key} has {}, which is not a number", shown_token(w)))),
        }
    }
    Ok(n)
}

/// Checks one face corner `v[/vt[/vn]]` against the counts defined so far.
fn corner(line: u32, c: &str, counts: [usize; 3], max_ref: &mut [(usize, u32); 3]) -> Result<(), LineError> {
    const KIND: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let parts: Vec<&str> = c.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err((line, format!("face corner {} is not v, v/vt, v//vn or v/vt/vn", shown_token(c))));
    }
    for (k, p) in parts.iter().enumerate() {
        if p.is_empty() {
            continue;
        }
        let Ok(i) = p.parse::<i64>() else {
            return Err((
                line,
                format!("face corner {}: {} is not an index", shown_token(c), shown_token(p)),
            ));
        };
        if i == 0 {
            return Err((
                line,
                format!(
                    "face corner {}: {} index 0 (OBJ numbers from 1, or from -1 backwards)",
                    shown_token(c),
                    KIND[k]
                ),
            ));
        }
        if i < 0 {
            if i.unsigned_abs() as usize > counts[k] {
                return Err((
                    line,
                    format!(
                        "face corner {}: {} {i} reaches before the first ({} defined so far)",
                        shown_token(c),
                        KIND[k],
                        counts[k]
                    ),
                ));
            }
        } else if i as usize > max_ref[k].0 {
            max_ref[k] = (i as usize, line);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_good_file_passes() {
        let s =
            scan("# c\nmtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m\nf 1/1 2/1 -1/1\n").unwrap();
        assert_eq!((s.mtllibs[0].line, s.mtllibs[0].name.as_str()), (2, "a.mtl"));
        assert_eq!(s.usemtls[0].name, "m");
        assert_eq!(s.faces, 1);
    }

    #[test]
    fn bad_indices_and_garbage_name_their_line() {
        let e = |t: &str| scan(t).unwrap_err();
        assert_eq!(e("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").0, 4);
        assert!(e("v 0 0 0\nf 1 2 3\n").1.contains("vertex 3, but the file defines 1"));
        assert!(e("v 0 0 0\nf -1 -2 1\n").1.contains("before the first"));
        assert!(e("v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1/4 2 3\n").1.contains("texture coordinate 4"));
        assert_eq!(e("v 0 0 0\nhello world\n"), (2, "\"hello\" is not an OBJ statement".into()));
        assert!(e("v 0 zero 0\n").1.contains("not a number"));
        assert!(e("v 0 0 0\nf 1 1\n").1.contains("at least 3 corners"));
        assert!(e("v 0 0 0\n").1.contains("no faces"));
    }

    #[test]
    fn forward_references_are_allowed() {
        assert!(scan("f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n").is_ok());
    }
}
