//! Bad scene files: each error class gives one message naming the file, the line (and column)
//! when there is one, and the problem. Nothing panics.

use lt_scene_io::{load_scene, load_scene_str, SceneError};
use std::path::{Path, PathBuf};

const FILE: &str = "/nowhere/bad-scene.toml";

/// A valid scene; tests break one thing in it.
const BASE: &str = r#"[camera]
eye = [0.0, 1.0, 4.0]
target = [0.0, 1.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 40.0
resolution = [32, 24]

[materials.white]
type = "diffuse"
albedo = 0.7

[materials.red]
type = "diffuse"
albedo = [0.6, 0.1, 0.1]

[[shapes]]
type = "quad"
material = "white"
scale = [2.0, 2.0, 1.0]
rotate = { axis = [1.0, 0.0, 0.0], angle = -90.0 }

[[shapes]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.5
material = "red"
emission = [4.0, 4.0, 4.0]
"#;

fn load_in(text: &str, path: &Path) -> Result<lt_core::Scene, SceneError> {
    load_scene_str(text, path)
}

fn fail_at(text: &str, path: &Path) -> SceneError {
    match load_in(text, path) {
        Ok(_) => panic!("scene should not load:\n{text}"),
        Err(e) => e,
    }
}

fn fail(text: &str) -> SceneError {
    fail_at(text, Path::new(FILE))
}

/// 1-based line of the first occurrence of `needle` in `text`.
fn line_of(text: &str, needle: &str) -> usize {
    let at = text
        .find(needle)
        .unwrap_or_else(|| panic!("`{needle}` not in the scene"));
    text[..at].matches('\n').count() + 1
}

/// Checks the file name, the line and that every word appears in the message.
fn assert_err(e: &SceneError, line: Option<usize>, words: &[&str]) {
    let shown = e.to_string();
    assert!(
        shown.contains("bad-scene.toml") || shown.contains(".toml"),
        "no file name in: {shown}"
    );
    assert_eq!(e.line, line, "wrong line in: {shown}");
    if let Some(l) = line {
        assert!(
            shown.contains(&format!(":{l}:")),
            "line not shown in: {shown}"
        );
    }
    for w in words {
        assert!(shown.contains(w), "`{w}` missing from: {shown}");
    }
}

fn replace(from: &str, to: &str) -> String {
    assert!(BASE.contains(from), "`{from}` not in BASE");
    BASE.replacen(from, to, 1)
}

/// A temporary directory for mesh files, removed when dropped.
struct Scratch(PathBuf);

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn scratch_dir(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("lt-scene-files-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

#[test]
fn base_scene_loads() {
    let s = load_in(BASE, Path::new(FILE)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 2);
    assert_eq!(s.lights.len(), 1);
}

#[test]
fn toml_syntax_error() {
    let text = replace("fov = 40.0", "fov = 40.0 40");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "fov = 40.0 40")),
        &["bad-scene.toml"],
    );
    assert!(e.column.is_some());
}

#[test]
fn unknown_key() {
    let text = replace("radius = 0.5", "radius = 0.5\ncolour = [1.0, 0.0, 0.0]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "colour")),
        &["unknown field", "colour"],
    );
}

#[test]
fn unknown_key_in_camera() {
    let text = replace("fov = 40.0", "fov = 40.0\nfocal_length = 3.0");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "focal_length")),
        &["unknown field", "focal_length"],
    );
}

#[test]
fn key_of_another_shape_type() {
    let text = replace(
        "scale = [2.0, 2.0, 1.0]",
        "scale = [2.0, 2.0, 1.0]\nradius = 3.0",
    );
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "radius = 3.0")),
        &["`radius`", "does not apply", "quad"],
    );
}

#[test]
fn unknown_shape_type() {
    let text = replace("type = \"quad\"", "type = \"torus\"");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "torus")),
        &["unknown shape type", "torus"],
    );
}

#[test]
fn wrong_type() {
    let text = replace("fov = 40.0", "fov = \"wide\"");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "\"wide\"")),
        &["invalid type", "string"],
    );
}

