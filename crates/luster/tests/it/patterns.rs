//! The built-in pattern library (`require "patterns"`, docs/patterns.md) in
//! a render: bricks and marble receding to the horizon at 1 sample per
//! pixel, filtered and plain, each compared with a 256-sample render of the
//! plain patterns (PSNR over the 8-bit image; the filtered image must be at
//! least 5 dB closer); and the contact sheet renders the same bytes on one
//! and two threads. The numbers are printed (`cargo test --release --test
//! it patterns -- --nocapture`).

use crate::common;
use common::folder;
use luster::render::{try_render_with, RenderOptions, Scene};
use std::path::PathBuf;

fn scene(filtered: &str) -> String {
    common::grazing_plane(128, 64, 0.75, "floor.lua", "filtered", filtered)
}

/// Bricks on the left, marble on the right, both at 3 repeats per unit.
const FLOOR: &str = "local P = require 'patterns'
params { filtered = 1 }
local BRICK = { size = vec3(1, 0.4, 0.6), mortar = 0.1 }
function color(s)
  local k = 3
  local fw = filterwidth_xyz(s, k) * param.filtered
  -- y held mid-course: the plane would otherwise lie on a course's edge.
  local p = vec3(s.P.x * k, 0.2, s.P.z * k)
  local v
  if s.P.x < 0 then v = P.brick(p, fw, BRICK) else v = P.marble(p, fw, { turbulence = 0.5 }) end
  return 255 * v, 255 * v, 255 * v
end";

#[test]
fn filtered_patterns_bring_one_sample_closer_to_the_converged_image() {
    let dir = folder(&[("filtered.xml", &scene("1")), ("plain.xml", &scene("0")), ("floor.lua", FLOOR)]);
    let reference = common::render_rgb8(&dir.path().join("plain.xml"), 256, 0);
    let plain = common::psnr(&common::render_rgb8(&dir.path().join("plain.xml"), 1, 0), &reference);
    let filtered = common::psnr(&common::render_rgb8(&dir.path().join("filtered.xml"), 1, 0), &reference);
    println!(
        "bricks and marble to the horizon, 1 spp against 256 spp: plain {plain:.2} dB, filtered {filtered:.2} dB \
         ({:+.2} dB)",
        filtered - plain
    );
    assert!(filtered >= plain + 5.0, "filtered {filtered:.2} dB, plain {plain:.2} dB");
}

#[test]
fn the_contact_sheet_is_the_same_on_any_number_of_threads() {
    let examples = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples");
    let text = std::fs::read_to_string(examples.join("scenes/patterns.xml")).expect("the sheet's scene");
    let shader = examples.join("shaders/patterns_sheet.lua").display().to_string();
    // A quarter of the size at 1 sample keeps this quick.
    let text = text
        .replace("<ImageResolution>924 910</ImageResolution>", "<ImageResolution>231 228</ImageResolution>")
        .replace("../shaders/patterns_sheet.lua", &shader);
    assert!(text.contains("231 228") && text.contains(shader.as_str()), "the sheet's scene changed");
    let dir = folder(&[("sheet.xml", &text)]);
    let desc = luster::scene::load(&dir.path().join("sheet.xml")).expect("the sheet loads");
    let s = Scene::build(&desc).expect("the sheet builds");
    let opts = RenderOptions { spp: Some(1), ..RenderOptions::default() };
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| try_render_with(&s, 0, &opts, &|_| {}).expect("no shader fails").to_rgb8())
    };
    let one = on(1);
    assert!(one == on(2));
    let (lo, hi) = one.iter().fold((255u8, 0u8), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    assert!(lo < 40 && hi > 215, "the tiles are not drawn: values from {lo} to {hi}");
}
