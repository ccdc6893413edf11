//! The watch page's shader editor, through its HTTP endpoints: the scene's
//! scripts and the modules they require are listed, read and saved (a save
//! re-renders with the new text); paths outside that list, oversized or
//! non-UTF-8 bodies and other methods are refused with nothing written; a
//! `params{}` override re-renders with the new value until a reset; a
//! shader error carries its file and line for the editor's mark.

use crate::common::folder;
use crate::watch::{
    dominant, events, exchange, finished, frame, get, save, scene, shader, start_with, status, until, WAIT,
};
use std::path::Path;

/// POST `body` to `path`: the status and the answer's body.
fn post(addr: &str, path: &str, body: &[u8]) -> (u16, String) {
    let mut request = format!(
        "POST {path} HTTP/1.1\r\nHost: {addr}\r\nOrigin: http://{addr}\r\nContent-Length: {}\r\n\
         Connection: close\r\n\r\n",
        body.len()
    )
    .into_bytes();
    request.extend_from_slice(body);
    let answer = exchange(addr, &request, WAIT).unwrap_or_else(|e| panic!("POST {path}: {e}"));
    let code = status(&answer).unwrap_or_else(|| panic!("POST {path}: no status"));
    let at = answer.windows(4).position(|w| w == b"\r\n\r\n").map_or(answer.len(), |i| i + 4);
    (code, String::from_utf8_lossy(&answer[at..]).into_owned())
}

fn shaders(addr: &str) -> serde_json::Value {
    let (code, _, body) = get(addr, "/shaders");
    assert_eq!(code, 200);
    serde_json::from_slice(&body).expect("/shaders is JSON")
}

fn names(list: &serde_json::Value) -> Vec<(String, bool)> {
    let files = list["files"].as_array().expect("a file list");
    files.iter().map(|f| (f["name"].as_str().unwrap().to_string(), f["module"] == true)).collect()
}

/// The folder's file names, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn the_scenes_shader_files_are_listed_read_and_saved_and_nothing_else() {
    let user = "local lib = require \"lib\"\nfunction color(s)\n  return vec3(lib.r, lib.g, lib.b)\nend\n";
    let other = shader(0.0, 0.0, 1.0);
    let dir = folder(&[
        ("s.xml", &scene("c.lua")),
        ("c.lua", user),
        ("lib.lua", "return { r = 1, g = 0, b = 0 }\n"),
        ("other.lua", &other),
    ]);
    let w = start_with(dir.path(), "s.xml", &[]);
    let rx = events(&w.addr);
    until(&rx, "a first frame", finished);
    let (n1, red, _) = frame(&w.addr);
    assert!(dominant(red, 0), "red from the module: {red:?}");
    // Modules are known once the shaders have run: by the end of the render.
    let list = shaders(&w.addr);
    assert_eq!(
        names(&list),
        [("c.lua".to_string(), false), ("lib.lua".to_string(), true)],
        "the script and the module it requires; not other.lua nor the scene"
    );
    let (code, _, text) = get(&w.addr, "/shader/c.lua");
    assert_eq!((code, text.as_slice()), (200, user.as_bytes()));

    // Saving the module re-renders with its new text.
    let (code, why) = post(&w.addr, "/shader/lib.lua", b"return { r = 0, g = 1, b = 0 }\n");
    assert_eq!(code, 200, "{why}");
    assert_eq!(
        std::fs::read_to_string(dir.path().join("lib.lua")).unwrap(),
        "return { r = 0, g = 1, b = 0 }\n"
    );
    until(&rx, "a frame after the save", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (n2, green, _) = frame(&w.addr);
    assert!(dominant(green, 1), "green after saving from the page: {green:?}");

    // Nothing else is read or written.
    let before = listing(dir.path());
    let green_script = shader(0.0, 1.0, 0.0);
    for name in
        ["other.lua", "s.xml", "..%2Fx.lua", "%2Ftmp%2Fluster-editor-test.lua", "sub%2Fc.lua", "C.lua"]
    {
        let (code, _) = post(&w.addr, &format!("/shader/{name}"), green_script.as_bytes());
        assert_eq!(code, 404, "POST /shader/{name}");
        assert_eq!(get(&w.addr, &format!("/shader/{name}")).0, 404, "GET /shader/{name}");
    }
    assert_eq!(post(&w.addr, "/shader/%zz", b"x").0, 400, "a bad escape");
    assert_eq!(post(&w.addr, "/shader/c.lua", b"function color(s) return vec3(1) end -- \xff\n").0, 400);
    let big = format!(
        "POST /shader/c.lua HTTP/1.1\r\nHost: {0}\r\nContent-Length: {1}\r\n\r\n",
        w.addr,
        (4 << 20) + 1
    );
    assert_eq!(status(&exchange(&w.addr, big.as_bytes(), WAIT).unwrap()), Some(413), "an oversized body");
    for (method, path) in
        [("PUT", "/shader/c.lua"), ("DELETE", "/shader/c.lua"), ("GET", "/params"), ("POST", "/shaders")]
    {
        let req = format!(
            "{method} {path} HTTP/1.1\r\nHost: {}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
            w.addr
        );
        assert_eq!(status(&exchange(&w.addr, req.as_bytes(), WAIT).unwrap()), Some(405), "{method} {path}");
    }
    assert_eq!(std::fs::read_to_string(dir.path().join("c.lua")).unwrap(), user, "c.lua untouched");
    assert_eq!(std::fs::read_to_string(dir.path().join("other.lua")).unwrap(), other, "other.lua untouched");
    assert!(!Path::new("/tmp/luster-editor-test.lua").exists());
    assert_eq!(listing(dir.path()), before, "no file created, no temporary file left");
    let (n3, _, _) = frame(&w.addr);
    assert_eq!(n3, n2, "no refused request re-rendered");
}

