//! The suite's scenes: every `tests/scenes/*/*.xml`, with the estimators its file name implies
//! and its reference images.

use std::path::{Path, PathBuf};

/// lt's estimators for the media scenes (Mitsuba's `volpath` and `volpathmis`), the one list the
/// suite, its table and `tests/mitsuba_suite.rs` read: judging another estimator on every media
/// scene is one entry here. `light` is judged only where the camera sees no delta surface
/// (`super::not_judged`); `bdpt` is judged by `lt mitsuba-suite`, not in CI (its cost there:
/// `tests/mitsuba_suite.rs`, `MEDIA_NOT_IN_CI`).
pub const MEDIA_ESTIMATORS: &[&str] = &["pt", "light", "bdpt"];

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
    /// The reference was traced from the camera (every integrator but `ptracer`): it holds what
    /// the camera sees through delta surfaces, which light tracing cannot join.
    pub traced_from_camera: bool,
}

/// lt's estimators for a file name's integrator suffix: Mitsuba's `path` and `direct` (a path
/// tracer) with `pt` and `bdpt`, its `ptracer` (a light tracer) with `light` and `bdpt`, its
/// volumetric path tracers `volpath` and `volpathmis` with [`MEDIA_ESTIMATORS`].
pub fn estimators_for(stem: &str) -> Option<(&str, &'static [&'static str])> {
    const SUFFIXES: [(&str, &[&str]); 5] = [
        ("_path", &["pt", "bdpt"]),
        ("_direct", &["pt", "bdpt"]),
        ("_ptracer", &["light", "bdpt"]),
        ("_volpathmis", MEDIA_ESTIMATORS),
        ("_volpath", MEDIA_ESTIMATORS),
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
        if !folder.is_dir() {
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
                    "{}: the file name ends in no integrator the suite knows (_path, _direct, \
                     _ptracer, _volpath, _volpathmis)",
                    xml.display()
                ));
            };
            let refs = folder.join("refs");
            cases.push(Case {
                name: format!("{fname}/{stem}"),
                reference: refs.join(format!("{base}_ref_rgb.exr")),
                reference_var: refs.join(format!("{base}_ref_rgb_var.exr")),
                traced_from_camera: !stem.ends_with("_ptracer"),
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
        assert_eq!(
            estimators_for("test_x_volpath"),
            Some(("test_x", MEDIA_ESTIMATORS))
        );
        assert_eq!(
            estimators_for("test_x_volpathmis"),
            Some(("test_x", MEDIA_ESTIMATORS))
        );
        assert_eq!(estimators_for("test_x_volprim"), None);
    }
}