#[test]
fn wrong_array_length() {
    let text = replace("eye = [0.0, 1.0, 4.0]", "eye = [0.0, 1.0]");
    let e = fail(&text);
    assert_err(&e, Some(line_of(&text, "eye =")), &["invalid length 2"]);
}

#[test]
fn missing_required_key() {
    let text = replace("material = \"red\"\n", "");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "type = \"sphere\"") - 1),
        &["missing field `material`"],
    );
}

#[test]
fn missing_material_parameter() {
    let text = replace("albedo = 0.7", "");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "[materials.white]")),
        &["missing required key `albedo`", "white"],
    );
}

#[test]
fn missing_mesh_file() {
    let text = format!("{BASE}\n[[shapes]]\ntype = \"mesh\"\nfile = \"meshes/no-such-mesh.obj\"\nmaterial = \"white\"\n");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "file = ")),
        &["meshes/no-such-mesh.obj", "not found"],
    );
}

#[test]
fn malformed_obj() {
    let dir = scratch_dir("malformed");
    std::fs::write(
        dir.0.join("broken.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 zero\nf 1 2 3\n",
    )
    .unwrap();
    let text = format!(
        "{BASE}\n[[shapes]]\ntype = \"mesh\"\nfile = \"broken.obj\"\nmaterial = \"white\"\n"
    );
    let e = fail_at(&text, &dir.0.join("bad-scene.toml"));
    assert_err(
        &e,
        Some(line_of(&text, "file = ")),
        &["broken.obj", "malformed OBJ", "line 3"],
    );
}

#[test]
fn obj_face_index_out_of_range() {
    let dir = scratch_dir("index");
    std::fs::write(
        dir.0.join("faces.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
    )
    .unwrap();
    let text = format!(
        "{BASE}\n[[shapes]]\ntype = \"mesh\"\nfile = \"faces.obj\"\nmaterial = \"white\"\n"
    );
    let e = fail_at(&text, &dir.0.join("bad-scene.toml"));
    assert_err(
        &e,
        Some(line_of(&text, "file = ")),
        &["faces.obj", "line 4", "index 4"],
    );
}

#[test]
fn mesh_loads_with_its_normals() {
    let dir = scratch_dir("good");
    let obj = "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvn 0 1 0\nf 1//1 4//1 3//1 2//1\n";
    std::fs::write(dir.0.join("floor.obj"), obj).unwrap();
    let text = format!("{BASE}\n[[shapes]]\ntype = \"mesh\"\nfile = \"floor.obj\"\nmaterial = \"white\"\nscale = 2.0\ntranslate = [0.0, 0.5, 0.0]\n");
    let s = load_in(&text, &dir.0.join("bad-scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    let lt_core::scene::ShapeGeometry::Mesh(m) = &s.shapes[2].geometry else {
        panic!("not a mesh")
    };
    assert_eq!(m.indices.len(), 2, "the quad face is triangulated");
    assert!(m.positions.iter().all(|p| p.y == 0.5 && p.x.abs() == 2.0));
    assert!(m
        .normals
        .as_ref()
        .is_some_and(|ns| ns.iter().all(|n| *n == lt_core::Vec3::Y)));
}

#[test]
fn nan_is_rejected() {
    let text = replace("radius = 0.5", "radius = nan");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "radius = nan")),
        &["`radius`", "NaN"],
    );
}

#[test]
fn infinity_is_rejected() {
    let text = replace("center = [0.0, 1.0, 0.0]", "center = [0.0, inf, 0.0]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "center = ")),
        &["`center`", "finite", "inf"],
    );
}

#[test]
fn negative_radius_is_rejected() {
    let text = replace("radius = 0.5", "radius = -0.5");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "radius = -0.5")),
        &["`radius`", "positive", "-0.5"],
    );
}

#[test]
fn negative_emission_is_rejected() {
    let text = replace("emission = [4.0, 4.0, 4.0]", "emission = [4.0, -4.0, 4.0]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "emission = ")),
        &["`emission`", "negative"],
    );
}

