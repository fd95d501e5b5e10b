//! Camera rays of a pinhole camera: pixel `(x, y)` with `y` growing downwards,
//! the vertical field of view from the camera, the aspect from the image.

use crate::raycast::Ray;
use crate::scene::Camera;
use glam::Vec3;

/// Generates camera rays for one image size.
#[derive(Clone, Copy, Debug)]
pub struct CameraRays {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    width: f32,
    height: f32,
}

impl CameraRays {
    /// Rays of `camera` for a `width x height` image. `right = forward x up`
    /// (right-handed world: the Cornell camera looking along +z sees +x on its left).
    pub fn new(camera: &Camera, width: u32, height: u32) -> Self {
        let forward = camera.forward.normalize_or(Vec3::Z);
        let mut right = forward.cross(camera.up);
        if right.length_squared() < 1e-12 {
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        let up = right.cross(forward);
        let tan_half = (camera.vfov_deg.clamp(1e-3, 179.0).to_radians() * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        CameraRays {
            eye: camera.eye,
            forward,
            right: right * tan_half * aspect,
            up: up * tan_half,
            width: width as f32,
            height: height as f32,
        }
    }

    /// The ray through image position `(px, py)` in pixels (pixel centres at `+0.5`).
    pub fn ray(&self, px: f32, py: f32) -> Ray {
        let sx = 2.0 * px / self.width - 1.0;
        let sy = 1.0 - 2.0 * py / self.height;
        let dir = (self.forward + self.right * sx + self.up * sy).normalize();
        Ray::new(self.eye, dir)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centre_ray_is_forward_and_corners_span_the_fov() {
        let cam = Camera::cornell();
        let rays = CameraRays::new(&cam, 64, 32);
        let c = rays.ray(32.0, 16.0);
        assert!((c.dir - Vec3::Z).length() < 1e-6);
        // Top edge: angle to forward is half the vertical fov.
        let top = rays.ray(32.0, 0.0);
        let angle = top.dir.dot(Vec3::Z).acos().to_degrees();
        assert!((angle - cam.vfov_deg / 2.0).abs() < 1e-3, "{angle}");
        assert!(top.dir.y > 0.0);
        // Left of the image is +x for the Cornell camera (red wall on the left).
        assert!(rays.ray(0.0, 16.0).dir.x > 0.0);
    }
}
