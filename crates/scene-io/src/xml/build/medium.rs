//! `<medium>`, `<phase>` and `<volume>`: Mitsuba 3's `homogeneous` and `heterogeneous` media
//! (`src/media/homogeneous.cpp`, `heterogeneous.cpp`), its `isotropic` and `hg` phase functions
//! (`src/phase/hg.cpp`: `g`, 0.8 by default) and its `gridvolume` and `constvolume`
//! (`src/volumes/grid.cpp`, `const.cpp`). Every value is checked by lt-core's constructors; their
//! message is placed at the medium's line.

use super::Loader;
use crate::world::{MediumAt, WorldGeometry};
use crate::xml::doc::Elem;
use crate::xml::props::{ColorUse, Plugin};
use crate::xml::resolve::Resolver;
use crate::SceneError;
use glam::{DMat4, DVec3};
use lt_core::math::Color;
use lt_core::medium::{
    GridMedium, GridVolume, Homogeneous, Medium, MediumId, PhaseFunction, Volume, WrapMode,
};
use lt_core::scene::MediumInterface;
use std::collections::HashMap;
use std::sync::Arc;

pub(crate) const MEDIA: [&str; 2] = ["homogeneous", "heterogeneous"];
pub(super) const PHASES: [&str; 2] = ["isotropic", "hg"];
pub(super) const VOLUMES: [&str; 2] = ["gridvolume", "constvolume"];

/// Parameters Mitsuba's media take that change nothing lt renders.
const MEDIUM_IGNORED: [&str; 2] = ["sample_emitters", "has_spectral_extinction"];

/// A volume as read, placed once the scene's origin is known.
#[derive(Clone)]
enum VolumeAt {
    /// A `constvolume` or a plain value; its `to_world` places the box a heterogeneous medium
    /// lives in (identity for a plain value, as Mitsuba's `get_volume` makes it).
    Constant(Color, DMat4),
    Grid {
        grid: Arc<lt_core::medium::VolumeGrid>,
        to_world: DMat4,
        use_grid_bbox: bool,
        wrap: WrapMode,
    },
}

impl VolumeAt {
    fn at(&self, origin: DVec3) -> Result<Volume, String> {
        match self {
            VolumeAt::Constant(c, to_world) => {
                let m = DMat4::from_translation(-origin) * *to_world;
                Volume::placed_constant(*c, m.as_mat4())
            }
            VolumeAt::Grid {
                grid,
                to_world,
                use_grid_bbox,
                wrap,
            } => {
                let m = DMat4::from_translation(-origin) * *to_world;
                GridVolume::new(grid.clone(), m.as_mat4(), *use_grid_bbox, *wrap).map(Volume::Grid)
            }
        }
    }
}

impl<'a> Loader<'a> {
    /// The id of a `<medium>` element (built once, however often it is referenced).
    pub(super) fn medium(&mut self, e: &'a Elem) -> Result<MediumId, SceneError> {
        let key = e as *const Elem;
        if let Some(&id) = self.media.get(&key) {
            return Ok(id);
        }
        let p = self.plugin(e)?;
        let phase = match p.one_nested(&["phase"], "phase function")? {
            Some(pe) => self.phase(pe)?,
            None => PhaseFunction::Isotropic,
        };
        let scale = p.float("scale")?.unwrap_or(1.0) as f32;
        let make: MediumAt = match p.kind {
            "homogeneous" => {
                let h = self.homogeneous(&p, scale, phase)?;
                Box::new(move |_| Ok(Medium::Homogeneous(h)))
            }
            "heterogeneous" => {
                let sigma_t = self.volume_param(&p, "sigma_t", ColorUse::Unbounded)?;
                let albedo = self.volume_param(&p, "albedo", ColorUse::Reflectance)?;
                let unplaced = |c| VolumeAt::Constant(c, DMat4::IDENTITY);
                let sigma_t = sigma_t.unwrap_or(unplaced(Color::ONE));
                let albedo = albedo.unwrap_or(unplaced(Color::splat(0.75)));
                let error = p.err(e, "");
                let make = move |origin: DVec3| -> Result<Medium, SceneError> {
                    let fail = |m: String| SceneError {
                        message: format!("medium `heterogeneous`: {m}"),
                        ..error.clone()
                    };
                    let s = sigma_t
                        .at(origin)
                        .map_err(|m| fail(format!("sigma_t: {m}")))?;
                    let a = albedo
                        .at(origin)
                        .map_err(|m| fail(format!("albedo: {m}")))?;
                    let g = GridMedium::new(s, scale, a, phase).map_err(fail)?;
                    Ok(Medium::Grid(Box::new(g)))
                };
                // Checked now, so that a bad medium is reported in file order.
                make(DVec3::ZERO)?;
                Box::new(make)
            }
            _ => return Err(super::kinds::unknown_type(self.doc, e)),
        };
        p.finish(&MEDIUM_IGNORED, &mut self.report)?;
        let id = self.media_made.len() as MediumId;
        self.media_made.push(make);
        self.media.insert(key, id);
        Ok(id)
    }

