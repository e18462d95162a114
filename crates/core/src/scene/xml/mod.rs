//! Mitsuba 3 scene XML, in and out (docs/xml.md lists what is covered and what is refused).
//!
//! In: `load_scene` reads a `.xml` file through `doc` (the XML tree with includes, defaults,
//! `$` substitution and the 0.6 → 3 name upgrade), `values` (numbers, colours, transforms),
//! `props` (each plugin's parameters, every one taken or reported) and `build` (the plugin subset,
//! assembled through `SceneBuilder`). Meshes come from OBJ (the TOML path's reader) and PLY
//! (`ply`). Out: `write::to_mitsuba_xml` writes one of our TOML scenes as Mitsuba 3 XML.
//!
//! Where a file asks for something lt lacks but has a near equivalent of (Beckmann → GGX of the
//! same α, a Gaussian or other pixel filter → the box, a spectrum → RGB, max_depth = -1 → 64),
//! the load is refused unless `LoadOptions::approximate`, and every substitution made is listed
//! in the `LoadReport`. Parameters Mitsuba writes by default that change nothing lt renders
//! (`near_clip`, a film's `pixel_format`, a `ref`'s `name`, …) are accepted and listed too.

mod build;
mod doc;
mod ply;
mod props;
mod spectrum;
mod values;
pub mod write;

use super::{Scene, SceneError};
use std::path::Path;
use std::sync::OnceLock;

pub use build::UNBOUNDED_DEPTH_SUBSTITUTE;

/// How a scene file is read.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Substitute the nearest feature lt has where a file asks for one it lacks (listed in the
    /// report); without it such a file is refused.
    pub approximate: bool,
    /// Print the accepted-but-ignored parameters too (the command line's `--verbose`).
    pub verbose: bool,
}

/// What a load changed or passed over, one line each, each starting with `file:line`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Substitutions `--approximate` made (the image differs from Mitsuba's by these).
    pub substitutions: Vec<String>,
    /// Parameters accepted and ignored because they change nothing lt renders.
    pub ignored: Vec<String>,
}

impl LoadReport {
    /// Prints the substitutions (always) and the ignored parameters (when `verbose`) to stderr.
    pub fn print(&self, verbose: bool) {
        for s in &self.substitutions {
            eprintln!("approximated: {s}");
        }
        if verbose {
            for s in &self.ignored {
                eprintln!("ignored: {s}");
            }
        }
    }
}

static DEFAULT_OPTIONS: OnceLock<LoadOptions> = OnceLock::new();

/// Sets the options `load_scene` uses (once per process: the command line's global flags).
/// Returns false when they were already set.
pub fn set_default_load_options(opts: LoadOptions) -> bool {
    DEFAULT_OPTIONS.set(opts).is_ok()
}

/// The options `load_scene` uses: those set by `set_default_load_options`, else the defaults.
pub fn default_load_options() -> LoadOptions {
    DEFAULT_OPTIONS.get().copied().unwrap_or_default()
}

/// Reads a Mitsuba XML scene. `source_files` is the XML file, every included file, then every
/// mesh file, in the order read.
pub fn load_xml(path: &Path, opts: &LoadOptions) -> Result<(Scene, LoadReport), SceneError> {
    let doc = doc::read(path)?;
    let (mut scene, report, meshes) = build::load(&doc, opts)?;
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
