//! Antialiased patterns (docs/shaders.md, "Antialiasing"): a checkerboard
//! receding to the horizon, rendered at 1 sample per pixel with the filtered
//! `checker(p, filterwidth_xyz(s, f))` and with the plain one, each compared with a 256-sample
//! render of the plain pattern. The metric is PSNR over the 8-bit RGB
//! image; the filtered image must be at least 5 dB closer (issue 14's
//! target). The numbers are printed (`cargo test --release --test shader_aa
//! -- --nocapture`).

use crate::common;
use common::folder;

fn scene(fw: &str) -> String {
    common::grazing_plane(128, 64, 0.75, "checker.lua", "filtered", fw)
}

const CHECKER: &str = "params { filtered = 1, frequency = 4 }
function color(s)
  local f = param.frequency
  local fw = filterwidth_xyz(s, f) * param.filtered
  -- y held mid-cell: the plane lies on a cell boundary, where rounding
  -- would flip cells at random.
  local p = s.P * f
  local c = 255 * checker(vec3(p.x, 0.5, p.z), fw)
  return c, c, c
end";

#[test]
fn filtering_brings_one_sample_closer_to_the_converged_image() {
    let dir = folder(&[("filtered.xml", &scene("1")), ("plain.xml", &scene("0")), ("checker.lua", CHECKER)]);
    let reference = common::render_rgb8(&dir.path().join("plain.xml"), 256, 0);
    let plain = common::psnr(&common::render_rgb8(&dir.path().join("plain.xml"), 1, 0), &reference);
    let filtered = common::psnr(&common::render_rgb8(&dir.path().join("filtered.xml"), 1, 0), &reference);
    println!(
        "checkerboard to the horizon, 1 spp against 256 spp: plain {plain:.2} dB, filtered {filtered:.2} dB \
         ({:+.2} dB)",
        filtered - plain
    );
    assert!(filtered >= plain + 5.0, "filtered {filtered:.2} dB, plain {plain:.2} dB");
}
