//! `luster suite` end to end on a tiny fake course folder: one good scene
//! whose expected image is our own render, one broken scene that has an
//! expected image, and one scene without any (which must be skipped).
//! The suite must not abort: the report and JSON exist, the good row passes,
//! the broken row is an error carrying the loader's message (escaped in HTML).

use std::path::Path;
use std::process::{Command, Output};

const GOOD: &str = r#"<Scene>
    <BackgroundColor>0 0 0</BackgroundColor>
    <Cameras>
        <Camera id="1">
            <Position>0 0 0</Position>
            <Gaze>0 0 -1</Gaze>
            <Up>0 1 0</Up>
            <NearPlane>-1 1 -1 1</NearPlane>
            <NearDistance>1</NearDistance>
            <ImageResolution>48 48</ImageResolution>
            <ImageName>a.png</ImageName>
        </Camera>
    </Cameras>
    <Lights>
        <AmbientLight>25 25 25</AmbientLight>
        <PointLight id="1">
            <Position>0 0 0</Position>
            <Intensity>1000 1000 1000</Intensity>
        </PointLight>
    </Lights>
    <Materials>
        <Material id="1">
            <AmbientReflectance>1 1 1</AmbientReflectance>
            <DiffuseReflectance>1 1 1</DiffuseReflectance>
            <SpecularReflectance>1 1 1</SpecularReflectance>
            <PhongExponent>1</PhongExponent>
        </Material>
    </Materials>
    <VertexData>
        -0.5 0.5 -2
        -0.5 -0.5 -2
        0.5 -0.5 -2
        0 0 -3
    </VertexData>
    <Objects>
        <Triangle id="1">
            <Material>1</Material>
            <Indices>1 2 3</Indices>
        </Triangle>
        <Sphere id="1">
            <Material>1</Material>
            <Center>4</Center>
            <Radius>0.5</Radius>
        </Sphere>
    </Objects>
</Scene>
"#;

/// A camera without a position: the loader rejects it with a message that
/// contains `<Camera>`, which the HTML must escape.
const BROKEN: &str = r#"<Scene>
    <Cameras><Camera id="1"><ImageName>broken.png</ImageName></Camera></Cameras>
</Scene>
"#;

fn luster(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_luster")).args(args).output().expect("the luster binary runs")
}

fn text(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{} is readable: {e}", p.display()))
}

/// Builds `root/hw1/{xml,expected}` and returns the root.
fn fake_course(dir: &Path) -> std::path::PathBuf {
    let root = dir.join("course");
    let xml = root.join("hw1/xml");
    let expected = root.join("hw1/expected");
    std::fs::create_dir_all(&xml).unwrap();
    std::fs::create_dir_all(&expected).unwrap();
    std::fs::write(xml.join("a.xml"), GOOD).unwrap();
    std::fs::write(xml.join("broken.xml"), BROKEN).unwrap();
    std::fs::write(xml.join("unjudged.xml"), GOOD.replace("a.png", "unjudged.png")).unwrap();
    // The expected image of the good scene is our own render of it.
    let out =
        luster(&["render", "-q", xml.join("a.xml").to_str().unwrap(), "-o", expected.to_str().unwrap()]);
    assert!(out.status.success(), "render failed: {}", String::from_utf8_lossy(&out.stderr));
    std::fs::copy(expected.join("a.png"), expected.join("broken.png")).unwrap();
    root
}

