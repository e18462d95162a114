//! The TOML scene format (docs/scene-format.md): text → `SceneFile` (`schema`, serde's view of
//! the file) → the plugin tree the XML reader builds from (`tree`: TOML's keys renamed, every
//! check that speaks of them made) → `Scene`, by `xml/build`, once for both formats.

pub(crate) mod schema;
pub(crate) mod tree;

use crate::error::Ctx;
use crate::xml::doc::Elem;
use crate::SceneError;
use lt_core::medium::MediumId;
use lt_core::Scene;
use schema::SceneFile;
use std::collections::HashMap;
use std::path::Path;

pub(crate) fn load_toml(path: &Path) -> Result<Scene, SceneError> {
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        file: path.display().to_string(),
        line: None,
        column: None,
        message: format!("cannot read the scene file: {e}"),
    })?;
    load_scene_str(&text, path)
}

/// Parses scene text; `path` names the file in errors and anchors relative mesh paths.
pub fn load_scene_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let ctx = Ctx {
        file: path.display().to_string(),
        text,
        base_dir,
    };
    let file: SceneFile = toml::from_str(text).map_err(|e| match e.span() {
        Some(span) => ctx.at(span, e.message().trim_end().to_string()),
        None => ctx.whole(e.message().trim_end().to_string()),
    })?;
    let (mut scene, volumes) = assemble(&ctx, path, &file)?;
    let meshes = file.shapes.iter().filter_map(|s| s.get_ref().file.as_ref());
    // Texture files in material order (as the XML loader meets them: BSDFs before shapes).
    let mut materials: Vec<_> = file.materials.values().collect();
    materials.sort_by_key(|m| m.span().start);
    let textures = materials.into_iter().flat_map(|m| {
        let m = m.get_ref();
        [
            &m.albedo_texture,
            &m.reflectance_texture,
            &m.alpha_texture,
            &m.normal_map,
            &m.bump_map,
        ]
        .into_iter()
        .flatten()
        .filter_map(|t| t.get_ref().file.as_ref())
    });
    // Lights' images last (environment maps, spot and projector textures): the XML writer puts
    // emitters after the shapes.
    let envmaps = file.lights.iter().filter_map(|l| {
        let l = l.get_ref();
        l.file
            .as_ref()
            .or_else(|| l.texture.as_ref().and_then(|t| t.get_ref().file.as_ref()))
    });
    scene.source_files = std::iter::once(path.to_path_buf())
        .chain(textures.map(|f| ctx.base_dir.join(f.get_ref())))
        .chain(volumes)
        .chain(meshes.map(|f| ctx.base_dir.join(f.get_ref())))
        .chain(envmaps.map(|f| ctx.base_dir.join(f.get_ref())))
        .collect();
    Ok(scene)
}

/// The parsed file as a scene, built from its plugin tree by the builders an XML scene goes
/// through; with the volume files its media read.
fn assemble(
    ctx: &Ctx,
    path: &Path,
    file: &SceneFile,
) -> Result<(Scene, Vec<std::path::PathBuf>), SceneError> {
    let doc = tree::document(path, ctx.text, plugins(ctx, file)?);
    let no_light = || {
        ctx.whole(
            "the scene has no light: give a shape a non-zero `emission` or add a [[lights]] entry",
        )
    };
    let opts = crate::LoadOptions::default();
    let (scene, _, files) = crate::xml::build::load(&doc, &opts, &no_light)?;
    Ok((scene, files.into_iter().filter(is_volume).collect()))
}

/// The file's top-level plugins in the order both builders and Mitsuba read them (every id
/// defined before a reference to it): integrator, media, sensor, BSDFs, emitters, shapes. The
/// TOML checks run in the file's own order (camera and `[render]` first, then materials, media,
/// lights and shapes), so the first error is the first a reader of the file meets.
pub(crate) fn plugins(ctx: &Ctx, file: &SceneFile) -> Result<Vec<Elem>, SceneError> {
    let settings = tree::settings(ctx, file)?;
    let sensor = tree::sensor(ctx, &file.camera, settings.spp)?;
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(_, def)| def.span().start);
    let mut media: Vec<_> = file.media.iter().collect();
    media.sort_by_key(|(_, def)| def.span().start);
    let bsdfs = materials
        .into_iter()
        .map(|(name, def)| tree::material(ctx, name, def))
        .collect::<Result<Vec<_>, _>>()?;
    let media = media
        .into_iter()
        .map(|(name, def)| tree::medium(ctx, name, def))
        .collect::<Result<Vec<_>, _>>()?;
    // Medium names checked in TOML's words before the tree refers to them by id.
    let media_names: HashMap<String, MediumId> =
        file.media.keys().map(|k| (k.clone(), 0)).collect();
    let mut emitters = Vec::new();
    for def in &file.lights {
        medium_named(ctx, &def.get_ref().medium, &media_names)?;
        emitters.push(tree::with_medium(tree::light(ctx, def)?, def.get_ref()));
    }
    let names: Vec<&str> = file.materials.keys().map(String::as_str).collect();
    let mut shapes = Vec::new();
    for def in &file.shapes {
        let d = def.get_ref();
        for m in [&d.interior, &d.exterior] {
            medium_named(ctx, m, &media_names)?;
        }
        shapes.push(tree::shape(ctx, def, &names)?);
    }
    medium_named(ctx, &file.camera.get_ref().medium, &media_names)?;
    let mut out = vec![tree::integrator(file, &settings)];
    out.extend(media);
    out.push(sensor);
    out.extend(bsdfs);
    out.extend(emitters);
    out.extend(shapes);
    Ok(out)
}

/// The files a medium read (its grids), as opposed to a material's textures.
fn is_volume(p: &std::path::PathBuf) -> bool {
    p.extension().is_some_and(|e| e.eq_ignore_ascii_case("vol"))
}

/// The id of the medium a `medium`, `interior` or `exterior` key names.
pub(super) fn medium_named(
    ctx: &Ctx,
    name: &Option<schema::S<String>>,
    media: &HashMap<String, MediumId>,
) -> Result<Option<MediumId>, SceneError> {
    let Some(name) = name else { return Ok(None) };
    match media.get(name.get_ref()) {
        Some(&id) => Ok(Some(id)),
        None => {
            let mut defined: Vec<&str> = media.keys().map(String::as_str).collect();
            defined.sort_unstable();
            let list = if defined.is_empty() {
                "no [media] are defined".to_string()
            } else {
                format!("defined: {}", defined.join(", "))
            };
            Err(ctx.at(
                name.span(),
                format!("medium `{}` is not defined ({list})", name.get_ref()),
            ))
        }
    }
}
