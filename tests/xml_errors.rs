//! Mitsuba XML scenes that lt cannot or must not render give one clear error naming the file, the
//! line and the element — never a panic — and the ones it can are read as Mitsuba reads them:
//! includes, defaults and `$` substitution, the 0.6 name upgrade, OBJ and PLY (ASCII and
//! binary) meshes, `--approximate` substitutions and the `--verbose` list of ignored parameters.

use lt_core::camera::{FilterShape, Lens};
use lt_core::scene::ShapeGeometry;
use lt_core::Scene;
use lt_scene_io::{load_scene_with, LoadOptions, LoadReport, SceneError};
use std::path::{Path, PathBuf};

/// A fresh folder for one test's files.
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-xml-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small valid scene with `body` added before its light.
fn scene_xml(body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="24"/>
            <rfilter type="box"/>
        </film>
    </sensor>
{body}
    <emitter type="point"><point name="position" x="0" y="2" z="0"/><rgb name="intensity" value="5"/></emitter>
</scene>
"#
    )
}

fn load_in(
    d: &Path,
    name: &str,
    text: &str,
    opts: LoadOptions,
) -> Result<(Scene, LoadReport), SceneError> {
    let path = d.join(name);
    std::fs::write(&path, text).unwrap();
    load_scene_with(&path, &opts)
}

/// The error of a load that must fail.
fn error_of(r: Result<(Scene, LoadReport), SceneError>) -> SceneError {
    match r {
        Err(e) => e,
        Ok(_) => panic!("the load should have failed"),
    }
}

/// The error, its line, and its message contains every `needle`.
fn fails(d: &Path, text: &str, line: usize, needles: &[&str]) -> SceneError {
    let e = match load_in(d, "scene.xml", text, LoadOptions::default()) {
        Err(e) => e,
        Ok(_) => panic!("expected an error containing {needles:?}"),
    };
    let shown = e.to_string();
    eprintln!("{shown}");
    assert!(e.file.ends_with("scene.xml"), "{shown}");
    assert_eq!(e.line, Some(line), "{shown}");
    for n in needles {
        assert!(shown.contains(n), "`{shown}` lacks `{n}`");
    }
    e
}

/// 1-based line of the first line containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect(needle) + 1
}