#[test]
fn negative_albedo_is_rejected() {
    let text = replace("albedo = [0.6, 0.1, 0.1]", "albedo = [0.6, -0.1, 0.1]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "albedo = [0.6")),
        &["`albedo`", "negative"],
    );
}

#[test]
fn albedo_above_one_is_rejected() {
    let text = replace("albedo = 0.7", "albedo = 1.2");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "albedo = 1.2")),
        &["`albedo`", "at most 1"],
    );
}

#[test]
fn negative_sun_solid_angle_is_rejected() {
    let text = format!("{BASE}\n[[lights]]\ntype = \"sun\"\ndirection = [0.0, 1.0, 0.0]\nsolid_angle = -6.87e-5\nradiance = 1.0\n");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "solid_angle")),
        &["`solid_angle`", "positive"],
    );
}

#[test]
fn sun_needs_exactly_one_of_radiance_and_irradiance() {
    let sun = "\n[[lights]]\ntype = \"sun\"\ndirection = [0.0, 1.0, 0.0]\nsolid_angle = 6.87e-5\n";
    let both = format!("{BASE}{sun}radiance = 1.0\nirradiance = 1.0\n");
    assert_err(
        &fail(&both),
        Some(line_of(&both, "irradiance")),
        &["not both"],
    );
    let neither = format!("{BASE}{sun}");
    assert_err(
        &fail(&neither),
        Some(line_of(&neither, "[[lights]]")),
        &["radiance", "irradiance", "missing"],
    );
}

/// A directional light table appended to BASE, with `keys` as its body.
fn with_directional(keys: &str) -> String {
    format!("{BASE}\n[[lights]]\ntype = \"directional\"\n{keys}")
}

#[test]
fn directional_light_loads_normalised() {
    let text = with_directional("direction = [0.0, 2.0, 0.0]\nirradiance = [3.0, 2.0, 1.0]\n");
    let s = load_in(&text, Path::new(FILE)).unwrap_or_else(|e| panic!("{e}"));
    let Some(lt_core::light::Light::Directional(d)) = s.lights.last() else {
        panic!("no directional light: {:?}", s.lights)
    };
    assert_eq!(d.direction, lt_core::math::Vec3::Y);
    assert_eq!(d.irradiance, lt_core::math::Color::new(3.0, 2.0, 1.0));
}

#[test]
fn directional_light_with_a_zero_direction_is_rejected() {
    let text = with_directional("direction = [0.0, 0.0, 0.0]\nirradiance = 1.0\n");
    assert_err(
        &fail(&text),
        Some(line_of(&text, "direction = [0.0, 0.0")),
        &["`direction`", "zero vector"],
    );
}

#[test]
fn directional_light_needs_irradiance_and_direction() {
    let text = with_directional("direction = [0.0, 1.0, 0.0]\n");
    assert_err(
        &fail(&text),
        Some(line_of(&text, "[[lights]]")),
        &["missing required key `irradiance`", "directional light"],
    );
    let text = with_directional("irradiance = 1.0\n");
    assert_err(
        &fail(&text),
        Some(line_of(&text, "[[lights]]")),
        &["missing required key `direction`", "directional light"],
    );
}

#[test]
fn directional_light_refuses_radiance() {
    // Alone or beside an irradiance: a delta in direction has no radiance.
    for keys in [
        "direction = [0.0, 1.0, 0.0]\nradiance = 1.0\n",
        "direction = [0.0, 1.0, 0.0]\nirradiance = 1.0\nradiance = 1.0\n",
    ] {
        let text = with_directional(keys);
        assert_err(
            &fail(&text),
            Some(line_of(&text, "\nradiance = 1.0") + 1),
            &[
                "directional light takes `irradiance`",
                "not `radiance`",
                "sun",
            ],
        );
    }
    // Keys of other light types are refused as for any element.
    let text =
        with_directional("direction = [0.0, 1.0, 0.0]\nirradiance = 1.0\nsolid_angle = 0.1\n");
    assert_err(
        &fail(&text),
        Some(line_of(&text, "solid_angle")),
        &["`solid_angle`", "does not apply", "directional"],
    );
}

