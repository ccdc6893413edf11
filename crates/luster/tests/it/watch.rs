//! `luster watch` end to end: the binary serves the page, streams its state
//! over Server-Sent Events and the newest frame as a PNG; saving the shader
//! re-renders, a syntax error is reported with the script's file:line while
//! the last good image stays, and fixing it recovers. A scene that does not
//! load at start still serves the page with the error. Hostile clients (a
//! huge or missing body, a foreign `Host` or `Origin`, hundreds of idle
//! connections, a head sent a byte a second) are refused or dropped without
//! delaying anyone else.

use crate::common;
use common::folder;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

/// Longest wait for any one state: generous for a loaded 2-core CI machine.
pub(crate) const WAIT: Duration = Duration::from_secs(30);

pub(crate) fn scene(shader: &str) -> String {
    format!(
        r#"<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 0 4</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
            <FovY>45</FovY><NearDistance>1</NearDistance>
            <ImageResolution>48 48</ImageResolution><ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>60 60 60</AmbientLight>
        <PointLight id="1"><Position>0 2 6</Position><Intensity>20000 20000 20000</Intensity></PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance><DiffuseReflectance>1 1 1</DiffuseReflectance>
            <SpecularReflectance>0 0 0</SpecularReflectance><PhongExponent>1</PhongExponent>
        </Material>
    </Materials>
    <Textures>
        <TextureMap id="1" type="shader"><Shader>{shader}</Shader><DecalMode>replace_kd</DecalMode></TextureMap>
    </Textures>
    <VertexData>0 0 0</VertexData>
    <Objects>
        <Sphere id="1"><Material>1</Material><Textures>1</Textures><Center>1</Center><Radius>1</Radius></Sphere>
    </Objects>
</Scene>"#
    )
}

/// Saves as editors do, writing a new file and renaming it over the old one:
/// the watch never reads a half-written file.
pub(crate) fn save(path: &std::path::Path, text: &str) {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).expect("a test file");
    std::fs::rename(&tmp, path).expect("a renamed test file");
}

pub(crate) fn shader(r: f32, g: f32, b: f32) -> String {
    format!("function color(s)\n  return vec3({r}, {g}, {b})\nend\n")
}

/// The running `luster watch`, killed when dropped.
pub(crate) struct Watch {
    child: Child,
    pub(crate) addr: String,
}

impl Drop for Watch {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(dir: &std::path::Path, scene: &str) -> Watch {
    start_with(dir, scene, &[])
}

pub(crate) fn start_with(dir: &std::path::Path, scene: &str, more: &[&str]) -> Watch {
    let mut child = Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["watch", scene, "--port", "0", "--threads", "2"])
        .args(more)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("luster watch starts");
    let mut line = String::new();
    BufReader::new(child.stdout.take().expect("stdout is piped")).read_line(&mut line).expect("a first line");
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap_or_else(|| panic!("the first line names the page: {line:?}"))
        .to_string();
    assert!(addr.starts_with("127.0.0.1:"), "bound to localhost only: {addr}");
    Watch { child, addr }
}

/// GET `path`: (status, headers, body).
pub(crate) fn get(addr: &str, path: &str) -> (u16, String, Vec<u8>) {
    get_within(addr, path, WAIT).unwrap_or_else(|e| panic!("GET {path}: {e}"))
}

/// GET `path` with the whole answer read within `limit`.
fn get_within(addr: &str, path: &str, limit: Duration) -> Result<(u16, String, Vec<u8>), String> {
    let request = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    let all = exchange(addr, request.as_bytes(), limit)?;
    let split = all.windows(4).position(|w| w == b"\r\n\r\n").ok_or("no end of headers")?;
    let head = String::from_utf8_lossy(&all[..split]).to_string();
    let status = head.split(' ').nth(1).and_then(|c| c.parse().ok()).ok_or("no status code")?;
    Ok((status, head, all[split + 4..].to_vec()))
}

