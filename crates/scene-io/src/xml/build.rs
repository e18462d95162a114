//! The plugin subset: the XML's sensor, integrator, BSDFs, shapes and emitters turned into a
//! `Scene` through `SceneBuilder`, each value checked on the way (reference: docs/xml.md).

use super::doc::{Doc, Elem};
use super::props::{ColorUse, Ids, Plugin};
use super::resolve::Resolver;
use super::values::Xform;
use crate::error::Ctx;
use crate::image_file::{filter_type_named, read_bitmap, read_environment_map, wrap_mode_named};
use crate::mesh::{ply, serialized};
use crate::principled_keys::{principled_eta, scalar_in_range, thin_eta};
use crate::transform::{check_quad, check_solid};
use crate::world::{out_of_range_message, LookAt, WorldBuilder, WorldGeometry, WorldMesh};
use crate::SceneError;
use crate::{LoadOptions, LoadReport};
use glam::{DMat4, DVec3, DVec4};
use lt_core::bsdf::conductor_ior::{conductor_names, named_conductor, PERFECT_MIRROR};
use lt_core::bsdf::fresnel::ComplexIor;
use lt_core::bsdf::microfacet::{Microfacet, MicrofacetType};
use lt_core::bsdf::plastic::{channel_mean, specular_sampling_weight};
use lt_core::bsdf::{Blend, Mask, NormalSource, Perturbed, TextureSlot, Textured};
use lt_core::bsdf::{
    Conductor, Dielectric, Diffuse, FrontDiffuse, Glossy, Material, Mirror, RoughConductor,
    RoughDielectric, ThinDielectric, TwoSided,
};
use lt_core::bsdf::{Plastic, Principled, PrincipledParam, PrincipledThin, RoughPlastic};
use lt_core::camera::{Camera, FilterShape, FovAxis, PixelFilter};
use lt_core::math::{Color, Vec2};
use lt_core::scene::{LightDesc, RenderSettings, Scene, TriangleMesh};
use lt_core::texture::{Texture, UvTransform};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// GGX α below this is numerically a mirror (the TOML loader's bound).
const MIN_ROUGHNESS: f64 = 1e-4;
/// What `--approximate` puts in place of Mitsuba's unbounded `max_depth = -1`.
pub const UNBOUNDED_DEPTH_SUBSTITUTE: u32 = 64;

/// Parameters Mitsuba writes by default that change nothing lt renders, per plugin kind.
const SENSOR_IGNORED: [&str; 5] = [
    "near_clip",
    "far_clip",
    "focus_distance",
    "shutter_open",
    "shutter_close",
];
const FILM_IGNORED: [&str; 4] = ["pixel_format", "component_format", "file_format", "banner"];
const SAMPLER_IGNORED: [&str; 3] = ["seed", "jitter", "strength"];

/// IORs Mitsuba knows by name (its `int_ior`/`ext_ior` strings).
const NAMED_IORS: [(&str, f64); 23] = [
    ("vacuum", 1.0),
    ("helium", 1.000036),
    ("hydrogen", 1.000132),
    ("air", 1.000277),
    ("carbon dioxide", 1.00045),
    ("water", 1.333),
    ("acetone", 1.36),
    ("ethanol", 1.361),
    ("carbon tetrachloride", 1.461),
    ("glycerol", 1.4729),
    ("benzene", 1.501),
    ("silicone oil", 1.52045),
    ("bromine", 1.661),
    ("water ice", 1.31),
    ("fused quartz", 1.458),
    ("pyrex", 1.470),
    ("acrylic glass", 1.49),
    ("polypropylene", 1.49),
    ("bk7", 1.5046),
    ("sodium chloride", 1.544),
    ("amber", 1.55),
    ("pet", 1.575),
    ("diamond", 2.419),
];

pub(super) struct Loader<'a> {
    doc: &'a Doc,
    opts: &'a LoadOptions,
    pub report: LoadReport,
    ids: Ids<'a>,
    /// Material ids of BSDF elements already converted (by element address).
    materials: HashMap<*const Elem, u32>,
    default_material: Option<u32>,
    /// The black diffuse of emitting shapes without a BSDF.
    default_emitter_material: Option<u32>,
    /// Mesh files read, in order.
    pub meshes: Vec<PathBuf>,
}

fn collect_ids<'a>(doc: &'a Doc, e: &'a Elem, ids: &mut Ids<'a>) -> Result<(), SceneError> {
    for c in &e.children {
        if c.tag != "ref" {
            if let Some(id) = c.attr("id") {
                if ids.insert(id, c).is_some() {
                    return Err(doc.err(c, format!("the id `{id}` is defined twice")));
                }
            }
        }
        collect_ids(doc, c, ids)?;
    }
    Ok(())
}

pub(super) fn load(
    doc: &Doc,
    opts: &LoadOptions,
) -> Result<(Scene, LoadReport, Vec<PathBuf>), SceneError> {
    let mut ids = Ids::new();
    collect_ids(doc, &doc.root, &mut ids)?;
    let mut l = Loader {
        doc,
        opts,
        report: LoadReport::default(),
        ids,
        materials: HashMap::new(),
        default_material: None,
        default_emitter_material: None,
        meshes: Vec::new(),
    };
    let root = &doc.root;
    let by_tag = |t: &'static str| root.children.iter().filter(move |c| c.tag == t);
    for c in &root.children {
        match c.tag.as_str() {
            "sensor" | "integrator" | "bsdf" | "shape" | "emitter" => {}
            // Read where they are referenced.
            "texture" => {}
            "medium" | "phase" => {
                return Err(doc.err(
                    c,
                    format!("participating media are not supported: <{}>", c.tag),
                ))
            }
            other => {
                return Err(doc.err(
                    c,
                    format!("<{other}> is not supported at the top level of a scene"),
                ))
            }
        }
    }
    let sensors: Vec<&Elem> = by_tag("sensor").collect();
    let sensor = match sensors[..] {
        [] => return Err(doc.err(root, "the scene has no <sensor> (lt needs a camera)")),
        [s] => s,
        [_, second, ..] => {
            return Err(doc.err(
                second,
                "a second <sensor>: lt renders one camera, keep only one",
            ))
        }
    };
    let (camera, spp) = l.sensor(sensor)?;
    let integrators: Vec<&Elem> = by_tag("integrator").collect();
    if integrators.len() > 1 {
        return Err(doc.err(integrators[1], "a second <integrator>"));
    }
    let (max_depth, rr_depth) = l.integrator(integrators.first().copied(), root)?;
    let settings = RenderSettings {
        max_depth,
        rr_depth,
        spp,
    };
    let mut b = WorldBuilder::new(settings);
    // Top-level BSDFs first, in document order, so each is checked even when unused.
    for c in by_tag("bsdf") {
        l.material(c, &mut b)?;
    }
    let mut emitters = 0;
    for c in &root.children {
        match c.tag.as_str() {
            "shape" => emitters += l.shape_or_instance(c, &mut b)?,
            "emitter" => {
                match l.emitter(c)? {
                    Some((desc, Some(position))) => b.add_light_at(desc, position),
                    Some((desc, None)) => b.add_light(desc),
                    None => continue,
                }
                emitters += 1;
            }
            _ => {}
        }
    }
    if emitters == 0 {
        return Err(doc.err(
            root,
            "the scene has no light: no emitter with a non-zero value",
        ));
    }
    let Loader { report, meshes, .. } = l;
    let (camera, optics) = camera;
    let scene = b.build(|origin| {
        camera
            .at(origin)
            .and_then(|c| optics.apply(c))
            .map_err(|m| doc.err(sensor, format!("degenerate camera: {m}")))
    })?;
    Ok((scene, report, meshes))
}

