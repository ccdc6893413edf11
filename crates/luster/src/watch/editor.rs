//! The shader editor's side of a watch session: which files the page may
//! read and save (the scene's shader scripts and the modules they
//! `require`, nothing else), the parameters each script declares with
//! `params{...}`, and the session's overrides of their values.
//!
//! The driver publishes the files and parameters at every load
//! ([`Editor::publish`]) and applies the overrides to the loaded scene
//! before it is built ([`Editor::apply`]); the server answers the page from
//! here. A save writes the file (a temporary file renamed over it) and the
//! file watch re-renders as for any save; an override re-renders through
//! the same cancel-and-reload path, and is never written to a file.

use luster_scene::description::TextureSource;
use luster_scene::Description;
use luster_shading::shader::{DeclaredParam, ParamKind, ParamValue, ShaderSet, ShaderSource};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard};
use std::time::Duration;

/// Largest script or module the page may save (what the scene loader and
/// `require` read).
pub const MAX_SAVE: usize = luster_shading::shader::MAX_MODULE_BYTES as usize;

/// A file the page may open and save.
#[derive(Clone, Debug, PartialEq)]
pub struct ShaderFile {
    /// Its name in URLs and on the page: relative to the scene's folder
    /// when inside it, else the whole path.
    pub name: String,
    /// Where it is (canonical folder, file name).
    pub path: PathBuf,
    /// Whether it is a module some script requires (not named by the scene).
    pub module: bool,
}

/// One use of a script by the scene (a texture map or a volume): the
/// parameters it declares and the values the scene gives them.
#[derive(Clone, Debug, PartialEq)]
pub struct ShaderUse {
    /// `texture ID` or `volume ID`: the key of its overrides.
    pub id: String,
    /// The script's [`ShaderFile::name`].
    pub file: String,
    /// The scene's `<Parameter>`s.
    pub scene: Vec<(String, ParamValue)>,
    /// What the script's `params{...}` declares.
    pub declared: Vec<DeclaredParam>,
}

/// Why a request to the editor was refused: a status code and one sentence
/// (never quoting a file's contents).
#[derive(Debug, PartialEq)]
pub struct Refused {
    /// The HTTP status.
    pub status: u16,
    /// The sentence.
    pub why: String,
}

fn refused(status: u16, why: impl Into<String>) -> Refused {
    Refused { status, why: why.into() }
}

#[derive(Default)]
struct Inner {
    /// Bumped when what `/shaders` answers changes.
    seq: u64,
    files: Vec<ShaderFile>,
    uses: Vec<ShaderUse>,
    /// (use id, parameter) → value, for the session.
    overrides: BTreeMap<(String, String), ParamValue>,
    /// The scene's folder (canonical) and file, in watched spelling.
    root: PathBuf,
    scene: PathBuf,
    /// Declarations by (script, text): compiled once per version of a script.
    declared: HashMap<(PathBuf, String), Option<Vec<DeclaredParam>>>,
}

/// A use of a script in a loaded scene: its id, file, text and the scene's
/// parameters.
type Script<'a> = (String, &'a Path, &'a str, &'a [(String, ParamValue)]);

/// The editor state shared by the driver and the server.
pub struct Editor {
    inner: Mutex<Inner>,
    /// Cancels the render in flight and asks for a reload.
    poke: Box<dyn Fn() + Send + Sync>,
}

impl Editor {
    /// An editor whose overrides call `poke` to re-render.
    pub fn new(poke: impl Fn() + Send + Sync + 'static) -> Editor {
        Editor { inner: Mutex::new(Inner::default()), poke: Box::new(poke) }
    }

    fn lock(&self) -> MutexGuard<'_, Inner> {
        self.inner.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Changes whenever the answer of [`Editor::to_json`] does.
    pub fn seq(&self) -> u64 {
        self.lock().seq
    }