#[test]
fn a_shader_error_carries_the_file_and_line_the_editor_marks() {
    let user = "local lib = require \"lib\"\nfunction color(s)\n  return vec3(lib.r, lib.g, lib.b)\nend\n";
    let dir = folder(&[
        ("s.xml", &scene("c.lua")),
        ("c.lua", user),
        ("lib.lua", "return { r = 1, g = 0, b = 0 }\n"),
    ]);
    let w = start_with(dir.path(), "s.xml", &[]);
    let rx = events(&w.addr);
    let s = until(&rx, "a first frame", finished);
    assert_eq!(s["error_at"], serde_json::Value::Null);

    let (code, _) = post(
        &w.addr,
        "/shader/c.lua",
        b"local lib = require \"lib\"\nfunction color(s)\n  return vec3(1, 0\nend\n",
    );
    assert_eq!(code, 200);
    let bad = until(&rx, "the syntax error", |s| s["error"].is_string() && s["busy"] == false);
    assert_eq!(bad["error_at"], serde_json::json!({ "file": "c.lua", "line": 4 }), "{}", bad["error"]);

    save(&dir.path().join("c.lua"), user);
    save(&dir.path().join("lib.lua"), "local t = { r = 1 }\nreturn t.x.y\n");
    let bad = until(&rx, "the module's error", |s| {
        s["error"].as_str().is_some_and(|e| e.contains("lib.lua")) && s["busy"] == false
    });
    assert_eq!(bad["error_at"], serde_json::json!({ "file": "lib.lua", "line": 2 }), "{}", bad["error"]);

    save(&dir.path().join("lib.lua"), "return { r = 0, g = 0, b = 1 }\n");
    let fixed = until(&rx, "a recovered frame", |s| finished(s) && s["error"].is_null());
    assert_eq!(fixed["error_at"], serde_json::Value::Null, "the mark is cleared");
}

/// A sphere whose colour is `tint * gain`, declared with params{}; the
/// scene gives the tint.
fn tinted() -> (String, String) {
    let script = "params{ tint = rgb(0, 0, 1), gain = range(1, 0, 2), label = 'x' }\n\
                  function color(s)\n  return param.tint * param.gain\nend\n";
    let xml = scene("t.lua").replace(
        "<DecalMode>replace_kd</DecalMode>",
        "<DecalMode>replace_kd</DecalMode><Parameter name=\"tint\">1 0 0</Parameter>",
    );
    (xml, script.to_string())
}

