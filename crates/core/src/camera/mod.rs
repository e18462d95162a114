//! Cameras (Mitsuba 3's `perspective`, `thinlens` and `orthographic` sensors) on a film with a
//! pixel filter (`filter`). `fov` is in degrees across the axis named by `fov_axis`, raster x grows
//! to the right and y downwards; `principal_point_offset` shifts the film in fractions of its size
//! (Mitsuba's definition: the ray of raster position x is the centred camera's ray of x + offset
//! · size).
//!
//! Besides generating rays the camera exposes what light tracing and BDPT need: the importance We
//! of a direction, the pdfs of the camera's positional and directional sampling, a sampled
//! connection from a world point to the lens, and the projection of a world point onto the raster.
//!
//! Importance is normalised per pixel for the box of one pixel (the filter's weights are applied
//! by the film, see `filter`): a pixel's value is the mean radiance over its raster square, so
//! We(ω) = N_pixels / (A · cos⁴θ), where A is the image-plane area at unit distance and θ the
//! angle to the viewing axis.
//!
//! Measures. A pinhole's position is a delta (its density the discrete 1). A thin lens samples
//! its aperture point uniformly, the same way for every technique that has a camera vertex (camera
//! rays and lens connections alike) and no technique hits the lens, so the aperture density
//! 1/(π r²) is common to every p_s and is folded out: positional density 1, importance stated per
//! aperture sample (We · π r² = the pinhole's N / (A cos⁴θ), θ measured at the lens point), and
//! the directional pdf given the lens point is the pinhole's 1 / (A cos³θ) (the focal plane at
//! distance F maps raster area to solid angle as the unit plane does from the eye: dA_F = F² A/N
//! per pixel, dω = dA_F cos³θ / F²). An orthographic camera is a delta in direction: its rays
//! leave the film rectangle (area S) along the viewing axis, its positional density is film-wide
//! uniform and its directional density the discrete 1, and a deterministic connection to it
//! (t = 1) is refused like a join to a directional light (`Camera::connect` returns `None`; the
//! camera vertex is flagged `delta`).

pub mod filter;

pub use filter::{FilmFilter, FilmSample, FilterShape, PixelFilter};

use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::{sample_concentric_disk, Sampler};

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FovAxis {
    X,
    Y,
    Smaller,
    Larger,
}

/// How the film maps to rays.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lens {
    /// Mitsuba's `perspective`: every ray leaves the eye.
    Pinhole,
    /// Mitsuba's `thinlens`: a ray leaves a uniform point of the aperture disk (radius
    /// `aperture_radius`, in the plane through the eye normal to the viewing axis) towards the
    /// point at depth `focus_distance` that the pinhole ray of the same raster position meets.
    ThinLens {
        aperture_radius: f32,
        focus_distance: f32,
    },
    /// Mitsuba's `orthographic`: rays along the viewing axis from the rectangle through the eye
    /// of half width `half_width` (world units; the half height follows the film's aspect).
    Orthographic { half_width: f32 },
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
    lens: Lens,
    /// Mitsuba's `principal_point_offset_x/y`, in fractions of the film's width and height.
    principal_offset: Vec2,
    /// Half extents of the image plane: at unit distance (perspective, thin lens), in world units
    /// at the eye (orthographic).
    tan_half: Vec2,
    /// Image-plane area at unit distance (A), or the film rectangle's area (orthographic, S).
    plane_area: f32,
    film: FilmFilter,
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

/// Where a world point lands on the film, seen from the centre of the lens.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    pub raster: Vec2,
    /// Unit direction from the camera to the point.
    pub dir: Vec3,
    pub distance: f32,
    /// We of that direction (per pixel, see module docs).
    pub importance: f32,
}