/// Sends `request` on a new connection and reads until the server closes
/// it; an error when that takes longer than `limit`. A reset after the
/// server closed counts as closed.
pub(crate) fn exchange(addr: &str, request: &[u8], limit: Duration) -> Result<Vec<u8>, String> {
    let mut s = TcpStream::connect(addr).map_err(|e| format!("cannot connect: {e}"))?;
    s.set_read_timeout(Some(limit)).unwrap();
    let end = Instant::now() + limit;
    // The server may answer and close before reading a refused request whole.
    let _ = s.write_all(request);
    let mut all = Vec::new();
    let mut chunk = [0u8; 65536];
    loop {
        match s.read(&mut chunk) {
            Ok(0) => return Ok(all),
            Ok(n) => all.extend_from_slice(&chunk[..n]),
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => return Ok(all),
            Err(e) => return Err(format!("no whole answer within {limit:?} ({e}); got {} bytes", all.len())),
        }
        let left = end.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(format!("no whole answer within {limit:?}; got {} bytes", all.len()));
        }
        s.set_read_timeout(Some(left)).unwrap();
    }
}

/// The status code an answer starts with (`None`: the server closed without one).
pub(crate) fn status(answer: &[u8]) -> Option<u16> {
    let line = answer.split(|&b| b == b'\r').next()?;
    std::str::from_utf8(line).ok()?.strip_prefix("HTTP/1.1 ")?.get(..3)?.parse().ok()
}

/// The states of the `/events` stream, parsed, as they arrive.
pub(crate) fn events(addr: &str) -> Receiver<serde_json::Value> {
    let mut s = TcpStream::connect(addr).expect("the page server answers");
    write!(s, "GET /events HTTP/1.1\r\nHost: {addr}\r\nAccept: text/event-stream\r\n\r\n").unwrap();
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for line in BufReader::new(s).lines() {
            let Ok(line) = line else { return };
            if let Some(data) = line.strip_prefix("data: ") {
                let state = serde_json::from_str(data).expect("every event is JSON");
                if tx.send(state).is_err() {
                    return;
                }
            }
        }
    });
    rx
}

/// The first state for which `ok` holds.
pub(crate) fn until(
    rx: &Receiver<serde_json::Value>,
    what: &str,
    ok: impl Fn(&serde_json::Value) -> bool,
) -> serde_json::Value {
    let end = Instant::now() + WAIT;
    loop {
        let left = end.saturating_duration_since(Instant::now());
        match rx.recv_timeout(left) {
            Ok(s) if ok(&s) => return s,
            Ok(_) => {}
            Err(_) => panic!("no state with {what} within {WAIT:?}"),
        }
    }
}

/// The newest frame: its number and its centre pixel.
pub(crate) fn frame(addr: &str) -> (u64, [u8; 3], Vec<u8>) {
    let (status, head, body) = get(addr, "/frame.png");
    assert_eq!(status, 200, "{head}");
    let number = head
        .lines()
        .find_map(|l| l.strip_prefix("X-Luster-Frame: "))
        .and_then(|n| n.trim().parse().ok())
        .expect("the frame number header");
    let img = image::load_from_memory(&body).expect("the frame is a PNG").to_rgb8();
    let p = img.get_pixel(img.width() / 2, img.height() / 2).0;
    (number, p, body)
}

/// Whether channel `c` of `p` exceeds the other two by a wide margin.
pub(crate) fn dominant(p: [u8; 3], c: usize) -> bool {
    (0..3).all(|o| o == c || p[c] > p[o].saturating_add(100))
}

pub(crate) fn finished(s: &serde_json::Value) -> bool {
    s["busy"] == false && s["frame"].is_u64()
}