    fn homogeneous(
        &mut self,
        p: &Plugin<'a>,
        scale: f32,
        phase: PhaseFunction,
    ) -> Result<Homogeneous, SceneError> {
        let opts = self.opts;
        let r = &mut self.report;
        let sigma_t = p.color("sigma_t", ColorUse::Unbounded, opts, r)?;
        let albedo = p.color("albedo", ColorUse::Reflectance, opts, r)?;
        let sigma_a = p.color("sigma_a", ColorUse::Unbounded, opts, r)?;
        let sigma_s = p.color("sigma_s", ColorUse::Unbounded, opts, r)?;
        let built = match (sigma_t, albedo, sigma_a, sigma_s) {
            (t, al, None, None) => Homogeneous::new(
                t.unwrap_or(Color::ONE),
                al.unwrap_or(Color::splat(0.75)),
                scale,
                phase,
            ),
            (None, None, Some(a), Some(s)) => Homogeneous::from_absorption(a, s, scale, phase),
            _ => {
                return Err(p.err(
                    p.elem,
                    "medium `homogeneous` takes sigma_t and albedo, or sigma_a and sigma_s \
                     (both), not a mix",
                ))
            }
        };
        built.map_err(|m| p.err(p.elem, format!("medium `homogeneous`: {m}")))
    }

    /// A phase function element.
    pub(super) fn phase(&mut self, e: &'a Elem) -> Result<PhaseFunction, SceneError> {
        let p = self.plugin(e)?;
        let phase = match p.kind {
            "isotropic" => PhaseFunction::Isotropic,
            "hg" => {
                let g = p.float("g")?.unwrap_or(0.8) as f32;
                PhaseFunction::henyey_greenstein(g).map_err(|m| p.err(e, m))?
            }
            _ => return Err(super::kinds::unknown_type(self.doc, e)),
        };
        p.finish(&[], &mut self.report)?;
        Ok(phase)
    }

    /// A medium's volume parameter: a nested or referenced `<volume name=…>`, or a plain colour
    /// (a constant volume).
    fn volume_param(
        &mut self,
        p: &Plugin<'a>,
        name: &str,
        usage: ColorUse,
    ) -> Result<Option<VolumeAt>, SceneError> {
        if let Some(c) = p.color(name, usage, self.opts, &mut self.report)? {
            return Ok(Some(VolumeAt::Constant(c, DMat4::IDENTITY)));
        }
        match p.named_nested(&["volume"], name)? {
            Some(v) => self.volume(v, usage).map(Some),
            None => Ok(None),
        }
    }

    fn volume(&mut self, e: &'a Elem, usage: ColorUse) -> Result<VolumeAt, SceneError> {
        let p = self.plugin(e)?;
        let v = match p.kind {
            "constvolume" => {
                let c = p.color("value", usage, self.opts, &mut self.report)?;
                // Its to_world places its box: where a heterogeneous medium over it exists.
                let to_world = p
                    .transform("to_world")?
                    .map_or(DMat4::IDENTITY, |(x, _)| x.m);
                let v = VolumeAt::Constant(c.unwrap_or(Color::ONE), to_world);
                v.at(DVec3::ZERO)
                    .map_err(|m| p.err(e, format!("volume `constvolume`: {m}")))?;
                v
            }
            "gridvolume" => self.grid_volume(&p)?,
            _ => return Err(super::kinds::unknown_type(self.doc, e)),
        };
        p.finish(&[], &mut self.report)?;
        Ok(v)
    }

