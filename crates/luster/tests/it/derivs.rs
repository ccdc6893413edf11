//! Automatic derivatives (docs/derivatives.md): a user-written stripe
//! pattern, `aastep(0.5, fract(k·(x + z)))`, on a plane seen at a grazing
//! angle, rendered at 1 sample per pixel with the hard step and with the
//! width `aastep` finds itself, each against a 1024-sample render of the
//! hard step (the converged image). The width `aastep` finds must bring the
//! 1-sample image closer, and the width of the stripe coordinate before it
//! wraps (`filterwidth(t)`) much closer, judged over blocks of pixels and
//! against the reference's own noise; the figures are printed (`cargo test --release --test it derivs -- --nocapture`).

use crate::common;
use common::folder;

fn scene(auto: u32) -> String {
    common::grazing_plane(96, 48, 0.8, "stripes.lua", "auto", &auto.to_string())
}

/// No width written by hand: with `auto = 1` aastep finds it, with 0 the
/// step is hard, and with 2 the width is that of the stripe coordinate
/// before it wraps (docs/derivatives.md, "Limits").
const STRIPES: &str = "params { auto = 1, frequency = 3 }
function color(s)
  local t = (s.P.x + s.P.z) * param.frequency
  local x = fract(t)
  local v
  if param.auto == 1 then
    v = aastep(0.5, x)
  elseif param.auto == 2 then
    v = aastep(0.5, x, filterwidth(t))
  else
    v = aastep(0.5, x, 0)
  end
  return 255 * v, 255 * v, 255 * v
end";

const W: usize = 96;
const H: usize = 48;

/// Squared errors (on a 0–1 scale) summed per 8×8 block of pixels.
fn block_sq_errors(a: &[u8], b: &[u8]) -> Vec<f64> {
    const B: usize = 8;
    let mut blocks = vec![0.0; (W / B) * (H / B)];
    for y in 0..H {
        for x in 0..W {
            for c in 0..3 {
                let i = (y * W + x) * 3 + c;
                let e = (f64::from(a[i]) - f64::from(b[i])) / 255.0;
                blocks[(y / B) * (W / B) + x / B] += e * e;
            }
        }
    }
    blocks
}

fn rmse(blocks: &[f64]) -> f64 {
    (blocks.iter().sum::<f64>() / (W * H * 3) as f64).sqrt()
}

#[test]
fn automatic_widths_bring_one_sample_close_to_the_converged_image() {
    let dir = folder(&[
        ("auto.xml", &scene(1)),
        ("hard.xml", &scene(0)),
        ("unwrapped.xml", &scene(2)),
        ("stripes.lua", STRIPES),
    ]);
    let (auto, hard) = (dir.path().join("auto.xml"), dir.path().join("hard.xml"));
    let unwrapped = dir.path().join("unwrapped.xml");
    let reference = common::render_rgb8(&hard, 1024, 7);
    // A second seed measures the reference's own noise (per-pixel RMSE of
    // one render: the two renders' RMSE over √2). One sample per pixel
    // sits at the pixel centre, whatever the seed.
    let noise = rmse(&block_sq_errors(&common::render_rgb8(&hard, 1024, 8), &reference)) / 2f64.sqrt();
    let h = block_sq_errors(&common::render_rgb8(&hard, 1, 0), &reference);
    let a = block_sq_errors(&common::render_rgb8(&auto, 1, 0), &reference);
    let u = block_sq_errors(&common::render_rgb8(&unwrapped, 1, 0), &reference);
    let (rh, ra, ru) = (rmse(&h), rmse(&a), rmse(&u));
    eprintln!(
        "stripes at a grazing angle, 1 spp against 1024 spp of the hard step (whose own noise is {noise:.4}): \
         RMSE hard step {rh:.4}, aastep(0.5, fract(t)) {ra:.4} ({:.0}% lower), aastep(0.5, fract(t), \
         filterwidth(t)) {ru:.4} ({:.0}% lower)",
        100.0 * (1.0 - ra / rh),
        100.0 * (1.0 - ru / rh)
    );
    // Much closer with the width of the unwrapped coordinate; closer
    // with the wrapped one's (its difference wraps where a pixel spans
    // a period: docs/derivatives.md, "Limits").
    assert!(ru < 0.6 * rh, "unwrapped {ru:.4}, hard {rh:.4}");
    for (what, f, r) in [("aastep(0.5, fract(t))", &a, ra), ("filterwidth(t)", &u, ru)] {
        let (mean, se) = mean_gain(&h, f);
        eprintln!("  gain in squared error per 8x8 block with {what}: {mean:.4} ± {se:.4}");
        assert!(mean > 5.0 * se, "{what}: the gain per block is {mean:.4} ± {se:.4}");
        assert!(
            rh - r > 5.0 * noise,
            "{what}: a gain of {:.4} against the reference's noise {noise:.4}",
            rh - r
        );
    }
}

/// The mean over blocks of the drop in squared error from `hard` to `f`,
/// and its standard error (blocks are independent pixels and samples).
fn mean_gain(hard: &[f64], f: &[f64]) -> (f64, f64) {
    let d: Vec<f64> = hard.iter().zip(f).map(|(h, a)| h - a).collect();
    let n = d.len() as f64;
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn automatic_widths_render_the_same_on_one_and_two_threads() {
    let dir = folder(&[("auto.xml", &scene(1)), ("stripes.lua", STRIPES)]);
    let path = dir.path().join("auto.xml");
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| common::render_rgb8(&path, 2, 0))
    };
    assert!(on(1) == on(2), "the image depends on the thread count");
}
