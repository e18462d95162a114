//! How study renders read their scene files: with the command line's load options, except that
//! `-D` definitions apply to Mitsuba XML scenes only. A study mixes Bitterli's XML scenes (which
//! need `-D integrator=path`) with ours in TOML (which have no `$parameters`); a TOML scene
//! there ignores the definitions, with one note per process, where `lt render` of a lone TOML
//! scene still refuses them (`lt_scene_io::load_scene_with`).

use lt_core::Scene;
use lt_scene_io::{default_load_options, load_scene_with, LoadOptions, SceneError};
use std::path::Path;
use std::sync::Once;

fn is_xml(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
}

/// The options `path` is read with: the process's (`default_load_options`), its definitions
/// dropped for a non-XML file, noted once per process.
pub fn options_for(path: &Path) -> LoadOptions {
    let opts = applicable(path, default_load_options());
    if opts.defines.is_empty() && !is_xml(path) && !default_load_options().defines.is_empty() {
        static NOTE: Once = Once::new();
        NOTE.call_once(|| {
            eprintln!(
                "note: -D definitions apply to Mitsuba XML scenes only; TOML scenes such as {} \
                 are read without them",
                path.display()
            )
        });
    }
    opts
}

/// `opts` as they apply to `path`: unchanged for an XML file, without definitions otherwise.
pub fn applicable(path: &Path, mut opts: LoadOptions) -> LoadOptions {
    if !is_xml(path) {
        opts.defines.clear();
    }
    opts
}

/// Reads a scene for a study render (`options_for`), printing what an XML load substituted.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let opts = options_for(path);
    let (scene, report) = load_scene_with(path, &opts)?;
    report.print(opts.verbose);
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::applicable;
    use lt_scene_io::{load_scene_with, LoadOptions};
    use std::path::Path;

    fn with_define() -> LoadOptions {
        LoadOptions {
            defines: vec![("integrator".into(), "path".into())],
            ..LoadOptions::default()
        }
    }

    #[test]
    fn definitions_apply_to_xml_scenes_only() {
        let xml = applicable(Path::new("a/scene.XML"), with_define());
        assert_eq!(xml.defines.len(), 1);
        let toml = applicable(Path::new("a/scene.toml"), with_define());
        assert!(toml.defines.is_empty());
    }

    /// A bad TOML scene read under `-D` still fails with its own error (file, place, problem),
    /// not with the definitions' refusal.
    #[test]
    fn a_bad_toml_scene_still_errors_clearly() {
        let dir = std::env::temp_dir().join(format!("lt-scene-load-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("bad.toml");
        std::fs::write(&path, "[camera]\neye = [0.0, 1.0\n").unwrap();
        let err = load_scene_with(&path, &applicable(&path, with_define()))
            .err()
            .expect("a malformed scene is refused")
            .to_string();
        assert!(err.contains("bad.toml"), "{err}");
        assert!(!err.contains("-D"), "{err}");
        // Without `applicable`, the library refuses the definitions themselves.
        let refused = load_scene_with(&path, &with_define())
            .err()
            .unwrap()
            .to_string();
        assert!(refused.contains("-D integrator"), "{refused}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
