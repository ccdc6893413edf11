//! User data that shaders read with `getattribute("name" [, default])`: the
//! attributes a scene gives its objects and instances (`<Attribute>` in a
//! CENG795 file, `extras` in glTF), keyed by the ids a shading point carries.
//!
//! A shading point names two elements of the scene: `s.instance_id`, the
//! object hit (an instance, a glTF node), and `s.object_id`, the geometry it
//! draws (the instanced mesh; the same id for an object drawn by itself).
//! `getattribute` looks the name up in the instance's attributes, then in the
//! object's, then returns the default. [`Attributes`] holds both tables; the
//! renderer fills them from the scene description and hands them to the
//! [`ShaderSet`](super::ShaderSet) through [`ShaderOptions`](super::ShaderOptions).
//! Every Lua state turns them into Lua tables once (`install`), so a lookup
//! is two table reads and allocates nothing.
//!
//! One more name is known to every object without a scene giving it:
//! `object:name`, the object's id in the scene file (a glTF node's name).
//! It is fetched from Rust on first use and cached per state, so a scene of
//! a million instances builds no million strings in every state.

use std::collections::BTreeMap;

use mlua::{Lua, Table};

use super::ParamValue;

/// Most attributes one element (an object, an instance, a volume) may have.
pub const MAX_PER_ELEMENT: usize = 256;

/// Most bytes a scene's attributes may take, counted by [`cost`]: each state
/// holds them all as Lua values, so this bounds the memory of every state.
pub const MAX_BYTES: usize = 16 << 20;

/// Longest attribute name accepted, in bytes.
pub const MAX_NAME_BYTES: usize = 256;

/// What one attribute counts against [`MAX_BYTES`]: its name, its value and
/// the table slot that holds them.
pub fn cost(name: &str, value: &ParamValue) -> usize {
    let value = match value {
        ParamValue::Number(_) => 8,
        ParamValue::Vec3(_) => 24,
        ParamValue::Text(t) => t.len(),
    };
    name.len() + value + 32
}

/// Whether `name` may name a user attribute: not empty, at most
/// [`MAX_NAME_BYTES`], no control characters, and no `:` (names with a colon
/// are the ones luster provides, such as `object:name`). The reason when not,
/// a sentence fragment that does not quote the name.
pub fn check_name(name: &str) -> Result<(), String> {
    if name.is_empty() {
        return Err("an attribute needs a name (name=\"...\")".into());
    }
    if name.len() > MAX_NAME_BYTES {
        return Err(format!("an attribute name is longer than {MAX_NAME_BYTES} bytes"));
    }
    if name.chars().any(char::is_control) {
        return Err("an attribute name has a control character".into());
    }
    if name.contains(':') {
        return Err(format!(
            "attribute {} has a colon in its name; names with a colon are reserved for the attributes \
             luster provides (object:name)",
            shown_name(name)
        ));
    }
    Ok(())
}

/// An attribute name for a message: itself when it is a short identifier,
/// else its length only (messages never quote a file's contents at length).
pub fn shown_name(name: &str) -> String {
    let ident = name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
    if !name.is_empty() && name.len() <= 64 && ident {
        format!("\"{name}\"")
    } else {
        format!("(a name of {} characters)", name.chars().count())
    }
}

/// Checks one element's list: at most [`MAX_PER_ELEMENT`] attributes, each
/// named as [`check_name`] wants, no name twice. The reason when not.
pub fn check_list(list: &[(String, ParamValue)]) -> Result<(), String> {
    if list.len() > MAX_PER_ELEMENT {
        return Err(format!(
            "{} attributes on one element; at most {MAX_PER_ELEMENT} are allowed",
            list.len()
        ));
    }
    for (i, (name, _)) in list.iter().enumerate() {
        check_name(name)?;
        if list[..i].iter().any(|(n, _)| n == name) {
            return Err(format!("attribute {} is given twice", shown_name(name)));
        }
    }
    Ok(())
}

/// The attributes of a scene's instances and objects, by the ids shading
/// points carry (see the module doc), and the objects' names.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Attributes {
    instances: BTreeMap<u32, Vec<(String, ParamValue)>>,
    objects: BTreeMap<u32, Vec<(String, ParamValue)>>,
    names: Vec<String>,
    bytes: usize,
}

/// Which table an element's attributes go into.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    /// An instance's own (`s.instance_id`): looked up first.
    Instance,
    /// A geometry's (`s.object_id`): what every instance of it shares.
    Object,
}

impl Attributes {
    /// No attributes, no names.
    pub fn new() -> Attributes {
        Attributes::default()
    }