impl<'a> Loader<'a> {
    fn plugin(&mut self, e: &'a Elem) -> Result<Plugin<'a>, SceneError> {
        Plugin::new(self.doc, &self.ids, e, &mut self.report)
    }

    /// Refuses, or with `--approximate` records, a substitution.
    fn substitute(
        &mut self,
        e: &Elem,
        refusal: String,
        substitution: String,
    ) -> Result<(), SceneError> {
        if !self.opts.approximate {
            return Err(self.doc.err(
                e,
                format!("{refusal}; pass --approximate to {substitution}"),
            ));
        }
        let place = self.doc.place(e);
        self.report
            .substitutions
            .push(format!("{place}: {refusal}: {substitution} instead"));
        Ok(())
    }

    // ---------------------------------------------------------------- sensor, film, sampler

    fn sensor(&mut self, e: &'a Elem) -> Result<((LookAt, Optics), u32), SceneError> {
        let p = self.plugin(e)?;
        if !matches!(p.kind, "perspective" | "thinlens" | "orthographic") {
            return Err(p.err(
                e,
                format!(
                    "sensor `{}` is not supported (lt reads perspective, thinlens and orthographic)",
                    p.kind
                ),
            ));
        }
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
        // An orthographic sensor's film spans [-1, 1] across x and ±1/aspect in y in camera
        // space (Mitsuba's `orthographic_projection`), scaled by to_world: the x column's length.
        let ortho_half_width = match (&to_world, p.kind) {
            (_, kind) if kind != "orthographic" => None,
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
    fn film(
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
        if p.kind != "hdrfilm" {
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
    fn rfilter(&mut self, r: &'a Elem) -> Result<PixelFilter, SceneError> {
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
            other => {
                return Err(rp.err(
                    r,
                    format!(
                        "reconstruction filter `{other}` is not supported (known: box, tent, \
                         gaussian, mitchell, catmullrom, lanczos)"
                    ),
                ))
            }
        };
        let filter = PixelFilter::new(shape).map_err(|m| rp.err(r, m))?;
        rp.finish(&[], &mut self.report)?;
        Ok(filter)
    }

    fn sampler(&mut self, s: &'a Elem) -> Result<u32, SceneError> {
        let p = self.plugin(s)?;
        match p.kind {
            "independent" | "stratified" | "multijitter" | "orthogonal" | "ldsampler" => {}
            other => return Err(p.err(s, format!("sampler `{other}` is not supported"))),
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

    fn integrator(&mut self, e: Option<&'a Elem>, root: &Elem) -> Result<(u32, u32), SceneError> {
        let (depth, rr, at) = match e {
            None => (-1, 5, root),
            Some(e) => {
                let p = self.plugin(e)?;
                match p.kind {
                    "path" | "volpath" | "volpathmis" | "ptracer" => {}
                    "moment" => return self.moment(&p, root),
                    "direct" => return self.direct(&p),
                    other => {
                        return Err(p.err(
                            e,
                            format!("integrator `{other}` is not supported (lt reads path, volpath, volpathmis, ptracer, direct and moment for their max_depth; the estimator is chosen on lt's command line); where the file writes type=\"$integrator\", -D integrator=path renders it"),
                        ))
                    }
                }
                if p.boolean("hide_emitters")? == Some(true) {
                    return Err(p.err(e, "`hide_emitters` = true is not supported"));
                }
                let depth = p.integer("max_depth")?.unwrap_or(-1);
                let rr = p.integer("rr_depth")?.unwrap_or(5);
                p.finish(&["samples_per_pass"], &mut self.report)?;
                (depth, rr, e)
            }
        };
        let depth = match depth {
            -1 => {
                self.substitute(
                    at,
                    "max_depth = -1 (unbounded, Mitsuba's default) is not supported: lt's estimators size their paths by max_depth".into(),
                    format!("use max_depth = {UNBOUNDED_DEPTH_SUBSTITUTE}"),
                )?;
                UNBOUNDED_DEPTH_SUBSTITUTE
            }
            d if (1..=1 << 20).contains(&d) => d as u32,
            d => {
                return Err(self.doc.err(
                    at,
                    format!("`max_depth` must be -1 or between 1 and 2^20, got {d} (1 = emitters seen directly)"),
                ))
            }
        };
        if !(0..=1 << 20).contains(&rr) {
            return Err(self.doc.err(
                at,
                format!("`rr_depth` must be between 0 and 2^20, got {rr}"),
            ));
        }
        Ok((depth, rr as u32))
    }

    /// Mitsuba's `moment` renders its inner integrator and adds the second moment as extra
    /// channels; lt's renders carry their own variance, so the inner integrator is what counts.
    fn moment(&mut self, p: &Plugin<'a>, root: &Elem) -> Result<(u32, u32), SceneError> {
        let inner = p.nested(&["integrator"]);
        p.finish(&[], &mut self.report)?;
        match inner[..] {
            [i] => self.integrator(Some(i), root),
            [] => Err(p.err(
                p.elem,
                "integrator `moment` needs the integrator it wraps inside it",
            )),
            [_, second, ..] => Err(p.err(
                second,
                "a second integrator inside `moment`: lt renders one estimator per image",
            )),
        }
    }

    /// Mitsuba's `direct`: emitters seen directly plus direct illumination at the first hit,
    /// emitter and BSDF samples joined by MIS. Its expectation is every path of at most two
    /// segments — lt's `max_depth = 2` (camera segment included), which every estimator renders
    /// (`pt` with next-event estimation and MIS is the same estimator). The sample counts change
    /// only the noise while both are positive; a zero count drops a whole class of paths (lights
    /// reached through a mirror, point lights), so it is refused.
    fn direct(&mut self, p: &Plugin<'a>) -> Result<(u32, u32), SceneError> {
        if p.boolean("hide_emitters")? == Some(true) {
            return Err(p.err(p.elem, "`hide_emitters` = true is not supported"));
        }
        for key in ["emitter_samples", "bsdf_samples", "shading_samples"] {
            if let Some(n) = p.integer(key)? {
                if n < 1 {
                    return Err(p.err(p.elem, format!("`{key}` = {n} of integrator `direct`: lt renders every path of two segments, a count below 1 leaves some out")));
                }
                self.report.ignored.push(format!(
                    "{}: `{key}` = {n} of integrator `direct` accepted and ignored (it changes the noise, not the expectation)",
                    self.doc.place(p.elem)
                ));
            }
        }
        p.finish(&[], &mut self.report)?;
        Ok((2, 5))
    }

    // ---------------------------------------------------------------- BSDFs

    /// The material id of a BSDF element (converted once, however often it is referenced).
    fn material(&mut self, e: &'a Elem, b: &mut WorldBuilder) -> Result<u32, SceneError> {
        let key = e as *const Elem;
        if let Some(&id) = self.materials.get(&key) {
            return Ok(id);
        }
        let m = self.bsdf(e, false)?;
        let id = b.add_material(m);
        self.materials.insert(key, id);
        Ok(id)
    }

    fn bsdf(&mut self, e: &'a Elem, in_twosided: bool) -> Result<Material, SceneError> {
        let p = self.plugin(e)?;
        let opts = self.opts;
        // Parameters given as textures: the material is built with their defaults and the
        // textures set them at each shading point.
        let mut slots: Vec<(TextureSlot, Texture)> = Vec::new();
        let m = match p.kind {
            "diffuse" => {
                let albedo = self
                    .color_or_texture(&p, "reflectance", TextureSlot::Reflectance, &mut slots)?
                    .unwrap_or(Color::splat(0.5));
                // Mitsuba's BSDFs reflect on the front only unless `twosided` wraps them.
                if in_twosided {
                    Material::Diffuse(Diffuse { albedo })
                } else {
                    Material::FrontDiffuse(FrontDiffuse { albedo })
                }
            }
            "twosided" => {
                if in_twosided {
                    return Err(p.err(e, "a twosided BSDF inside a twosided BSDF"));
                }
                let inner = p.nested(&["bsdf"]);
                match inner[..] {
                    [one] => {
                        let m = self.bsdf(one, true)?;
                        if matches!(m, Material::Dielectric(_) | Material::RoughDielectric(_) | Material::ThinDielectric(_)) {
                            return Err(p.err(one, "twosided cannot wrap a dielectric (it transmits)"));
                        }
                        m
                    }
                    [] => return Err(p.err(e, "twosided needs a nested BSDF")),
                    [_, second, ..] => {
                        return Err(p.err(
                            second,
                            "twosided with different front and back BSDFs is not supported (lt's materials reflect alike on both sides)",
                        ))
                    }
                }
            }
            "dielectric" => {
                for k in ["specular_reflectance", "specular_transmittance"] {
                    if let Some(c) = p.color(k, ColorUse::Reflectance, opts, &mut self.report)? {
                        if c != Color::ONE {
                            return Err(p.err(e, format!("`{k}` ≠ 1 on a dielectric is not supported (lt's glass has exact Fresnel only)")));
                        }
                    }
                }
                Material::Dielectric(Dielectric {
                    ior: self.relative_ior(&p)?,
                })
            }
            "roughdielectric" | "thindielectric" => {
                let ior = self.relative_ior(&p)?;
                let specular_reflectance = self
                    .color_or_texture(&p, "specular_reflectance", TextureSlot::SpecularReflectance, &mut slots)?
                    .unwrap_or(Color::ONE);
                let specular_transmittance = p
                    .color("specular_transmittance", ColorUse::Reflectance, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                if p.kind == "thindielectric" {
                    Material::ThinDielectric(ThinDielectric {
                        ior,
                        specular_reflectance,
                        specular_transmittance,
                    })
                } else {
                    Material::RoughDielectric(RoughDielectric {
                        distribution: self.microfacet(&p, &mut slots)?,
                        ior,
                        specular_reflectance,
                        specular_transmittance,
                    })
                }
            }
            "conductor" | "roughconductor" => {
                let ior = self.complex_ior(&p)?;
                let specular_reflectance = self
                    .color_or_texture(&p, "specular_reflectance", TextureSlot::SpecularReflectance, &mut slots)?
                    .unwrap_or(Color::ONE);
                let one_sided = if p.kind == "conductor" {
                    Material::Conductor(Conductor {
                        ior,
                        specular_reflectance,
                    })
                } else {
                    Material::RoughConductor(RoughConductor {
                        distribution: self.microfacet(&p, &mut slots)?,
                        ior,
                        specular_reflectance,
                    })
                };
                // Mitsuba's conductors reflect on the front only; `twosided` gives them a back.
                // Two-sided and with material "none" (Fresnel = 1), a smooth conductor is lt's
                // mirror and an isotropic GGX one sampling visible normals is lt's glossy: the
                // same BSDFs, kept as those so scenes written by `lt convert` read back exactly.
                let ideal = in_twosided && ior == PERFECT_MIRROR;
                match one_sided {
                    Material::Conductor(_) if ideal => Material::Mirror(Mirror {
                        reflectance: specular_reflectance,
                    }),
                    Material::RoughConductor(r)
                        if ideal
                            && r.distribution.kind == MicrofacetType::Ggx
                            && !r.distribution.is_anisotropic()
                            && !slots.iter().any(|(s, _)| {
                                matches!(s, TextureSlot::AlphaU | TextureSlot::AlphaV)
                            })
                            && r.distribution.sample_visible =>
                    {
                        Material::Glossy(Glossy {
                            reflectance: specular_reflectance,
                            roughness: r.distribution.alpha_u,
                        })
                    }
                    one_sided if in_twosided => Material::TwoSided(TwoSided {
                        inner: Box::new(one_sided),
                    }),
                    one_sided => one_sided,
                }
            }
            "plastic" | "roughplastic" => {
                let one_sided = self.plastic(&p, &mut slots)?;
                if in_twosided {
                    Material::TwoSided(TwoSided {
                        inner: Box::new(one_sided),
                    })
                } else {
                    one_sided
                }
            }
            "principled" | "principledthin" => {
                let m = self.principled(&p, &mut slots)?;
                if in_twosided {
                    return Err(p.err(e, format!("twosided cannot wrap {} (it transmits, and its back side is its own)", p.kind)));
                }
                m
            }
            "normalmap" | "bumpmap" => {
                let inner = match p.nested(&["bsdf"])[..] {
                    [one] => self.bsdf(one, in_twosided)?,
                    [] => return Err(p.err(e, format!("{} needs a nested BSDF", p.kind))),
                    [_, second, ..] => {
                        return Err(p.err(second, format!("{} takes one nested BSDF, this is a second one", p.kind)))
                    }
                };
                let source = if p.kind == "normalmap" {
                    let Some(t) = p.texture("normalmap") else {
                        return Err(p.err(e, "normalmap needs a texture named `normalmap`"));
                    };
                    NormalSource::NormalMap(self.texture(t)?)
                } else {
                    let height = match p.any_textures()[..] {
                        [one] => self.texture(one)?,
                        [] => return Err(p.err(e, "bumpmap needs a nested height texture")),
                        [_, second, ..] => {
                            return Err(p.err(second, "bumpmap takes one texture, this is a second one"))
                        }
                    };
                    let scale = p.float("scale")?.unwrap_or(1.0) as f32;
                    if !scale.is_finite() {
                        return Err(p.err(e, format!("bumpmap `scale` = {scale} is not a finite number")));
                    }
                    NormalSource::BumpMap { height, scale }
                };
                Material::Perturbed(Box::new(Perturbed {
                    source,
                    inner,
                    flip_invalid_normals: p.boolean("flip_invalid_normals")?.unwrap_or(true),
                    shadowing: p.boolean("use_shadowing_function")?.unwrap_or(true),
                }))
            }
            "mask" => {
                let inner = match p.nested(&["bsdf"])[..] {
                    [one] => self.bsdf(one, in_twosided)?,
                    [] => return Err(p.err(e, "mask needs a nested BSDF")),
                    [_, second, ..] => {
                        return Err(p.err(second, "mask takes one nested BSDF, this is a second one"))
                    }
                };
                let opacity = match p.texture("opacity") {
                    Some(t) => self.texture(t)?,
                    None => Texture::Constant(
                        p.color("opacity", ColorUse::Reflectance, opts, &mut self.report)?
                            .unwrap_or(Color::splat(0.5)),
                    ),
                };
                Material::Mask(Box::new(Mask { opacity, inner }))
            }
            "blendbsdf" => {
                let (first, second) = match p.nested(&["bsdf"])[..] {
                    [a, b] => (self.bsdf(a, in_twosided)?, self.bsdf(b, in_twosided)?),
                    [_, _, third, ..] => {
                        return Err(p.err(third, "blendbsdf takes two nested BSDFs, this is a third one"))
                    }
                    _ => return Err(p.err(e, "blendbsdf needs two nested BSDFs")),
                };
                for m in [&first, &second] {
                    if m.refraction_ior().is_some() || m.perturbation().is_some() {
                        return Err(p.err(
                            e,
                            "blendbsdf of a refracting or normal/bump-mapped BSDF is not supported (its η² scaling and shading normal belong to one material)",
                        ));
                    }
                }
                let weight = match p.texture("weight") {
                    Some(t) => self.texture(t)?,
                    None => Texture::Constant(
                        p.color("weight", ColorUse::Reflectance, opts, &mut self.report)?
                            .unwrap_or(Color::splat(0.5)),
                    ),
                };
                Material::Blend(Box::new(Blend { weight, first, second }))
            }
            other => {
                return Err(p.err(
                    e,
                    format!("BSDF `{other}` is not supported (lt reads diffuse, dielectric, roughdielectric, thindielectric, conductor, roughconductor, plastic, roughplastic, principled, principledthin, twosided, normalmap, bumpmap, mask and blendbsdf)"),
                ))
            }
        };
        p.finish(&[], &mut self.report)?;
        Ok(if slots.is_empty() {
            m
        } else {
            Material::Textured(Box::new(Textured { base: m, slots }))
        })
    }

    /// A colour parameter that may be a texture: a texture goes to `slots` (and None is returned,
    /// so the material keeps its default there); a plain colour is returned.
    fn color_or_texture(
        &mut self,
        p: &Plugin<'a>,
        name: &str,
        slot: TextureSlot,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Option<Color>, SceneError> {
        if let Some(t) = p.texture(name) {
            let texture = self.texture(t)?;
            if !slot.is_scalar() && texture.max_value() > 1.0 {
                return Err(p.err(
                    t,
                    format!(
                        "the texture of `{name}` reaches {} (a reflectance must be at most 1)",
                        texture.max_value()
                    ),
                ));
            }
            slots.push((slot, texture));
            return Ok(None);
        }
        let usage = if slot.is_scalar() {
            ColorUse::Emission
        } else {
            ColorUse::Reflectance
        };
        p.color(name, usage, self.opts, &mut self.report)
    }

    /// A `<texture>`: Mitsuba's `bitmap` (`filename`, `filter_type` bilinear or nearest, `wrap_mode`
    /// repeat, mirror or clamp, `raw`, `to_uv`) or `checkerboard` (`color0` 0.4, `color1` 0.2,
    /// `to_uv`).
    fn texture(&mut self, e: &'a Elem) -> Result<Texture, SceneError> {
        let p = self.plugin(e)?;
        let to_uv = match p.transform("to_uv")? {
            None => UvTransform::IDENTITY,
            Some((x, _)) => {
                let m = x.m;
                // A 2-D affine map given as a 4×4 (Mitsuba builds it with translate/scale/rotate
                // about z): its upper-left 2×2 and the translation's x, y.
                UvTransform {
                    m: [
                        [m.x_axis.x as f32, m.y_axis.x as f32],
                        [m.x_axis.y as f32, m.y_axis.y as f32],
                    ],
                    t: glam::Vec2::new(m.w_axis.x as f32, m.w_axis.y as f32),
                }
            }
        };
        let texture = match p.kind {
            "bitmap" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, "a bitmap texture needs a `filename`"));
                };
                let path = self.doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("texture file", file, &looked))
                })?;
                let raw = p.boolean("raw")?.unwrap_or(false);
                let filter = parse_named(&p, e, "filter_type", filter_type_named)?;
                let wrap = parse_named(&p, e, "wrap_mode", wrap_mode_named)?;
                let bitmap =
                    read_bitmap(&path, raw, filter, wrap, to_uv).map_err(|m| p.err(fe, m))?;
                self.meshes.push(path);
                p.finish(&["format"], &mut self.report)?;
                Texture::Bitmap(Arc::new(bitmap))
            }
            "checkerboard" => {
                let opts = self.opts;
                let color0 = p
                    .color("color0", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::splat(0.4));
                let color1 = p
                    .color("color1", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::splat(0.2));
                p.finish(&[], &mut self.report)?;
                Texture::Checkerboard {
                    color0,
                    color1,
                    to_uv,
                }
            }
            "mesh_attribute" => {
                let Some((name, ne)) = p.string("name")? else {
                    return Err(p.err(e, "a mesh_attribute texture needs a `name`"));
                };
                if !(name.starts_with("vertex_") || name.starts_with("face_")) {
                    return Err(p.err(
                        ne,
                        format!("mesh attribute `{name}`: its name must start with `vertex_` or `face_`"),
                    ));
                }
                p.finish(&[], &mut self.report)?;
                Texture::MeshAttribute { name: name.into() }
            }
            "rawconstant" => {
                // Mitsuba's `rawconstant`: `value`, a float or a 3-vector used as is (no colour
                // conversion: normal maps store directions in it).
                let is_float = e.children.iter().any(|c| {
                    c.attr("name") == Some("value") && matches!(c.tag.as_str(), "float" | "integer")
                });
                let value = if is_float {
                    p.float("value")?.map(|x| Color::splat(x as f32))
                } else {
                    p.vec3("value")?
                        .map(|v| Color::new(v[0] as f32, v[1] as f32, v[2] as f32))
                };
                let Some(value) = value else {
                    return Err(p.err(e, "a rawconstant texture needs a `value`"));
                };
                p.finish(&[], &mut self.report)?;
                Texture::Constant(value)
            }
            other => {
                return Err(p.err(
                    e,
                    format!(
                        "texture `{other}` is not supported (lt reads bitmap, checkerboard, mesh_attribute and rawconstant)"
                    ),
                ))
            }
        };
        Ok(texture)
    }

    /// Mitsuba's `plastic` and `roughplastic` (one-sided): `int_ior` (polypropylene), `ext_ior`
    /// (air), `diffuse_reflectance` (0.5) and `specular_reflectance` (1), either a texture,
    /// `nonlinear` (false); `roughplastic` adds the microfacet parameters (isotropic, α a
    /// number). The lobe-sampling weight reads a textured reflectance's mean, as Mitsuba does.
    fn plastic(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Material, SceneError> {
        let e = p.elem;
        let int = self.ior(p, "int_ior", 1.49)?;
        let ext = self.ior(p, "ext_ior", 1.000277)?;
        let eta = (int / ext) as f32;
        if !(eta.is_finite() && eta > 0.0) {
            return Err(p.err(
                e,
                format!("the relative IOR {int}/{ext} is not a positive number"),
            ));
        }
        if p.kind == "roughplastic" && int == ext {
            return Err(p.err(e, "roughplastic needs `int_ior` ≠ `ext_ior` (as Mitsuba)"));
        }
        let mut reflectance = |this: &mut Self, name, slot, default| {
            let c = this.color_or_texture(p, name, slot, slots)?;
            let mean = match c {
                Some(c) => c,
                None => slots
                    .iter()
                    .rfind(|(s, _)| *s == slot)
                    .map_or(default, |(_, t)| t.mean()),
            };
            Ok::<_, SceneError>((c.unwrap_or(default), mean))
        };
        let (diffuse, diffuse_mean) = reflectance(
            self,
            "diffuse_reflectance",
            TextureSlot::Reflectance,
            Color::splat(0.5),
        )?;
        let (specular, specular_mean) = reflectance(
            self,
            "specular_reflectance",
            TextureSlot::SpecularReflectance,
            Color::ONE,
        )?;
        let nonlinear = p.boolean("nonlinear")?.unwrap_or(false);
        let weight =
            specular_sampling_weight(channel_mean(diffuse_mean), channel_mean(specular_mean));
        Ok(if p.kind == "plastic" {
            let mut m = Plastic::new(eta, diffuse, specular, nonlinear);
            m.specular_sampling_weight = weight;
            Material::Plastic(m)
        } else {
            let distribution = self.microfacet(p, slots)?;
            if slots.iter().any(|(s, _)| s.is_roughness()) {
                return Err(p.err(
                    e,
                    "roughplastic's `alpha` must be a number (Mitsuba takes no texture there)",
                ));
            }
            if distribution.is_anisotropic() {
                return Err(p.err(
                    e,
                    "roughplastic is isotropic in Mitsuba: give `alpha`, not `alpha_u` ≠ `alpha_v`",
                ));
            }
            let mut m = RoughPlastic::new(distribution, eta, diffuse, specular, nonlinear);
            m.specular_sampling_weight = weight;
            Material::RoughPlastic(m)
        })
    }

    /// Mitsuba's `principled` and `principledthin`: `base_color` (0.5) and the scalars
    /// `roughness` (0.5), `anisotropic`, `metallic`*, `spec_trans`, `spec_tint`, `sheen`,
    /// `sheen_tint`, `flatness`, `clearcoat`*, `clearcoat_gloss`* (0), `diff_trans`† (0, range
    /// 0–2), each a number or a texture; principled's `eta` or `specular` (0.5, one of the two;
    /// numbers), principledthin's `eta` (1.5, a number or a texture); the sampling rates (1).
    /// (* principled only, † principledthin only.)
    fn principled(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Material, SceneError> {
        use PrincipledParam::*;
        let e = p.elem;
        let thin = p.kind == "principledthin";
        let base_color = self
            .color_or_texture(p, "base_color", TextureSlot::Principled(BaseColor), slots)?
            .unwrap_or(Color::splat(0.5));
        // A scalar: a number in [0, max], or a texture whose values stay there.
        let mut scalar = |this: &mut Self, name: &str, param, default: f32, max: f32| {
            if let Some(t) = p.texture(name) {
                let texture = this.texture(t)?;
                let top = texture.max_value();
                if !(top <= max) {
                    return Err(p.err(
                        t,
                        format!("the texture of `{name}` reaches {top} (at most {max})"),
                    ));
                }
                slots.push((TextureSlot::Principled(param), texture));
                return Ok((default, true));
            }
            match p.float(name)? {
                None => Ok((default, false)),
                Some(x) => scalar_in_range(name, x, max)
                    .map(|v| (v, x != 0.0))
                    .map_err(|m| p.err(e, m)),
            }
        };
        let (roughness, _) = scalar(self, "roughness", Roughness, 0.5, 1.0)?;
        let (anisotropic, _) = scalar(self, "anisotropic", Anisotropic, 0.0, 1.0)?;
        let (spec_trans, has_spec_trans) = scalar(self, "spec_trans", SpecTrans, 0.0, 1.0)?;
        let (spec_tint, _) = scalar(self, "spec_tint", SpecTint, 0.0, 1.0)?;
        let (sheen, _) = scalar(self, "sheen", Sheen, 0.0, 1.0)?;
        let (sheen_tint, _) = scalar(self, "sheen_tint", SheenTint, 0.0, 1.0)?;
        let (flatness, _) = scalar(self, "flatness", Flatness, 0.0, 1.0)?;
        let rate = |name: &str| -> Result<f32, SceneError> {
            match p.float(name)? {
                None => Ok(1.0),
                Some(x) if x >= 0.0 && x.is_finite() => Ok(x as f32),
                Some(x) => Err(p.err(
                    e,
                    format!("`{name}` must be a non-negative number, got {x}"),
                )),
            }
        };
        if thin {
            let (diff_trans, _) = scalar(self, "diff_trans", DiffTrans, 0.0, 2.0)?;
            let eta = match p.texture("eta") {
                Some(t) => {
                    let texture = self.texture(t)?;
                    slots.push((TextureSlot::Principled(Eta), texture));
                    1.5
                }
                None => thin_eta(p.float("eta")?, "eta").map_err(|m| p.err(e, m))?,
            };
            let sampling_rates = [
                rate("specular_reflectance_sampling_rate")?,
                rate("specular_transmittance_sampling_rate")?,
                rate("diffuse_reflectance_sampling_rate")?,
                rate("diffuse_transmittance_sampling_rate")?,
            ];
            return Ok(Material::PrincipledThin(PrincipledThin {
                base_color,
                roughness,
                anisotropic,
                spec_trans,
                diff_trans,
                eta,
                spec_tint,
                sheen,
                sheen_tint,
                flatness,
                sampling_rates,
            }));
        }
        let (metallic, _) = scalar(self, "metallic", Metallic, 0.0, 1.0)?;
        let (clearcoat, _) = scalar(self, "clearcoat", Clearcoat, 0.0, 1.0)?;
        let (clearcoat_gloss, _) = scalar(self, "clearcoat_gloss", ClearcoatGloss, 0.0, 1.0)?;
        let eta = principled_eta(p.float("eta")?, p.float("specular")?, has_spec_trans, "eta")
            .map_err(|m| p.err(e, m))?;
        let sampling_rates = [
            rate("diffuse_reflectance_sampling_rate")?,
            rate("clearcoat_sampling_rate")?,
            rate("main_specular_sampling_rate")?,
        ];
        Ok(Material::Principled(Principled {
            base_color,
            roughness,
            anisotropic,
            metallic,
            spec_trans,
            eta,
            spec_tint,
            sheen,
            sheen_tint,
            flatness,
            clearcoat,
            clearcoat_gloss,
            sampling_rates,
            has_spec_trans,
        }))
    }

    /// An IOR given as a number or by one of Mitsuba's names.
    fn ior(&self, p: &Plugin<'a>, key: &str, default: f64) -> Result<f64, SceneError> {
        let Some(e) = p.take_elem(key) else {
            return Ok(default);
        };
        let v = e.attr("value").unwrap_or("");
        let x = match e.tag.as_str() {
            "float" | "integer" => super::values::number(self.doc, e, v, key)?,
            "string" => match NAMED_IORS
                .iter()
                .find(|(n, _)| *n == v.trim().to_ascii_lowercase())
            {
                Some(&(_, x)) => x,
                None => {
                    return Err(p.err(
                        e,
                        format!("`{key}`: `{v}` is not an IOR Mitsuba knows by name"),
                    ))
                }
            },
            _ => {
                return Err(p.err(
                    e,
                    format!("`{key}` must be a <float> or a <string> naming a material"),
                ))
            }
        };
        if !(x > 0.0) {
            return Err(p.err(e, format!("`{key}` must be positive, got {x}")));
        }
        Ok(x)
    }

    /// A dielectric's `int_ior / ext_ior` (Mitsuba's defaults: bk7 = 1.5046 inside, air =
    /// 1.000277 outside; either a number or a name Mitsuba knows).
    fn relative_ior(&self, p: &Plugin<'a>) -> Result<f32, SceneError> {
        let int = self.ior(p, "int_ior", 1.5046)?;
        let ext = self.ior(p, "ext_ior", 1.000277)?;
        let ior = int / ext;
        if !(ior > 0.0) || !(ior as f32).is_finite() {
            return Err(p.err(
                p.elem,
                format!("the relative IOR {int}/{ext} is not a positive number"),
            ));
        }
        Ok(ior as f32)
    }

    /// Mitsuba's microfacet parameters: `distribution` (beckmann, the default, or ggx), `alpha` or
    /// `alpha_u` and `alpha_v` (default 0.1), `sample_visible` (default true).
    fn microfacet(
        &mut self,
        p: &Plugin<'a>,
        slots: &mut Vec<(TextureSlot, Texture)>,
    ) -> Result<Microfacet, SceneError> {
        let e = p.elem;
        let kind = match p.string("distribution")? {
            None | Some(("beckmann", _)) => MicrofacetType::Beckmann,
            Some(("ggx", _)) => MicrofacetType::Ggx,
            Some((other, de)) => {
                return Err(p.err(
                    de,
                    format!("`distribution` must be ggx or beckmann, got `{other}`"),
                ))
            }
        };
        // A texture of α (or of α_u, α_v): the distribution keeps the default 0.1 there until a
        // point sets it (`TextureSlot::Alpha`, `AlphaU`, `AlphaV`).
        let mut roughness = |name: &str, slot| -> Result<Option<Option<f64>>, SceneError> {
            match p.texture(name) {
                Some(t) => {
                    let texture = self.texture(t)?;
                    slots.push((slot, texture));
                    Ok(Some(None))
                }
                None => Ok(p.float(name)?.map(Some)),
            }
        };
        let alpha = roughness("alpha", TextureSlot::Alpha)?;
        let au = roughness("alpha_u", TextureSlot::AlphaU)?;
        let av = roughness("alpha_v", TextureSlot::AlphaV)?;
        // α_u runs along the shading frame's x axis, ∂p/∂u made orthogonal to the normal
        // (`SurfaceHit::tangent`), as in Mitsuba.
        let (u, v) = match (alpha, au, av) {
            (Some(a), None, None) => (a, a),
            (None, None, None) => (Some(0.1), Some(0.1)),
            (None, Some(u), Some(v)) => (u, v),
            _ => return Err(p.err(e, "give `alpha`, or both `alpha_u` and `alpha_v`")),
        };
        for a in [u, v].into_iter().flatten() {
            if !(a >= MIN_ROUGHNESS) || !(a.is_finite()) {
                return Err(p.err(e, format!("`alpha` must be at least {MIN_ROUGHNESS}, got {a} (use a conductor for a mirror)")));
            }
        }
        let sample_visible = p.boolean("sample_visible")?.unwrap_or(true);
        let (u, v) = (u.unwrap_or(0.1) as f32, v.unwrap_or(0.1) as f32);
        Ok(Microfacet::new(kind, u, v, sample_visible))
    }

    /// A conductor's complex IOR: Mitsuba's `material` name (default "none", a perfect mirror), or
    /// `eta` and `k` given together (RGB, spectrum or float).
    fn complex_ior(&mut self, p: &Plugin<'a>) -> Result<ComplexIor, SceneError> {
        let opts = self.opts;
        let eta = p.color("eta", ColorUse::Unbounded, opts, &mut self.report)?;
        let k = p.color("k", ColorUse::Unbounded, opts, &mut self.report)?;
        let named = p.string("material")?;
        match (named, eta, k) {
            (None, None, None) => Ok(named_conductor("none").expect("none is a conductor")),
            (Some((name, me)), None, None) => named_conductor(name).ok_or_else(|| {
                let names: Vec<&str> = conductor_names().collect();
                p.err(
                    me,
                    format!(
                        "conductor material `{name}` is not one Mitsuba knows (known: {})",
                        names.join(", ")
                    ),
                )
            }),
            (None, Some(eta), Some(k)) => Ok(ComplexIor { eta, k }),
            (Some((_, me)), _, _) => {
                Err(p.err(me, "give a conductor `material` or `eta` and `k`, not both"))
            }
            _ => Err(p.err(p.elem, "a conductor's `eta` and `k` go together: give both")),
        }
    }

    // ---------------------------------------------------------------- shapes

    /// Adds the shape; returns whether it emits.
    /// A top-level `<shape>`: a shape, a `shapegroup` (nothing until instanced) or an `instance`
    /// of one, which adds a copy of each of the group's shapes under the instance's `to_world`
    /// (flattened: lt's ray core has no instancing, the geometry is repeated). Returns how many
    /// emitting shapes it added.
    fn shape_or_instance(
        &mut self,
        e: &'a Elem,
        b: &mut WorldBuilder,
    ) -> Result<usize, SceneError> {
        match e.attr("type").unwrap_or("") {
            "shapegroup" => {
                let p = self.plugin(e)?;
                for s in p.nested(&["shape"]) {
                    if matches!(s.attr("type"), Some("shapegroup" | "instance")) {
                        return Err(p.err(s, "a shapegroup holds shapes, not groups or instances"));
                    }
                }
                p.finish(&[], &mut self.report)?;
                Ok(0)
            }
            "instance" => {
                let p = self.plugin(e)?;
                let parent = p
                    .transform("to_world")?
                    .map_or(DMat4::IDENTITY, |(x, _)| x.m);
                let groups = p.nested(&["shape"]);
                let group = match groups[..] {
                    [g] if g.attr("type") == Some("shapegroup") => g,
                    _ => {
                        return Err(p.err(e, "an instance needs exactly one <ref> to a shapegroup"))
                    }
                };
                p.finish(&[], &mut self.report)?;
                let gp = self.plugin(group)?;
                let members = gp.nested(&["shape"]);
                let mut emitters = 0;
                for s in members {
                    emitters += self.shape(s, b, parent)? as usize;
                }
                Ok(emitters)
            }
            _ => Ok(self.shape(e, b, DMat4::IDENTITY)? as usize),
        }
    }

    /// Adds the shape, placed by `parent` (an instance's transform) after its own `to_world`;
    /// returns whether it emits.
    fn shape(
        &mut self,
        e: &'a Elem,
        b: &mut WorldBuilder,
        parent: DMat4,
    ) -> Result<bool, SceneError> {
        let p = self.plugin(e)?;
        let doc = self.doc;
        let xform = p.transform("to_world")?.map(|(x, te)| {
            (
                Xform {
                    m: parent * x.m,
                    ..x
                },
                te,
            )
        });
        let xform = match xform {
            None if parent != DMat4::IDENTITY => Some((
                Xform {
                    m: parent,
                    lookat: None,
                },
                e,
            )),
            x => x,
        };
        let flip = p.boolean("flip_normals")?.unwrap_or(false);
        let ctx = doc.ctx(e.src);
        let (m, span) = match &xform {
            Some((x, te)) => (x.m, te.range.clone()),
            None => (DMat4::IDENTITY, e.range.clone()),
        };
        let placed = |mesh: WorldMesh, span: std::ops::Range<usize>| match mesh.out_of_range() {
            Some(p) => Err(ctx.at(span, out_of_range_message("the transformed shape", p))),
            None => Ok(WorldGeometry::Mesh(mesh)),
        };
        let geometry = match p.kind {
            "rectangle" => {
                check_quad(&ctx, &m, span.clone())?;
                placed(WorldMesh::place(&TriangleMesh::unit_rectangle(), &m), span)?
            }
            "cube" => {
                check_solid(&ctx, &m, span.clone(), "cube")?;
                placed(WorldMesh::place(&TriangleMesh::unit_cube(), &m), span)?
            }
            "sphere" => {
                let c = DVec3::from_array(p.vec3("center")?.unwrap_or([0.0; 3]));
                let r = p.float("radius")?.unwrap_or(1.0);
                if !(r > 0.0) {
                    return Err(p.err(e, format!("sphere `radius` must be positive, got {r}")));
                }
                let (center, radius, rotation) = match &xform {
                    None => (c, r, None),
                    Some((x, te)) => {
                        let s = similarity_scale(&x.m).ok_or_else(|| {
                            p.err(te, "a sphere's to_world must be a rotation, uniform scale and translation (an ellipsoid is not supported)")
                        })?;
                        // The rotation is kept for uv and tangents (Mitsuba's are in the
                        // sphere's object frame); none when there is none.
                        let rot = glam::DMat3::from_mat4(x.m) * (1.0 / s);
                        let rotation = (rot != glam::DMat3::IDENTITY).then_some(rot);
                        (x.m.transform_point3(c), r * s, rotation)
                    }
                };
                if !crate::world::in_range(center) || !(radius as f32).is_finite() {
                    return Err(p.err(e, out_of_range_message("the sphere", center + radius)));
                }
                WorldGeometry::Sphere {
                    center,
                    radius,
                    rotation,
                }
            }
            // Exact disk: the unit disk under `to_world` (an ellipse under a non-uniform scale).
            "disk" => {
                check_quad(&ctx, &m, span.clone())?;
                WorldGeometry::Disk {
                    to_world: checked_map(&p, e, &m, "disk")?,
                }
            }
            // Mitsuba's cylinder: to_world · translate(p0) · to_frame(p1 − p0) · scale(r, r, |p1 −
            // p0|) maps the unit cylinder; Mitsuba then keeps only that map's rotation and its
            // diagonal stretch (r, l), so a shear or unequal x/y scale is refused here rather
            // than rendered differently.
            "cylinder" => {
                let r = p.float("radius")?.unwrap_or(1.0);
                let p0 = DVec3::from_array(p.vec3("p0")?.unwrap_or([0.0; 3]));
                let p1 = DVec3::from_array(p.vec3("p1")?.unwrap_or([0.0, 0.0, 1.0]));
                let axis = p1 - p0;
                let len = axis.length();
                if !(len > 0.0) || !(r != 0.0) || !r.is_finite() {
                    return Err(p.err(e, format!("a cylinder needs p0 ≠ p1 and a non-zero radius (got radius {r}, |p1 − p0| = {len})")));
                }
                // Duff et al.'s orthonormal basis around the axis (Mitsuba's Frame, lt's Frame::from_z).
                let f = lt_core::math::Frame::from_z(axis.normalize().as_vec3());
                let frame = DMat4::from_cols(
                    f.x.as_dvec3().extend(0.0),
                    f.y.as_dvec3().extend(0.0),
                    (axis / len).extend(0.0),
                    glam::DVec4::W,
                );
                let full = m
                    * DMat4::from_translation(p0)
                    * frame
                    * DMat4::from_scale(DVec3::new(r, r, len));
                if !lt_core::geometry::quadric::is_round_cylinder_map(&glam::DMat3::from_mat4(full), 1e-5) {
                    return Err(p.err(
                        xform.as_ref().map_or(e, |(_, te)| te),
                        "a cylinder's to_world must be a rotation, a scale equal along x and y, and a translation (Mitsuba drops shear and unequal x/y scales, with a warning)",
                    ));
                }
                WorldGeometry::Cylinder {
                    to_world: checked_map(&p, e, &full, "cylinder")?,
                }
            }
            // Mitsuba's SDF grid: its file's values over the unit cube, under to_world.
            "sdfgrid" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, "shape `sdfgrid` needs a `filename`"));
                };
                let smooth = match p.string("normals")? {
                    None | Some(("smooth", _)) => true,
                    Some(("analytic", _)) => false,
                    Some((other, ne)) => {
                        return Err(p.err(ne, format!("sdfgrid `normals` must be `smooth` or `analytic`, got `{other}`")))
                    }
                };
                let path = doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("volume grid file", file, &looked))
                })?;
                let resolved = Ctx { base_dir: PathBuf::new(), ..doc.ctx(e.src) };
                let spanned =
                    toml::Spanned::new(fe.range.clone(), path.to_string_lossy().into_owned());
                let grid = crate::mesh::vol::load_sdf_grid(&resolved, &spanned, smooth)?;
                self.meshes.push(path);
                WorldGeometry::SdfGrid {
                    grid: std::sync::Arc::new(grid),
                    to_world: checked_map(&p, e, &m, "sdfgrid")?,
                }
            }
            "obj" | "ply" | "serialized" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, format!("shape `{}` needs a `filename`", p.kind)));
                };
                let mut face_normals = p.boolean("face_normals")?.unwrap_or(false);
                let shape_index = match p.kind {
                    "serialized" => p.integer("shape_index")?.map_or(Ok(0), |i| {
                        u32::try_from(i).map_err(|_| {
                            p.err(e, format!("`shape_index` must be a non-negative integer, got {i}"))
                        })
                    })?,
                    _ => 0,
                };
                check_solid(&ctx, &m, span.clone(), "mesh")?;
                let path = doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("mesh file", file, &looked))
                })?;
                // The mesh readers join their context's folder with the name: give them the
                // resolved path and no folder.
                let resolved = Ctx { base_dir: PathBuf::new(), ..doc.ctx(e.src) };
                let spanned =
                    toml::Spanned::new(fe.range.clone(), path.to_string_lossy().into_owned());
                let mut mesh = match p.kind {
                    "obj" => crate::mesh::obj::load_obj(&resolved, &spanned)?,
                    "ply" => ply::load_ply(&resolved, &spanned)?,
                    _ => {
                        // The file's own "face normals" flag is the same as `face_normals`.
                        let s = serialized::load_serialized(&resolved, &spanned, shape_index)?;
                        face_normals |= s.face_normals;
                        s.mesh
                    }
                };
                self.meshes.push(path);
                if face_normals {
                    mesh.normals = None;
                } else if mesh.normals.is_none() {
                    // Mitsuba shades a mesh without normals smoothly, with normals it computes.
                    mesh.normals = Some(vertex_normals(&mesh));
                }
                let mesh = WorldMesh::place(&mesh, &m);
                if !(mesh.area() > 0.0) {
                    return Err(p.err(fe, "the mesh has zero area (every triangle is degenerate)"));
                }
                placed(mesh, span)?
            }
            other => {
                return Err(p.err(
                    e,
                    format!("shape `{other}` is not supported (lt reads rectangle, cube, sphere, disk, cylinder, sdfgrid, obj, ply and serialized)"),
                ))
            }
        };
        let bsdf = p.one_nested(&["bsdf"], "BSDF")?;
        // Mitsuba gives a shape without a BSDF a diffuse one of reflectance 0.5, except an
        // emitting shape, whose default is black: a light does not reflect unless it is told to
        // (the material grid's floor was 0.35 % too bright by light bounced off the lamp).
        let emits = p.one_nested(&["emitter"], "emitter")?.is_some();
        let material = match bsdf {
            Some(be) => self.material(be, b)?,
            None if emits => match self.default_emitter_material {
                Some(id) => id,
                None => {
                    let id = b.add_material(Material::Diffuse(Diffuse {
                        albedo: Color::ZERO,
                    }));
                    self.default_emitter_material = Some(id);
                    id
                }
            },
            None => match self.default_material {
                Some(id) => id,
                None => {
                    let id = b.add_material(Material::Diffuse(Diffuse {
                        albedo: Color::splat(0.5),
                    }));
                    self.default_material = Some(id);
                    id
                }
            },
        };
        let emission = match p.one_nested(&["emitter"], "emitter")? {
            None => None,
            Some(em) => {
                let ep = self.plugin(em)?;
                if ep.kind != "area" {
                    return Err(ep.err(
                        em,
                        format!(
                            "emitter `{}` inside a shape: only `area` emitters attach to shapes",
                            ep.kind
                        ),
                    ));
                }
                // A textured radiance is read at the shape's uv, as materials' textures are.
                if let Some(t) = ep.texture("radiance") {
                    let texture = self.texture(t)?;
                    if texture.mesh_attribute().is_some() {
                        return Err(ep.err(
                            t,
                            "a mesh attribute as an area emitter's `radiance` is not supported \
                             (light samples know a point's uv, not its attributes)",
                        ));
                    }
                    ep.finish(&["sampling_weight"], &mut self.report)?;
                    return self.finish_shape(&p, b, geometry, material, Some(texture), flip);
                }
                let r = ep
                    .color("radiance", ColorUse::Emission, self.opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                ep.finish(&["sampling_weight"], &mut self.report)?;
                (r.max_element() > 0.0).then_some(Texture::Constant(r))
            }
        };
        self.finish_shape(&p, b, geometry, material, emission, flip)
    }

    /// The shape's last step: its remaining parameters checked, then added (emitting when
    /// `radiance` is given); whether it emits.
    fn finish_shape(
        &mut self,
        p: &Plugin<'a>,
        b: &mut WorldBuilder,
        geometry: WorldGeometry,
        material: u32,
        radiance: Option<Texture>,
        flip: bool,
    ) -> Result<bool, SceneError> {
        if let Some(name) = b.material(material).mesh_attribute() {
            let has = match &geometry {
                WorldGeometry::Mesh(m) => m.attributes.iter().any(|a| a.name == name),
                _ => false,
            };
            if !has {
                let known: Vec<&str> = match &geometry {
                    WorldGeometry::Mesh(m) => {
                        m.attributes.iter().map(|a| a.name.as_str()).collect()
                    }
                    _ => Vec::new(),
                };
                return Err(p.err(
                    p.elem,
                    format!(
                        "the shape's material reads mesh attribute `{name}`, which the shape does not have (it has: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ),
                ));
            }
        }
        if radiance.is_some() && matches!(geometry, WorldGeometry::SdfGrid { .. }) {
            return Err(p.err(
                p.elem,
                "an sdfgrid cannot be an area emitter (Mitsuba's cannot either)",
            ));
        }
        let ignored: &[&str] = match p.kind {
            "obj" | "ply" => &["flip_tex_coords"],
            _ => &[],
        };
        p.finish(ignored, &mut self.report)?;
        let emits = radiance.is_some();
        b.add_shape(geometry, material, radiance, flip);
        Ok(emits)
    }

    // ---------------------------------------------------------------- emitters

    /// The light and, for a point light, its world position in f64 (`WorldBuilder` rounds it).
    fn emitter(&mut self, e: &'a Elem) -> Result<Option<(LightDesc, Option<DVec3>)>, SceneError> {
        let p = self.plugin(e)?;
        let opts = self.opts;
        let desc = match p.kind {
            "point" => {
                let intensity = p
                    .color("intensity", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                let pos = p.vec3("position")?;
                let xf = p.transform("to_world")?;
                let position = match (pos, xf) {
                    (Some(_), Some((_, te))) => {
                        return Err(p.err(te, "give a point light `position` or `to_world`, not both"))
                    }
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some((x, _))) => x.m.transform_point3(DVec3::ZERO),
                    (None, None) => DVec3::ZERO,
                };
                if !crate::world::in_range(position) {
                    return Err(p.err(e, out_of_range_message("the point light", position)));
                }
                p.finish(&["sampling_weight"], &mut self.report)?;
                return Ok((intensity.max_element() > 0.0).then_some((
                    LightDesc::Point {
                        position: glam::Vec3::ZERO,
                        intensity,
                    },
                    Some(position),
                )));
            }
            "constant" => LightDesc::Environment {
                radiance: p
                    .color("radiance", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE),
            },
            "directional" => {
                let irradiance = p
                    .color("irradiance", ColorUse::Emission, opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                let d = p.vec3("direction")?;
                let xf = p.transform("to_world")?;
                // Mitsuba's direction is the one the light travels along; lt's points to the light.
                let travel = match (d, xf) {
                    (Some(_), Some((_, te))) => {
                        return Err(p.err(te, "give a directional light `direction` or `to_world`, not both"))
                    }
                    (Some(v), None) => DVec3::from_array(v),
                    (None, Some((x, _))) => x.m.transform_vector3(DVec3::Z),
                    (None, None) => DVec3::Z,
                };
                // Normalised in f32 as the TOML loader does, so a converted scene reads back exactly.
                let towards = -travel.as_vec3();
                if !(towards.length() > 0.0) || !towards.is_finite() {
                    return Err(p.err(e, "the directional light's `direction` is the zero vector"));
                }
                LightDesc::Directional {
                    direction: towards.normalize(),
                    irradiance,
                }
            }
            "area" => return Err(p.err(e, "an area emitter must be nested in a shape")),
            "envmap" => {
                let Some((file, fe)) = p.string("filename")? else {
                    return Err(p.err(e, "an envmap needs a `filename`"));
                };
                let path = self.doc.resolver.resolve(file).map_err(|looked| {
                    p.err(fe, Resolver::not_found("environment map", file, &looked))
                })?;
                let scale = p.float("scale")?.unwrap_or(1.0) as f32;
                let (to_world, _) = rigid_to_world(&p, "an envmap")?;
                if p.has("mis_compensation") {
                    return Err(p.err(e, "`mis_compensation` of an envmap is not supported"));
                }
                let map = read_environment_map(&path, scale, to_world).map_err(|m| p.err(fe, m))?;
                self.meshes.push(path);
                LightDesc::EnvironmentMap {
                    map: std::sync::Arc::new(map),
                }
            }
            "spot" => return self.spot(p).map(|d| d.map(|(d, at)| (d, Some(at)))),
            "projector" => return self.projector(p).map(|d| d.map(|(d, at)| (d, Some(at)))),
            other => {
                return Err(p.err(
                    e,
                    format!("emitter `{other}` is not supported (lt reads area, point, spot, projector, constant, directional and envmap)"),
                ))
            }
        };
        p.finish(&["sampling_weight"], &mut self.report)?;
        let power = match &desc {
            LightDesc::Point { intensity: c, .. }
            | LightDesc::Directional { irradiance: c, .. }
            | LightDesc::Environment { radiance: c }
            | LightDesc::Sun { radiance: c, .. } => c.max_element(),
            LightDesc::EnvironmentMap { map } => map.integral(),
            LightDesc::Spot { .. } | LightDesc::Projector { .. } => {
                unreachable!("spot and projector return above")
            }
        };
        Ok((power > 0.0).then_some((desc, None)))
    }

    /// Mitsuba's `spot`: `intensity` (default 1), an optional `texture` over the cone,
    /// `cutoff_angle` (degrees, default 20), `beam_width` (default ¾ of the cutoff), `to_world`
    /// (a rigid motion: +z is the beam's axis). None when it emits nothing.
    fn spot(&mut self, p: Plugin<'a>) -> Result<Option<(LightDesc, DVec3)>, SceneError> {
        let e = p.elem;
        let opts = self.opts;
        let intensity = p
            .color("intensity", ColorUse::Emission, opts, &mut self.report)?
            .unwrap_or(Color::ONE);
        let texture = match p.texture("texture") {
            Some(t) => Some(self.texture(t)?),
            None if p.has("texture") => {
                return Err(p.err(e, "a spot light's `texture` must be a <texture>"))
            }
            None => None,
        };
        let cutoff = p.float("cutoff_angle")?.unwrap_or(20.0);
        let beam = p.float("beam_width")?.unwrap_or(0.75 * cutoff);
        // The texture lies on the plane z = 1 in front of the light, so its cone must be too.
        let max = if texture.is_some() { 90.0 } else { 180.0 };
        if !(cutoff > 0.0 && cutoff < max) {
            return Err(p.err(
                e,
                format!(
                    "a spot light's `cutoff_angle` must lie in (0°, {max}°){}, got {cutoff}",
                    if texture.is_some() {
                        " with a texture"
                    } else {
                        ""
                    }
                ),
            ));
        }
        if !(beam >= 0.0 && beam.is_finite()) {
            return Err(p.err(e, format!("a spot light's `beam_width` must be a non-negative angle in degrees, got {beam}")));
        }
        let (to_world, position) = rigid_to_world(&p, "a spot light")?;
        p.finish(&["sampling_weight"], &mut self.report)?;
        let dark = intensity.max_element() <= 0.0
            || texture.as_ref().is_some_and(|t| t.max_value() <= 0.0);
        Ok((!dark).then_some((
            LightDesc::Spot {
                position: glam::Vec3::ZERO,
                to_world,
                intensity,
                texture,
                cutoff: (cutoff as f32).to_radians(),
                beam_width: (beam as f32).to_radians(),
            },
            position,
        )))
    }

    /// Mitsuba's `projector`: `irradiance` (a colour or a texture on the image plane at z = 1,
    /// default 1), `scale` (default 1), the field of view as a perspective sensor gives it (`fov`
    /// with `fov_axis`, or `focal_length` 50mm by default) for the image's aspect ratio (1 for a
    /// colour), `to_world` (a rigid motion: +z is the optical axis). None when it emits nothing.
    fn projector(&mut self, p: Plugin<'a>) -> Result<Option<(LightDesc, DVec3)>, SceneError> {
        let e = p.elem;
        let opts = self.opts;
        let (irradiance, aspect) = match p.texture("irradiance") {
            Some(t) => {
                let tex = self.texture(t)?;
                let aspect = match &tex {
                    Texture::Bitmap(b) => b.width as f64 / b.height as f64,
                    _ => 1.0,
                };
                (tex, aspect)
            }
            None => (
                Texture::Constant(
                    p.color("irradiance", ColorUse::Emission, opts, &mut self.report)?
                        .unwrap_or(Color::ONE),
                ),
                1.0,
            ),
        };
        let scale = p.float("scale")?.unwrap_or(1.0);
        if !(scale >= 0.0 && scale.is_finite()) {
            return Err(p.err(
                e,
                format!("a projector's `scale` must be finite and non-negative, got {scale}"),
            ));
        }
        let tan_x = projector_tan_half_x(&p, aspect)?;
        let (to_world, position) = rigid_to_world(&p, "a projector")?;
        p.finish(&["sampling_weight"], &mut self.report)?;
        let dark = scale == 0.0 || irradiance.max_value() <= 0.0;
        Ok((!dark).then_some((
            LightDesc::Projector {
                position: glam::Vec3::ZERO,
                to_world,
                irradiance,
                scale: scale as f32,
                tan_half: Vec2::new(tan_x as f32, (tan_x / aspect) as f32),
            },
            position,
        )))
    }
}

/// The rotation and the translation of a light's `to_world` (identity when absent), which must
/// be a rigid motion: angles and directions in the light's frame keep their meaning only then.
fn rigid_to_world(p: &Plugin, what: &str) -> Result<(glam::Mat3, DVec3), SceneError> {
    let Some((x, te)) = p.transform("to_world")? else {
        return Ok((glam::Mat3::IDENTITY, DVec3::ZERO));
    };
    let m = glam::DMat3::from_mat4(x.m);
    let ortho = (m.transpose() * m - glam::DMat3::IDENTITY)
        .to_cols_array()
        .iter()
        .fold(0.0f64, |a, v| a.max(v.abs()));
    if !(ortho < 1e-6) || m.determinant() < 0.0 {
        return Err(p.err(
            te,
            format!("{what}'s to_world must be a rotation (no scale, shear or mirror)"),
        ));
    }
    let position = x.m.transform_point3(DVec3::ZERO);
    if !crate::world::in_range(position) {
        return Err(p.err(te, out_of_range_message(what, position)));
    }
    Ok((crate::transform::positive_zeros(m).as_mat3(), position))
}

/// tan(fov_x / 2) of a projector whose image has width / height = `aspect`, read as Mitsuba reads
/// a perspective sensor's field of view: `fov` across `fov_axis` (x, y, diagonal, smaller or
/// larger; default x), or a 35 mm `focal_length` (default 50mm) across the diagonal.
fn projector_tan_half_x(p: &Plugin, aspect: f64) -> Result<f64, SceneError> {
    let e = p.elem;
    let axis = match p.string("fov_axis")? {
        None => "x",
        Some((a @ ("x" | "y" | "diagonal" | "smaller" | "larger"), _)) => a,
        Some((a, ae)) => {
            return Err(p.err(
                ae,
                format!("`fov_axis` must be x, y, diagonal, smaller or larger, got `{a}`"),
            ))
        }
    };
    let (tan_half, axis) = match (p.float("fov")?, p.string("focal_length")?) {
        (Some(_), Some((_, fe))) => {
            return Err(p.err(fe, "give the projector `fov` or `focal_length`, not both"))
        }
        (Some(f), None) => {
            if !(f > 0.0 && f < 180.0) {
                return Err(p.err(
                    e,
                    format!("a projector's `fov` must lie in (0°, 180°), got {f}"),
                ));
            }
            ((0.5 * f).to_radians().tan(), axis)
        }
        (None, f) => {
            let (text, at) = f.unwrap_or(("50mm", e));
            let mm = text.trim().trim_end_matches("mm").trim();
            let f: f64 = mm.parse().ok().filter(|f: &f64| *f > 0.0 && f.is_finite()).ok_or_else(|| {
                p.err(at, format!("`focal_length` must be a positive length in mm like \"50mm\", got `{text}`"))
            })?;
            // 35 mm film equivalent: half the 36 × 24 mm frame's diagonal over the focal length.
            (
                (36.0f64 * 36.0 + 24.0 * 24.0).sqrt() / (2.0 * f),
                "diagonal",
            )
        }
    };
    let to_x = match axis {
        "y" => aspect,
        "diagonal" => aspect / (1.0 + aspect * aspect).sqrt(),
        "smaller" if aspect > 1.0 => aspect,
        "larger" if aspect < 1.0 => aspect,
        _ => 1.0,
    };
    Ok(tan_half * to_x)
}

/// The object-to-world map `m` of a disk, cylinder or sdfgrid (of its unit shape), refused when
/// singular or reaching beyond the coordinates the scene can hold.
fn checked_map(p: &Plugin, e: &Elem, m: &DMat4, what: &str) -> Result<DMat4, SceneError> {
    let corner = m.transform_point3(DVec3::ONE);
    let det = glam::DMat3::from_mat4(*m).determinant();
    if !crate::world::in_range(corner) || !crate::world::in_range(m.w_axis.truncate()) {
        return Err(p.err(e, out_of_range_message(&format!("the {what}"), corner)));
    }
    if !(det.abs() > 0.0) || !det.is_finite() {
        return Err(p.err(
            e,
            format!("the {what}'s to_world is singular (determinant {det})"),
        ));
    }
    Ok(*m)
}

/// Angle-weighted vertex normals (each face's unit normal weighted by its angle at the vertex),
/// what Mitsuba computes for a mesh file without normals (checked against it on a tetrahedron).
fn vertex_normals(m: &TriangleMesh) -> Vec<glam::Vec3> {
    let mut acc = vec![DVec3::ZERO; m.positions.len()];
    for t in &m.indices {
        let p = t.map(|i| m.positions[i as usize].as_dvec3());
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        if !(n.length() > 0.0) {
            continue;
        }
        let n = n.normalize();
        for k in 0..3 {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let angle = a.angle_between(b);
            if angle.is_finite() {
                acc[t[k] as usize] += angle * n;
            }
        }
    }
    acc.into_iter()
        .map(|n| n.normalize_or_zero().as_vec3())
        .collect()
}

/// The uniform scale of a similarity transform (rotation × uniform scale + translation).
fn similarity_scale(m: &DMat4) -> Option<f64> {
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate());
    let s = cols[0].length();
    let tol = 1e-5 * s;
    let ok = s > 0.0
        && cols.iter().all(|c| (c.length() - s).abs() <= tol)
        && cols[0].dot(cols[1]).abs() <= tol * s
        && cols[0].dot(cols[2]).abs() <= tol * s
        && cols[1].dot(cols[2]).abs() <= tol * s;
    ok.then_some(s)
}