    fn grid_volume(&mut self, p: &Plugin<'a>) -> Result<VolumeAt, SceneError> {
        let (doc, e) = (self.doc, p.elem);
        let Some((file, fe)) = p.string("filename")? else {
            return Err(p.err(e, "volume `gridvolume` needs a `filename`"));
        };
        let to_world = p
            .transform("to_world")?
            .map_or(DMat4::IDENTITY, |(x, _)| x.m);
        let use_grid_bbox = p.boolean("use_grid_bbox")?.unwrap_or(false);
        let wrap = match p.string("wrap_mode")? {
            None | Some(("clamp", _)) => WrapMode::Clamp,
            Some(("repeat", _)) => WrapMode::Repeat,
            Some(("mirror", _)) => WrapMode::Mirror,
            Some((other, we)) => {
                return Err(p.err(
                    we,
                    format!("`wrap_mode` must be clamp, repeat or mirror, got `{other}`"),
                ))
            }
        };
        match p.string("filter_type")? {
            None | Some(("trilinear", _)) => {}
            Some((other, fe)) => {
                return Err(p.err(
                    fe,
                    format!("`filter_type` `{other}` is not supported (lt reads trilinear)"),
                ))
            }
        }
        let path = doc
            .resolver
            .resolve(file)
            .map_err(|looked| p.err(fe, Resolver::not_found("volume grid file", file, &looked)))?;
        let resolved = crate::error::Ctx {
            base_dir: std::path::PathBuf::new(),
            ..doc.ctx(e.src)
        };
        let spanned = toml::Spanned::new(fe.range.clone(), path.to_string_lossy().into_owned());
        let grid = crate::mesh::vol::load_volume_grid(&resolved, &spanned)?;
        self.meshes.push(path);
        let v = VolumeAt::Grid {
            grid: Arc::new(grid),
            to_world,
            use_grid_bbox,
            wrap,
        };
        v.at(DVec3::ZERO)
            .map_err(|m| p.err(e, format!("volume `gridvolume`: {m}")))?;
        Ok(v)
    }

    /// The media a shape, sensor or emitter names (`<ref name=… id=…/>` or a nested `<medium
    /// name=…>`), by name; a name outside `allowed` is an error.
    pub(super) fn media_of(
        &mut self,
        p: &Plugin<'a>,
        allowed: &[&str],
    ) -> Result<Vec<(&'a str, MediumId)>, SceneError> {
        let mut found = Vec::new();
        for (name, written, target) in p.named_all(&["medium"]) {
            let name = name.unwrap_or("");
            if !allowed.contains(&name) {
                return Err(p.err(
                    written,
                    format!(
                        "a medium inside {} must be named {} (got `{name}`)",
                        p.what,
                        allowed
                            .iter()
                            .map(|a| format!("`{a}`"))
                            .collect::<Vec<_>>()
                            .join(" or ")
                    ),
                ));
            }
            if found.iter().any(|(n, _)| *n == name) {
                return Err(p.err(written, format!("a second `{name}` medium in {}", p.what)));
            }
            found.push((name, self.medium(target)?));
        }
        Ok(found)
    }

    /// A shape's `interior` and `exterior` media; an interior needs a closed surface.
    pub(super) fn shape_media(
        &mut self,
        p: &Plugin<'a>,
        geometry: &WorldGeometry,
    ) -> Result<MediumInterface, SceneError> {
        let mut media = MediumInterface::default();
        for (name, id) in self.media_of(p, &["interior", "exterior"])? {
            match name {
                "interior" => media.interior = Some(id),
                _ => media.exterior = Some(id),
            }
        }
        if media.interior.is_some() {
            if let Some(why) = open_surface(geometry) {
                return Err(p.err(
                    p.elem,
                    format!(
                        "{} has an interior medium but is not closed ({why}): a medium needs a \
                         surface that bounds it",
                        p.what
                    ),
                ));
            }
        }
        Ok(media)
    }
}

/// Why a shape bounds no volume, or None when it is closed: a sphere or an sdfgrid is; a disk or
/// an open cylinder is not; a mesh is when every edge, its vertices welded by position, is shared
/// by exactly two triangles.
pub(crate) fn open_surface(geometry: &WorldGeometry) -> Option<String> {
    let m = match geometry {
        WorldGeometry::Sphere { .. } | WorldGeometry::SdfGrid { .. } => return None,
        WorldGeometry::Disk { .. } => return Some("a disk".into()),
        WorldGeometry::Cylinder { .. } => return Some("a cylinder is open at both ends".into()),
        WorldGeometry::Mesh(m) => m,
    };
    let key = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
    let mut welded: HashMap<[u64; 3], u32> = HashMap::new();
    let ids: Vec<u32> = m
        .positions
        .iter()
        .map(|&p| {
            let n = welded.len() as u32;
            *welded.entry(key(p)).or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &m.indices {
        for k in 0..3 {
            let (a, b) = (ids[t[k] as usize], ids[t[(k + 1) % 3] as usize]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    let bad = edges.values().filter(|&&n| n != 2).count();
    (bad > 0).then(|| {
        format!(
            "{bad} of its {} edges are not shared by exactly two triangles",
            edges.len()
        )
    })
}