    /// Gives element `id` of `level` the attributes in `list` (an empty list
    /// adds nothing). Fails, with a sentence fragment, when the list breaks
    /// [`check_list`], the element already has attributes at that level, or
    /// the scene's attributes together pass [`MAX_BYTES`].
    pub fn insert(&mut self, level: Level, id: u32, list: &[(String, ParamValue)]) -> Result<(), String> {
        if list.is_empty() {
            return Ok(());
        }
        check_list(list)?;
        let bytes = list.iter().map(|(n, v)| cost(n, v)).sum::<usize>();
        if self.bytes + bytes > MAX_BYTES {
            return Err(format!(
                "the scene's attributes take more than {} MiB; at most that much is allowed",
                MAX_BYTES >> 20
            ));
        }
        let table = match level {
            Level::Instance => &mut self.instances,
            Level::Object => &mut self.objects,
        };
        if table.contains_key(&id) {
            return Err(format!("element {id} already has attributes"));
        }
        table.insert(id, list.to_vec());
        self.bytes += bytes;
        Ok(())
    }

    /// Sets the names `getattribute("object:name")` returns, by instance id.
    pub fn set_names(&mut self, names: Vec<String>) {
        self.names = names;
    }

    /// Whether no element has an attribute (names aside).
    pub fn is_empty(&self) -> bool {
        self.instances.is_empty() && self.objects.is_empty()
    }

    /// The value `getattribute(name)` gives a point of instance `instance`
    /// drawing object `object`: the instance's own, else the object's.
    pub fn get(&self, instance: u32, object: u32, name: &str) -> Option<&ParamValue> {
        fn find<'a>(
            t: &'a BTreeMap<u32, Vec<(String, ParamValue)>>,
            id: u32,
            name: &str,
        ) -> Option<&'a ParamValue> {
            t.get(&id).and_then(|l| l.iter().find(|(n, _)| n == name)).map(|(_, v)| v)
        }
        find(&self.instances, instance, name).or_else(|| find(&self.objects, object, name))
    }

    /// The name of instance `id` (`object:name`), if it has one.
    pub fn name(&self, id: u32) -> Option<&str> {
        self.names.get(id as usize).map(String::as_str).filter(|n| !n.is_empty())
    }
}

/// A table of Lua tables, one per element, keyed by its id: numbers as Lua
/// numbers, text as strings, and three numbers as `{x, y, z}`, which the
/// prelude turns into a `vec3`.
fn lua_tables(lua: &Lua, by_id: &BTreeMap<u32, Vec<(String, ParamValue)>>) -> mlua::Result<Table> {
    let out = lua.create_table()?;
    for (&id, list) in by_id {
        let t = lua.create_table_with_capacity(0, list.len())?;
        for (name, value) in list {
            match value {
                ParamValue::Number(x) => t.raw_set(name.as_str(), *x)?,
                ParamValue::Vec3(v) => {
                    t.raw_set(name.as_str(), lua.create_sequence_from(v.iter().copied())?)?
                }
                ParamValue::Text(s) => t.raw_set(name.as_str(), s.as_str())?,
            }
        }
        out.raw_set(id, t)?;
    }
    Ok(out)
}

/// Hands the attributes to the prelude of a new state (its
/// `set_attributes`): the two tables, and a function that gives an
/// instance's name, for `object:name`.
pub(crate) fn install(lua: &Lua, api: &Table, attrs: &std::sync::Arc<Attributes>) -> mlua::Result<()> {
    let set: mlua::Function = api.get("set_attributes")?;
    let instances = lua_tables(lua, &attrs.instances)?;
    let objects = lua_tables(lua, &attrs.objects)?;
    let names = std::sync::Arc::clone(attrs);
    let name_of = lua.create_function(move |_, id: i64| {
        Ok(u32::try_from(id).ok().and_then(|id| names.name(id)).map(str::to_string))
    })?;
    set.call::<()>((instances, objects, name_of))
}

#[cfg(test)]
mod tests {
    use super::super::{ShadeInput, ShaderOptions, ShaderSet, ShaderSource};
    use super::*;
    use std::sync::Arc;

    fn list(items: &[(&str, ParamValue)]) -> Vec<(String, ParamValue)> {
        items.iter().map(|(n, v)| (n.to_string(), v.clone())).collect()
    }

