//! Tiles rendered images into one gallery image (three per row), for
//! `docs/gallery.png`:
//!
//! ```sh
//! for s in marble wood copper planet brick stones; do
//!     cargo run --release -- render examples/scenes/$s.xml -o /tmp/gallery
//! done
//! cargo run --release --example gallery -- docs/gallery.png /tmp/gallery/{marble,wood,copper,planet,brick,stones}.png
//! ```
//!
//! Four images make a 2×2 sheet (`docs/volumes.png`).

use image::{GenericImage, RgbImage};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((out, inputs)) = args.split_first() else {
        return Err("usage: gallery OUT.png IMAGE...".into());
    };
    let tiles: Vec<RgbImage> =
        inputs.iter().map(|p| image::open(p).map(|i| i.to_rgb8())).collect::<Result<_, _>>()?;
    let (w, h) = tiles.first().map(|t| t.dimensions()).ok_or("no images given")?;
    let cols = if tiles.len() == 4 { 2 } else { 3.min(tiles.len()) as u32 };
    let rows = (tiles.len() as u32).div_ceil(cols);
    let mut sheet = RgbImage::new(w * cols, h * rows);
    for (i, t) in tiles.iter().enumerate() {
        if t.dimensions() != (w, h) {
            return Err(format!("{} is not {w}x{h}", inputs[i]).into());
        }
        sheet.copy_from(t, (i as u32 % cols) * w, (i as u32 / cols) * h)?;
    }
    sheet.save(out)?;
    Ok(())
}
