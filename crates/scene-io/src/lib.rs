//! Scene files in and out: TOML (the format in docs/scene-format.md), Mitsuba 3 XML (docs/xml.md),
//! OBJ and PLY meshes. Everything here builds `lt_core::Scene` through `SceneBuilder`; the core
//! itself reads no file format. Every problem — syntax, unknown key, wrong type, missing key, bad
//! value, missing or malformed mesh, undefined material, degenerate transform or camera, no
//! light — becomes one `SceneError` that names the file, the line and column when there is one,
//! and the problem. Nothing here panics on input.

mod error;
mod image_file;
mod mesh;
mod options;
mod principled_keys;
mod toml_scene;
mod transform;
mod world;
pub mod xml;

pub use error::SceneError;
pub use options::{default_load_options, set_default_load_options, LoadOptions, LoadReport};
pub use toml_scene::load_scene_str;
/// The TOML schema's spanned values under their old path, for `mesh/vol.rs` (being extended by
/// the media work); new code imports `toml_scene::schema`.
use toml_scene::schema as format;

use lt_core::Scene;
use std::path::Path;

/// Reads a scene file, TOML or (by the `.xml` extension) Mitsuba XML, with the process's default
/// `LoadOptions` (`set_default_load_options`); an XML load's substitutions are printed to
/// stderr, and with `verbose` its ignored parameters too.
pub fn load_scene(path: &Path) -> Result<Scene, SceneError> {
    let opts = default_load_options();
    let (scene, report) = load_scene_with(path, &opts)?;
    report.print(opts.verbose);
    Ok(scene)
}

/// Reads a scene file with explicit options; the report lists what an XML load substituted and
/// ignored (always empty for TOML).
pub fn load_scene_with(path: &Path, opts: &LoadOptions) -> Result<(Scene, LoadReport), SceneError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
    {
        return xml::load_xml(path, opts);
    }
    if let Some((k, _)) = opts.defines.first() {
        return Err(SceneError {
            file: path.display().to_string(),
            line: None,
            column: None,
            message: format!("-D {k}=…: definitions apply to Mitsuba XML scenes only (a TOML scene has no $parameters)"),
        });
    }
    Ok((toml_scene::load_toml(path)?, Default::default()))
}
