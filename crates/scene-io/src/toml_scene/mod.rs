//! The TOML scene format (docs/scene-format.md): text → `SceneFile` (`schema`, serde's view of
//! the file) → `Scene` (`assemble` here, with one file per table: `camera`, `material` with
//! `material_params`, `principled` and `texture`, `shape`, `light`).

mod camera;
mod light;
mod material;
mod material_params;
pub(crate) mod principled;
pub(crate) mod schema;
mod shape;
pub(crate) mod texture;

use crate::error::Ctx;
use crate::world::WorldBuilder;
use crate::SceneError;
use camera::{camera, render};
use glam::DVec3;
use light::{light, Placed};
use lt_core::Scene;
use material::material;
use schema::SceneFile;
use shape::shape;
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
    let mut scene = assemble(&ctx, &file)?;
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
        .chain(meshes.map(|f| ctx.base_dir.join(f.get_ref())))
        .chain(envmaps.map(|f| ctx.base_dir.join(f.get_ref())))
        .collect();
    Ok(scene)
}

/// The parsed file as a scene, built in file order so that ids and the first error follow it.
fn assemble(ctx: &Ctx, file: &SceneFile) -> Result<Scene, SceneError> {
    // Checked here, at the origin, so that a degenerate camera is the error reported first.
    camera(ctx, &file.camera, DVec3::ZERO)?;
    let settings = render(ctx, file)?;
    let mut b = WorldBuilder::new(settings);
    let mut ids = HashMap::new();
    // In file order, so ids and the first error reported follow the file.
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(_, def)| def.span().start);
    for (name, def) in materials {
        ids.insert(name.as_str(), b.add_material(material(ctx, name, def)?));
    }
    let mut emitters = 0;
    for def in &file.shapes {
        emitters += shape(ctx, def, &ids, &mut b)? as usize;
    }
    for def in &file.lights {
        match light(ctx, def)? {
            Some(Placed::At(position, l)) => b.add_light_at(l, position),
            Some(Placed::Anywhere(l)) => b.add_light(l),
            None => continue,
        }
        emitters += 1;
    }
    if emitters == 0 {
        return Err(ctx.whole(
            "the scene has no light: give a shape a non-zero `emission` or add a [[lights]] entry",
        ));
    }
    b.build(|origin| camera(ctx, &file.camera, origin))
}
