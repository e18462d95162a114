//! `<sensor>` with its `<film>`, `<rfilter>` and `<sampler>`: the camera, resolution, pixel
//! filter and sample count.

use super::Loader;
use crate::world::LookAt;
use crate::xml::doc::Elem;
use crate::xml::props::Plugin;
use crate::xml::values::Xform;
use crate::SceneError;
use glam::{DMat4, DVec3, DVec4};
use lt_core::camera::{Camera, FilterShape, FovAxis, PixelFilter};
use lt_core::math::Vec2;

/// Parameters Mitsuba writes by default that change nothing lt renders, per plugin kind.
const SENSOR_IGNORED: [&str; 5] = [
    "near_clip",
    "far_clip",
    "focus_distance",
    "shutter_open",
    "shutter_close",
];
const FILM_IGNORED: [&str; 4] = ["pixel_format", "component_format", "file_format", "banner"];
/// The types of each kind this file builds.
pub(super) const SENSORS: [&str; 3] = ["perspective", "thinlens", "orthographic"];
pub(super) const FILMS: [&str; 1] = ["hdrfilm"];
pub(super) const RFILTERS: [&str; 6] = [
    "box",
    "tent",
    "gaussian",
    "mitchell",
    "catmullrom",
    "lanczos",
];
pub(super) const SAMPLERS: [&str; 5] = [
    "independent",
    "stratified",
    "multijitter",
    "orthogonal",
    "ldsampler",
];
const SAMPLER_IGNORED: [&str; 3] = ["seed", "jitter", "strength"];

impl<'a> Loader<'a> {
    pub(super) fn sensor(&mut self, e: &'a Elem) -> Result<((LookAt, Optics), u32), SceneError> {
        let p = self.plugin(e)?;
        if !SENSORS.contains(&p.kind) {
            return Err(super::kinds::unknown_type(self.doc, e));
        }
        self.camera_medium = self.media_of(&p, &["medium"])?.first().map(|&(_, m)| m);
        let principal = Vec2::new(
            p.float("principal_point_offset_x")?.unwrap_or(0.0) as f32,
            p.float("principal_point_offset_y")?.unwrap_or(0.0) as f32,
        );
        let lens = if p.kind == "thinlens" {
            let (Some(r), Some(fd)) = (p.float("aperture_radius")?, p.float("focus_distance")?)
            else {
                return Err(p.err(
                    e,
                    "a thinlens sensor needs `aperture_radius` and `focus_distance`",
                ));
            };
            Some((r as f32, fd as f32))
        } else {
            None
        };
        if p.has("srf") {
            return Err(p.err(e, "a sensor response function (`srf`) is not supported"));
        }
        let film = p.one_nested(&["film"], "film")?;
        let (w, h, filter) = self.film(film, e)?;
        let spp = match p.one_nested(&["sampler"], "sampler")? {
            Some(s) => self.sampler(s)?,
            None => 4,
        };
        let fov_given = p.float("fov")?;
        let focal = p.string("focal_length")?;
        let axis = match p.string("fov_axis")? {
            None => "x",
            Some((a, ae)) => match a {
                "x" | "y" | "diagonal" | "smaller" | "larger" => a,
                _ => {
                    return Err(p.err(
                        ae,
                        format!("`fov_axis` must be x, y, diagonal, smaller or larger, got `{a}`"),
                    ))
                }
            },
        };
        let (fov, axis) = match (fov_given, focal) {
            (Some(_), Some((_, fe))) => {
                return Err(p.err(fe, "give the sensor `fov` or `focal_length`, not both"))
            }
            (Some(f), None) => (f, axis),
            (None, f) => {
                let (text, at) = f.unwrap_or(("50mm", e));
                let mm = text.trim().trim_end_matches("mm").trim();
                let f: f64 = mm.parse().ok().filter(|f: &f64| *f > 0.0 && f.is_finite()).ok_or_else(|| {
                    p.err(at, format!("`focal_length` must be a positive length in mm like \"50mm\", got `{text}`"))
                })?;
                // 35 mm film equivalent: the field of view across the 36 × 24 mm frame's diagonal.
                let diag = (36.0f64 * 36.0 + 24.0 * 24.0).sqrt();
                (2.0 * (diag / (2.0 * f)).atan().to_degrees(), "diagonal")
            }
        };
        // A diagonal fov is the same camera as the x fov of this resolution (exact).
        let (fov, axis) = if axis == "diagonal" {
            let t = (0.5 * fov.to_radians()).tan() * w as f64 / ((w * w + h * h) as f64).sqrt();
            (2.0 * t.atan().to_degrees(), FovAxis::X)
        } else {
            let a = match axis {
                "x" => FovAxis::X,
                "y" => FovAxis::Y,
                "smaller" => FovAxis::Smaller,
                _ => FovAxis::Larger,
            };
            (fov, a)
        };
        let to_world = p.transform("to_world")?;
        // lt's own `half_width` (what a TOML orthographic camera gives, with a look-at taken
        // exactly); Mitsuba writes it as a to_world scale, read below.
        let half_width = match p.float("half_width")? {
            Some(_) if p.kind != "orthographic" => {
                return Err(p.err(e, "`half_width` belongs to an orthographic sensor"))
            }
            Some(hw) if !matches!(&to_world, None | Some((Xform { lookat: Some(_), .. }, _))) => {
                return Err(p.err(e, format!("give an orthographic sensor `half_width` ({hw}) or a to_world scale, not both (with `half_width`, to_world is one look-at)")))
            }
            hw => hw,
        };
        // An orthographic sensor's film spans [-1, 1] across x and ±1/aspect in y in camera
        // space (Mitsuba's `orthographic_projection`), scaled by to_world: the x column's length.
        let ortho_half_width = match (&to_world, p.kind) {
            (_, kind) if kind != "orthographic" => None,
            _ if half_width.is_some() => half_width.map(|hw| hw as f32),
            (Some((Xform { m, lookat: None }, te)), _) => {
                let (sx, sy) = (m.x_axis.truncate().length(), m.y_axis.truncate().length());
                if !((sx - sy).abs() <= 1e-6 * sx.max(sy)) {
                    return Err(p.err(te, format!("an orthographic sensor scaled unequally in x ({sx}) and y ({sy}) is not supported")));
                }
                Some(sx as f32)
            }
            _ => Some(1.0),
        };
        let (eye, target, up) = match to_world {
            None => (DVec3::ZERO, DVec3::Z, DVec3::Y),
            Some((
                Xform {
                    lookat: Some([o, t, u]),
                    ..
                },
                _,
            )) => (o, t, u),
            Some((Xform { m, .. }, te)) => camera_frame(&p, &m, te)?,
        };
        let camera = LookAt {
            eye,
            target,
            up,
            fov_deg: fov as f32,
            fov_axis: axis,
            width: w,
            height: h,
        };
        let optics = Optics {
            lens,
            ortho_half_width,
            principal,
            filter,
        };
        // Checked at the world origin now, so that a degenerate camera is reported in file order.
        camera
            .at(DVec3::ZERO)
            .and_then(|c| optics.apply(c))
            .map_err(|m| p.err(e, format!("degenerate camera: {m}")))?;
        p.finish(&SENSOR_IGNORED, &mut self.report)?;
        Ok(((camera, optics), spp))
    }