#[test]
fn shader_edits_rerender_errors_overlay_and_recover() {
    let dir = folder(&[("s.xml", &scene("c.lua")), ("c.lua", &shader(1.0, 0.0, 0.0))]);
    let w = start(dir.path(), "s.xml");
    let (status, _, page) = get(&w.addr, "/");
    let page = String::from_utf8_lossy(&page);
    assert_eq!(status, 200);
    assert!(page.contains("EventSource(\"/events\")") && !page.contains("://"), "a self-contained page");

    let rx = events(&w.addr);
    let first = until(&rx, "a first frame", finished);
    assert_eq!(first["error"], serde_json::Value::Null);
    let (n1, red, _) = frame(&w.addr);
    assert!(dominant(red, 0), "a red sphere: {red:?}");

    save(&dir.path().join("c.lua"), &shader(0.0, 1.0, 0.0));
    until(&rx, "a newer frame", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (n2, green, good) = frame(&w.addr);
    assert!(n2 > n1 && dominant(green, 1), "green after the save: {green:?}");

    save(&dir.path().join("c.lua"), "function color(s)\n  return vec3(0, 0, 1\nend\n");
    let bad = until(&rx, "an error", |s| s["error"].is_string());
    let msg = bad["error"].as_str().unwrap();
    assert!(msg.contains("c.lua:3") && msg.contains("s.xml"), "the error names file:line: {msg}");
    assert_eq!(bad["frame"].as_u64(), Some(n2), "the last good frame stays");
    let (n3, _, kept) = frame(&w.addr);
    assert_eq!((n3, &kept), (n2, &good), "the last good image is still served");

    save(&dir.path().join("c.lua"), &shader(0.0, 0.0, 1.0));
    let fixed = until(&rx, "a recovered frame", |s| finished(s) && s["frame"].as_u64() > Some(n2));
    assert_eq!(fixed["error"], serde_json::Value::Null, "the error is gone");
    let (_, blue, _) = frame(&w.addr);
    assert!(dominant(blue, 2), "blue after the fix: {blue:?}");
}

#[test]
fn a_scene_that_fails_at_start_serves_the_error_then_recovers() {
    let dir = folder(&[("s.xml", "<Scene><Cameras>")]);
    let w = start(dir.path(), "s.xml");
    let rx = events(&w.addr);
    let s = until(&rx, "the load error", |s| s["error"].is_string() && s["busy"] == false);
    assert!(s["error"].as_str().unwrap().contains("s.xml"), "{s}");
    assert_eq!(s["frame"], serde_json::Value::Null);
    assert_eq!(get(&w.addr, "/").0, 200, "the page is served anyway");
    assert_eq!(get(&w.addr, "/frame.png").0, 404, "no frame yet");

    save(&dir.path().join("c.lua"), &shader(1.0, 1.0, 0.0));
    save(&dir.path().join("s.xml"), &scene("c.lua"));
    let s = until(&rx, "a frame after the fix", finished);
    assert_eq!(s["error"], serde_json::Value::Null);
}

#[test]
fn the_watched_files_are_the_ones_the_scene_reads() {
    let xml = r#"<Scene>
    <Cameras><Camera id="1" type="lookAt"><Position>0 0 4</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
        <FovY>45</FovY><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution><ImageName>o.png</ImageName>
    </Camera></Cameras>
    <Materials><Material id="1"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>
    <Textures>
        <Images><Image id="1">img/stripes.png</Image></Images>
        <TextureMap id="1" type="image"><ImageId>1</ImageId><DecalMode>replace_kd</DecalMode></TextureMap>
        <TextureMap id="2" type="shader"><Shader>sh/c.lua</Shader><DecalMode>replace_ks</DecalMode></TextureMap>
    </Textures>
    <Objects><Mesh id="1"><Material>1</Material><Textures>1 2</Textures><Faces plyFile="m.ply"/></Mesh></Objects>
</Scene>"#;
    let dir = folder(&[("s.xml", xml), ("m.ply", ""), ("c.lua", "")]);
    for sub in ["img", "sh"] {
        std::fs::create_dir(dir.path().join(sub)).unwrap();
    }
    std::fs::write(dir.path().join("img/stripes.png"), "").unwrap();
    std::fs::write(dir.path().join("sh/c.lua"), shader(1.0, 1.0, 1.0)).unwrap();
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let files = luster::watch::files::scene_files(&desc);
    let root = dir.path().canonicalize().unwrap();
    let want: std::collections::BTreeSet<_> =
        ["s.xml", "m.ply", "img/stripes.png", "sh/c.lua"].iter().map(|f| root.join(f)).collect();
    assert_eq!(files, want, "the scene, its PLY, its image and its shader; not the unused c.lua");
}

#[test]
fn passes_are_shown_as_they_end_and_a_cancel_stops_the_render() {
    use luster::render::{render_progressive, try_render_with, Progress, RenderOptions, Scene};
    use std::sync::atomic::{AtomicBool, Ordering};
    let dir = folder(&[("s.xml", &scene("c.lua")), ("c.lua", &shader(0.2, 0.6, 0.9))]);
    let desc = luster::scene::load(&dir.path().join("s.xml")).expect("the scene loads");
    let scene = Scene::build(&desc).expect("the scene builds");
    let opts = RenderOptions { spp: Some(16), ..Default::default() };

    let cancel = AtomicBool::new(false);
    let mut seen = Vec::new();
    let mut last = None;
    let mut on_pass = |film: &luster::film::Film, spp: u32| {
        seen.push(spp);
        last = Some(film.clone());
    };
    let img = render_progressive(&scene, 0, &opts, Progress { cancel: &cancel, on_pass: &mut on_pass })
        .expect("no shader fails");
    assert_eq!(seen, [1, 2, 4, 6, 8, 10, 12, 14, 16], "passes of 1, 1, 2, 2, ... samples");
    let whole = try_render_with(&scene, 0, &opts, &|_| {}).expect("no shader fails");
    assert_eq!(img.film, whole.film, "the progressive render is the plain render");
    assert_eq!(last.as_ref(), Some(&whole.film), "the last pass shown is the finished image");

    let mut passes = 0;
    let mut stop_after_one = |_: &luster::film::Film, _: u32| {
        passes += 1;
        cancel.store(true, Ordering::SeqCst);
    };
    let img =
        render_progressive(&scene, 0, &opts, Progress { cancel: &cancel, on_pass: &mut stop_after_one })
            .expect("no shader fails");
    assert_eq!((passes, img.spp), (1, 1), "a cancel stops the render before the next pass");
}

#[test]
fn saving_a_required_module_rerenders() {
    let user = "local lib = require \"lib\"\nfunction color(s)\n  return vec3(lib.r, lib.g, lib.b)\nend\n";
    let lib = |r: u8, g: u8| format!("return {{ r = {r}, g = {g}, b = 0 }}\n");
    let dir = folder(&[("s.xml", &scene("c.lua")), ("c.lua", user), ("lib.lua", &lib(1, 0))]);
    let w = start(dir.path(), "s.xml");
    let rx = events(&w.addr);
    until(&rx, "a first frame", finished);
    let (n1, red, _) = frame(&w.addr);
    assert!(dominant(red, 0), "red from the module: {red:?}");

    save(&dir.path().join("lib.lua"), &lib(0, 1));
    until(&rx, "a frame after the module's save", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (_, green, _) = frame(&w.addr);
    assert!(dominant(green, 1), "green after saving the module: {green:?}");
}

/// A glowing ball (a volume whose script takes its colour from module
/// `glow`), baked on a grid, in front of a black background.
fn volume_scene() -> String {
    r#"<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras>
        <Camera id="1" type="lookAt">
            <Position>0 0 4</Position><GazePoint>0 0 0</GazePoint><Up>0 1 0</Up>
            <FovY>45</FovY><NearDistance>1</NearDistance>
            <ImageResolution>24 24</ImageResolution><ImageName>out.png</ImageName>
        </Camera>
    </Cameras>
    <Volumes>
        <Volume id="ball">
            <Sphere><Center>0 0 0</Center><Radius>1</Radius></Sphere>
            <Shader>v.lua</Shader>
            <GridResolution>6</GridResolution>
            <Absorption>0.01 0.01 0.01</Absorption>
            <Scattering>0 0 0</Scattering>
        </Volume>
    </Volumes>
</Scene>"#
        .to_string()
}

#[test]
fn saving_a_module_a_volume_script_requires_rerenders() {
    let script = "local g = require \"glow\"\nfunction density(s) return 1 end\n\
                  function emission(s) return g.r, g.g, 0 end\n";
    let glow = |r: u32, g: u32| format!("return {{ r = {r}, g = {g} }}\n");
    let dir = folder(&[("s.xml", &volume_scene()), ("v.lua", script), ("glow.lua", &glow(400, 0))]);
    let w = start(dir.path(), "s.xml");
    let rx = events(&w.addr);
    until(&rx, "a first frame", finished);
    let (n1, red, _) = frame(&w.addr);
    assert!(dominant(red, 0), "a red glow from the module: {red:?}");

    // The grid baked from the old module must not be reused.
    save(&dir.path().join("glow.lua"), &glow(0, 400));
    until(&rx, "a frame after the module's save", |s| finished(s) && s["frame"].as_u64() > Some(n1));
    let (_, green, _) = frame(&w.addr);
    assert!(dominant(green, 1), "a green glow after saving the module: {green:?}");
}

/// Reads one tev packet: (type, body after the type byte).
fn tev_packet(s: &mut TcpStream) -> (u8, Vec<u8>) {
    let mut len = [0u8; 4];
    s.read_exact(&mut len).expect("a packet's length");
    let mut body = vec![0u8; u32::from_le_bytes(len) as usize - 4];
    s.read_exact(&mut body).expect("a whole packet");
    (body[0], body[1..].to_vec())
}

#[test]
fn tev_gets_each_pass_as_create_and_update_packets() {
    let viewer = std::net::TcpListener::bind("127.0.0.1:0").expect("a fake tev");
    let addr = viewer.local_addr().unwrap().to_string();
    let dir = folder(&[("s.xml", &scene("c.lua")), ("c.lua", &shader(1.0, 0.0, 0.0))]);
    let _w = start_with(dir.path(), "s.xml", &["--tev", &addr]);
    let (mut s, _) = viewer.accept().expect("luster connects to tev");
    s.set_read_timeout(Some(WAIT)).unwrap();
    let (kind, create) = tev_packet(&mut s);
    assert_eq!(kind, 4, "the first packet creates the image");
    // grab_focus, "out.png\0", width, height, channel count, "R\0G\0B\0".
    let name_end = 1 + create[1..].iter().position(|&c| c == 0).unwrap();
    assert_eq!(&create[1..name_end], b"out.png");
    let word = |b: &[u8], at: usize| u32::from_le_bytes(b[at..at + 4].try_into().unwrap());
    let at = name_end + 1;
    assert_eq!((word(&create, at), word(&create, at + 4), word(&create, at + 8)), (48, 48, 3));
    assert_eq!(&create[at + 12..], b"R\0G\0B\0");
    let (kind, update) = tev_packet(&mut s);
    assert_eq!(kind, 6, "then the pass's pixels");
    // The floats fill the rest: 48 × 48 pixels of 3 channels after the header.
    let header = 1 + 8 + 4 + 6 + 16 + 48;
    assert_eq!(update.len() - header, 48 * 48 * 3 * 4, "a whole 48×48 RGB image");
    let floats: Vec<f32> =
        update[header..].chunks(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    let centre = &floats[(24 * 48 + 24) * 3..][..3];
    assert!(centre[0] > centre[1] + 100.0, "the red sphere's linear radiance: {centre:?}");
}

/// `scene(shader)` with several samples a pixel (so the watch refines over
/// several passes) and, when given, a scene-level display transform.
fn refined_scene(shader: &str, display: Option<&str>) -> String {
    let s = scene(shader).replace("</ImageResolution>", "</ImageResolution><NumSamples>6</NumSamples>");
    match display {
        Some(d) => s.replacen("<Scene>", &format!("<Scene>\n    <Display>{d}</Display>"), 1),
        None => s,
    }
}

/// The 8-bit pixels of a PNG, with its size.
fn pixels(png: &[u8]) -> (u32, u32, Vec<u8>) {
    let img = image::load_from_memory(png).expect("a PNG").to_rgb8();
    (img.width(), img.height(), img.into_raw())
}

/// What `luster render` writes for `scene` in `dir`: the pixels of its PNG.
fn rendered(dir: &std::path::Path, scene: &str, out: &str) -> (u32, u32, Vec<u8>) {
    let status = Command::new(env!("CARGO_BIN_EXE_luster"))
        .args(["render", "-q", scene, "-o", out, "--threads", "2"])
        .current_dir(dir)
        .stdin(Stdio::null())
        .status()
        .expect("luster render runs");
    assert!(status.success(), "luster render {scene} failed");
    pixels(&std::fs::read(dir.join(out).join("out.png")).expect("the rendered PNG"))
}

/// The refined frame's state: finished, at full resolution and all samples.
fn refined(s: &serde_json::Value) -> bool {
    finished(s) && s["preview"] == false && s["spp"].is_u64() && s["spp"] == s["target_spp"]
}

#[test]
fn the_refined_frame_is_the_rendered_image_at_load_and_after_a_save() {
    // The watch encodes its frames for speed, so the files differ; the
    // pixels, decoded, must not differ in a single byte.
    let dir = folder(&[("s.xml", &refined_scene("c.lua", None)), ("c.lua", &shader(0.9, 0.3, 0.1))]);
    let w = start(dir.path(), "s.xml");
    let rx = events(&w.addr);
    let first = until(&rx, "the refined first frame", refined);
    assert_eq!(first["target_spp"], 6);
    let (n1, _, png) = frame(&w.addr);
    let ours = pixels(&png);
    assert_eq!((ours.0, ours.1), (48, 48), "the full resolution");
    assert!(ours == rendered(dir.path(), "s.xml", "r1"), "the watch's frame differs from `luster render`");

    // One save that changes both the shader (a new file) and the display
    // transform, so a stale frame or a transform the watch missed shows.
    std::fs::write(dir.path().join("d.lua"), shader(0.1, 0.5, 0.9)).unwrap();
    save(&dir.path().join("s.xml"), &refined_scene("d.lua", Some("srgb")));
    until(&rx, "a refined frame after the save", |s| refined(s) && s["frame"].as_u64() > Some(n1));
    let (_, _, png) = frame(&w.addr);
    let after = pixels(&png);
    assert!(after != ours, "the save changed the image");
    assert!(
        after == rendered(dir.path(), "s.xml", "r2"),
        "the watch's frame differs from `luster render` after the save"
    );
}

/// A session on a scene that does not load: the server runs, the CPUs idle.
fn idle_session() -> (tempfile::TempDir, Watch) {
    let dir = folder(&[("s.xml", "<Scene><Cameras>")]);
    let w = start(dir.path(), "s.xml");
    (dir, w)
}

/// Whether the process is still running.
fn alive(w: &mut Watch) -> bool {
    matches!(w.child.try_wait(), Ok(None))
}

#[test]
fn a_huge_body_is_refused_without_reading_it_and_the_server_lives_on() {
    let (_dir, mut w) = idle_session();
    let lengths = ["99999999999999", "18446744073709551615", "99999999999999999999999", "4194305"];
    // With and without asking for a go-ahead; the head comes with the first
    // bytes of the body. A server that allocates the announced length
    // aborts on one of these.
    for expect in ["Expect: 100-continue\r\n", ""] {
        for method in ["POST", "GET"] {
            for length in lengths {
                let what = format!("{method} with Content-Length {length} {expect:?}");
                let request = format!(
                    "{method} /state HTTP/1.1\r\nHost: {}\r\nContent-Length: {length}\r\n{expect}\r\nabc",
                    w.addr
                );
                let answer = exchange(&w.addr, request.as_bytes(), Duration::from_secs(10))
                    .unwrap_or_else(|e| panic!("{what}: {e}"));
                let code = status(&answer);
                assert!(code.is_none() || code == Some(413), "{what}: {code:?}");
                let (code, _, _) = get_within(&w.addr, "/state", Duration::from_secs(10))
                    .unwrap_or_else(|e| panic!("/state after {what}: {e}"));
                assert_eq!(code, 200, "/state after {what}");
                assert!(alive(&mut w), "the server died on {what}");
            }
        }
    }
}

#[test]
fn a_body_that_never_comes_does_not_delay_another_client() {
    let (_dir, w) = idle_session();
    let mut stalled = Vec::new();
    for (method, length, sent) in [("POST", 100, 10), ("GET", 5, 0), ("POST", 4 << 20, 1000)] {
        let mut s = TcpStream::connect(&w.addr).expect("the page server answers");
        write!(s, "{method} /state HTTP/1.1\r\nHost: {}\r\nContent-Length: {length}\r\n\r\n", w.addr)
            .unwrap();
        s.write_all(&vec![b'x'; sent]).unwrap();
        stalled.push(s);
    }
    std::thread::sleep(Duration::from_millis(300));
    for _ in 0..3 {
        let t = Instant::now();
        let (code, _, _) = get_within(&w.addr, "/state", Duration::from_secs(3)).expect("/state answers");
        assert_eq!(code, 200);
        assert!(t.elapsed() < Duration::from_secs(3), "/state took {:?}", t.elapsed());
    }
}

#[test]
fn a_foreign_host_or_origin_is_refused() {
    let (_dir, w) = idle_session();
    let port = w.addr.rsplit(':').next().unwrap();
    let ask = |request: String| status(&exchange(&w.addr, request.as_bytes(), WAIT).expect("an answer"));
    // DNS rebinding: a page of evil.example whose name now points to 127.0.0.1.
    for host in [
        "evil.example".to_string(),
        format!("evil.example:{port}"),
        format!("127.0.0.1.evil.example:{port}"),
        "127.0.0.1:1".to_string(),
        "127.0.0.1".to_string(),
        format!("localhost:{port}0"),
        String::new(),
    ] {
        for path in ["/state", "/", "/frame.png", "/events"] {
            let code = ask(format!("GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"));
            assert!(matches!(code, Some(400 | 403 | 421)), "GET {path} with Host {host:?} answered {code:?}");
        }
    }
    let code = ask("GET /state HTTP/1.1\r\nConnection: close\r\n\r\n".to_string());
    assert_eq!(code, Some(400), "no Host at all");
    for host in [format!("127.0.0.1:{port}"), format!("localhost:{port}"), format!("LocalHost:{port}")] {
        let code = ask(format!("GET /state HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"));
        assert_eq!(code, Some(200), "Host {host}");
    }
    // A state-changing request from another site's page (CSRF) is refused by
    // its Origin; one from the page itself reaches the router, where /state
    // takes no POST.
    let post = |origin: &str| {
        ask(format!(
            "POST /state HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nOrigin: {origin}\r\nContent-Length: 2\r\n\
             Connection: close\r\n\r\n{{}}"
        ))
    };
    for origin in ["http://evil.example", "null", &format!("http://evil.example:{port}"), "https://127.0.0.1"]
    {
        assert_eq!(post(origin), Some(403), "POST with Origin {origin}");
    }
    assert_eq!(post(&format!("http://127.0.0.1:{port}")), Some(405), "POST from the page");
}

/// The `Threads:` line of /proc/PID/status.
fn threads(pid: u32) -> usize {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).expect("the process's status");
    status
        .lines()
        .find_map(|l| l.strip_prefix("Threads:"))
        .and_then(|n| n.trim().parse().ok())
        .expect("Threads:")
}

#[test]
fn hundreds_of_idle_connections_neither_lock_out_a_client_nor_spawn_a_thread_each() {
    let (_dir, w) = idle_session();
    let before = threads(w.child.id());
    // Half say nothing, half start a request and stop.
    let idle: Vec<TcpStream> = (0..200)
        .map(|i| {
            let mut s = TcpStream::connect(&w.addr).expect("a connection");
            if i % 2 == 1 {
                write!(s, "GET /state HTTP/1.1\r\nHost: {}\r\n", w.addr).unwrap();
            }
            s
        })
        .collect();
    std::thread::sleep(Duration::from_millis(500));
    let t = Instant::now();
    let (code, _, _) = get_within(&w.addr, "/state", Duration::from_secs(3)).expect("a new client is served");
    assert_eq!(code, 200);
    assert!(t.elapsed() < Duration::from_secs(3), "/state took {:?}", t.elapsed());
    // The session's own threads, plus at most the connection cap (64) and a
    // few threads of dropped connections on their way out.
    let during = threads(w.child.id());
    assert!(during <= before + 64 + 8, "{during} threads with 200 idle connections ({before} before)");
    drop(idle);
}

#[test]
fn a_head_sent_a_byte_a_second_is_dropped() {
    let (_dir, w) = idle_session();
    let mut s = TcpStream::connect(&w.addr).expect("the page server answers");
    s.set_read_timeout(Some(Duration::from_secs(1))).unwrap();
    let head = format!("GET /state HTTP/1.1\r\nHost: {}\r\nX-Slow: {}\r\n\r\n", w.addr, "a".repeat(60));
    let t = Instant::now();
    let mut dropped = false;
    for &b in head.as_bytes() {
        if t.elapsed() > Duration::from_secs(20) {
            break;
        }
        let _ = s.write_all(&[b]);
        let mut answer = Vec::new();
        match s.read_to_end(&mut answer) {
            // Closed, with a 408 or nothing at all.
            Ok(_) => {
                assert!(
                    matches!(status(&answer), None | Some(408)),
                    "{:?}",
                    String::from_utf8_lossy(&answer)
                );
                dropped = true;
                break;
            }
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionReset => {
                dropped = true;
                break;
            }
            Err(_) => {} // still open: one more byte
        }
    }
    assert!(dropped, "a slow head still held its connection after {:?}", t.elapsed());
    assert_eq!(get(&w.addr, "/state").0, 200);
}

#[test]
fn requests_on_one_connection_are_answered_in_order() {
    let (_dir, w) = idle_session();
    let one = |path: &str, close: &str| format!("GET {path} HTTP/1.1\r\nHost: {}\r\n{close}\r\n", w.addr);
    // Sent at once (pipelined): the server must not lose the bytes after the first head.
    let all =
        format!("{}{}{}", one("/state", ""), one("/frame.png", ""), one("/nothing", "Connection: close\r\n"));
    let answer = exchange(&w.addr, all.as_bytes(), WAIT).expect("three answers");
    let text = String::from_utf8_lossy(&answer);
    let codes: Vec<&str> = text.match_indices("HTTP/1.1 ").map(|(i, _)| &text[i + 9..i + 12]).collect();
    assert_eq!(codes, ["200", "404", "404"], "{text}");
}