    /// Takes the files and parameters of a loaded scene: its scripts, the
    /// modules among `watched` (files the last loads required), and what
    /// each script declares (its top level run once per version of its
    /// text, within `timeout`; a script that fails keeps the declaration of
    /// its last good version).
    pub fn publish(&self, desc: &Description, watched: &BTreeSet<PathBuf>, timeout: Duration) {
        let scene = super::files::watched_name(&desc.file);
        let root = scene.parent().map(Path::to_path_buf).unwrap_or_default();
        let name_of = |p: &Path| name_in(&root, p);
        let mut scripts: Vec<Script> = Vec::new();
        for t in &desc.texture_maps {
            if let TextureSource::Shader { path, code, params } = &t.source {
                scripts.push((format!("texture {}", t.id), path, code, params));
            }
        }
        for v in &desc.volumes {
            if let Some(s) = &v.script {
                scripts.push((format!("volume {}", v.id), &s.path, &s.code, &s.params));
            }
        }
        let mut files: Vec<ShaderFile> = Vec::new();
        let mut listed = BTreeSet::new();
        for (_, path, _, _) in &scripts {
            let path = super::files::watched_name(path);
            if listed.insert(path.clone()) {
                files.push(ShaderFile { name: name_of(&path), path, module: false });
            }
        }
        let dirs = desc.module_search_path();
        // Compiled without the lock: a script's top level may take up to `timeout`.
        let cached: Vec<_> = {
            let inner = self.lock();
            scripts
                .iter()
                .map(|(_, p, c, _)| inner.declared.get(&(p.to_path_buf(), c.to_string())).cloned())
                .collect()
        };
        let found: Vec<_> = scripts
            .iter()
            .zip(cached)
            .map(|((_, p, c, _), known)| known.unwrap_or_else(|| declare(p, c, timeout, dirs.clone())))
            .collect();
        let mut inner = self.lock();
        let mut uses = Vec::new();
        for ((id, path, code, params), declared) in scripts.into_iter().zip(found) {
            inner.declared.insert((path.to_path_buf(), code.to_string()), declared.clone());
            let declared = declared
                .or_else(|| inner.uses.iter().find(|u| u.id == id).map(|u| u.declared.clone()))
                .unwrap_or_default();
            let file = name_of(&super::files::watched_name(path));
            uses.push(ShaderUse { id, file, scene: params.to_vec(), declared });
        }
        // Only the current versions are kept.
        let current: BTreeSet<(&Path, &str)> = desc
            .texture_maps
            .iter()
            .filter_map(|t| match &t.source {
                TextureSource::Shader { path, code, .. } => Some((path.as_path(), code.as_str())),
                _ => None,
            })
            .chain(
                desc.volumes
                    .iter()
                    .filter_map(|v| v.script.as_ref().map(|s| (s.path.as_path(), s.code.as_str()))),
            )
            .collect();
        inner.declared.retain(|(p, c), _| current.contains(&(p.as_path(), c.as_str())));
        let modules = inner.files.iter().filter(|f| f.module).cloned();
        let files: Vec<ShaderFile> = files.into_iter().chain(modules).collect();
        if inner.files != files || inner.uses != uses {
            inner.files = files;
            inner.uses = uses;
            inner.seq += 1;
        }
        inner.root = root;
        inner.scene = scene;
        drop(inner);
        self.modules(watched);
    }

    /// Lists the modules among `watched` (the files the loads read: the
    /// `.lua` ones that are neither a script of the scene nor the scene).
    pub fn modules(&self, watched: &BTreeSet<PathBuf>) {
        let mut inner = self.lock();
        let mut files: Vec<ShaderFile> = inner.files.iter().filter(|f| !f.module).cloned().collect();
        for path in watched.iter().filter(|p| p.extension().is_some_and(|e| e == "lua")) {
            if *path != inner.scene && !files.iter().any(|f| f.path == *path) {
                files.push(ShaderFile { name: name_in(&inner.root, path), path: path.clone(), module: true });
            }
        }
        if inner.files != files {
            inner.files = files;
            inner.seq += 1;
        }
    }