    /// Width, height and the pixel filter.
    pub(super) fn film(
        &mut self,
        film: Option<&'a Elem>,
        sensor: &Elem,
    ) -> Result<(u32, u32, PixelFilter), SceneError> {
        let Some(f) = film else {
            // Mitsuba's default hdrfilm: 768 × 576, Gaussian filter of stddev 0.5.
            let _ = sensor;
            let gaussian = PixelFilter::new(FilterShape::Gaussian { stddev: 0.5 })
                .expect("Mitsuba's default filter is valid");
            return Ok((768, 576, gaussian));
        };
        let p = self.plugin(f)?;
        if !FILMS.contains(&p.kind) {
            return Err(p.err(
                f,
                format!("film `{}` is not supported (only hdrfilm)", p.kind),
            ));
        }
        let dim = |k: &str, d: i64| -> Result<u32, SceneError> {
            let v = p.integer(k)?.unwrap_or(d);
            if !(1..=1 << 16).contains(&v) {
                return Err(p.err(
                    f,
                    format!("film `{k}` must be between 1 and 65536, got {v}"),
                ));
            }
            Ok(v as u32)
        };
        let (w, h) = (dim("width", 768)?, dim("height", 576)?);
        for k in [
            "crop_offset_x",
            "crop_offset_y",
            "crop_width",
            "crop_height",
        ] {
            if p.has(k) {
                let v = p.integer(k)?.unwrap_or(0);
                let full = match k {
                    "crop_width" => v == w as i64,
                    "crop_height" => v == h as i64,
                    _ => v == 0,
                };
                if !full {
                    return Err(p.err(f, format!("a crop window (`{k}` = {v}) is not supported")));
                }
            }
        }
        if p.boolean("sample_border")? == Some(true) {
            return Err(p.err(f, "`sample_border` = true is not supported"));
        }
        // Mitsuba's hdrfilm reconstructs with a Gaussian (stddev 0.5) unless told otherwise.
        let filter = match p.one_nested(&["rfilter"], "rfilter")? {
            None => PixelFilter::new(FilterShape::Gaussian { stddev: 0.5 })
                .expect("Mitsuba's default filter is valid"),
            Some(r) => self.rfilter(r)?,
        };
        p.finish(&FILM_IGNORED, &mut self.report)?;
        Ok((w, h, filter))
    }