    #[test]
    fn instance_attributes_come_before_the_objects() {
        let mut a = Attributes::new();
        a.insert(
            Level::Object,
            1,
            &list(&[("tint", ParamValue::Vec3([1.0, 0.0, 0.0])), ("wear", ParamValue::Number(0.5))]),
        )
        .unwrap();
        a.insert(Level::Instance, 4, &list(&[("tint", ParamValue::Vec3([0.0, 1.0, 0.0]))])).unwrap();
        assert_eq!(a.get(4, 1, "tint"), Some(&ParamValue::Vec3([0.0, 1.0, 0.0])));
        assert_eq!(a.get(4, 1, "wear"), Some(&ParamValue::Number(0.5)));
        assert_eq!(a.get(5, 1, "tint"), Some(&ParamValue::Vec3([1.0, 0.0, 0.0])));
        assert_eq!(a.get(5, 2, "tint"), None);
        assert!(!a.is_empty());
    }

    #[test]
    fn bad_lists_are_refused() {
        let n = |name: &str| list(&[(name, ParamValue::Number(1.0))]);
        assert!(check_list(&n("")).unwrap_err().contains("needs a name"));
        assert!(check_list(&n("object:name")).unwrap_err().contains("reserved"));
        assert!(check_list(&n("a\u{7}b")).unwrap_err().contains("control"));
        assert!(check_list(&n(&"x".repeat(MAX_NAME_BYTES + 1))).unwrap_err().contains("longer"));
        let twice = list(&[("wear", ParamValue::Number(1.0)), ("wear", ParamValue::Number(2.0))]);
        assert!(check_list(&twice).unwrap_err().contains("\"wear\" is given twice"));
        let many: Vec<_> =
            (0..=MAX_PER_ELEMENT).map(|i| (format!("a{i}"), ParamValue::Number(0.0))).collect();
        assert!(check_list(&many).unwrap_err().contains("at most 256"));
        let mut a = Attributes::new();
        a.insert(Level::Instance, 0, &n("x")).unwrap();
        assert!(a.insert(Level::Instance, 0, &n("y")).unwrap_err().contains("already"));
    }

    #[test]
    fn the_total_is_capped() {
        let mut a = Attributes::new();
        let big = list(&[("label", ParamValue::Text("x".repeat(MAX_BYTES / 4)))]);
        for id in 0..3 {
            a.insert(Level::Instance, id, &big).unwrap();
        }
        let e = a.insert(Level::Instance, 3, &big).unwrap_err();
        assert!(e.contains("more than 16 MiB"), "{e}");
        assert!(a.get(3, 3, "label").is_none());
    }

    /// A set of one script, with the attributes of the tests below: object
    /// 1 has a tint, a wear and a label; its instance 4 a tint of its own,
    /// instance 5 none; object 2 has no attributes. Instance 4 is "crate_a".
    fn scene_set(code: &str) -> ShaderSet {
        let mut a = Attributes::new();
        let object = [
            ("tint", ParamValue::Vec3([0.8, 0.2, 0.1])),
            ("wear", ParamValue::Number(0.25)),
            ("label", ParamValue::Text("oak".into())),
        ];
        a.insert(Level::Object, 1, &list(&object)).unwrap();
        a.insert(Level::Instance, 4, &list(&[("tint", ParamValue::Vec3([0.1, 0.7, 0.3]))])).unwrap();
        a.set_names(vec![String::new(), "crate".into(), String::new(), String::new(), "crate_a".into()]);
        let options = ShaderOptions { attributes: Arc::new(a), ..ShaderOptions::default() };
        ShaderSet::build(vec![ShaderSource::new("t", "t.lua", code)], options).unwrap()
    }

    fn at(instance: u32, object: u32) -> ShadeInput {
        ShadeInput { instance_id: instance, object_id: object, ..ShadeInput::default() }
    }

    fn close(a: [f32; 3], b: [f64; 3]) -> bool {
        a.iter().zip(b).all(|(x, y)| (f64::from(*x) - y).abs() < 1e-6)
    }

    #[test]
    fn getattribute_reads_the_instance_then_the_object_then_the_default() {
        let set = scene_set("function color(s) return getattribute(\"tint\", rgb(1, 1, 1)) end");
        assert!(close(set.color(0, &at(4, 1)).unwrap(), [0.1, 0.7, 0.3]));
        assert!(close(set.color(0, &at(5, 1)).unwrap(), [0.8, 0.2, 0.1]));
        assert!(close(set.color(0, &at(1, 1)).unwrap(), [0.8, 0.2, 0.1]));
        assert!(close(set.color(0, &at(6, 2)).unwrap(), [1.0, 1.0, 1.0]));
        let set = scene_set("function color(s) return getattribute(\"tint\", vec3(1, 0.5, 0)) end");
        assert!(close(set.color(0, &at(6, 2)).unwrap(), [1.0, 0.5, 0.0]));
    }

