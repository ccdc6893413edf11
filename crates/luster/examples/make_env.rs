//! Writes the studio environment map of `examples/scenes/closures.xml`: a
//! lat-long OpenEXR (1024×512, half floats, ZIP-compressed, about 80 KB)
//! with a soft blue-grey sky, a warm grey floor below the horizon, a large
//! warm "softbox" up and to the front left (the key light), a tall cool strip
//! behind on the right (a rim light) and a faint fill on the front right.
//!
//! ```sh
//! cargo run --release --example make_env -- examples/scenes/textures/studio.exr
//! ```
//!
//! Radiance is in luster's output units (docs/hdr.md: the film's 255 is
//! linear 1.0 under `<Display>`), so the sky is about 0.2–0.4 × 255 and the
//! softbox 7 × 255: a white diffuse sphere under it comes out a light
//! grey, not clipped. Directions follow docs/environment-light.md: `-z` is
//! the image's centre, `+y` its top row, `+x` three quarters across.
//!
//! It writes through the `exr` crate rather than `image` only to get ZIP
//! compression (`image` writes run-length encoded 32-bit floats, ten times
//! larger for smooth gradients).

use exr::prelude::*;
use std::f32::consts::PI;

const WIDTH: usize = 1024;
const HEIGHT: usize = 512;
/// Linear 1.0 on the display.
const WHITE: f32 = 255.0;

type V = [f32; 3];

fn normalize(v: V) -> V {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    [v[0] / l, v[1] / l, v[2] / l]
}
fn dot(a: V, b: V) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn smoothstep(e0: f32, e1: f32, x: f32) -> f32 {
    let t = ((x - e0) / (e1 - e0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
fn lerp(a: V, b: V, t: f32) -> V {
    [a[0] + (b[0] - a[0]) * t, a[1] + (b[1] - a[1]) * t, a[2] + (b[2] - a[2]) * t]
}

/// A rectangular light facing the origin: 1 inside a rectangle of half
/// sizes `half` (in the tangent plane at distance 1 along `centre`), falling
/// off over `soft` at its edges, 0 outside and behind.
fn panel(d: V, centre: V, half: [f32; 2], soft: f32) -> f32 {
    let c = normalize(centre);
    let t = dot(d, c);
    if t <= 0.0 {
        return 0.0;
    }
    let right = normalize(cross([0.0, 1.0, 0.0], c));
    let up = cross(c, right);
    // The point where the direction meets the panel's plane.
    let (x, y) = (dot(d, right) / t, dot(d, up) / t);
    let edge = |p: f32, h: f32| 1.0 - smoothstep(h - soft, h + soft, p.abs());
    edge(x, half[0]) * edge(y, half[1])
}

/// Radiance (linear, 1.0 = display white) arriving from direction `d`.
fn radiance(d: V) -> V {
    let y = d[1];
    // Sky: pale at the horizon, a deeper blue-grey overhead.
    let horizon = [0.42, 0.42, 0.44];
    let zenith = [0.16, 0.2, 0.3];
    let sky = lerp(horizon, zenith, y.max(0.0).powf(0.6));
    // Floor: a warm mid grey, darker straight down.
    let ground = lerp([0.14, 0.125, 0.11], [0.07, 0.065, 0.06], (-y).max(0.0).sqrt());
    let mut c = lerp(ground, sky, smoothstep(-0.03, 0.03, y));
    // Key: a warm softbox up and to the front left (towards the camera, +z).
    let key = panel(d, [-0.75, 0.6, 0.55], [0.42, 0.3], 0.06) * 7.0;
    // Rim: a tall cool strip behind on the right.
    let rim = panel(d, [0.75, 0.5, -0.55], [0.07, 0.38], 0.02) * 7.0;
    // Fill: a faint wide panel on the front right.
    let fill = panel(d, [0.8, 0.15, 0.6], [0.35, 0.22], 0.1) * 1.5;
    for (i, ch) in c.iter_mut().enumerate() {
        *ch += key * [1.0, 0.9, 0.76][i] + rim * [0.8, 0.9, 1.0][i] + fill * [0.95, 0.97, 1.0][i];
    }
    c
}

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args().nth(1).ok_or("usage: make_env OUT.exr")?;
    let pixel = |p: Vec2<usize>| {
        // Texel centre to direction (docs/environment-light.md's lat-long).
        let u = (p.x() as f32 + 0.5) / WIDTH as f32;
        let v = (p.y() as f32 + 0.5) / HEIGHT as f32;
        let (phi, theta) = ((2.0 * u - 1.0) * PI, v * PI);
        let d = [theta.sin() * phi.sin(), theta.cos(), -theta.sin() * phi.cos()];
        let c = radiance(d);
        (f16::from_f32(c[0] * WHITE), f16::from_f32(c[1] * WHITE), f16::from_f32(c[2] * WHITE))
    };
    let image =
        Image::from_encoded_channels((WIDTH, HEIGHT), Encoding::SMALL_LOSSLESS, SpecificChannels::rgb(pixel));
    image.write().to_file(&out)?;
    println!("wrote {out} ({WIDTH}×{HEIGHT})");
    Ok(())
}
