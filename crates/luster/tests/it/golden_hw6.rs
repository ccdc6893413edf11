//! Golden-image tests for hw6 (BRDFs): every hw6 scene against the course's
//! expected image, and the JSON encoding of `<BRDFs>` against the XML one.
//!
//! Metric and bar come from `luster::conformance::thresholds` (shared with
//! `luster suite`): the scenes are single-sample and deterministic, so the
//! default bar applies, PSNR ≥ 40 dB and mean LDR-FLIP ≤ 0.01 per image
//! (stricter than the issue's ≥ 40 dB or FLIP ≤ 0.05). Renders and FLIP
//! heatmaps go under `target/tmp/golden/hw6/`.
//!
//! Without `../shared/scenes/ceng795` the test says it skipped, and fails
//! when `CI=true`: CI must not pass by skipping.

use crate::common;
use common::{course_root, folder};
use luster::conformance::{discover, run_case};
use luster::scene::description::{BrdfKind, Description};
use std::path::PathBuf;

#[test]
fn hw6_scenes_match_expected_images() {
    let Some(root) = course_root("hw6") else { return };
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("golden").join("hw6");
    let _ = std::fs::create_dir_all(&out);
    let cases: Vec<_> = discover(&root).into_iter().filter(|c| c.hw == "hw6").collect();
    assert!(cases.len() >= 5, "expected the 5 hw6 scenes under {}, found {}", root.display(), cases.len());
    let mut failures = Vec::new();
    let mut compared = 0;
    println!("{:<48} {:>8} {:>7}", "scene", "PSNR", "FLIP");
    for case in &cases {
        let r = run_case(case, &out);
        if let Some(e) = &r.error {
            failures.push(format!("{}: {e}", case.label()));
            continue;
        }
        if !r.warnings.is_empty() {
            failures.push(format!("{}: warnings {:?}", case.label(), r.warnings));
        }
        for img in &r.images {
            let Some(c) = &img.comparison else {
                failures.push(format!(
                    "{} {}: no expected image to compare with",
                    case.label(),
                    img.image_name
                ));
                continue;
            };
            compared += 1;
            println!(
                "{:<48} {:>8.2} {:>7.4} {}",
                case.label(),
                c.psnr,
                c.flip,
                if img.pass { "ok" } else { "FAIL" }
            );
            if !img.pass {
                failures.push(format!(
                    "{} {}: PSNR {:.2} dB, FLIP {:.4} (needs PSNR ≥ {} and FLIP ≤ {}); render {}",
                    case.label(),
                    img.image_name,
                    c.psnr,
                    c.flip,
                    img.bar.min_psnr,
                    img.bar.max_flip,
                    img.render.display()
                ));
            }
        }
    }
    assert!(compared >= 5, "only {compared} hw6 images were compared");
    assert!(failures.is_empty(), "{} hw6 image(s) failed:\n{}", failures.len(), failures.join("\n"));
}

const XML: &str = r#"<Scene>
  <Cameras><Camera id="1"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>
    <NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance>
    <ImageResolution>8 8</ImageResolution><ImageName>a.png</ImageName></Camera></Cameras>
  <BRDFs>
    <OriginalPhong id="1"><Exponent>10</Exponent></OriginalPhong>
    <ModifiedPhong id="2" normalized="true"><Exponent>20</Exponent></ModifiedPhong>
    <OriginalBlinnPhong id="3"/>
    <ModifiedBlinnPhong id="4" normalized="false"><Exponent>40</Exponent></ModifiedBlinnPhong>
    <TorranceSparrow id="5" kdfresnel="true"><Exponent>50</Exponent></TorranceSparrow>
  </BRDFs>
  <Materials>
    <Material id="1" BRDF="1"><PhongExponent>3</PhongExponent></Material>
    <Material id="2" BRDF="2"/>
    <Material id="3" BRDF="3"><PhongExponent>7</PhongExponent></Material>
    <Material id="4" BRDF="4"/>
    <Material id="5" BRDF="5"/>
    <Material id="6"/>
  </Materials>
  <VertexData>0 0 0</VertexData>
  <Objects><Sphere id="1"><Material>1</Material><Center>1</Center><Radius>1</Radius></Sphere></Objects>
</Scene>"#;

const JSON: &str = r#"{"Scene": {
  "Cameras": {"Camera": {"_id": "1", "Position": "0 0 5", "Gaze": "0 0 -1", "Up": "0 1 0",
    "NearPlane": "-1 1 -1 1", "NearDistance": "1", "ImageResolution": "8 8", "ImageName": "a.png"}},
  "BRDFs": {
    "OriginalPhong": {"_id": "1", "Exponent": "10"},
    "ModifiedPhong": {"_id": "2", "_normalized": "true", "Exponent": "20"},
    "OriginalBlinnPhong": {"_id": "3"},
    "ModifiedBlinnPhong": [{"_id": "4", "_normalized": "false", "Exponent": "40"}],
    "TorranceSparrow": {"_id": "5", "_kdfresnel": "true", "Exponent": "50"}
  },
  "Materials": {"Material": [
    {"_id": "1", "_BRDF": "1", "PhongExponent": "3"},
    {"_id": "2", "_BRDF": "2"},
    {"_id": "3", "_BRDF": "3", "PhongExponent": "7"},
    {"_id": "4", "_BRDF": "4"},
    {"_id": "5", "_BRDF": "5"},
    {"_id": "6"}
  ]},
  "VertexData": "0 0 0",
  "Objects": {"Sphere": {"_id": "1", "Material": "1", "Center": "1", "Radius": "1"}}
}}"#;

/// (kind, exponent, normalized, kdfresnel) of a BRDF.
type Read = (BrdfKind, Option<f32>, bool, bool);

/// What each material's BRDF was read as.
fn brdfs(d: &Description) -> Vec<Option<Read>> {
    d.materials
        .iter()
        .map(|m| m.brdf.as_ref().map(|b| (b.kind, b.exponent, b.normalized, b.kd_fresnel)))
        .collect()
}

#[test]
fn brdfs_read_alike_from_xml_and_json() {
    let dir = folder(&[("s.xml", XML), ("s.json", JSON)]);
    let xml = luster::scene::load(&dir.path().join("s.xml")).expect("the XML scene loads");
    let json = luster::scene::load(&dir.path().join("s.json")).expect("the JSON scene loads");
    let want = vec![
        Some((BrdfKind::OriginalPhong, Some(10.0), false, false)),
        Some((BrdfKind::ModifiedPhong, Some(20.0), true, false)),
        Some((BrdfKind::OriginalBlinnPhong, None, false, false)),
        Some((BrdfKind::ModifiedBlinnPhong, Some(40.0), false, false)),
        Some((BrdfKind::TorranceSparrow, Some(50.0), false, true)),
        None,
    ];
    assert_eq!(brdfs(&xml), want);
    assert_eq!(brdfs(&json), want);
    assert!(xml.warnings.is_empty() && json.warnings.is_empty(), "{:?} {:?}", xml.warnings, json.warnings);
}