    /// Gives `desc`'s scripts the session's overrides of parameters they
    /// declare (an override of a parameter the script no longer declares,
    /// or with another kind, waits unused).
    pub fn apply(&self, desc: &mut Description) {
        let inner = self.lock();
        if inner.overrides.is_empty() {
            return;
        }
        let set = |id: String, params: &mut Vec<(String, ParamValue)>| {
            let Some(u) = inner.uses.iter().find(|u| u.id == id) else { return };
            for ((oid, name), value) in &inner.overrides {
                let declared = u.declared.iter().any(|d| &d.name == name && fits(d.kind, value));
                if *oid != id || !declared {
                    continue;
                }
                params.retain(|(n, _)| n != name);
                params.push((name.clone(), value.clone()));
            }
        };
        for t in &mut desc.texture_maps {
            if let TextureSource::Shader { params, .. } = &mut t.source {
                set(format!("texture {}", t.id), params);
            }
        }
        for v in &mut desc.volumes {
            if let Some(s) = &mut v.script {
                set(format!("volume {}", v.id), &mut s.params);
            }
        }
    }

    /// The file named `name` in the list, if it is one.
    fn file(&self, name: &str) -> Option<ShaderFile> {
        self.lock().files.iter().find(|f| f.name == name).cloned()
    }

    /// The text of the listed file `name`.
    pub fn read(&self, name: &str) -> Result<String, Refused> {
        let f = self.file(name).ok_or_else(|| refused(404, "no shader file of the scene has that name"))?;
        luster_core::file::read_text(&f.path, MAX_SAVE as u64)
            .map_err(|why| refused(409, format!("cannot read {}: {why}", shown(&f.name))))
    }