#[test]
fn suite_reports_a_pass_and_a_broken_scene_without_aborting() {
    let dir = tempfile::tempdir().unwrap();
    let root = fake_course(dir.path());
    let report = dir.path().join("report");
    let out = luster(&["suite", root.to_str().unwrap(), "-o", report.to_str().unwrap(), "--threads", "2"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "stdout:\n{stdout}\nstderr:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("hw1/xml/a.xml"), "{stdout}");
    assert!(stdout.contains("1 without an expected image skipped"), "{stdout}");
    assert!(stdout.contains("1 passed, 0 failed, 1 errored, 0 unsupported"), "{stdout}");

    let json: serde_json::Value = serde_json::from_str(&text(&report.join("results.json"))).unwrap();
    assert_eq!(json["summary"]["scenes"], 2);
    assert_eq!(json["summary"]["passed"], 1);
    assert_eq!(json["summary"]["errored"], 1);
    let scenes = json["scenes"].as_array().unwrap();
    let labels: Vec<&str> = scenes.iter().map(|s| s["label"].as_str().unwrap()).collect();
    assert_eq!(labels, ["hw1/xml/a.xml", "hw1/xml/broken.xml"]);

    let good = &scenes[0]["images"][0];
    assert_eq!(good["verdict"], "pass");
    assert_eq!(good["metrics"]["psnr"], serde_json::Value::Null, "identical images have infinite PSNR");
    assert_eq!(good["metrics"]["flip"], 0.0);
    for key in ["render", "expected", "heatmap"] {
        let rel = good[key].as_str().unwrap_or_else(|| panic!("{key} is missing"));
        assert!(report.join(rel).is_file(), "{key} {rel} is not in the report folder");
    }
    for key in ["render", "expected", "heatmap"] {
        let rel = good["thumbs"][key].as_str().unwrap();
        assert!(report.join(rel).is_file(), "thumbnail {rel} is missing");
    }

    let broken = &scenes[1];
    let error = broken["error"].as_str().expect("the broken scene carries its error");
    assert!(error.contains("<Camera> is missing its <Position>"), "{error}");
    assert!(broken["images"].as_array().unwrap().is_empty());

    let html = text(&report.join("index.html"));
    assert!(html.contains("broken.xml"));
    assert!(html.contains("&lt;Camera&gt; is missing its &lt;Position&gt;"), "error text is shown, escaped");
    assert!(!html.contains("<Camera>"), "no unescaped scene text");
    assert!(html.contains("class=\"row error first\""));
    assert!(html.contains("class=\"row pass first\""));
    assert!(!html.contains("unjudged"), "a scene without an expected image is skipped");
}

#[test]
fn suite_only_strict_and_bad_arguments() {
    let dir = tempfile::tempdir().unwrap();
    let root = fake_course(dir.path());
    let report = dir.path().join("only");
    let r = root.to_str().unwrap();

    let out = luster(&["suite", r, "-o", report.to_str().unwrap(), "--only", "a.xml", "--jobs", "2"]);
    assert_eq!(out.status.code(), Some(0));
    let json: serde_json::Value = serde_json::from_str(&text(&report.join("results.json"))).unwrap();
    assert_eq!(json["summary"]["scenes"], 1);
    assert_eq!(json["only"], "a.xml");

    let strict = luster(&["suite", r, "-o", report.to_str().unwrap(), "--strict"]);
    assert_eq!(strict.status.code(), Some(1), "--strict fails on the broken scene");

    let missing = dir.path().join("no_such_course");
    let out = luster(&["suite", missing.to_str().unwrap(), "-o", report.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no_such_course"));

    let out = luster(&["suite", r, "-o", report.to_str().unwrap(), "--only", "nothing-matches"]);
    assert_eq!(out.status.code(), Some(2));
}

/// An HDR camera (`.exr`, hw5's semantics: the `.exr` and a tone-mapped
/// `.png`) whose expected `.exr` is our render made 10% brighter: the row
/// must carry the HDR numbers (relative MAE = 0.1/1.1 exactly, HDR-FLIP
/// above 0) and two thumbnails of the linear images tone-mapped by one
/// curve, so ours shows darker than the course's.
#[test]
fn suite_shows_hdr_rows_with_tone_mapped_thumbnails_and_hdr_metrics() {
    use luster::image::Rgb32Image;
    let dir = tempfile::tempdir().unwrap();
    let root = dir.path().join("course");
    let (xml, expected) = (root.join("hw5/xml"), root.join("hw5/expected"));
    std::fs::create_dir_all(&xml).unwrap();
    std::fs::create_dir_all(&expected).unwrap();
    std::fs::write(xml.join("h.xml"), GOOD.replace("a.png", "h.exr")).unwrap();
    let out =
        luster(&["render", "-q", xml.join("h.xml").to_str().unwrap(), "-o", expected.to_str().unwrap()]);
    assert!(out.status.success(), "render failed: {}", String::from_utf8_lossy(&out.stderr));
    let exr = expected.join("h.exr");
    let ours = Rgb32Image::load(&exr).unwrap();
    let brighter: Vec<luster::math::Vec3> =
        ours.pixels.iter().map(|p| luster::math::Vec3::from(*p) * 1.1).collect();
    luster::image::output::write_rgb32f(&exr, ours.width, ours.height, &brighter).unwrap();

    let report = dir.path().join("report");
    let out = luster(&["suite", root.to_str().unwrap(), "-o", report.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_str(&text(&report.join("results.json"))).unwrap();
    let row = &json["scenes"][0]["images"][0];
    let hdr = &row["hdr"];
    let mae = hdr["relative_mae"].as_f64().expect("the HDR row has a relative MAE");
    assert!((mae - 0.1 / 1.1).abs() < 1e-4, "relative MAE {mae}");
    assert!(hdr["hdr_flip"].as_f64().is_some_and(|f| f > 0.0), "{hdr}");
    assert!(report.join(hdr["render"].as_str().unwrap()).is_file());
    assert!(report.join(hdr["expected"].as_str().unwrap()).is_file());
    let thumbs: Vec<image::RgbImage> = hdr["thumbs"]
        .as_array()
        .expect("the HDR row has thumbnails")
        .iter()
        .map(|t| image::open(report.join(t.as_str().unwrap())).unwrap().to_rgb8())
        .collect();
    let mean =
        |t: &image::RgbImage| t.as_raw().iter().map(|&v| f64::from(v)).sum::<f64>() / t.as_raw().len() as f64;
    assert!(mean(&thumbs[0]) > 1.0, "our thumbnail is not black");
    let (a, b) = (mean(&thumbs[0]), mean(&thumbs[1]));
    assert!(a < 0.99 * b, "one curve for both: ours shows darker ({a} against {b})");

    let html = text(&report.join("index.html"));
    assert!(html.contains(&format!("rel. MAE {:.2}%", 100.0 * mae)), "HDR numbers shown");
    assert!(html.contains("HDR-FLIP"));
    assert!(html.contains("HDR, same curve"), "tone-mapped HDR thumbnails shown");
}