    /// `<rfilter>`: Mitsuba's filters with their parameters and defaults.
    pub(super) fn rfilter(&mut self, r: &'a Elem) -> Result<PixelFilter, SceneError> {
        let rp = self.plugin(r)?;
        let num =
            |k: &str, d: f64| -> Result<f32, SceneError> { Ok(rp.float(k)?.unwrap_or(d) as f32) };
        let shape = match rp.kind {
            "box" => FilterShape::Box {
                radius: num("radius", 0.5)?,
            },
            "tent" => FilterShape::Tent {
                radius: num("radius", 1.0)?,
            },
            "gaussian" => FilterShape::Gaussian {
                stddev: num("stddev", 0.5)?,
            },
            "mitchell" => FilterShape::Mitchell {
                b: num("B", 1.0 / 3.0)?,
                c: num("C", 1.0 / 3.0)?,
            },
            "catmullrom" => FilterShape::CatmullRom,
            "lanczos" => {
                let lobes = rp.integer("lobes")?.unwrap_or(3);
                if !(1..=64).contains(&lobes) {
                    return Err(rp.err(r, format!("lanczos `lobes` must be 1 to 64, got {lobes}")));
                }
                FilterShape::Lanczos {
                    lobes: lobes as u32,
                }
            }
            _ => return Err(super::kinds::unknown_type(self.doc, r)),
        };
        let filter = PixelFilter::new(shape).map_err(|m| rp.err(r, m))?;
        rp.finish(&[], &mut self.report)?;
        Ok(filter)
    }

    pub(super) fn sampler(&mut self, s: &'a Elem) -> Result<u32, SceneError> {
        let p = self.plugin(s)?;
        match p.kind {
            kind if SAMPLERS.contains(&kind) => {}
            _ => return Err(super::kinds::unknown_type(self.doc, s)),
        }
        if p.kind != "independent" {
            self.report.ignored.push(format!(
                "{}: sampler `{}`: lt draws its own independent streams (same expectation, other noise)",
                self.doc.place(s),
                p.kind
            ));
        }
        let n = p.integer("sample_count")?.unwrap_or(4);
        if !(1..=u32::MAX as i64).contains(&n) {
            return Err(p.err(s, format!("`sample_count` must be at least 1, got {n}")));
        }
        p.finish(&SAMPLER_IGNORED, &mut self.report)?;
        Ok(n as u32)
    }
}

/// What a sensor adds to its look-at: a thin lens (aperture radius, focus distance), the
/// principal point offset and the film's pixel filter.
pub(super) struct Optics {
    lens: Option<(f32, f32)>,
    /// An orthographic sensor's film half width at the eye.
    ortho_half_width: Option<f32>,
    principal: Vec2,
    filter: PixelFilter,
}

impl Optics {
    pub(super) fn apply(&self, camera: Camera) -> Result<Camera, String> {
        let mut camera = camera
            .with_principal_point_offset(self.principal)?
            .with_filter(self.filter.clone());
        if let Some((r, fd)) = self.lens {
            camera = camera.thin_lens(r, fd)?;
        }
        if let Some(hw) = self.ortho_half_width {
            camera = camera.orthographic(hw)?;
        }
        Ok(camera)
    }
}

/// Eye, target and up of a camera `to_world` matrix (Mitsuba's camera looks along local +z with
/// +y up; its local +x is image left). Refuses matrices that skew or mirror the view.
pub(super) fn camera_frame(
    p: &Plugin,
    m: &DMat4,
    te: &Elem,
) -> Result<(DVec3, DVec3, DVec3), SceneError> {
    let eye = m.transform_point3(DVec3::ZERO);
    let col = |v: DVec4| (*m * v).truncate();
    let (left, up, fwd) = (col(DVec4::X), col(DVec4::Y), col(DVec4::Z));
    let (ln, un, fnn) = (
        left.normalize_or_zero(),
        up.normalize_or_zero(),
        fwd.normalize_or_zero(),
    );
    let skew = ln
        .dot(un)
        .abs()
        .max(ln.dot(fnn).abs())
        .max(un.dot(fnn).abs());
    if !(fnn.length() > 0.0 && un.length() > 0.0 && ln.length() > 0.0) || skew > 1e-4 {
        return Err(p.err(te, "the camera's to_world skews or flattens the view (it must be a rotation and translation)"));
    }
    if un.cross(fnn).dot(ln) < 0.0 {
        return Err(p.err(
            te,
            "the camera's to_world mirrors the image (negative determinant): not supported",
        ));
    }
    Ok((eye, eye + fnn, un))
}
