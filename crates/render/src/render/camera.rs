//! The camera of the course: an eye, an image plane at `NearDistance` spanning
//! `NearPlane` (or a vertical field of view), and the pixel grid on it. With an
//! `ApertureSize`, a thin lens: rays start on a square lens of that edge
//! around the eye and pass through the point where the pinhole ray meets the
//! plane `FocusDistance` ahead (measured along the gaze), so that plane is sharp.

use luster_core::math::{Ray, Vec3};
use luster_scene::description::{CameraDesc, Projection};

/// A camera ready to make rays.
#[derive(Clone, Debug)]
pub struct Camera {
    eye: Vec3,
    /// The top-left corner of the image plane.
    corner: Vec3,
    /// One pixel to the right.
    du: Vec3,
    /// One pixel down.
    dv: Vec3,
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Output file name.
    pub image_name: String,
    /// Tone mappings for the outputs (see [`luster_core::image::outputs`]).
    pub tonemaps: Vec<luster_core::tonemap::Tonemap>,
    /// The scene's display transform (set by the scene build; `course` from
    /// [`Camera::from_desc`]).
    pub display: luster_core::tonemap::Display,
    /// Samples per pixel the scene asks for.
    pub num_samples: u32,
    /// Adaptive sampling's threshold the scene asks for (`<NoiseThreshold>`).
    pub noise_threshold: Option<f32>,
    /// The integrator the camera asks for (`<Renderer>`, `<RendererParams>`).
    pub renderer: luster_scene::description::RendererDesc,
    /// Unit gaze, and the lens's right and up axes scaled by the aperture edge.
    gaze: Vec3,
    lens_u: Vec3,
    lens_v: Vec3,
    focus_distance: f32,
}

impl Camera {
    /// From the description. The basis is `w = -gaze`, `u = up × w`, `v = w × u`,
    /// so an `Up` that is not perpendicular to the gaze is straightened.
    pub fn from_desc(d: &CameraDesc) -> Camera {
        let (width, height) = d.resolution;
        let (gaze, [l, r, b, t]) = match d.projection {
            Projection::Plane { gaze, near_plane } => (gaze.normalize(), near_plane),
            Projection::LookAt { gaze_point, fov_y } => {
                let half_h = d.near_distance * (fov_y.to_radians() * 0.5).tan();
                let half_w = half_h * width as f32 / height as f32;
                ((gaze_point - d.position).normalize(), [-half_w, half_w, -half_h, half_h])
            }
        };
        let w = -gaze;
        let u = d.up.cross(w).normalize_or(gaze.any_orthonormal_vector());
        let v = w.cross(u);
        let center = d.position + gaze * d.near_distance;
        Camera {
            eye: d.position,
            corner: center + u * l + v * t,
            du: u * ((r - l) / width as f32),
            dv: -v * ((t - b) / height as f32),
            width,
            height,
            image_name: d.image_name.clone(),
            tonemaps: d.tonemaps.clone(),
            display: Default::default(),
            num_samples: d.num_samples,
            noise_threshold: d.noise_threshold,
            renderer: d.renderer,
            gaze,
            lens_u: u * d.aperture_size,
            lens_v: v * d.aperture_size,
            focus_distance: d.focus_distance,
        }
    }

