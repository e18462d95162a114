//! The plugin subset: the XML's sensor, integrator, BSDFs, shapes and emitters turned into a
//! `Scene` through `SceneBuilder`, each value checked on the way (reference: docs/xml.md).

use crate::world::{MediumAt, WorldBuilder};
use crate::xml::doc::{Doc, Elem};
use crate::xml::props::{Ids, Plugin};
use crate::SceneError;
use crate::{LoadOptions, LoadReport};
use lt_core::medium::MediumId;
use lt_core::scene::{RenderSettings, Scene};
use std::collections::{HashMap, HashSet};
use std::path::PathBuf;

mod bsdf;
mod bsdf_params;
mod bsdf_toml;
mod emitter;
mod integrator;
mod kinds;
mod medium;
mod sensor;
mod shape;
mod texture;

pub(crate) use bsdf::{toml_material, toml_materials};
pub(crate) use bsdf_toml::Keys;
pub use integrator::UNBOUNDED_DEPTH_SUBSTITUTE;
pub(crate) use medium::MEDIA;

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
    /// Medium ids of medium elements already built (by element address).
    media: HashMap<*const Elem, MediumId>,
    /// The media built, in id order, handed to the builder at the end.
    media_made: Vec<MediumAt>,
    camera_medium: Option<MediumId>,
    /// The medium of the emitter read last.
    emitter_medium: Option<MediumId>,
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

/// The scene of a plugin tree (an XML file's, or one a TOML file was turned into), its report
/// and the files its meshes, volumes and textures came from; `no_light` is the error for a scene
/// that emits nothing, in the words of the tree's format.
pub(crate) fn load(
    doc: &Doc,
    opts: &LoadOptions,
    no_light: &dyn Fn() -> SceneError,
) -> Result<(Scene, LoadReport, Vec<PathBuf>), SceneError> {
    let mut ids = Ids::new();
    collect_ids(doc, &doc.root, &mut ids)?;
    // Unknown types, undefined ids and media first, all of them, before any value is read.
    let mut referenced = HashSet::new();
    let problems = kinds::problems(doc, &ids, &mut referenced);
    if !problems.is_empty() {
        return Err(kinds::combined(problems));
    }
    let mut l = Loader::new(doc, opts, ids);
    let root = &doc.root;
    let by_tag = |t: &'static str| root.children.iter().filter(move |c| c.tag == t);
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
    // Top-level media and phase functions likewise, referenced or not.
    for c in by_tag("phase") {
        l.phase(c)?;
    }
    for c in by_tag("medium") {
        l.medium(c)?;
    }
    let mut emitters = 0;
    for c in &root.children {
        match c.tag.as_str() {
            "shape" => emitters += l.shape_or_instance(c, &mut b)?,
            // An area emitter given its own id is attached where a shape references it (Mitsuba
            // resolves such references in any order).
            "emitter"
                if c.attr("type") == Some("area")
                    && c.attr("id").is_some_and(|id| referenced.contains(id)) => {}
            "emitter" => {
                match l.emitter(c)? {
                    Some((desc, Some(position))) => b.add_light_at(desc, position),
                    Some((desc, None)) => b.add_light(desc),
                    None => continue,
                }
                b.set_last_light_medium(l.emitter_medium.take());
                emitters += 1;
            }
            _ => {}
        }
    }
    if emitters == 0 {
        return Err(no_light());
    }
    let Loader {
        report,
        meshes,
        media_made,
        camera_medium,
        ..
    } = l;
    for make in media_made {
        b.add_medium(make);
    }
    b.set_camera_medium(camera_medium);
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
    fn new(doc: &'a Doc, opts: &'a LoadOptions, ids: Ids<'a>) -> Self {
        Loader {
            doc,
            opts,
            report: LoadReport::default(),
            ids,
            materials: HashMap::new(),
            default_material: None,
            default_emitter_material: None,
            meshes: Vec::new(),
            media: HashMap::new(),
            media_made: Vec::new(),
            camera_medium: None,
            emitter_medium: None,
        }
    }

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
}