#[test]
fn a_parameter_override_rerenders_with_the_new_value_and_a_reset_restores_the_scenes() {
    let (xml, script) = tinted();
    let dir = folder(&[("s.xml", &xml), ("t.lua", &script)]);
    let w = start_with(dir.path(), "s.xml", &[]);
    let rx = events(&w.addr);
    until(&rx, "a first frame", finished);
    let (n1, red, _) = frame(&w.addr);
    assert!(dominant(red, 0), "the scene's red tint: {red:?}");

    let list = shaders(&w.addr);
    let shader = &list["shaders"][0];
    assert_eq!(shader["id"], "texture 1");
    assert_eq!(shader["file"], "t.lua");
    let param = |list: &serde_json::Value, name: &str| {
        let params = list["shaders"][0]["params"].as_array().unwrap().clone();
        params.into_iter().find(|p| p["name"] == name).unwrap_or_else(|| panic!("no {name} in {list}"))
    };
    let tint = param(&list, "tint");
    assert_eq!(
        (&tint["kind"], &tint["default"], &tint["scene"]),
        (&"rgb".into(), &serde_json::json!([0.0, 0.0, 1.0]), &serde_json::json!([1.0, 0.0, 0.0]))
    );
    assert_eq!((&tint["value"], &tint["overridden"]), (&serde_json::json!([1.0, 0.0, 0.0]), &false.into()));
    let gain = param(&list, "gain");
    assert_eq!(
        (&gain["kind"], &gain["min"], &gain["max"], &gain["ranged"]),
        (&"number".into(), &0.0.into(), &2.0.into(), &true.into())
    );

    let set = |body: serde_json::Value| post(&w.addr, "/params", body.to_string().as_bytes());
    let (code, why) = set(serde_json::json!({ "shader": "texture 1", "name": "tint", "value": [0, 1, 0] }));
    assert_eq!(code, 200, "{why}");
    until(&rx, "a frame with the override", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (n2, green, _) = frame(&w.addr);
    assert!(dominant(green, 1), "the overriding green: {green:?}");
    let tint = param(&shaders(&w.addr), "tint");
    assert_eq!((&tint["value"], &tint["overridden"]), (&serde_json::json!([0.0, 1.0, 0.0]), &true.into()));
    assert_eq!(
        std::fs::read_to_string(dir.path().join("t.lua")).unwrap(),
        script,
        "the script is not written"
    );

    // A second, numeric override multiplies in; bad ones change nothing.
    let (code, _) = set(serde_json::json!({ "shader": "texture 1", "name": "gain", "value": 0.0 }));
    assert_eq!(code, 200);
    until(&rx, "a frame with gain 0", |s| finished(s) && s["frame"].as_u64() > Some(n2));
    let (n3, black, _) = frame(&w.addr);
    // Only the ambient term is left: 60 × AmbientReflectance 1, grey.
    assert!(black.iter().all(|&c| c <= 61) && !dominant(black, 1), "gain 0 darkens the sphere: {black:?}");
    for (body, want) in [
        (serde_json::json!({ "shader": "texture 1", "name": "nope", "value": 1 }), 404),
        (serde_json::json!({ "shader": "texture 9", "name": "gain", "value": 1 }), 404),
        (serde_json::json!({ "shader": "texture 1", "name": "gain", "value": [1, 2, 3] }), 400),
        (serde_json::json!({ "shader": "texture 1", "name": "tint", "value": [1, 2] }), 400),
        (serde_json::json!({ "shader": "texture 1", "name": "label", "value": "y" }), 400),
        (serde_json::json!({ "name": "gain", "value": 1 }), 400),
    ] {
        assert_eq!(set(body.clone()).0, want, "{body}");
    }
    assert_eq!(post(&w.addr, "/params", b"{not json").0, 400);

    let (code, _) = post(&w.addr, "/params/reset", b"");
    assert_eq!(code, 200);
    until(&rx, "a frame after the reset", |s| finished(s) && s["frame"].as_u64() > Some(n3));
    let (_, again, _) = frame(&w.addr);
    assert!(dominant(again, 0), "the scene's red again: {again:?}");
    assert_eq!(param(&shaders(&w.addr), "tint")["overridden"], false);
}
