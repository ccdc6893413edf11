//! The parameters a script declares with `params{...}`, as tools show them
//! (the watch page's sliders): each one's name, kind, default and, for a
//! number declared with `range(default, min, max)`, its range.

use mlua::{Table, Value};

use super::ParamValue;

/// The kind of a declared parameter: the kind of its default.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParamKind {
    /// A number.
    Number,
    /// A colour, `rgb(r, g, b)`.
    Rgb,
    /// A vector, `vec3(x, y, z)`.
    Vec3,
    /// Text.
    Text,
    /// The name of one of the scene's images, `image("name")`.
    Image,
}

impl ParamKind {
    /// The kind's name in `params{}` error messages.
    pub fn name(self) -> &'static str {
        match self {
            ParamKind::Number => "number",
            ParamKind::Rgb => "rgb",
            ParamKind::Vec3 => "vec3",
            ParamKind::Text => "string",
            ParamKind::Image => "image",
        }
    }
}

/// One parameter of a script's `params{...}`.
#[derive(Debug, Clone, PartialEq)]
pub struct DeclaredParam {
    /// Its name (`param.NAME`).
    pub name: String,
    /// Its kind.
    pub kind: ParamKind,
    /// Its default: a number, three numbers, or text (also for an image).
    pub default: ParamValue,
    /// `(min, max)` of a number declared with `range(default, min, max)`.
    pub range: Option<(f64, f64)>,
}

/// The declaration the prelude recorded (a list of `{name, kind, value,
/// min, max}`), in name order; `None` when it is not one (never for the
/// prelude's own lists).
pub(super) fn from_lua(list: &Table) -> Option<Vec<DeclaredParam>> {
    let mut out = Vec::new();
    for entry in list.sequence_values::<Table>() {
        let entry = entry.ok()?;
        let name: String = entry.get("name").ok()?;
        let kind = match entry.get::<String>("kind").ok()?.as_str() {
            "number" => ParamKind::Number,
            "rgb" => ParamKind::Rgb,
            "vec3" => ParamKind::Vec3,
            "string" => ParamKind::Text,
            "image" => ParamKind::Image,
            _ => return None,
        };
        let default = match entry.get::<Value>("value").ok()? {
            Value::Number(x) => ParamValue::Number(x),
            Value::Integer(x) => ParamValue::Number(x as f64),
            Value::String(s) => ParamValue::Text(s.to_str().ok()?.to_string()),
            Value::Table(t) => ParamValue::Vec3([t.get(1).ok()?, t.get(2).ok()?, t.get(3).ok()?]),
            _ => return None,
        };
        let min: Option<f64> = entry.get("min").ok()?;
        let max: Option<f64> = entry.get("max").ok()?;
        out.push(DeclaredParam { name, kind, default, range: min.zip(max) });
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shader::{ShadeInput, ShaderSet, ShaderSource};
    use std::time::Duration;

    fn set(code: &str) -> Result<ShaderSet, crate::shader::ShaderError> {
        ShaderSet::new(vec![ShaderSource::new("t", "t.lua", code)], Duration::from_secs(5))
    }

    #[test]
    fn every_kind_is_listed_in_name_order_with_its_default_and_range() {
        let s = set("params{ freq = range(4, 1, 16), tint = rgb(1, 0.5, 0), up = vec3(0, 1, 0),\n\
                     label = 'x', map = image('wood'), gain = 0.25 }\n\
                     function color(s) return vec3(param.freq / 16) end\n")
        .expect("the script compiles");
        let got: Vec<_> = s.declared(0).iter().map(|d| (d.name.as_str(), d.kind, d.range)).collect();
        assert_eq!(
            got,
            [
                ("freq", ParamKind::Number, Some((1.0, 16.0))),
                ("gain", ParamKind::Number, None),
                ("label", ParamKind::Text, None),
                ("map", ParamKind::Image, None),
                ("tint", ParamKind::Rgb, None),
                ("up", ParamKind::Vec3, None),
            ]
        );
        let default = |n: &str| s.declared(0).iter().find(|d| d.name == n).map(|d| d.default.clone());
        assert_eq!(default("freq"), Some(ParamValue::Number(4.0)));
        assert_eq!(default("tint"), Some(ParamValue::Vec3([1.0, 0.5, 0.0])));
        assert_eq!(default("map"), Some(ParamValue::Text("wood".into())));
        // The script reads a ranged parameter as a plain number.
        assert_eq!(s.color(0, &ShadeInput::default()).unwrap(), [0.25; 3]);
    }

    #[test]
    fn a_script_without_params_declares_nothing() {
        let s = set("function color(s) return vec3(1) end").expect("the script compiles");
        assert!(s.declared(0).is_empty() && s.declared(7).is_empty());
    }

    #[test]
    fn a_bad_range_is_an_error_at_its_line() {
        for (code, why) in [
            ("params{ f = range(20, 1, 16) }", "between"),
            ("params{ f = range(2, 3, 1) }", "min < max"),
            ("params{ f = range('a', 0, 1) }", "argument 1"),
            ("params{ f = range(0, 0, 1/0) }", "argument 3"),
        ] {
            let e = set(&format!("\n{code}\nfunction color(s) return vec3(1) end")).unwrap_err().to_string();
            assert!(e.contains("t.lua:2") && e.contains(why), "{code}: {e}");
        }
    }
}
