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

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
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
    /// The field of view as given (degrees, and the axis it spans), so a change of resolution
    /// keeps it along that axis.
    fov_deg: f32,
    fov_axis: FovAxis,
    /// Half extents of the image plane at unit distance.
    tan_half: Vec2,
    /// Image-plane area at unit distance.
    plane_area: f32,
}

/// Half extents of the image plane at unit distance for a fov across `axis` (Mitsuba's rule for
/// `smaller` / `larger`: the axis of the smaller or larger image side).
fn tan_half(fov_deg: f32, axis: FovAxis, width: u32, height: u32) -> Vec2 {
    let t = (fov_deg.to_radians() * 0.5).tan();
    let aspect = width as f32 / height as f32;
    let along_x = match axis {
        FovAxis::X => true,
        FovAxis::Y => false,
        FovAxis::Smaller => width <= height,
        FovAxis::Larger => width >= height,
    };
    if along_x {
        Vec2::new(t, t / aspect)
    } else {
        Vec2::new(t * aspect, t)
    }
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
        let tan_half = tan_half(fov_deg, fov_axis, width, height);
        Ok(Camera {
            eye,
            frame: Frame {
                x: right,
                y: true_up,
                z: forward,
            },
            width,
            height,
            fov_deg,
            fov_axis,
            tan_half,
            plane_area: 4.0 * tan_half.x * tan_half.y,
        })
    }

    /// The same view at another resolution (tests and previews render scenes smaller): the fov
    /// spans the axis `fov_axis` names at the new resolution, exactly as `look_at` would set it.
    /// A zero dimension is raised to 1.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        let (width, height) = (width.max(1), height.max(1));
        let tan_half = tan_half(self.fov_deg, self.fov_axis, width, height);
        Camera {
            width,
            height,
            tan_half,
            plane_area: 4.0 * tan_half.x * tan_half.y,
            ..self.clone()
        }
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The side of one pixel's footprint at `distance` along the viewing axis (the square root of
    /// a pixel's area on the plane at that distance): the unit photon radii are relative to.
    pub fn pixel_footprint(&self, distance: f32) -> f32 {
        distance * (self.plane_area / self.pixel_count() as f32).sqrt()
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
    use crate::sampling::{sample_uniform_cone, uniform_cone_pdf, Sampler};

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

    fn cam_with(axis: FovAxis, width: u32, height: u32) -> Camera {
        Camera::look_at(
            Vec3::new(0.3, -0.2, 3.9),
            Vec3::new(0.1, 0.2, 0.0),
            Vec3::Y,
            39.3077,
            axis,
            width,
            height,
        )
        .unwrap()
    }

    /// Full angle between the rays through the middles of two opposite film edges, in degrees.
    fn measured_fov(c: &Camera, along_x: bool) -> f32 {
        let (w, h) = (c.width as f32, c.height as f32);
        let (a, b) = if along_x {
            (Vec2::new(0.0, 0.5 * h), Vec2::new(w, 0.5 * h))
        } else {
            (Vec2::new(0.5 * w, 0.0), Vec2::new(0.5 * w, h))
        };
        let (da, db) = (c.generate_ray(a).d, c.generate_ray(b).d);
        da.dot(db).clamp(-1.0, 1.0).acos().to_degrees()
    }

    #[test]
    fn a_new_resolution_keeps_the_fov_along_the_named_axis() {
        for axis in [FovAxis::X, FovAxis::Y, FovAxis::Smaller, FovAxis::Larger] {
            let c = cam_with(axis, 64, 48);
            // Landscape to portrait and back: `smaller`/`larger` then name the other side.
            for (w, h) in [(32, 48), (48, 16), (64, 48), (13, 7)] {
                let r = c.with_resolution(w, h);
                let along_x = match axis {
                    FovAxis::X => true,
                    FovAxis::Y => false,
                    FovAxis::Smaller => w <= h,
                    FovAxis::Larger => w >= h,
                };
                let fov = measured_fov(&r, along_x);
                // acos of a dot product near cos 39° loses ~1e-7 / sin 39° rad: far below 1e-3°.
                assert!((fov - 39.3077).abs() < 1e-3, "{axis:?} at {w}x{h}: {fov}");
                // And it is what look_at makes of the same view at that resolution.
                let direct = cam_with(axis, w, h);
                assert_eq!(
                    (r.tan_half, r.plane_area),
                    (direct.tan_half, direct.plane_area)
                );
            }
        }
    }

    #[test]
    fn a_downscale_of_the_same_aspect_gives_the_same_rays() {
        for axis in [FovAxis::X, FovAxis::Y, FovAxis::Smaller, FovAxis::Larger] {
            let c = cam_with(axis, 64, 48);
            let r = c.with_resolution(16, 12);
            for j in 0..12 {
                for i in 0..16 {
                    // Raster fractions that are exact at both resolutions.
                    let f = Vec2::new((i as f32 + 0.25) / 16.0, (j as f32 + 0.75) / 12.0);
                    let a = c.generate_ray(f * Vec2::new(64.0, 48.0));
                    let b = r.generate_ray(f * Vec2::new(16.0, 12.0));
                    assert_eq!((a.o, a.d), (b.o, b.d), "{axis:?} at {f}");
                }
            }
        }
    }

    /// Mean and standard error of `n` samples of `f`.
    fn mc(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let x = f();
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let var = (sum2 / n as f64 - mean * mean) * n as f64 / (n as f64 - 1.0);
        (mean, (var / n as f64).sqrt())
    }

    /// |z| threshold for the five Monte Carlo checks below: a two-sided tail of 6.3e-5 each, so a
    /// family false-alarm rate of 3.2e-4 (Šidák), with fixed seeds.
    const Z_MAX: f64 = 4.0;

    /// Directions uniform in a cone about `axis` of half-angle with 1 − cos = `h`: (ω, 1/pdf).
    /// The parametrisation knows nothing of the film, so a wrong cosine power in the camera shows.
    fn cone_sample(s: &mut Sampler, axis: Vec3, h: f32) -> (Vec3, f64) {
        let d = Frame::from_z(axis).to_world(sample_uniform_cone(s.next_2d(), h));
        (d.normalize(), 1.0 / uniform_cone_pdf(h) as f64)
    }

    #[test]
    fn directional_pdf_integrates_to_one_over_solid_angle() {
        let c = cam();
        // A cone about the viewing axis just wider than the film's corner direction.
        let corner = c.generate_ray(Vec2::ZERO).d;
        let h = (1.0 - corner.dot(c.forward())) * 1.05;
        let mut s = Sampler::new(17, 0, 0);
        let (mean, se) = mc(1_000_000, || {
            let (d, inv_pdf) = cone_sample(&mut s, c.forward(), h);
            c.pdf_dir(d) as f64 * inv_pdf
        });
        assert!(
            ((mean - 1.0) / se).abs() < Z_MAX,
            "∫ pdf_dir dω = {mean} ± {se}"
        );
    }

    #[test]
    fn importance_integrates_to_one_over_each_pixel() {
        // ∫_pixel We(ω) cos θ dω = 1 (the per-pixel normalisation), at the centre, an edge and
        // corners, where cos θ is smallest and a wrong power of it matters most.
        let c = cam().with_resolution(8, 6);
        let mut s = Sampler::new(18, 0, 0);
        for (i, j) in [(0u32, 0u32), (7, 5), (4, 3), (0, 3)] {
            let centre = c.generate_ray(Vec2::new(i as f32 + 0.5, j as f32 + 0.5)).d;
            // A cone about the pixel's centre direction enclosing its four corners.
            let h = [(0, 0), (1, 0), (0, 1), (1, 1)]
                .iter()
                .map(|&(a, b)| {
                    let d = c.generate_ray(Vec2::new((i + a) as f32, (j + b) as f32)).d;
                    1.0 - d.dot(centre)
                })
                .fold(0.0f32, f32::max)
                * 1.05;
            let (mean, se) = mc(400_000, || {
                let (d, inv_pdf) = cone_sample(&mut s, centre, h);
                let in_pixel = c
                    .raster_of(d)
                    .is_some_and(|r| r.x as u32 == i && r.y as u32 == j);
                if !in_pixel {
                    return 0.0;
                }
                (c.importance(d) * d.dot(c.forward())) as f64 * inv_pdf
            });
            assert!(
                ((mean - 1.0) / se).abs() < Z_MAX,
                "pixel ({i}, {j}): ∫ We cos θ dω = {mean} ± {se}"
            );
        }
    }
}
