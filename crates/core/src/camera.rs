//! Pinhole perspective camera with a box pixel filter, following Mitsuba 3's conventions: `fov` is
//! in degrees across the axis named by `fov_axis`, raster x grows to the right and y downwards.
//!
//! Besides generating rays it exposes what light tracing and BDPT need: the importance We of a
//! direction, the pdfs of the camera's positional (delta) and directional sampling, and the
//! projection of a world point onto the raster.
//!
//! Importance is normalised per pixel: a pixel's value is the mean radiance over its raster square,
//! so We(ω) = N_pixels / (A · cos⁴θ), where A is the image-plane area at unit distance and θ the
//! angle to the viewing axis (pinhole: the position is a delta, its pdf is 1 by convention).

use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum FovAxis {
    X,
    Y,
    Smaller,
    Larger,
}

#[derive(Clone, Debug)]
pub struct Camera {
    pub eye: Vec3,
    /// x = image right, y = image up, z = viewing direction.
    frame: Frame,
    pub width: u32,
    pub height: u32,
    /// Half extents of the image plane at unit distance.
    tan_half: Vec2,
    /// Image-plane area at unit distance.
    plane_area: f32,
}

/// Where a world point lands on the film, seen from the camera.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    pub raster: Vec2,
    /// Unit direction from the camera to the point.
    pub dir: Vec3,
    pub distance: f32,
    /// We of that direction (per pixel, see module docs).
    pub importance: f32,
}