    /// Saves `text` as the listed file `name`: a temporary file in the same
    /// folder, renamed over it (a symbolic link's target is replaced, the
    /// link kept), with the old file's permissions.
    pub fn save(&self, name: &str, text: &[u8]) -> Result<(), Refused> {
        let f = self.file(name).ok_or_else(|| refused(404, "no shader file of the scene has that name"))?;
        if text.len() > MAX_SAVE {
            return Err(refused(413, format!("a shader file may have at most {} MiB", MAX_SAVE >> 20)));
        }
        if let Err(e) = std::str::from_utf8(text) {
            let line = text[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
            return Err(refused(400, format!("the text is not UTF-8 (line {line})")));
        }
        let target = std::fs::canonicalize(&f.path).unwrap_or_else(|_| f.path.clone());
        let fail = |e: std::io::Error| {
            refused(409, format!("cannot save {}: {}", shown(&f.name), luster_core::file::io_reason(&e)))
        };
        let dir = target.parent().ok_or_else(|| refused(409, "the file has no folder"))?;
        let mut tmp =
            tempfile::Builder::new().prefix(".luster-save-").suffix(".tmp").tempfile_in(dir).map_err(fail)?;
        tmp.write_all(text).map_err(fail)?;
        tmp.as_file().sync_all().map_err(fail)?;
        if let Ok(meta) = std::fs::metadata(&target) {
            tmp.as_file().set_permissions(meta.permissions()).map_err(fail)?;
        }
        tmp.persist(&target).map_err(|e| fail(e.error))?;
        // Through a link the watch sees no change in the scene's folder.
        if target != f.path {
            (self.poke)();
        }
        Ok(())
    }

    /// Overrides parameter `name` of use `id` with the JSON `value` (a
    /// number, or three numbers for an rgb or vec3 parameter; `null`
    /// removes the override), and re-renders.
    pub fn set(&self, id: &str, name: &str, value: &serde_json::Value) -> Result<(), Refused> {
        let mut inner = self.lock();
        let u =
            inner.uses.iter().find(|u| u.id == id).ok_or_else(|| refused(404, "no shader has that id"))?;
        let d = u
            .declared
            .iter()
            .find(|d| d.name == name)
            .ok_or_else(|| refused(404, "the script declares no parameter of that name in params{}"))?;
        let key = (id.to_string(), name.to_string());
        if value.is_null() {
            inner.overrides.remove(&key);
        } else {
            let v = param_value(d.kind, value)
                .ok_or_else(|| refused(400, format!("{}: expected {}", shown(name), expected(d.kind))))?;
            inner.overrides.insert(key, v);
        }
        inner.seq += 1;
        drop(inner);
        (self.poke)();
        Ok(())
    }

    /// Removes every override and re-renders.
    pub fn reset(&self) {
        let mut inner = self.lock();
        inner.overrides.clear();
        inner.seq += 1;
        drop(inner);
        (self.poke)();
    }

    /// Where in the listed files `error` points: the file's name and the
    /// line of the first `file:line` it mentions.
    pub fn locate(&self, error: &str) -> Option<(String, u32)> {
        let inner = self.lock();
        let mut best: Option<(usize, usize, String, u32)> = None;
        for f in &inner.files {
            let spellings = [f.path.display().to_string(), f.name.clone()];
            for s in spellings.iter().filter(|s| !s.is_empty()) {
                for (at, _) in error.match_indices(s.as_str()) {
                    let before = error[..at].chars().next_back();
                    if before.is_some_and(|c| !(c.is_whitespace() || c == '/' || c == '"' || c == '\'')) {
                        continue;
                    }
                    let rest = &error[at + s.len()..];
                    let Some(digits) = rest.strip_prefix(':') else { continue };
                    let n: String = digits.chars().take_while(char::is_ascii_digit).collect();
                    let Ok(line) = n.parse::<u32>() else { continue };
                    let better = best.as_ref().is_none_or(|b| at < b.0 || (at == b.0 && s.len() > b.1));
                    if better {
                        best = Some((at, s.len(), f.name.clone(), line));
                    }
                }
            }
        }
        best.map(|(_, _, file, line)| (file, line))
    }

    /// What the page shows: the files, and each use's parameters with
    /// their kinds, defaults, the scene's values, overrides and slider ranges.
    pub fn to_json(&self) -> String {
        let inner = self.lock();
        let files: Vec<_> = inner
            .files
            .iter()
            .map(|f| serde_json::json!({ "name": f.name, "label": shown(&f.name), "module": f.module }))
            .collect();
        let uses: Vec<_> = inner
            .uses
            .iter()
            .map(|u| {
                let params: Vec<_> = u
                    .declared
                    .iter()
                    .map(|d| {
                        let scene = u.scene.iter().find(|(n, _)| *n == d.name).map(|(_, v)| v);
                        let over = inner.overrides.get(&(u.id.clone(), d.name.clone()));
                        let base = scene.unwrap_or(&d.default);
                        let (min, max) = d.range.unwrap_or_else(|| default_range(base));
                        serde_json::json!({
                            "name": d.name,
                            "kind": d.kind.name(),
                            "default": json_value(&d.default),
                            "scene": scene.map(json_value),
                            "value": json_value(over.unwrap_or(base)),
                            "overridden": over.is_some(),
                            "min": min,
                            "max": max,
                            "ranged": d.range.is_some(),
                        })
                    })
                    .collect();
                serde_json::json!({ "id": u.id, "file": u.file, "params": params })
            })
            .collect();
        let overridden = !inner.overrides.is_empty();
        serde_json::json!({ "seq": inner.seq, "files": files, "shaders": uses, "overridden": overridden })
            .to_string()
    }
}

/// What a script declares, or `None` when it does not compile.
fn declare(path: &Path, code: &str, timeout: Duration, dirs: Vec<PathBuf>) -> Option<Vec<DeclaredParam>> {
    let name =
        path.file_stem().map_or_else(|| path.display().to_string(), |s| s.to_string_lossy().into_owned());
    let src = ShaderSource::new(name, path, code);
    ShaderSet::with_modules(vec![src], timeout, None, dirs).ok().map(|s| s.declared(0).to_vec())
}

/// The slider range of a number without `range()`: 0 to 1, widened to
/// twice the value (and to its negative side) when it lies outside.
pub fn default_range(v: &ParamValue) -> (f64, f64) {
    let x = match v {
        ParamValue::Number(x) => *x,
        ParamValue::Vec3(v) => v.iter().copied().fold(0.0, |a: f64, b| if b.abs() > a.abs() { b } else { a }),
        ParamValue::Text(_) => 0.0,
    };
    ((2.0 * x).min(0.0), (2.0 * x).max(1.0))
}

fn fits(kind: ParamKind, v: &ParamValue) -> bool {
    matches!(
        (kind, v),
        (ParamKind::Number, ParamValue::Number(_)) | (ParamKind::Rgb | ParamKind::Vec3, ParamValue::Vec3(_))
    )
}

fn expected(kind: ParamKind) -> &'static str {
    match kind {
        ParamKind::Number => "a finite number",
        ParamKind::Rgb | ParamKind::Vec3 => "three finite numbers",
        ParamKind::Text | ParamKind::Image => "no override (text and image parameters have no control)",
    }
}