#[test]
fn xml_bad_files_give_one_clear_error() {
    let d = dir("errors");
    // Malformed XML: roxmltree's position of the unclosed element.
    let text = scene_xml("    <shape type=\"sphere\">\n    <bsdf type=\"diffuse\"/>");
    let e = error_of(load_in(&d, "scene.xml", &text, LoadOptions::default()));
    assert!(e.to_string().contains("malformed XML"), "{e}");
    assert!(e.line.is_some(), "{e}");

    // An unknown plugin.
    let text =
        scene_xml("    <shape type=\"sphere\">\n        <bsdf type=\"measured\"/>\n    </shape>");
    fails(
        &d,
        &text,
        line_of(&text, "measured"),
        &["BSDF `measured` is not supported"],
    );
    let text = scene_xml("    <shape type=\"bsplinecurve\"/>");
    fails(
        &d,
        &text,
        line_of(&text, "bsplinecurve"),
        &["shape `bsplinecurve` is not supported"],
    );
    let text = scene_xml("    <shape type=\"sdfgrid\"/>");
    fails(
        &d,
        &text,
        line_of(&text, "sdfgrid"),
        &["sdfgrid", "needs a `filename`"],
    );
    // A sheared cylinder: Mitsuba would drop the shear; refused at its transform.
    let text = scene_xml(
        "    <shape type=\"cylinder\">\n        <transform name=\"to_world\"><scale x=\"1\" y=\"2\" z=\"1\"/></transform>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "y=\"2\""),
        &["cylinder", "to_world", "equal along x and y"],
    );

    // A texture whose image is missing: named as resolved, at the filename; an unknown texture.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\">\n            <texture type=\"bitmap\" name=\"reflectance\"><string name=\"filename\" value=\"a.png\"/></texture>\n        </bsdf>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "a.png"),
        &["texture file `a.png` not found", "looked for"],
    );
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\">\n            <texture type=\"voronoi\" name=\"reflectance\"/>\n        </bsdf>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "voronoi"),
        &["texture `voronoi` is not supported"],
    );

    // A missing mesh file: named as written and as resolved, at the filename.
    let text = scene_xml("    <shape type=\"obj\">\n        <string name=\"filename\" value=\"meshes/nope.obj\"/>\n    </shape>");
    fails(
        &d,
        &text,
        line_of(&text, "nope.obj"),
        &["mesh file `meshes/nope.obj` not found", "looked for"],
    );
    let text = scene_xml("    <shape type=\"ply\">\n        <string name=\"filename\" value=\"nope.ply\"/>\n    </shape>");
    fails(
        &d,
        &text,
        line_of(&text, "nope.ply"),
        &["mesh file `nope.ply` not found"],
    );

    // Bad numbers.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <float name=\"radius\" value=\"1.o\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "1.o"),
        &["`1.o` is not a number", "radius"],
    );
    let text = scene_xml("    <shape type=\"rectangle\">\n        <transform name=\"to_world\"><translate value=\"1 2\"/></transform>\n    </shape>");
    fails(
        &d,
        &text,
        line_of(&text, "translate"),
        &["expected 3 numbers"],
    );
    let text = scene_xml("    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\"><rgb name=\"reflectance\" value=\"0.5, nan, 0.5\"/></bsdf>\n    </shape>");
    fails(&d, &text, line_of(&text, "nan"), &["not a finite number"]);

    // A reference to an undefined id, and an undefined $ parameter.
    let text = scene_xml("    <shape type=\"sphere\">\n        <ref id=\"glass\"/>\n    </shape>");
    fails(
        &d,
        &text,
        line_of(&text, "glass"),
        &["reference to an undefined id `glass`"],
    );
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <float name=\"radius\" value=\"$r\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "$r"),
        &["parameter `$r` is not defined"],
    );

    // A parameter the plugin does not take, a wrong type, an unknown top-level element.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <float name=\"radious\" value=\"1\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "radious"),
        &["parameter `radious` of shape `sphere` is not supported"],
    );
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <string name=\"radius\" value=\"1\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "name=\"radius\""),
        &["must be a <float>"],
    );
    let text = scene_xml(
        "    <medium type=\"homogeneous\"><float name=\"density\" value=\"1\"/></medium>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "density"),
        &["parameter `density` of medium `homogeneous` is not supported"],
    );

    // Emitters: a textured area emitter whose bitmap names no file, a spot whose textured cone
    // reaches 90°, a scaled spot frame, a projector's fov out of range.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <emitter type=\"area\">\n            <texture type=\"bitmap\" name=\"radiance\"/>\n        </emitter>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "bitmap"),
        &["a bitmap texture needs a `filename`"],
    );
    let text = scene_xml(
        "    <emitter type=\"spot\">\n        <float name=\"cutoff_angle\" value=\"95\"/>\n        <texture type=\"checkerboard\" name=\"texture\"/>\n    </emitter>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "type=\"spot\""),
        &["`cutoff_angle` must lie in (0°, 90°) with a texture, got 95"],
    );
    let text = scene_xml(
        "    <emitter type=\"spot\">\n        <transform name=\"to_world\"><scale value=\"2\"/></transform>\n    </emitter>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "<scale value=\"2\"/>"),
        &["a spot light's to_world must be a rotation"],
    );
    let text = scene_xml(
        "    <emitter type=\"projector\">\n        <float name=\"fov\" value=\"180\"/>\n    </emitter>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "type=\"projector\""),
        &["a projector's `fov` must lie in (0°, 180°), got 180"],
    );

    // Not a scene at all, or no version.
    let e = error_of(load_in(
        &d,
        "scene.xml",
        "<scene><shape type=\"sphere\"/></scene>",
        LoadOptions::default(),
    ));
    assert!(e.to_string().contains("no `version`"), "{e}");
    let e = error_of(load_in(&d, "scene.xml", "<shape/>", LoadOptions::default()));
    assert!(e.to_string().contains("root element"), "{e}");
    // A file that does not exist.
    let e = error_of(load_scene_with(
        &d.join("missing.xml"),
        &LoadOptions::default(),
    ));
    assert!(e.to_string().contains("cannot read"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// Every prefix of the shipped XML scene (cut at many places) loads or fails with an error; none
/// panics.
#[test]
fn xml_truncated_files_never_panic() {
    let d = dir("truncated");
    let text = std::fs::read_to_string(lt_tests::scenes_dir().join("xml/cornell-box.xml")).unwrap();
    let mut errors = 0;
    for cut in (0..text.len()).step_by(37) {
        let Some(prefix) = text.get(..cut) else {
            continue;
        };
        let r = std::panic::catch_unwind(|| load_in(&d, "cut.xml", prefix, LoadOptions::default()));
        match r {
            Ok(Err(_)) => errors += 1,
            Ok(Ok(_)) => {}
            Err(_) => panic!("loading the first {cut} bytes panicked"),
        }
    }
    assert!(errors > 50, "{errors}");
    let _ = std::fs::remove_dir_all(&d);
}

/// What lt lacks is refused without `--approximate` and substituted, and listed, with it.
#[test]
fn xml_approximations_are_refused_or_listed() {
    let d = dir("approx");
    let opts = LoadOptions {
        approximate: true,
        ..Default::default()
    };
    // Mitsuba's roughconductor defaults (Beckmann, α 0.1 → here 0.2, material "none", one-sided)
    // load as they are: nothing to approximate any more.
    let rough = scene_xml("    <shape type=\"sphere\">\n        <bsdf type=\"roughconductor\"><float name=\"alpha\" value=\"0.2\"/></bsdf>\n    </shape>");
    let (scene, report) = load_in(&d, "scene.xml", &rough, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    let m = format!("{:?}", scene.material(scene.shapes[0].material));
    assert!(
        m.starts_with("RoughConductor") && m.contains("Beckmann") && m.contains("alpha_u: 0.2"),
        "{m}"
    );

    // Mitsuba's pixel filters load as they are, and hdrfilm's default (no rfilter) is its
    // Gaussian of stddev 0.5: nothing to approximate any more.
    let gauss = scene_xml("").replace(
        "<rfilter type=\"box\"/>",
        "<rfilter type=\"gaussian\"><float name=\"stddev\" value=\"0.25\"/></rfilter>",
    );
    let (scene, report) = load_in(&d, "scene.xml", &gauss, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    assert_eq!(
        scene.camera.filter().shape(),
        FilterShape::Gaussian { stddev: 0.25 }
    );
    let nofilter = scene_xml("").replace("<rfilter type=\"box\"/>", "");
    let (scene, report) = load_in(&d, "scene.xml", &nofilter, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    assert_eq!(
        scene.camera.filter().shape(),
        FilterShape::Gaussian { stddev: 0.5 }
    );
    let mitchell = scene_xml("").replace(
        "<rfilter type=\"box\"/>",
        "<rfilter type=\"mitchell\"><float name=\"B\" value=\"0.5\"/></rfilter>",
    );
    let (scene, _) = load_in(&d, "scene.xml", &mitchell, LoadOptions::default()).unwrap();
    assert_eq!(
        scene.camera.filter().shape(),
        FilterShape::Mitchell {
            b: 0.5,
            c: 1.0 / 3.0
        }
    );
    let thin = scene_xml("").replace(
        "<sensor type=\"perspective\">",
        "<sensor type=\"thinlens\"><float name=\"aperture_radius\" value=\"0.1\"/>\
         <float name=\"focus_distance\" value=\"3\"/>\
         <float name=\"principal_point_offset_x\" value=\"0.25\"/>",
    );
    let (scene, report) = load_in(&d, "scene.xml", &thin, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    assert_eq!(
        scene.camera.lens(),
        Lens::ThinLens {
            aperture_radius: 0.1,
            focus_distance: 3.0
        }
    );
    assert_eq!(
        scene.camera.principal_point_offset(),
        lt_core::Vec2::new(0.25, 0.0)
    );
    let unknown = scene_xml("").replace("<rfilter type=\"box\"/>", "<rfilter type=\"sinc\"/>");
    fails(
        &d,
        &unknown,
        line_of(&unknown, "sinc"),
        &["reconstruction filter `sinc` is not supported"],
    );

    let unbounded = scene_xml("").replace("<integer name=\"max_depth\" value=\"5\"/>", "");
    fails(
        &d,
        &unbounded,
        line_of(&unbounded, "integrator"),
        &["max_depth = -1", "--approximate"],
    );
    let (scene, _) = load_in(&d, "scene.xml", &unbounded, opts.clone()).unwrap();
    assert_eq!(
        scene.settings.max_depth,
        lt_scene_io::xml::UNBOUNDED_DEPTH_SUBSTITUTE
    );

    // Spectra convert as Mitsuba's RGB variants convert them, with no flag and no substitution.
    let spectral = scene_xml("    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"400:0.2, 500:0.5, 600:0.8, 700:0.9\"/></bsdf>\n    </shape>");
    let (scene, report) = load_in(&d, "scene.xml", &spectral, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    let lt_core::bsdf::Material::FrontDiffuse(diffuse) = scene.material(scene.shapes[0].material)
    else {
        panic!()
    };
    // Mitsuba 3.9.1 holds (0.880858, 0.631926, 0.321875) for it (f32, printed to 6 digits).
    for (ours, theirs) in diffuse
        .albedo
        .to_array()
        .iter()
        .zip([0.880858, 0.631926, 0.321875])
    {
        assert!(
            (ours - theirs).abs() < 1e-5 * theirs,
            "{:?}",
            diffuse.albedo
        );
    }
    // A spectrum of one value is grey, exactly, and needs no approximation.
    let grey = scene_xml("    <shape type=\"sphere\">\n        <bsdf type=\"diffuse\"><spectrum name=\"reflectance\" value=\"0.25\"/></bsdf>\n    </shape>");
    let (scene, report) = load_in(&d, "scene.xml", &grey, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty());
    assert!(format!("{:?}", scene.material(0)).contains("0.25"));
    let _ = std::fs::remove_dir_all(&d);
}

/// Includes, defaults and `$` substitution, a 0.6 file's camelCase names, ids and refs, the
/// parameters accepted and ignored, OBJ and PLY meshes with the mesh files in `source_files`.
#[test]
fn xml_features_read_as_mitsuba_reads_them() {
    let d = dir("features");
    std::fs::write(
        d.join("materials.xml"),
        r#"<scene version="0.6.0">
    <bsdf type="dielectric" id="glass"><float name="intIOR" value="1.5"/><float name="extIOR" value="1.25"/></bsdf>
    <bsdf type="twosided" id="grey"><bsdf type="diffuse"><rgb name="reflectance" value="$grey"/></bsdf></bsdf>
</scene>
"#,
    )
    .unwrap();
    // A quad as OBJ, as ASCII PLY (with normals) and as binary little-endian PLY.
    std::fs::write(
        d.join("quad.obj"),
        "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    std::fs::write(
        d.join("quad.ply"),
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n-1 -1 0 0 0 1\n1 -1 0 0 0 1\n1 1 0 0 0 1\n-1 1 0 0 0 1\n4 0 1 2 3\n",
    )
    .unwrap();
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 2\nproperty list uchar uint vertex_indices\nend_header\n".to_vec();
    for p in [
        [-1.0f32, -1.0, 0.0],
        [1.0, -1.0, 0.0],
        [1.0, 1.0, 0.0],
        [-1.0, 1.0, 0.0],
    ] {
        for c in p {
            bin.extend(c.to_le_bytes());
        }
    }
    for t in [[0u32, 1, 2], [0, 2, 3]] {
        bin.push(3);
        for i in t {
            bin.extend(i.to_le_bytes());
        }
    }
    std::fs::write(d.join("quad-bin.ply"), bin).unwrap();
    let body = r#"    <default name="grey" value="0.25"/>
    <include filename="materials.xml"/>
    <shape type="obj"><string name="filename" value="quad.obj"/><ref name="bsdf" id="grey"/>
        <transform name="to_world"><translate z="-1"/></transform></shape>
    <shape type="ply"><string name="filename" value="quad.ply"/><ref id="glass"/>
        <transform name="to_world"><translate z="-2"/></transform></shape>
    <shape type="ply"><string name="filename" value="quad-bin.ply"/>
        <transform name="to_world"><scale value="2"/><translate z="-3"/></transform></shape>
    <shape type="sphere"><point name="center" x="0" y="0" z="-5"/><float name="radius" value="0.5"/>
        <emitter type="area"><rgb name="radiance" value="1, 2, 3"/></emitter></shape>"#;
    let text = scene_xml(body)
        .replace(
            "<float name=\"fov\" value=\"40\"/>",
            "<float name=\"fov\" value=\"40\"/><float name=\"near_clip\" value=\"0.01\"/>",
        )
        .replace(
            "<rfilter",
            "<boolean name=\"banner\" value=\"false\"/><rfilter",
        );
    let (scene, report) = load_in(&d, "scene.xml", &text, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    // near_clip, the film's banner and the ref's name.
    assert_eq!(report.ignored.len(), 3, "{report:#?}");
    assert!(report.ignored.iter().any(|s| s.contains("banner")));
    assert!(report.ignored.iter().any(|s| s.contains("near_clip")));
    assert!(report.ignored.iter().any(|s| s.contains("`name`")));
    assert_eq!(
        scene.source_files,
        [
            "scene.xml",
            "materials.xml",
            "quad.obj",
            "quad.ply",
            "quad-bin.ply"
        ]
        .map(|f| d.join(f))
    );
    let mats: Vec<String> = scene
        .shapes
        .iter()
        .map(|s| format!("{:?}", scene.material(s.material)))
        .collect();
    assert!(
        mats[0].contains("Diffuse") && mats[0].contains("0.25"),
        "{mats:?}"
    );
    assert!(
        mats[1].contains("Dielectric") && mats[1].contains("1.2"),
        "{mats:?}"
    );
    assert!(
        mats[2].contains("Diffuse") && mats[2].contains("0.5"),
        "{mats:?}"
    ); // Mitsuba's default
    let mesh = |i: usize| match &scene.shapes[i].geometry {
        ShapeGeometry::Mesh(m) => m.clone(),
        _ => panic!(),
    };
    let (obj, ply, bin) = (mesh(0), mesh(1), mesh(2));
    assert_eq!(obj.indices.len(), 2);
    // No normals in the OBJ: computed (angle-weighted) as Mitsuba does; a flat quad's are +z.
    assert!(obj
        .normals
        .as_ref()
        .unwrap()
        .iter()
        .all(|n| *n == lt_core::Vec3::Z));
    assert!(ply.normals.is_some());
    assert_eq!(bin.indices, vec![[0, 1, 2], [0, 2, 3]]);
    assert!(obj.positions.iter().all(|p| p.z == -1.0));
    assert!(ply.positions.iter().all(|p| p.z == -2.0));
    assert!(bin
        .positions
        .iter()
        .all(|p| p.z == -3.0 && p.x.abs() == 2.0));
    assert_eq!(scene.lights.len(), 2);
    assert!(scene.shapes[3].light.is_some());
    let _ = std::fs::remove_dir_all(&d);
}

/// The x field of view Mitsuba 3.9.1 reports (`x_fov`) for a 64 × 32 film with each way of
/// giving it, held to our camera's ray at the middle of the image's right edge.
#[test]
fn xml_fields_of_view_are_mitsubas() {
    let d = dir("fov");
    for (sensor, mitsuba_x_fov) in [
        (
            "<float name=\"fov\" value=\"45\"/><string name=\"fov_axis\" value=\"y\"/>",
            79.2785,
        ),
        ("<string name=\"focal_length\" value=\"35mm\"/>", 57.8712),
        ("", 42.3117),
        (
            "<float name=\"fov\" value=\"45\"/><string name=\"fov_axis\" value=\"diagonal\"/>",
            40.6577,
        ),
    ] {
        let text = scene_xml("")
            .replace("<float name=\"fov\" value=\"40\"/>", sensor)
            .replace("value=\"24\"", "value=\"32\"")
            .replace("value=\"32\"/><integer", "value=\"64\"/><integer");
        let (scene, _) = load_in(&d, "scene.xml", &text, LoadOptions::default()).unwrap();
        let c = &scene.camera;
        assert_eq!((c.width, c.height), (64, 32));
        let r = c.generate_ray(lt_core::Vec2::new(64.0, 16.0));
        let x_fov = 2.0 * r.d.angle_between(c.forward()).to_degrees();
        assert!(
            (x_fov - mitsuba_x_fov).abs() < 2e-3,
            "{sensor}: {x_fov} vs {mitsuba_x_fov}"
        );
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// A disk is exact (no `--approximate`): Mitsuba's unit disk under `to_world`, an ellipse of area
/// π·0.5·1.5 under a non-uniform scale, facing +z, and a camera ray through its centre hits it.
#[test]
fn xml_disk_is_exact() {
    let d = dir("disk");
    let text = scene_xml(
        "    <shape type=\"disk\">\n        <transform name=\"to_world\"><scale x=\"0.5\" y=\"1.5\" z=\"1\"/></transform>\n        <emitter type=\"area\"/>\n    </shape>",
    );
    let (scene, report) = load_in(&d, "scene.xml", &text, LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    let ShapeGeometry::Disk { to_world } = &scene.shapes[0].geometry else {
        panic!("not a disk: {:?}", scene.shapes[0].geometry)
    };
    assert_eq!(to_world.m.x_axis.x, 0.5);
    assert_eq!(to_world.m.y_axis.y, 1.5);
    let lt_core::light::Light::Area(a) = &scene.lights[0] else {
        panic!()
    };
    let exact = std::f32::consts::PI * 0.75;
    assert!(
        (a.area - exact).abs() < 1e-5 * exact,
        "{} vs {exact}",
        a.area
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// The shipped Cornell box rewritten with Mitsuba 0.6's camelCase names (`toWorld`, `maxDepth`,
/// `sampleCount`, `fovAxis`, …; Mitsuba 3.9.1 loads this file too) is the same scene.
#[test]
fn xml_version_0_6_names_are_upgraded() {
    let d = dir("v06");
    let shipped = lt_tests::scenes_dir().join("xml/cornell-box.xml");
    let mut text = std::fs::read_to_string(&shipped)
        .unwrap()
        .replace("version=\"3.0.0\"", "version=\"0.6.0\"");
    for (new, old) in [
        ("to_world", "toWorld"),
        ("max_depth", "maxDepth"),
        ("fov_axis", "fovAxis"),
        ("sample_count", "sampleCount"),
        ("near_clip", "nearClip"),
        ("far_clip", "farClip"),
        ("focus_distance", "focusDistance"),
        ("pixel_format", "pixelFormat"),
        ("component_format", "componentFormat"),
    ] {
        text = text.replace(&format!("\"{new}\""), &format!("\"{old}\""));
    }
    assert!(text.contains("\"toWorld\"") && !text.contains("\"to_world\""));
    let (old, report) = load_in(&d, "cornell-0.6.xml", &text, LoadOptions::default()).unwrap();
    let (new, _) = load_scene_with(&shipped, &LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty());
    assert_eq!(report.ignored.len(), 5, "{report:?}");
    assert_eq!(old.settings, new.settings);
    assert_eq!(
        format!("{:?}", old.materials),
        format!("{:?}", new.materials)
    );
    assert_eq!(format!("{:?}", old.shapes), format!("{:?}", new.shapes));
    assert_eq!(format!("{:?}", old.lights), format!("{:?}", new.lights));
    let r = lt_core::Vec2::new(100.0, 30.0);
    let (a, b) = (old.camera.generate_ray(r), new.camera.generate_ray(r));
    assert_eq!((a.o, a.d), (b.o, b.d));
    let _ = std::fs::remove_dir_all(&d);
}

/// Geometry that overflows f32 (or is not finite) is one clear error at the shape's transform,
/// not a panic inside the BVH builder (a `to_world` entry of 1e38 once panicked in obvhs).
#[test]
fn xml_overflowing_geometry_is_one_clear_error() {
    let d = dir("overflow");
    for (entry, what) in [("1e38", "1e38"), ("3e18", "3e18")] {
        let text = scene_xml(&format!(
            "    <shape type=\"rectangle\">\n        <transform name=\"to_world\">\n            <matrix value=\"1 0 0 {entry}  0 1 0 0  0 0 1 0  0 0 0 1\"/>\n        </transform>\n    </shape>"
        ));
        fails(
            &d,
            &text,
            line_of(&text, "rectangle") + 1,
            &["world coordinates", "finite", what],
        );
    }
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <point name=\"center\" value=\"0, 2e18, 0\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "sphere"),
        &["the sphere", "world coordinates"],
    );
}

/// A `mesh_attribute` texture names an attribute the PLY has (`vertex_<p>` from `<p>_0.._2`,
/// `face_<p>` from a lone `<p>_0`): a misspelt one is refused at the shape with the names it has,
/// a name without `vertex_`/`face_` at the texture; the right ones load.
#[test]
fn mesh_attribute_names_are_checked_against_the_mesh() {
    let d = dir("mesh-attribute");
    std::fs::write(
        d.join("tri.ply"),
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nproperty float color_0\nproperty float color_1\nproperty float color_2\nelement face 1\nproperty list uchar int vertex_indices\nproperty float weight_0\nend_header\n-1 -1 0 1 0 0\n1 -1 0 0 1 0\n0 1 0 0 0 1\n3 0 1 2 0.25\n",
    )
    .unwrap();
    let with = |name: &str| {
        scene_xml(&format!(
            "    <texture type=\"mesh_attribute\" id=\"t\"><string name=\"name\" value=\"{name}\"/></texture>\n    <bsdf type=\"diffuse\" id=\"m\"><ref name=\"reflectance\" id=\"t\"/></bsdf>\n    <shape type=\"ply\">\n        <string name=\"filename\" value=\"tri.ply\"/><ref id=\"m\"/>\n    </shape>"
        ))
    };
    let text = with("vertex_colour");
    fails(
        &d,
        &text,
        line_of(&text, "<shape type=\"ply\">"),
        &["`vertex_colour`", "vertex_color, face_weight"],
    );
    let text = with("colour");
    fails(
        &d,
        &text,
        line_of(&text, "value=\"colour\""),
        &["must start with `vertex_` or `face_`"],
    );
    for ok in ["vertex_color", "face_weight"] {
        load_in(&d, "scene.xml", &with(ok), LoadOptions::default()).unwrap();
    }
}

/// TOML's `principled`/`principledthin` build the material Mitsuba's XML names build, with the
/// same defaults, and refuse what the XML refuses (one shared set of checks).
#[test]
fn principled_reads_alike_from_toml_and_xml() {
    let d = dir("principled-toml");
    let toml = |material: &str| {
        format!(
            "[camera]\neye = [0.0, 0.0, 4.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nfov = 40.0\nresolution = [32, 24]\n\n[materials.m]\n{material}\n\n[[shapes]]\ntype = \"sphere\"\ncenter = [0.0, 0.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n\n[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 0.0]\nintensity = [5.0, 5.0, 5.0]\n"
        )
    };
    let from_toml = |material: &str| {
        let text = toml(material);
        lt_scene_io::load_scene_str(&text, &d.join("scene.toml"))
    };
    let material_of = |s: &Scene| format!("{:?}", s.material(s.shapes[0].material));
    let cases = [
        (
            "type = \"principled\"",
            "<bsdf type=\"principled\"/>",
        ),
        (
            "type = \"principled\"\nbase_color = [0.8, 0.2, 0.1]\nroughness = 0.3\nanisotropic = 0.5\nmetallic = 0.7\nspec_trans = 0.2\nspecular = 0.6\nspec_tint = 0.1\nsheen = 0.4\nsheen_tint = 0.2\nflatness = 0.3\nclearcoat = 0.5\nclearcoat_gloss = 0.9",
            "<bsdf type=\"principled\"><rgb name=\"base_color\" value=\"0.8, 0.2, 0.1\"/><float name=\"roughness\" value=\"0.3\"/><float name=\"anisotropic\" value=\"0.5\"/><float name=\"metallic\" value=\"0.7\"/><float name=\"spec_trans\" value=\"0.2\"/><float name=\"specular\" value=\"0.6\"/><float name=\"spec_tint\" value=\"0.1\"/><float name=\"sheen\" value=\"0.4\"/><float name=\"sheen_tint\" value=\"0.2\"/><float name=\"flatness\" value=\"0.3\"/><float name=\"clearcoat\" value=\"0.5\"/><float name=\"clearcoat_gloss\" value=\"0.9\"/></bsdf>",
        ),
        (
            "type = \"principled\"\nior = 1.0\nspec_trans = 1.0",
            "<bsdf type=\"principled\"><float name=\"eta\" value=\"1.0\"/><float name=\"spec_trans\" value=\"1\"/></bsdf>",
        ),
        (
            "type = \"principledthin\"",
            "<bsdf type=\"principledthin\"/>",
        ),
        (
            "type = \"principledthin\"\nbase_color = 0.3\nroughness = 0.2\ndiff_trans = 1.5\nspec_trans = 0.4\nior = 1.33\nsheen = 0.5",
            "<bsdf type=\"principledthin\"><rgb name=\"base_color\" value=\"0.3\"/><float name=\"roughness\" value=\"0.2\"/><float name=\"diff_trans\" value=\"1.5\"/><float name=\"spec_trans\" value=\"0.4\"/><float name=\"eta\" value=\"1.33\"/><float name=\"sheen\" value=\"0.5\"/></bsdf>",
        ),
    ];
    for (t, x) in cases {
        let a = from_toml(t).unwrap_or_else(|e| panic!("{t}: {e}"));
        let xml = scene_xml(&format!("    <shape type=\"sphere\">{x}</shape>"));
        let (b, _) = load_in(&d, "scene.xml", &xml, LoadOptions::default()).unwrap();
        assert_eq!(material_of(&a), material_of(&b), "{t}");
    }
    // A textured base colour becomes a textured principled material.
    let checker = "type = \"principled\"\nbase_color_texture = { type = \"checkerboard\", color0 = 0.2, color1 = 0.8 }";
    let m = material_of(&from_toml(checker).unwrap());
    assert!(
        m.starts_with("Textured") && m.contains("Principled(BaseColor)"),
        "{m}"
    );
    // Refusals name the key and point at its line.
    for (material, at, words) in [
        ("type = \"principled\"\nmetallic = 1.5", "metallic", &["`metallic`", "[0, 1]"][..]),
        ("type = \"principled\"\nior = 1.5\nspecular = 0.5", "specular", &["`ior` or `specular`"]),
        ("type = \"principledthin\"\nclearcoat = 0.5", "clearcoat", &["`clearcoat`", "does not apply"]),
        ("type = \"principled\"\ndiff_trans = 0.5", "diff_trans", &["`diff_trans`", "does not apply"]),
        ("type = \"principledthin\"\ndiff_trans = 2.5", "diff_trans", &["`diff_trans`", "[0, 2]"]),
        ("type = \"diffuse\"\nalbedo = 0.5\nsheen = 0.5", "sheen", &["`sheen`", "does not apply"]),
        (
            "type = \"principled\"\nbase_color = 0.5\nbase_color_texture = { type = \"checkerboard\" }",
            "base_color_texture",
            &["not both"],
        ),
    ] {
        let text = toml(material);
        let Err(e) = from_toml(material) else {
            panic!("{material}: should not load")
        };
        let e = e.to_string();
        let line = 1 + text.lines().position(|l| l.starts_with(at)).unwrap();
        for w in words {
            assert!(e.contains(w), "`{w}` missing from: {e}");
        }
        assert!(e.contains(&format!(":{line}:")), "line {line} not in: {e}");
    }
}

/// What a user needs first comes first: an unknown plugin type is named, at its line and with the
/// known types of its kind, before anything about the sensor or the integrator's max_depth.
#[test]
fn xml_unknown_types_come_first_with_the_known_ones() {
    let d = dir("unknown-first");
    // No sensor and an unbounded max_depth: both would be refused, but later.
    let text = r#"<scene version="3.0.0">
    <integrator type="path"/>
    <shape type="nosuchshape"/>
</scene>
"#;
    fails(
        &d,
        text,
        3,
        &[
            "shape `nosuchshape` is not supported",
            "rectangle, cube, sphere, disk, cylinder, sdfgrid, obj, ply, serialized",
        ],
    );
    // Deep inside a wrapper, below a valid scene: the BSDF's line and every BSDF type lt reads.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <bsdf type=\"twosided\">\n            <bsdf type=\"velvet\"/>\n        </bsdf>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "velvet"),
        &["BSDF `velvet` is not supported", "diffuse", "blendbsdf"],
    );
}

/// Several problems of one file are listed together, each with its line, in document order.
#[test]
fn xml_problems_of_one_file_are_listed_together() {
    let d = dir("listed-together");
    let text = scene_xml(
        "    <shape type=\"sphere\"><bsdf type=\"velvet\"/></shape>\n    <shape type=\"sphere\"><ref id=\"nowhere\"/></shape>\n    <emitter type=\"sunsky\"/>",
    );
    let e = fails(
        &d,
        &text,
        line_of(&text, "velvet"),
        &[
            "3 problems",
            "BSDF `velvet`",
            "undefined id `nowhere`",
            "emitter `sunsky`",
        ],
    );
    let shown = e.to_string();
    for needle in ["velvet", "nowhere", "sunsky"] {
        let at = format!("scene.xml:{}:", line_of(&text, needle));
        assert!(shown.contains(&at), "`{shown}` lacks {at}");
    }
    let order: Vec<usize> = ["velvet", "`nowhere`", "sunsky"]
        .iter()
        .map(|n| shown.rfind(n).unwrap())
        .collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{shown}");
}

/// A top-level `area` emitter referenced by id from a shape (mitsuba-data's `cbox-rgb.xml` does
/// this), defined before or after the shape, is that shape's emitter, as Mitsuba reads it; an
/// area emitter no shape references is still refused.
#[test]
fn xml_top_level_area_emitters_attach_by_reference() {
    let d = dir("area-by-id");
    let light =
        "    <emitter type=\"area\" id=\"lamp\"><rgb name=\"radiance\" value=\"4\"/></emitter>\n";
    let shape = "    <shape type=\"rectangle\"><ref id=\"lamp\"/></shape>\n";
    let nested = "    <shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"4\"/></emitter></shape>\n";
    let (reference, _) = load_in(&d, "nested.xml", &scene_xml(nested), LoadOptions::default())
        .unwrap_or_else(|e| panic!("{e}"));
    for (name, body) in [
        ("before.xml", format!("{light}{shape}")),
        ("after.xml", format!("{shape}{light}")),
    ] {
        let (scene, _) = load_in(&d, name, &scene_xml(&body), LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.lights.len(), reference.lights.len(), "{name}");
        assert_eq!(scene.shapes.len(), reference.shapes.len(), "{name}");
        assert_eq!(
            format!("{:?}", scene.lights),
            format!("{:?}", reference.lights),
            "{name}"
        );
    }
    let text = scene_xml(light);
    fails(
        &d,
        &text,
        line_of(&text, "lamp"),
        &["an area emitter must be nested in a shape"],
    );
}