/// What a sensor adds to its look-at: a thin lens (aperture radius, focus distance), the
/// principal point offset and the film's pixel filter.
struct Optics {
    lens: Option<(f32, f32)>,
    /// An orthographic sensor's film half width at the eye.
    ortho_half_width: Option<f32>,
    principal: Vec2,
    filter: PixelFilter,
}

impl Optics {
    fn apply(&self, camera: Camera) -> Result<Camera, String> {
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
fn camera_frame(p: &Plugin, m: &DMat4, te: &Elem) -> Result<(DVec3, DVec3, DVec3), SceneError> {
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

/// A string parameter parsed by `parse`, its error placed at the parameter (or at the element
/// `e` when the parameter is absent).
fn parse_named<T>(
    p: &Plugin,
    e: &Elem,
    key: &str,
    parse: fn(Option<&str>) -> Result<T, String>,
) -> Result<T, SceneError> {
    let given = p.string(key)?;
    parse(given.map(|(name, _)| name))
        .map_err(|m| p.err(given.map_or(e, |(_, ke)| ke), format!("`{key}` {m}")))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's vertex normals of the OBJ tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1)
    /// with faces 1 3 2, 1 2 4, 1 4 3, 2 3 4, at the vertex (0,1,0).
    #[test]
    fn xml_vertex_normals_are_mitsubas() {
        let m = TriangleMesh {
            positions: vec![
                glam::Vec3::ZERO,
                glam::Vec3::X,
                glam::Vec3::Y,
                glam::Vec3::Z,
            ],
            normals: None,
            uvs: None,
            indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            attributes: Vec::new(),
        };
        let n = vertex_normals(&m);
        let theirs = glam::Vec3::new(-0.275_421_47, 0.921_024_4, -0.275_421_47);
        assert!((n[2] - theirs).abs().max_element() < 1e-6, "{:?}", n[2]);
        let k = -(1.0f32 / 3.0).sqrt();
        assert!((n[0] - glam::Vec3::splat(k)).abs().max_element() < 1e-6);
    }
}
