//! The pinhole camera of the course: an eye, an image plane at `NearDistance`
//! spanning `NearPlane` (or a vertical field of view), and the pixel grid on it.

use crate::math::{Ray, Vec3};
use crate::scene::description::{CameraDesc, Projection};

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
    /// Samples per pixel the scene asks for.
    pub num_samples: u32,
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
            num_samples: d.num_samples,
        }
    }

    /// The ray through image position `(x, y)` in pixels from the top-left
    /// corner; pixel `(i, j)`'s centre is `(i + 0.5, j + 0.5)`.
    #[inline]
    pub fn ray(&self, x: f32, y: f32) -> Ray {
        let p = self.corner + self.du * x + self.dv * y;
        Ray::new(self.eye, (p - self.eye).normalize())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Loc;

    fn desc(projection: Projection, res: (u32, u32)) -> CameraDesc {
        CameraDesc {
            id: "1".into(),
            position: Vec3::ZERO,
            up: Vec3::Y,
            projection,
            near_distance: 1.0,
            resolution: res,
            image_name: "x.png".into(),
            num_samples: 1,
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
}