impl Camera {
    /// Fails with a description when the view is degenerate.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        fov_deg: f32,
        fov_axis: FovAxis,
        width: u32,
        height: u32,
    ) -> Result<Camera, String> {
        let forward = target - eye;
        if !(forward.length() > 0.0) {
            return Err("camera eye and target coincide".into());
        }
        let forward = forward.normalize();
        let right = forward.cross(up);
        if !(right.length() > 1e-6 * up.length()) {
            return Err("camera up is parallel to the viewing direction".into());
        }
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(format!(
                "camera fov {fov_deg} must lie strictly between 0 and 180 degrees"
            ));
        }
        if width == 0 || height == 0 {
            return Err("camera resolution must be at least 1×1".into());
        }
        let right = right.normalize();
        let true_up = right.cross(forward);
        let t = (fov_deg.to_radians() * 0.5).tan();
        let aspect = width as f32 / height as f32;
        let along_x = match fov_axis {
            FovAxis::X => true,
            FovAxis::Y => false,
            FovAxis::Smaller => width <= height,
            FovAxis::Larger => width >= height,
        };
        let tan_half = if along_x {
            Vec2::new(t, t / aspect)
        } else {
            Vec2::new(t * aspect, t)
        };
        Ok(Camera {
            eye,
            frame: Frame {
                x: right,
                y: true_up,
                z: forward,
            },
            width,
            height,
            tan_half,
            plane_area: 4.0 * tan_half.x * tan_half.y,
        })
    }

    /// The same view at another resolution (tests and previews render scenes smaller). The field of
    /// view is kept along the axis it was given for.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        let mut c = self.clone();
        let aspect = width as f32 / height as f32;
        let old_aspect = self.width as f32 / self.height as f32;
        // Keep the horizontal extent when the old image was at least as wide as tall, else the vertical.
        c.tan_half = if old_aspect >= 1.0 {
            Vec2::new(self.tan_half.x, self.tan_half.x / aspect)
        } else {
            Vec2::new(self.tan_half.y * aspect, self.tan_half.y)
        };
        c.width = width;
        c.height = height;
        c.plane_area = 4.0 * c.tan_half.x * c.tan_half.y;
        c
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    pub fn forward(&self) -> Vec3 {
        self.frame.z
    }

    /// The primary ray through a raster position (pixel (i, j) covers [i, i+1) × [j, j+1)).
    pub fn generate_ray(&self, raster: Vec2) -> Ray {
        let ndc = Vec2::new(
            2.0 * raster.x / self.width as f32 - 1.0,
            1.0 - 2.0 * raster.y / self.height as f32,
        );
        let local = Vec3::new(ndc.x * self.tan_half.x, ndc.y * self.tan_half.y, 1.0);
        Ray::new(self.eye, self.frame.to_world(local).normalize())
    }

    /// Raster position of a direction from the eye, if it falls on the film.
    pub fn raster_of(&self, dir: Vec3) -> Option<Vec2> {
        let l = self.frame.to_local(dir);
        if l.z <= 0.0 {
            return None;
        }
        let x = l.x / (l.z * self.tan_half.x);
        let y = l.y / (l.z * self.tan_half.y);
        let raster = Vec2::new(
            (x + 1.0) * 0.5 * self.width as f32,
            (1.0 - y) * 0.5 * self.height as f32,
        );
        (raster.x >= 0.0
            && raster.y >= 0.0
            && raster.x < self.width as f32
            && raster.y < self.height as f32)
            .then_some(raster)
    }

    /// We(ω) per pixel for a unit direction from the eye; zero off the film.
    pub fn importance(&self, dir: Vec3) -> f32 {
        if self.raster_of(dir).is_none() {
            return 0.0;
        }
        let cos = dir.dot(self.frame.z);
        self.pixel_count() as f32 / (self.plane_area * cos * cos * cos * cos)
    }

    /// Solid-angle pdf of the direction of a primary ray whose raster position is uniform over the
    /// whole film (zero off the film). The positional pdf of a pinhole is a delta (1).
    pub fn pdf_dir(&self, dir: Vec3) -> f32 {
        if self.raster_of(dir).is_none() {
            return 0.0;
        }
        let cos = dir.dot(self.frame.z);
        1.0 / (self.plane_area * cos * cos * cos)
    }

    /// Projects a world point onto the film.
    pub fn project(&self, p: Vec3) -> Option<Projection> {
        let to = p - self.eye;
        let distance = to.length();
        if !(distance > 0.0) {
            return None;
        }
        let dir = to / distance;
        let raster = self.raster_of(dir)?;
        Some(Projection {
            raster,
            dir,
            distance,
            importance: self.importance(dir),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cam() -> Camera {
        Camera::look_at(
            Vec3::new(0.0, 0.0, 3.9),
            Vec3::ZERO,
            Vec3::Y,
            39.3077,
            FovAxis::X,
            64,
            48,
        )
        .unwrap()
    }

    #[test]
    fn projection_inverts_ray_generation() {
        let c = cam();
        for r in [
            Vec2::new(0.5, 0.5),
            Vec2::new(63.2, 1.7),
            Vec2::new(31.9, 47.1),
        ] {
            let ray = c.generate_ray(r);
            let back = c.project(ray.at(2.5)).unwrap().raster;
            assert!((back - r).length() < 1e-3, "{r} -> {back}");
        }
    }

    #[test]
    fn image_right_is_world_plus_x_for_the_cornell_view() {
        let c = cam();
        assert!(c.generate_ray(Vec2::new(63.0, 24.0)).d.x > 0.0);
        assert!(c.generate_ray(Vec2::new(32.0, 0.0)).d.y > 0.0);
    }

    #[test]
    fn directional_pdf_integrates_to_one_over_the_film() {
        // ∫ pdf_dir dω over the film, by a Riemann sum over raster cells: dω = cos³θ dA / 1.
        let c = cam();
        let n = 200;
        let mut total = 0.0f64;
        for j in 0..n {
            for i in 0..n {
                let r = Vec2::new(
                    (i as f32 + 0.5) / n as f32 * 64.0,
                    (j as f32 + 0.5) / n as f32 * 48.0,
                );
                let d = c.generate_ray(r).d;
                let cos = d.dot(c.forward()) as f64;
                let da = c.plane_area as f64 / (n * n) as f64;
                total += c.pdf_dir(d) as f64 * cos * cos * cos * da;
            }
        }
        assert!((total - 1.0).abs() < 1e-3, "{total}");
    }
}
