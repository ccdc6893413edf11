//! Malformed glTF files through `luster render`: each is one line on
//! stderr naming the file and the GLB part or JSON path at fault, exit code
//! 2, no panic, no output image, within seconds; the file claiming 10⁸
//! vertices runs under a 2 GiB address-space limit, so an allocation sized
//! by the claim would abort instead of failing politely.

use crate::common::{run_limited, Run};
use crate::gltf::Gltf;
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;
use std::time::Duration;

const TIMEOUT: Duration = Duration::from_secs(60);

/// Renders `name` in `dir` (tiny: 8×8, 1 spp), under `limit` bytes of
/// address space when given.
fn render(dir: &Path, name: &str, limit: Option<u64>) -> Run {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_luster"));
    cmd.args(["render", "-q", "--threads", "2", "--spp", "1", "--size", "8x8", "-o", "out", name])
        .current_dir(dir);
    if let Some(bytes) = limit {
        use std::os::unix::process::CommandExt;
        // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
        unsafe {
            cmd.pre_exec(move || {
                let l = libc::rlimit { rlim_cur: bytes, rlim_max: bytes };
                if libc::setrlimit(libc::RLIMIT_AS, &l) == 0 {
                    Ok(())
                } else {
                    Err(std::io::Error::last_os_error())
                }
            });
        }
    }
    run_limited(cmd, TIMEOUT)
}

/// Asserts the one-line refusal naming `name` and every one of `words`.
fn refused(dir: &Path, name: &str, words: &[&str], limit: Option<u64>) {
    let run = render(dir, name, limit);
    let err = run.stderr.trim_end();
    assert_eq!(run.code, Some(2), "{name}: stderr: {err}");
    assert_eq!(err.lines().count(), 1, "{name}: one line expected: {err}");
    assert!(err.starts_with("error: ") && err.contains(name), "{name}: the error names no file: {err}");
    for w in words {
        assert!(err.contains(w), "{name}: the error lacks {w:?}: {err}");
    }
    for crash in ["panicked", "RUST_BACKTRACE", "memory allocation", "Aborted"] {
        assert!(!err.contains(crash), "{name}: crashed: {err}");
    }
    let out = dir.join("out");
    assert!(std::fs::read_dir(&out).map_or(true, |mut d| d.next().is_none()), "{name}: an image was written");
}

