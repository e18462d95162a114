//! Mitsuba 3 scene XML, in and out (docs/xml.md lists what is covered and what is refused).
//!
//! In: `load_xml` reads a `.xml` file through `doc` (the plugin tree: includes, defaults, `$`
//! substitution and the 0.6 → 3 name upgrade), `values` (numbers, colours, transforms), `props`
//! (each plugin's parameters, every one taken or reported) and `build/` (one builder per plugin
//! kind, assembled through `SceneBuilder`; `build/kinds.rs` checks the whole tree first). Meshes
//! come from `crate::mesh`. Out: `write::to_mitsuba_xml` writes one of our TOML scenes as
//! Mitsuba 3 XML.
//!
//! Relative file names go through `resolve` (Mitsuba's resolver: the scene's folder, then each
//! `<path>`); spectra become RGB exactly as Mitsuba's RGB variants convert them (`spectrum`,
//! with the tables in `cie_table`).
//!
//! Where a file asks for something lt lacks but has a near equivalent of (max_depth = -1 → 64),
//! the load is refused unless `LoadOptions::approximate`, and every substitution made is listed
//! in the `LoadReport`. Parameters Mitsuba writes by default that change nothing lt renders
//! (`near_clip`, a film's `pixel_format`, a `ref`'s `name`, …) are accepted and listed too.

pub(crate) mod build;
mod cie_table;
pub(crate) mod doc;
mod print;
mod props;
pub(crate) mod resolve;
mod spectrum;
mod values;
pub mod write;

use crate::{LoadOptions, LoadReport, SceneError};
use lt_core::Scene;
use std::path::Path;

pub use build::UNBOUNDED_DEPTH_SUBSTITUTE;

/// Reads a Mitsuba XML scene. `source_files` is the XML file, every included file, then every
/// mesh file, in the order read.
pub fn load_xml(path: &Path, opts: &LoadOptions) -> Result<(Scene, LoadReport), SceneError> {
    let doc = doc::read(path, &opts.defines)?;
    let no_light = || {
        doc.err(
            &doc.root,
            "the scene has no light: no emitter with a non-zero value",
        )
    };
    let (mut scene, report, meshes) = build::load(&doc, opts, &no_light)?;
    scene.source_files = doc
        .sources
        .iter()
        .map(|s| s.path.clone())
        .chain(meshes)
        .collect();
    Ok((scene, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn scenes() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
    }

    #[test]
    fn xml_cornell_box_loads_with_its_report() {
        let path = scenes().join("xml/cornell-box.xml");
        let (scene, report) =
            load_xml(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(scene.shapes.len(), 8);
        assert_eq!(scene.lights.len(), 1);
        assert_eq!((scene.camera.width, scene.camera.height), (256, 256));
        assert_eq!(scene.settings.spp, 64);
        assert_eq!(scene.settings.max_depth, 8);
        assert_eq!(scene.source_files, vec![path]);
        assert!(report.substitutions.is_empty(), "{report:?}");
        // near_clip, far_clip, focus_distance, pixel_format, component_format.
        assert_eq!(report.ignored.len(), 5, "{report:#?}");
    }
}
