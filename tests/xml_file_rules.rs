//! Mitsuba's file rules as lt reads them: the file resolver (the scene's folder, then each
//! `<path>` folder; an included fragment's names resolve the same way, as in mitsuba-data's
//! `scenes/cbox/cbox-rgb.xml`), `-D key=value` over `<default>`, the `moment` wrapper, `direct`
//! as paths of two segments, and an unknown integrator refused with the `-D` way out named.

use lt_scene_io::{load_scene_with, LoadOptions, SceneError};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-rules-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

const SENSOR: &str = r#"<sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/><rfilter type="box"/></film>
    </sensor>"#;

const LIGHT: &str = r#"<emitter type="point"><point name="position" x="0" y="2" z="0"/><rgb name="intensity" value="5"/></emitter>"#;

fn with_defines(defines: &[(&str, &str)]) -> LoadOptions {
    LoadOptions {
        defines: defines
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        ..Default::default()
    }
}

fn message<T>(r: Result<T, SceneError>) -> String {
    match r {
        Ok(_) => panic!("the load must fail"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn xml_fragment_paths_resolve_through_the_scene_folder_and_path_elements() {
    let d = dir("resolver");
    write(
        &d.join("common/meshes/quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n",
    );
    // The fragment names `meshes/quad.obj`: not next to the fragment, found through <path>.
    write(
        &d.join("scene/fragments/shapes.xml"),
        r#"<scene version="3.0.0"><shape type="obj"><string name="filename" value="meshes/quad.obj"/></shape></scene>"#,
    );
    let main = format!(
        r#"<scene version="3.0.0">
    <path value="../common"/>
    <default name="integrator" value="path"/>
    <integrator type="moment"><integrator type="$integrator"><integer name="max_depth" value="6"/></integrator></integrator>
    {SENSOR}
    <include filename="fragments/shapes.xml"/>
    {LIGHT}
</scene>"#
    );
    let path = d.join("scene/main.xml");
    write(&path, &main);
    let (scene, _) = load_scene_with(&path, &LoadOptions::default()).unwrap();
    assert_eq!(scene.settings.max_depth, 6);
    assert_eq!(scene.shapes.len(), 1);
    assert_eq!(
        scene.source_files.last().unwrap(),
        &d.join("scene/../common/meshes/quad.obj")
    );

    // Without the <path>, the mesh is one error at the fragment's filename, naming where it looked.
    write(&path, &main.replace(r#"<path value="../common"/>"#, ""));
    let m = message(load_scene_with(&path, &LoadOptions::default()));
    assert!(
        m.contains("shapes.xml:1:") && m.contains("mesh file `meshes/quad.obj` not found"),
        "{m}"
    );
    assert!(m.contains("scene/meshes/quad.obj"), "{m}");

    // -D comes before the file's <default>: an unknown integrator is refused, the way out named.
    let opts = with_defines(&[("integrator", "aov")]);
    write(&path, &main);
    let m = message(load_scene_with(&path, &opts));
    assert!(
        m.contains("main.xml:4:")
            && m.contains("integrator `aov` is not supported")
            && m.contains("-D integrator=path"),
        "{m}"
    );
    // `direct`: paths of at most two segments, whatever the wrapped max_depth; sample counts listed.
    let direct = main.replace(
        r#"<integer name="max_depth" value="6"/>"#,
        r#"<integer name="emitter_samples" value="4"/>"#,
    );
    write(&path, &direct);
    let (scene, report) =
        load_scene_with(&path, &with_defines(&[("integrator", "direct")])).unwrap();
    assert_eq!(scene.settings.max_depth, 2);
    assert!(
        report.ignored.iter().any(|s| s.contains("emitter_samples")),
        "{report:?}"
    );
    // A missing include names the include's line and the candidates.
    write(
        &path,
        &main.replace("fragments/shapes.xml", "fragments/none.xml"),
    );
    let m = message(load_scene_with(&path, &LoadOptions::default()));
    assert!(
        m.contains("main.xml:9:") && m.contains("included file `fragments/none.xml` not found"),
        "{m}"
    );
    // -D on a TOML scene is refused rather than ignored.
    let toml = d.join("scene.toml");
    write(&toml, "");
    let m = message(load_scene_with(&toml, &with_defines(&[("spp", "4")])));
    assert!(m.contains("Mitsuba XML scenes only"), "{m}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn xml_define_parsing_names_the_problem() {
    assert_eq!(
        LoadOptions::parse_define("spp=64").unwrap(),
        ("spp".to_string(), "64".to_string())
    );
    assert!(LoadOptions::parse_define("spp")
        .unwrap_err()
        .contains("key=value"));
    assert!(LoadOptions::parse_define("s p=1")
        .unwrap_err()
        .contains("not a parameter name"));
}