    /// The ray through image position `(x, y)` in pixels from the top-left
    /// corner; pixel `(i, j)`'s centre is `(i + 0.5, j + 0.5)`.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let p = self.corner + self.du * x + self.dv * y;
        Ray::new(self.eye, (p - self.eye).normalize())
    }

    /// The angle one pixel spans at the image centre, radians: the spread of
    /// a ray cone (Akenine-Möller et al., Ray Tracing Gems ch. 20) that sizes
    /// texture footprints for mipmapping.
    pub fn pixel_spread(&self) -> f32 {
        let to_center =
            (self.corner + self.du * (self.width as f32 * 0.5) + self.dv * (self.height as f32 * 0.5)
                - self.eye)
                .length();
        let pixel = self.du.length().min(self.dv.length());
        if to_center > 0.0 {
            (pixel / to_center).atan()
        } else {
            0.0
        }
    }

    /// The camera's frame for shaders' camera space: x right, y up, z back.
    pub fn view(&self) -> crate::texture::View {
        let right = self.du.normalize_or_zero();
        let up = -self.dv.normalize_or_zero();
        crate::texture::View { eye: self.eye, right, up, back: right.cross(up) }
    }

    /// Whether the camera has a lens (depth of field).
    pub fn has_lens(&self) -> bool {
        self.lens_u != Vec3::ZERO
    }

    /// The ray through image position `(x, y)` from lens position `lens` in
    /// `[0, 1)²` (ignored for a pinhole).
    #[inline]
    pub fn lens_ray(&self, x: f32, y: f32, lens: (f32, f32)) -> Ray {
        let pinhole = self.ray(x, y);
        if !self.has_lens() {
            return pinhole;
        }
        let focus = self.eye + pinhole.d * (self.focus_distance / pinhole.d.dot(self.gaze));
        let o = self.eye + self.lens_u * (lens.0 - 0.5) + self.lens_v * (lens.1 - 0.5);
        Ray::new(o, (focus - o).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use luster_scene::Loc;

    fn desc(projection: Projection, res: (u32, u32)) -> CameraDesc {
        CameraDesc {
            id: "1".into(),
            position: Vec3::ZERO,
            up: Vec3::Y,
            projection,
            near_distance: 1.0,
            resolution: res,
            image_name: "x.png".into(),
            tonemaps: Vec::new(),
            num_samples: 1,
            noise_threshold: None,
            aperture_size: 0.0,
            focus_distance: 1.0,
            renderer: Default::default(),
            loc: Loc::default(),
        }
    }

    #[test]
    fn centre_ray_follows_gaze_and_corners_span_near_plane() {
        let c = Camera::from_desc(&desc(
            Projection::Plane { gaze: -Vec3::Z, near_plane: [-1.0, 1.0, -1.0, 1.0] },
            (2, 2),
        ));
        assert!((c.ray(1.0, 1.0).d - -Vec3::Z).length() < 1e-6);
        // The top-left corner of the image is at (-1, 1, -1): x grows right, y grows down.
        let d = c.ray(0.0, 0.0).d;
        assert!((d - Vec3::new(-1.0, 1.0, -1.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn look_at_matches_equivalent_near_plane() {
        let a = Camera::from_desc(&desc(
            Projection::LookAt { gaze_point: Vec3::new(0.0, 0.0, -3.0), fov_y: 90.0 },
            (200, 100),
        ));
        let b = Camera::from_desc(&desc(
            Projection::Plane { gaze: -Vec3::Z, near_plane: [-2.0, 2.0, -1.0, 1.0] },
            (200, 100),
        ));
        for (x, y) in [(0.5, 0.5), (199.5, 3.5), (100.0, 50.0)] {
            assert!((a.ray(x, y).d - b.ray(x, y).d).length() < 1e-5);
        }
    }

    #[test]
    fn lens_rays_meet_on_the_focal_plane() {
        let mut d = desc(Projection::Plane { gaze: -Vec3::Z, near_plane: [-1.0, 1.0, -1.0, 1.0] }, (10, 10));
        d.aperture_size = 0.5;
        d.focus_distance = 4.0;
        let c = Camera::from_desc(&d);
        let pin = c.ray(2.5, 7.5);
        let target = pin.at(4.0 / pin.d.dot(-Vec3::Z));
        for lens in [(0.0, 0.0), (0.9, 0.1), (0.5, 0.5), (0.3, 0.99)] {
            let r = c.lens_ray(2.5, 7.5, lens);
            // Origins spread over the lens, all rays pass through the same focal point.
            assert!(r.o.z.abs() < 1e-6 && r.o.x.abs() <= 0.25 + 1e-6 && r.o.y.abs() <= 0.25 + 1e-6);
            let t = (target - r.o).dot(r.d);
            assert!((r.at(t) - target).length() < 1e-4);
        }
    }
}