/// A world point joined to a sampled point of the lens (light tracing, BDPT's t = 1).
#[derive(Clone, Copy, Debug)]
pub struct LensConnection {
    /// The lens point: the camera vertex of the connection.
    pub origin: Vec3,
    /// Unit direction from `origin` to the point.
    pub dir: Vec3,
    pub distance_squared: f32,
    pub raster: Vec2,
    /// We per aperture sample (module docs) and cos θ at the lens.
    pub importance: f32,
    pub cos_lens: f32,
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
            lens: Lens::Pinhole,
            principal_offset: Vec2::ZERO,
            tan_half,
            plane_area: 4.0 * tan_half.x * tan_half.y,
            film: FilmFilter::new(PixelFilter::default(), width, height),
        })
    }

    /// The same view through a thin lens (Mitsuba's `thinlens`: `aperture_radius`,
    /// `focus_distance`, both in world units).
    pub fn thin_lens(self, aperture_radius: f32, focus_distance: f32) -> Result<Camera, String> {
        if !(aperture_radius > 0.0 && aperture_radius.is_finite()) {
            return Err(format!(
                "thinlens aperture_radius must be positive and finite, got {aperture_radius}"
            ));
        }
        if !(focus_distance > 0.0 && focus_distance.is_finite()) {
            return Err(format!(
                "thinlens focus_distance must be positive and finite, got {focus_distance}"
            ));
        }
        Ok(Camera {
            lens: Lens::ThinLens {
                aperture_radius,
                focus_distance,
            },
            ..self
        })
    }

    /// The same position and axis as an orthographic camera whose film rectangle at the eye is
    /// `2 half_width` wide (the height follows the aspect).
    pub fn orthographic(self, half_width: f32) -> Result<Camera, String> {
        if !(half_width > 0.0 && half_width.is_finite()) {
            return Err(format!(
                "orthographic half width must be positive and finite, got {half_width}"
            ));
        }
        Ok(Camera {
            lens: Lens::Orthographic { half_width },
            ..self
        }
        .with_resolution(self.width, self.height))
    }

    /// Mitsuba's `principal_point_offset_x/y` (fractions of the film's width and height).
    pub fn with_principal_point_offset(self, offset: Vec2) -> Result<Camera, String> {
        if !(offset.x.is_finite() && offset.y.is_finite()) {
            return Err(format!(
                "principal point offset must be finite, got {offset}"
            ));
        }
        Ok(Camera {
            principal_offset: offset,
            ..self
        })
    }

    /// The same camera with another pixel filter.
    pub fn with_filter(self, filter: PixelFilter) -> Camera {
        Camera {
            film: FilmFilter::new(filter, self.width, self.height),
            ..self
        }
    }

    /// The same view at another resolution (tests and previews render scenes smaller): the fov
    /// spans the axis `fov_axis` names at the new resolution, exactly as `look_at` would set it.
    /// A zero dimension is raised to 1.
    pub fn with_resolution(&self, width: u32, height: u32) -> Camera {
        let (width, height) = (width.max(1), height.max(1));
        let tan_half = match self.lens {
            Lens::Orthographic { half_width } => {
                Vec2::new(half_width, half_width * height as f32 / width as f32)
            }
            _ => tan_half(self.fov_deg, self.fov_axis, width, height),
        };
        Camera {
            width,
            height,
            tan_half,
            plane_area: 4.0 * tan_half.x * tan_half.y,
            film: FilmFilter::new(self.film.filter.clone(), width, height),
            ..self.clone()
        }
    }

    pub fn lens(&self) -> Lens {
        self.lens
    }

    pub fn filter(&self) -> &PixelFilter {
        &self.film.filter
    }

    pub fn film(&self) -> &FilmFilter {
        &self.film
    }

    pub fn principal_point_offset(&self) -> Vec2 {
        self.principal_offset
    }

    /// Whether the camera is a delta in direction (orthographic): its vertex cannot be joined.
    pub fn is_delta_direction(&self) -> bool {
        matches!(self.lens, Lens::Orthographic { .. })
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The side of one pixel's footprint at `distance` along the viewing axis (the square root of
    /// a pixel's area on the plane at that distance): the unit photon radii are relative to.
    pub fn pixel_footprint(&self, distance: f32) -> f32 {
        let per_pixel = (self.plane_area / self.pixel_count() as f32).sqrt();
        match self.lens {
            Lens::Orthographic { .. } => per_pixel,
            _ => distance * per_pixel,
        }
    }

    pub fn forward(&self) -> Vec3 {
        self.frame.z
    }

    /// Image-plane coordinates (at unit distance, or world units at the eye for orthographic) of
    /// a raster position, with the principal point offset.
    #[inline]
    fn plane_of_raster(&self, raster: Vec2) -> Vec2 {
        let ndc = Vec2::new(
            2.0 * (raster.x / self.width as f32 + self.principal_offset.x) - 1.0,
            1.0 - 2.0 * (raster.y / self.height as f32 + self.principal_offset.y),
        );
        Vec2::new(ndc.x * self.tan_half.x, ndc.y * self.tan_half.y)
    }

    /// The raster position of image-plane coordinates, if it falls on the film.
    #[inline]
    fn raster_of_plane(&self, x: f32, y: f32) -> Option<Vec2> {
        let raster = Vec2::new(
            ((x + 1.0) * 0.5 - self.principal_offset.x) * self.width as f32,
            ((1.0 - y) * 0.5 - self.principal_offset.y) * self.height as f32,
        );
        (raster.x >= 0.0
            && raster.y >= 0.0
            && raster.x < self.width as f32
            && raster.y < self.height as f32)
            .then_some(raster)
    }

    /// The camera sample of film pixel (x, y) from two uniform numbers, with the pixel filter's
    /// weight (`filter`); `None` when the filter's offset left the film.
    #[inline]
    pub fn sample_pixel(&self, x: u32, y: u32, u: Vec2) -> Option<FilmSample> {
        self.film.sample_pixel(x, y, u)
    }

    /// The ray through a raster position (pixel (i, j) covers [i, i+1) × [j, j+1)) from the
    /// centre of the lens.
    #[inline]
    pub fn generate_ray(&self, raster: Vec2) -> Ray {
        let plane = self.plane_of_raster(raster);
        match self.lens {
            Lens::Orthographic { .. } => Ray::new(
                self.eye + self.frame.to_world(Vec3::new(plane.x, plane.y, 0.0)),
                self.frame.z,
            ),
            _ => {
                let local = Vec3::new(plane.x, plane.y, 1.0);
                Ray::new(self.eye, self.frame.to_world(local).normalize())
            }
        }
    }

    /// Numbers `sample_ray` and `connect` draw for the lens: two for a thin lens, none otherwise
    /// (so pinhole renders keep their random streams).
    #[inline]
    fn lens_point(&self, sampler: &mut Sampler) -> Option<(Vec2, f32)> {
        match self.lens {
            Lens::ThinLens {
                aperture_radius,
                focus_distance,
            } => Some((
                sample_concentric_disk(sampler.next_2d()) * aperture_radius,
                focus_distance,
            )),
            _ => None,
        }
    }

    /// The primary ray of a raster position: through a sampled lens point for a thin lens (two
    /// numbers from `sampler`), `generate_ray` otherwise. The ray's origin is the camera vertex.
    #[inline]
    pub fn sample_ray(&self, raster: Vec2, sampler: &mut Sampler) -> Ray {
        let Some((lens, focus)) = self.lens_point(sampler) else {
            return self.generate_ray(raster);
        };
        let plane = self.plane_of_raster(raster);
        let focus_point = Vec3::new(plane.x * focus, plane.y * focus, focus);
        let local = focus_point - Vec3::new(lens.x, lens.y, 0.0);
        Ray::new(
            self.eye + self.frame.to_world(Vec3::new(lens.x, lens.y, 0.0)),
            self.frame.to_world(local).normalize(),
        )
    }

    /// Raster position of a direction from the centre of the lens, if it falls on the film.
    pub fn raster_of(&self, dir: Vec3) -> Option<Vec2> {
        self.raster_from(self.eye, dir)
    }

    /// Raster position of the ray from camera vertex `from` (a lens point; any point of the film
    /// rectangle for orthographic, whose direction is the axis) along `dir`, if on the film.
    #[inline]
    pub fn raster_from(&self, from: Vec3, dir: Vec3) -> Option<Vec2> {
        match self.lens {
            Lens::Pinhole => {
                let l = self.frame.to_local(dir);
                if l.z <= 0.0 {
                    return None;
                }
                self.raster_of_plane(l.x / (l.z * self.tan_half.x), l.y / (l.z * self.tan_half.y))
            }
            Lens::ThinLens { focus_distance, .. } => {
                let l = self.frame.to_local(dir);
                if l.z <= 0.0 {
                    return None;
                }
                // Where the ray meets the plane in focus, seen from the lens centre.
                let o = self.frame.to_local(from - self.eye);
                let t = (focus_distance - o.z) / l.z;
                let q = o + l * t;
                let (x, y) = (q.x / focus_distance, q.y / focus_distance);
                self.raster_of_plane(x / self.tan_half.x, y / self.tan_half.y)
            }
            Lens::Orthographic { .. } => {
                let o = self.frame.to_local(from - self.eye);
                self.raster_of_plane(o.x / self.tan_half.x, o.y / self.tan_half.y)
            }
        }
    }

    /// We(from, ω) per pixel (per aperture sample for a thin lens; the film-area importance N / S
    /// with the direction's delta stripped for orthographic); zero off the film.
    pub fn importance(&self, from: Vec3, dir: Vec3) -> f32 {
        if self.raster_from(from, dir).is_none() {
            return 0.0;
        }
        self.importance_on_film(dir)
    }

    /// `importance` for a direction already known to reach the film (`connect` has its raster).
    #[inline]
    fn importance_on_film(&self, dir: Vec3) -> f32 {
        if self.is_delta_direction() {
            return self.pixel_count() as f32 / self.plane_area;
        }
        let cos = dir.dot(self.frame.z);
        self.pixel_count() as f32 / (self.plane_area * cos * cos * cos * cos)
    }

    /// Solid-angle pdf of the direction of a primary ray from camera vertex `from` whose raster
    /// position is uniform over the whole film (zero off the film); the discrete 1 for
    /// orthographic. The positional density is 1 (module docs).
    ///
    /// The MIS weights of every estimator read this film-wide uniform density whatever the pixel
    /// filter: any weights that sum to one over the techniques keep every pixel unbiased, these
    /// are the same for every filter, and for the box of one pixel they are Veach's heuristics.
    pub fn pdf_dir(&self, from: Vec3, dir: Vec3) -> f32 {
        if self.raster_from(from, dir).is_none() {
            return 0.0;
        }
        if self.is_delta_direction() {
            return 1.0;
        }
        let cos = dir.dot(self.frame.z);
        1.0 / (self.plane_area * cos * cos * cos)
    }

    /// Joins world point `p` to the lens: the pinhole's eye, or a uniform aperture point (two
    /// numbers from `sampler`). `None` off the film, behind the lens, or for an orthographic
    /// camera (a delta in direction: no deterministic connection reaches it).
    pub fn connect(&self, p: Vec3, sampler: &mut Sampler) -> Option<LensConnection> {
        let origin = match self.lens {
            Lens::Orthographic { .. } => return None,
            Lens::Pinhole => self.eye,
            Lens::ThinLens { .. } => {
                let (lens, _) = self.lens_point(sampler)?;
                self.eye + self.frame.to_world(Vec3::new(lens.x, lens.y, 0.0))
            }
        };
        let d = p - origin;
        let distance_squared = d.length_squared();
        if !(distance_squared > 0.0) {
            return None;
        }
        let dir = d / distance_squared.sqrt();
        // The direction in the camera frame, once: its z is the cosine at the lens that the
        // raster position, We and `cos_lens` each read (`raster_from`, `importance_on_film` and
        // `frame.z.dot(dir)` compute the same products in the same order, so the same bits).
        let l = self.frame.to_local(dir);
        let cos = l.z;
        let raster = match self.lens {
            Lens::Pinhole => {
                if cos <= 0.0 {
                    return None;
                }
                self.raster_of_plane(l.x / (cos * self.tan_half.x), l.y / (cos * self.tan_half.y))?
            }
            _ => self.raster_from(origin, dir)?,
        };
        Some(LensConnection {
            origin,
            dir,
            distance_squared,
            raster,
            importance: self.pixel_count() as f32 / (self.plane_area * cos * cos * cos * cos),
            cos_lens: cos,
        })
    }

    /// Joins a light at infinity in direction `dir` (unit, from the scene towards the light) to
    /// the lens: the connection's distance is 1 by convention (no 1/d² at infinity).
    pub fn connect_direction(&self, dir: Vec3, sampler: &mut Sampler) -> Option<LensConnection> {
        let origin = match self.lens {
            Lens::Orthographic { .. } => return None,
            Lens::Pinhole => self.eye,
            Lens::ThinLens { .. } => {
                let (lens, _) = self.lens_point(sampler)?;
                self.eye + self.frame.to_world(Vec3::new(lens.x, lens.y, 0.0))
            }
        };
        let raster = self.raster_from(origin, dir)?;
        Some(LensConnection {
            origin,
            dir,
            distance_squared: 1.0,
            raster,
            importance: self.importance_on_film(dir),
            cos_lens: self.frame.z.dot(dir),
        })
    }

    /// Projects a world point onto the film through the centre of the lens.
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
            importance: self.importance(self.eye, dir),
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
    fn a_thin_lens_ray_maps_back_to_its_raster_position() {
        let c = cam()
            .thin_lens(0.2, 3.0)
            .unwrap()
            .with_principal_point_offset(Vec2::new(0.05, -0.03))
            .unwrap();
        let mut s = Sampler::new(5, 0, 0);
        for r in [
            Vec2::new(0.5, 0.5),
            Vec2::new(63.2, 1.7),
            Vec2::new(31.9, 47.1),
        ] {
            for _ in 0..8 {
                let ray = c.sample_ray(r, &mut s);
                let back = c.raster_from(ray.o, ray.d).unwrap();
                assert!((back - r).length() < 1e-3, "{r} -> {back}");
                // The lens connection of a point on that ray finds the same raster position
                // from the same lens point.
                let p = ray.at(2.0);
                let lc = c.raster_from(ray.o, (p - ray.o).normalize()).unwrap();
                assert!((lc - r).length() < 1e-3);
            }
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
            c.pdf_dir(c.eye, d) as f64 * inv_pdf
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
                (c.importance(c.eye, d) * d.dot(c.forward())) as f64 * inv_pdf
            });
            assert!(
                ((mean - 1.0) / se).abs() < Z_MAX,
                "pixel ({i}, {j}): ∫ We cos θ dω = {mean} ± {se}"
            );
        }
    }
}