/// A valid triangle scene: the builder and the rest of its JSON.
fn triangle() -> (Gltf, Value) {
    let mut g = Gltf::default();
    let mesh = g.mesh(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0], &[0, 1, 2]);
    (g, json!({"scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}], "meshes": [mesh]}))
}

fn write_doc(dir: &Path, name: &str, doc: &Value) {
    std::fs::write(dir.join(name), serde_json::to_vec(doc).expect("JSON")).expect("the file");
}

#[test]
fn truncated_and_lying_glb_files_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (g, rest) = triangle();
    let glb = g.glb(rest);
    std::fs::write(dir.path().join("header.glb"), &glb[..7]).expect("file");
    refused(dir.path(), "header.glb", &["GLB header", "cut short"], None);
    // Cut inside the BIN chunk, the header's length mended: the chunk is short.
    let mut cut = glb[..glb.len() - 6].to_vec();
    let n = cut.len() as u32;
    cut[8..12].copy_from_slice(&n.to_le_bytes());
    std::fs::write(dir.path().join("chunk.glb"), &cut).expect("file");
    refused(dir.path(), "chunk.glb", &["GLB chunk 1", "cut short"], None);
    // Cut without mending: the header's length is wrong.
    std::fs::write(dir.path().join("cut.glb"), &glb[..glb.len() - 6]).expect("file");
    refused(dir.path(), "cut.glb", &["GLB header", "length"], None);
    // The JSON chunk claims more than the file holds.
    let mut lying = glb.clone();
    lying[12..16].copy_from_slice(&1_000_000u32.to_le_bytes());
    std::fs::write(dir.path().join("json.glb"), &lying).expect("file");
    refused(dir.path(), "json.glb", &["GLB chunk 0", "claims 1000000 bytes"], None);
}

#[test]
fn bad_references_and_ranges_name_their_json_path() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (g, rest) = triangle();
    let good = g.document(rest.clone(), None);

    let mut doc = good.clone();
    doc["bufferViews"][0]["buffer"] = json!(5);
    write_doc(dir.path(), "buffer_index.gltf", &doc);
    refused(dir.path(), "buffer_index.gltf", &["bufferViews[0].buffer", "out of range"], None);

    let mut doc = good.clone();
    doc["accessors"][0]["count"] = json!(4);
    write_doc(dir.path(), "past.gltf", &doc);
    refused(dir.path(), "past.gltf", &["accessors[0]", "past the end of bufferViews[0]"], None);

    let mut doc = good.clone();
    doc["bufferViews"][0]["byteLength"] = json!(4000);
    write_doc(dir.path(), "view.gltf", &doc);
    refused(dir.path(), "view.gltf", &["bufferViews[0]", "past the end of buffers[0]"], None);

    let mut doc = good.clone();
    doc["buffers"][0]["uri"] = json!("data:application/octet-stream,AAAA");
    write_doc(dir.path(), "data.gltf", &doc);
    refused(dir.path(), "data.gltf", &["buffers[0].uri", "not base64"], None);

    let mut doc = good.clone();
    doc["buffers"][0]["uri"] = json!("missing.bin");
    write_doc(dir.path(), "nobin.gltf", &doc);
    refused(dir.path(), "nobin.gltf", &["buffers[0].uri", "\"missing.bin\"", "no such file"], None);

    let mut doc = good.clone();
    doc["buffers"][0]["byteLength"] = json!(1000);
    write_doc(dir.path(), "short.gltf", &doc);
    refused(dir.path(), "short.gltf", &["buffers[0]", "byteLength is 1000"], None);

    let mut doc = good.clone();
    doc["images"] = json!([{"uri": "missing.png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    write_doc(dir.path(), "texture.gltf", &doc);
    refused(dir.path(), "texture.gltf", &["images[0]", "\"missing.png\"", "no such file"], None);

    let mut doc = good.clone();
    let (mut g2, _) = triangle();
    g2.indices(&[0, 1, 7]);
    doc["bufferViews"] = Value::Array(g2.views.clone());
    doc["accessors"] = Value::Array(g2.accessors.clone());
    doc["buffers"] = g2.document(json!({}), None)["buffers"].clone();
    doc["meshes"][0]["primitives"][0]["indices"] = json!(2);
    write_doc(dir.path(), "index.gltf", &doc);
    refused(dir.path(), "index.gltf", &["accessors[2]", "index 7 is out of range of the 3 vertices"], None);
}

#[test]
fn broken_node_graphs_and_transforms_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (g, rest) = triangle();
    let good = g.document(rest, None);

    let mut doc = good.clone();
    doc["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [1]}]);
    write_doc(dir.path(), "cycle.gltf", &doc);
    refused(dir.path(), "cycle.gltf", &["nodes[", "children"], None);

    let mut doc = good.clone();
    doc["nodes"] =
        json!([{"mesh": 0, "children": [1]}, {"children": [2]}, {"children": [3]}, {"children": [1]}]);
    doc["scenes"] = json!([{"nodes": [0]}]);
    write_doc(dir.path(), "loop.gltf", &doc);
    refused(dir.path(), "loop.gltf", &["nodes[", "parent"], None);

    // A cycle with no second parent anywhere: 1 → 2 → 1, the scene naming 0.
    let mut doc = good.clone();
    doc["nodes"] = json!([{"mesh": 0}, {"children": [2]}, {"children": [1]}]);
    write_doc(dir.path(), "ring.gltf", &doc);
    refused(dir.path(), "ring.gltf", &["its own ancestor"], None);

    let mut doc = good.clone();
    doc["nodes"][0]["matrix"] = json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 1e39, 0, 0, 1]);
    write_doc(dir.path(), "matrix.gltf", &doc);
    refused(dir.path(), "matrix.gltf", &["nodes[0].matrix", "not finite"], None);

    let mut doc = good.clone();
    doc["nodes"][0]["translation"] = json!([0, -1e39, 0]);
    write_doc(dir.path(), "trs.gltf", &doc);
    refused(dir.path(), "trs.gltf", &["nodes[0].translation", "not finite"], None);
}

#[test]
fn invalid_json_and_huge_claims_are_refused() {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("json.gltf"), "{\"asset\": {\"version\": \"2.0\"},\n \"nodes\": [")
        .expect("file");
    refused(dir.path(), "json.gltf", &["line 2", "JSON ends early"], None);
    std::fs::write(dir.path().join("junk.gltf"), "{\"asset\": {\"version\": \"2.0\"}, ]").expect("file");
    refused(dir.path(), "junk.gltf", &["line 1", "malformed"], None);
    // 10⁸ vertices claimed over 36 bytes, with and without a buffer view.
    let (g, rest) = triangle();
    let mut doc = g.document(rest, None);
    doc["accessors"][0]["count"] = json!(100_000_000u64);
    write_doc(dir.path(), "huge.gltf", &doc);
    refused(dir.path(), "huge.gltf", &["accessors[0]", "100000000 elements"], Some(2 << 30));
    // Without a buffer view (zeros, a sparse value over them).
    doc["accessors"][0].as_object_mut().expect("an object").remove("bufferView");
    doc["accessors"][0]["sparse"] =
        json!({"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}});
    write_doc(dir.path(), "zeros.gltf", &doc);
    refused(
        dir.path(),
        "zeros.gltf",
        &["accessors[0]", "100000000 elements without a buffer view"],
        Some(2 << 30),
    );
}