/// The page's JSON value as a parameter of `kind`, when it is one.
fn param_value(kind: ParamKind, v: &serde_json::Value) -> Option<ParamValue> {
    let finite = |v: &serde_json::Value| v.as_f64().filter(|x| x.is_finite());
    match kind {
        ParamKind::Number => finite(v).map(ParamValue::Number),
        ParamKind::Rgb | ParamKind::Vec3 => {
            let a = v.as_array().filter(|a| a.len() == 3)?;
            Some(ParamValue::Vec3([finite(&a[0])?, finite(&a[1])?, finite(&a[2])?]))
        }
        ParamKind::Text | ParamKind::Image => None,
    }
}

fn json_value(v: &ParamValue) -> serde_json::Value {
    match v {
        ParamValue::Number(x) => serde_json::json!(x),
        ParamValue::Vec3(v) => serde_json::json!(v),
        ParamValue::Text(s) => serde_json::json!(s),
    }
}

/// `path`'s name in the editor: relative to the scene's folder `root` when
/// inside it, else the whole path.
fn name_in(root: &Path, path: &Path) -> String {
    match path.strip_prefix(root) {
        Ok(rel) => rel.display().to_string(),
        Err(_) => path.display().to_string(),
    }
}

fn shown(s: &str) -> String {
    luster_core::text::shown(s, false).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_slider_range_holds_the_value() {
        assert_eq!(default_range(&ParamValue::Number(0.3)), (0.0, 1.0));
        assert_eq!(default_range(&ParamValue::Number(4.0)), (0.0, 8.0));
        assert_eq!(default_range(&ParamValue::Number(-3.0)), (-6.0, 1.0));
        assert_eq!(default_range(&ParamValue::Vec3([0.2, -5.0, 1.0])), (-10.0, 1.0));
    }

    #[test]
    fn values_must_fit_the_declared_kind() {
        use serde_json::json;
        assert_eq!(param_value(ParamKind::Number, &json!(2.5)), Some(ParamValue::Number(2.5)));
        assert_eq!(param_value(ParamKind::Rgb, &json!([1, 0.5, 0])), Some(ParamValue::Vec3([1.0, 0.5, 0.0])));
        for (kind, bad) in [
            (ParamKind::Number, json!("2")),
            (ParamKind::Number, json!([1, 2, 3])),
            (ParamKind::Rgb, json!([1, 2])),
            (ParamKind::Vec3, json!([1, "a", 3])),
            (ParamKind::Text, json!("x")),
        ] {
            assert_eq!(param_value(kind, &bad), None, "{kind:?} {bad}");
        }
    }

    #[test]
    fn an_error_is_located_at_the_first_file_line_it_names() {
        let e = Editor::new(|| {});
        e.lock().files = vec![
            ShaderFile { name: "c.lua".into(), path: "/s/c.lua".into(), module: false },
            ShaderFile { name: "lib/c.lua".into(), path: "/s/lib/c.lua".into(), module: true },
        ];
        let at = |s: &str| e.locate(s);
        assert_eq!(at("s.xml: /s/lib/c.lua:7: boom (from /s/c.lua:2)"), Some(("lib/c.lua".into(), 7)));
        assert_eq!(at("s.xml: /s/c.lua:12: unexpected symbol"), Some(("c.lua".into(), 12)));
        assert_eq!(at("s.xml: c.lua:3: x"), Some(("c.lua".into(), 3)));
        assert_eq!(at("s.xml: abc.lua:3: x"), None, "another file whose name ends alike");
        assert_eq!(at("s.xml: /s/c.lua: no entry point"), None, "no line");
    }
}
