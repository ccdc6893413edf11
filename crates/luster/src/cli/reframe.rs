//! `--size`, `--scale` and `--crop` for scenes: the same view at another
//! resolution, or one window of it, for quick iterations on a shader.
//!
//! Each camera's image plane (its `NearPlane`, or the one `FovY` gives) is
//! kept, so `--size` and `--scale` change only how finely it is sampled, and
//! `--crop X0,Y0,X1,Y1` narrows the plane to the pixels `X0..X1` × `Y0..Y1`
//! of the (resized) image, which then renders alone: its pixels are the same
//! rays as in the full image.

use anyhow::bail;
use luster::scene::description::{CameraDesc, Description, Projection};

/// The command-line options (under `luster render`).
#[derive(clap::Args, Debug, Clone, Default)]
#[command(next_help_heading = "Resolution and crop (scenes)")]
pub struct FrameArgs {
    /// Multiply every camera's resolution by F (e.g. 0.25 for a quick preview),
    /// keeping its view.
    #[arg(long, value_name = "F", value_parser = parse_scale)]
    pub scale: Option<f32>,
    /// Render only the pixels X0..X1 × Y0..Y1 (of the image after --size or
    /// --scale); the image is that window.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = parse_crop)]
    pub crop: Option<[u32; 4]>,
    /// Print every shader call at pixel X,Y (of the image after --size,
    /// --scale and --crop): its inputs and result; `print` in shaders shows
    /// only there.
    #[arg(long, value_name = "X,Y", value_parser = parse_pixel)]
    pub debug_pixel: Option<[u32; 2]>,
}

fn parse_pixel(s: &str) -> Result<[u32; 2], String> {
    match s.split_once(',').map(|(x, y)| (x.trim().parse::<u32>(), y.trim().parse::<u32>())) {
        Some((Ok(x), Ok(y))) => Ok([x, y]),
        _ => Err(format!("\"{s}\" is not X,Y (pixels)")),
    }
}

fn parse_scale(s: &str) -> Result<f32, String> {
    match s.trim().parse::<f32>() {
        Ok(f) if f.is_finite() && f > 0.0 && f <= 64.0 => Ok(f),
        _ => Err(format!("\"{s}\" is not a scale between 0 and 64")),
    }
}

fn parse_crop(s: &str) -> Result<[u32; 4], String> {
    let parts: Vec<Option<u32>> = s.split(',').map(|t| t.trim().parse::<u32>().ok()).collect();
    match parts[..] {
        [Some(x0), Some(y0), Some(x1), Some(y1)] if x0 < x1 && y0 < y1 => Ok([x0, y0, x1, y1]),
        _ => Err(format!("\"{s}\" is not X0,Y0,X1,Y1 with X0 < X1 and Y0 < Y1 (pixels)")),
    }
}

/// Applies `size` (from `--size`), `--scale` and `--crop` to every camera.
pub fn apply(desc: &mut Description, size: Option<(u32, u32)>, args: &FrameArgs) -> anyhow::Result<()> {
    luster::shader::set_debug_pixel(args.debug_pixel);
    if size.is_none() && args.scale.is_none() && args.crop.is_none() {
        return Ok(());
    }
    for cam in &mut desc.cameras {
        reframe(cam, size, args.scale, args.crop)?;
    }
    Ok(())
}

/// The camera with the same view at a new resolution, cropped.
fn reframe(
    cam: &mut CameraDesc,
    size: Option<(u32, u32)>,
    scale: Option<f32>,
    crop: Option<[u32; 4]>,
) -> anyhow::Result<()> {
    let (w0, h0) = cam.resolution;
    let (gaze, [l, r, b, t]) = match cam.projection {
        Projection::Plane { gaze, near_plane } => (gaze, near_plane),
        Projection::LookAt { gaze_point, fov_y } => {
            let half_h = cam.near_distance * (fov_y.to_radians() * 0.5).tan();
            let half_w = half_h * w0 as f32 / h0.max(1) as f32;
            (gaze_point - cam.position, [-half_w, half_w, -half_h, half_h])
        }
    };
    let (mut w, mut h) = size.unwrap_or((w0, h0));
    if let Some(f) = scale {
        w = ((w as f32 * f).round() as u32).clamp(1, 16384);
        h = ((h as f32 * f).round() as u32).clamp(1, 16384);
    }
    let [x0, y0, x1, y1] = crop.unwrap_or([0, 0, w, h]);
    if x1 > w || y1 > h {
        bail!(
            "camera {}: --crop {x0},{y0},{x1},{y1} reaches outside its {w}x{h} image",
            if cam.id.is_empty() { "(no id)" } else { cam.id.as_str() }
        );
    }
    let (fw, fh) = ((r - l) / w as f32, (t - b) / h as f32);
    let plane = [l + fw * x0 as f32, l + fw * x1 as f32, t - fh * y1 as f32, t - fh * y0 as f32];
    cam.projection = Projection::Plane { gaze, near_plane: plane };
    cam.resolution = (x1 - x0, y1 - y0);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster::math::Vec3;
    use luster::render::camera::Camera;

    fn look_at() -> CameraDesc {
        CameraDesc {
            id: "1".into(),
            position: Vec3::new(0.0, 1.0, 5.0),
            up: Vec3::Y,
            projection: Projection::LookAt { gaze_point: Vec3::ZERO, fov_y: 45.0 },
            near_distance: 1.0,
            resolution: (200, 100),
            image_name: "a.png".into(),
            tonemaps: Vec::new(),
            num_samples: 1,
            noise_threshold: None,
            aperture_size: 0.0,
            focus_distance: 1.0,
            renderer: Default::default(),
            loc: Default::default(),
        }
    }

    /// A cropped pixel is the same ray as that pixel of the full image, and a
    /// scaled image covers the same view.
    #[test]
    fn crops_keep_their_rays_and_scales_their_view() {
        let full = Camera::from_desc(&look_at());
        let mut cropped = look_at();
        reframe(&mut cropped, None, None, Some([50, 20, 130, 70])).unwrap();
        assert_eq!(cropped.resolution, (80, 50));
        let cropped = Camera::from_desc(&cropped);
        let (a, b) = (full.ray(50.5 + 17.0, 20.5 + 9.0), cropped.ray(17.5, 9.5));
        assert!((a.d - b.d).length() < 1e-5, "{:?} {:?}", a.d, b.d);
        let mut half = look_at();
        reframe(&mut half, None, Some(0.5), None).unwrap();
        assert_eq!(half.resolution, (100, 50));
        let half = Camera::from_desc(&half);
        assert!((full.ray(200.0, 0.0).d - half.ray(100.0, 0.0).d).length() < 1e-5);
        let mut bad = look_at();
        assert!(reframe(&mut bad, Some((64, 32)), None, Some([0, 0, 65, 10])).is_err());
    }
}