#[test]
fn unknown_light_type_lists_the_known_ones() {
    let text = format!("{BASE}\n[[lights]]\ntype = \"sunsky\"\n");
    assert_err(
        &fail(&text),
        Some(line_of(&text, "\"sunsky\"")),
        &[
            "unknown light type `sunsky`",
            "point, spot, projector, sun, directional, environment or envmap",
        ],
    );
}

#[test]
fn spot_and_projector_errors_name_the_key() {
    let spot = format!(
        "{BASE}\n[[lights]]\ntype = \"spot\"\nposition = [0, 0.9, 0]\ntarget = [0, 0.9, 0]\nintensity = 1\n"
    );
    assert_err(
        &fail(&spot),
        Some(line_of(&spot, "target = [0, 0.9, 0]")),
        &["`position` and `target` coincide"],
    );
    let wide = format!(
        "{BASE}\n[[lights]]\ntype = \"spot\"\nposition = [0, 0.9, 0]\ntarget = [0, 0, 0]\nintensity = 1\ncutoff_angle = 95\ntexture = {{ type = \"checkerboard\" }}\n"
    );
    assert_err(
        &fail(&wide),
        Some(line_of(&wide, "cutoff_angle = 95")),
        &["`cutoff_angle` must be below 90°", "with a texture"],
    );
    let both = format!(
        "{BASE}\n[[lights]]\ntype = \"projector\"\nposition = [0, 0.9, 0]\ntarget = [0, 0, 0]\nfov = 30\nirradiance = 1\ntexture = {{ type = \"checkerboard\" }}\n"
    );
    assert_err(
        &fail(&both),
        Some(line_of(&both, "irradiance = 1")),
        &["`irradiance` or `texture`, not both"],
    );
}

#[test]
fn undefined_material() {
    let text = replace("material = \"red\"", "material = \"blue\"");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "\"blue\"")),
        &["material `blue` is not defined", "red, white"],
    );
}

#[test]
fn zero_area_quad() {
    let text = replace("scale = [2.0, 2.0, 1.0]", "scale = [2.0, 0.0, 1.0]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "scale = [2.0, 0.0")),
        &["degenerate transform", "zero area"],
    );
}

#[test]
fn flat_cube() {
    let text = format!(
        "{BASE}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"white\"\nscale = [1.0, 1.0, 0.0]\n"
    );
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "scale = [1.0, 1.0, 0.0]")),
        &["degenerate transform", "cube"],
    );
}

#[test]
fn projective_to_world() {
    let m = "to_world = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.5, 1.0]]";
    let text = format!("{BASE}\n[[shapes]]\ntype = \"cube\"\nmaterial = \"white\"\n{m}\n");
    let e = fail(&text);
    assert_err(
        &e,
        Some(line_of(&text, "to_world")),
        &["to_world", "affine"],
    );
}

#[test]
fn degenerate_camera() {
    let text = replace("target = [0.0, 1.0, 0.0]", "target = [0.0, 1.0, 4.0]");
    let e = fail(&text);
    assert_err(
        &e,
        Some(1),
        &["degenerate camera", "eye and target coincide"],
    );
    let text = replace("up = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 1.0]");
    assert_err(&fail(&text), Some(1), &["degenerate camera", "parallel"]);
}

#[test]
fn scene_without_light() {
    let text = replace("emission = [4.0, 4.0, 4.0]\n", "");
    let e = fail(&text);
    assert_err(&e, None, &["no light"]);
}

#[test]
fn missing_scene_file() {
    let e = match load_scene(Path::new("/nowhere/bad-scene.toml")) {
        Ok(_) => panic!("loaded a missing file"),
        Err(e) => e,
    };
    assert_err(&e, None, &["bad-scene.toml"]);
}
