//! The suite's scenes: every `tests/scenes/*/*.xml` outside `participating_media`, with the
//! estimators its file name implies and its reference images.

use std::path::{Path, PathBuf};

/// Folders left out: they need participating media, which lt does not simulate.
const SKIPPED_FOLDERS: [&str; 1] = ["participating_media"];

/// One scene of the suite.
#[derive(Clone, Debug)]
pub struct Case {
    /// "folder/file stem", e.g. `bsdf_spheres/test_arealight_path`.
    pub name: String,
    pub xml: PathBuf,
    /// `refs/<stem without the integrator>_ref_rgb.exr` and its `_var.exr`.
    pub reference: PathBuf,
    pub reference_var: PathBuf,
    /// lt's estimators for the Mitsuba integrator the file name ends in.
    pub estimators: &'static [&'static str],
}

/// lt's estimators for a file name's integrator suffix: Mitsuba's `path` and `direct` (a path
/// tracer) with `pt` and `bdpt`, its `ptracer` (a light tracer) with `light` and `bdpt`.
pub fn estimators_for(stem: &str) -> Option<(&str, &'static [&'static str])> {
    const SUFFIXES: [(&str, &[&str]); 3] = [
        ("_path", &["pt", "bdpt"]),
        ("_direct", &["pt", "bdpt"]),
        ("_ptracer", &["light", "bdpt"]),
    ];
    SUFFIXES
        .into_iter()
        .find(|(s, _)| stem.ends_with(s))
        .map(|(s, e)| (&stem[..stem.len() - s.len()], e))
}

/// Every scene under `dir/tests/scenes`, sorted by name.
pub fn discover(dir: &Path) -> Result<Vec<Case>, String> {
    let scenes = dir.join("tests/scenes");
    let list = |d: &Path| -> Result<Vec<PathBuf>, String> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d)
            .map_err(|e| format!("cannot list {}: {e}", d.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        v.sort();
        Ok(v)
    };
    let mut cases = Vec::new();
    for folder in list(&scenes)? {
        let Some(fname) = folder.file_name().and_then(|f| f.to_str()) else {
            continue;
        };
        if !folder.is_dir() || SKIPPED_FOLDERS.contains(&fname) {
            continue;
        }
        for xml in list(&folder)? {
            if xml.extension().and_then(|e| e.to_str()) != Some("xml") {
                continue;
            }
            let Some(stem) = xml.file_stem().and_then(|s| s.to_str()) else {
                continue;
            };
            let Some((base, estimators)) = estimators_for(stem) else {
                return Err(format!(
                    "{}: the file name ends in no integrator the suite knows (_path, _direct, _ptracer)",
                    xml.display()
                ));
            };
            let refs = folder.join("refs");
            cases.push(Case {
                name: format!("{fname}/{stem}"),
                reference: refs.join(format!("{base}_ref_rgb.exr")),
                reference_var: refs.join(format!("{base}_ref_rgb_var.exr")),
                xml,
                estimators,
            });
        }
    }
    if cases.is_empty() {
        return Err(format!("no scenes under {}", scenes.display()));
    }
    Ok(cases)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn suite_file_names_pick_the_estimators() {
        assert_eq!(
            estimators_for("test_spot_direct"),
            Some(("test_spot", &["pt", "bdpt"][..]))
        );
        assert_eq!(
            estimators_for("scene_path"),
            Some(("scene", &["pt", "bdpt"][..]))
        );
        assert_eq!(
            estimators_for("test_various_emitters_ptracer"),
            Some(("test_various_emitters", &["light", "bdpt"][..]))
        );
        assert_eq!(estimators_for("test_x_volpath"), None);
    }
}