    #[test]
    fn getattribute_gives_each_kind_and_nil() {
        let set = scene_set(
            "function color(s)
               local w, l, n = getattribute(\"wear\"), getattribute(\"label\"), getattribute(\"none\")
               assert(type(w) == \"number\" and l == \"oak\" and n == nil)
               return w, #l, getattribute(\"tint\").x
             end",
        );
        assert!(close(set.color(0, &at(5, 1)).unwrap(), [0.25, 3.0, 0.8]));
        let set = scene_set(
            "function color(s)
               return getattribute(\"wear\", 7), getattribute(\"label\") == nil and 1 or 0, 0
             end",
        );
        assert!(close(set.color(0, &at(3, 2)).unwrap(), [7.0, 1.0, 0.0]));
    }

    #[test]
    fn the_default_sets_the_kind() {
        // A number serves as a grey colour or as text.
        let set = scene_set("function color(s) return getattribute(\"wear\", vec3(0)) end");
        assert!(close(set.color(0, &at(4, 1)).unwrap(), [0.25; 3]));
        let set = scene_set("function color(s) return #getattribute(\"wear\", \"\"), 0, 0 end");
        assert!(close(set.color(0, &at(4, 1)).unwrap(), [4.0, 0.0, 0.0]));
        let set = scene_set("function color(s) return getattribute(\"label\", 0), 0, 0 end");
        let e = set.color(0, &at(4, 1)).unwrap_err().to_string();
        assert!(
            e.contains("t.lua:1")
                && e.contains("attribute 'label' of this object is text, but the default is a number"),
            "{e}"
        );
        let set = scene_set("function color(s) return getattribute(42), 0, 0 end");
        let e = set.color(0, &at(4, 1)).unwrap_err().to_string();
        assert!(e.contains("expected an attribute name (a string), got a number"), "{e}");
    }

    #[test]
    fn a_changed_vector_does_not_change_the_scene() {
        let set = scene_set(
            "function color(s) local t = getattribute(\"tint\"); local r = t.x; t.x = 5; return r, 0, 0 end",
        );
        for _ in 0..3 {
            assert!(close(set.color(0, &at(4, 1)).unwrap(), [0.1, 0.0, 0.0]));
        }
    }

    #[test]
    fn object_name_is_the_instance_s() {
        let set = scene_set(
            "function color(s) local n = getattribute(\"object:name\") or \"\"
               return #n, n == \"crate_a\" and 1 or 0, getattribute(\"object:name\", \"?\") == \"?\" and 1 or 0 end",
        );
        assert!(close(set.color(0, &at(4, 1)).unwrap(), [7.0, 1.0, 0.0]));
        assert!(close(set.color(0, &at(1, 1)).unwrap(), [5.0, 0.0, 0.0]));
        assert!(close(set.color(0, &at(2, 2)).unwrap(), [0.0, 0.0, 1.0]));
    }

    #[test]
    fn every_entry_point_reads_its_point_s_attributes() {
        // material(s): the closure's colour.
        let set =
            scene_set("function material(s) return diffuse{ albedo = getattribute(\"tint\", vec3(1)) } end");
        let c = set.material(0, &at(4, 1)).unwrap().closure.unwrap();
        assert!(close(c.nodes[usize::from(c.root)].c[0], [0.1, 0.7, 0.3]), "{:?}", c.nodes[0]);
        // height(s), three points in one call, each with its own ids.
        let set = scene_set("function height(s) return getattribute(s, \"wear\", -1) end");
        let h = set.heights3(0, &[at(4, 1), at(3, 2), at(5, 1)]).unwrap();
        assert_eq!(h, [0.25, -1.0, 0.25]);
        // density(s) of a volume.
        let set = scene_set("function density(s) return getattribute(\"wear\", 0) * 4 end");
        assert_eq!(set.density(0, &at(1, 1)).unwrap(), 1.0);
        assert_eq!(set.density(0, &at(0, 0)).unwrap(), 0.0);
    }

    #[test]
    fn a_set_without_attributes_gives_defaults() {
        let src =
            ShaderSource::new("t", "t.lua", "function color(s) return getattribute(\"tint\", vec3(0.5)) end");
        let set = ShaderSet::new(vec![src], super::super::DEFAULT_TIMEOUT).unwrap();
        assert!(close(set.color(0, &at(4, 1)).unwrap(), [0.5; 3]));
    }

    #[test]
    fn names_are_shown_only_when_short_identifiers() {
        assert_eq!(shown_name("tint"), "\"tint\"");
        assert_eq!(shown_name("a b"), "(a name of 3 characters)");
        assert_eq!(shown_name(&"y".repeat(100)), "(a name of 100 characters)");
    }
}
