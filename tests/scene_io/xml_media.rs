//! Mitsuba XML media: `homogeneous` and `heterogeneous` media, `isotropic`/`hg` phase functions,
//! `gridvolume`/`constvolume` volumes, `null` boundaries, shapes' interior and exterior media, a
//! sensor's and an emitter's medium — read as Mitsuba reads them, and every bad value one error
//! naming the file, the line and the problem. Mitsuba's own media suite loads.

use lt_core::math::Color;
use lt_core::medium::{Medium, PhaseFunction};
use lt_core::Scene;
use lt_scene_io::{load_scene_with, LoadOptions, SceneError};
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("lt-xml-media-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A small valid scene with `sensor_extra` inside its sensor and `body` before its light.
fn scene_with(sensor_extra: &str, body: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="5"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="24"/>
            <rfilter type="box"/>
        </film>
{sensor_extra}
    </sensor>
{body}
    <emitter type="point"><point name="position" x="0" y="2" z="0"/><rgb name="intensity" value="5"/></emitter>
</scene>
"#
    )
}

fn scene_xml(body: &str) -> String {
    scene_with("", body)
}

fn load(d: &Path, text: &str) -> Result<Scene, SceneError> {
    let path = d.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    load_scene_with(&path, &LoadOptions::default()).map(|(s, _)| s)
}

fn loads(d: &Path, text: &str) -> Scene {
    load(d, text).unwrap_or_else(|e| panic!("{e}"))
}

/// The load fails at `line` of scene.xml with every needle in its message.
fn fails(d: &Path, text: &str, line: usize, needles: &[&str]) {
    let e = match load(d, text) {
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
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect(needle) + 1
}

/// A `.vol` file: header (version 3, f32), resolution, channels, unit bounding box, values.
fn vol_bytes(res: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, res[0], res[1], res[2], channels] {
        b.extend(v.to_le_bytes());
    }
    for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
        b.extend(v.to_le_bytes());
    }
    for v in values {
        b.extend(v.to_le_bytes());
    }
    b
}

fn homogeneous(m: &Medium) -> lt_core::medium::Homogeneous {
    *m.as_homogeneous().expect("a homogeneous medium")
}

/// Whether shape `i` has an interior medium.
fn interior(s: &Scene, i: usize) -> Option<u32> {
    s.interfaces[s.shapes[i].interface as usize].interior
}

#[test]
fn xml_media_read_as_mitsuba_reads_them() {
    let d = dir("read");
    // σt/albedo with scale and hg; a forward reference from the shape; a nested exterior.
    let text = scene_xml(
        r#"    <shape type="sphere">
        <bsdf type="null"/>
        <ref name="interior" id="fog"/>
        <medium name="exterior" type="homogeneous">
            <float name="sigma_a" value="1"/>
            <rgb name="sigma_s" value="1, 2, 3"/>
        </medium>
    </shape>
    <medium type="homogeneous" id="fog">
        <rgb name="sigma_t" value="1, 2, 3"/>
        <float name="albedo" value="0.5"/>
        <float name="scale" value="2"/>
        <phase type="hg"><float name="g" value="0.7"/></phase>
    </medium>"#,
    );
    let s = loads(&d, &text);
    assert_eq!(s.media.len(), 2);
    let inside = interior(&s, 0).unwrap();
    let h = homogeneous(&s.media[inside as usize]);
    assert_eq!(h.sigma_t, Color::new(2.0, 4.0, 6.0));
    assert_eq!(h.albedo, Color::splat(0.5));
    assert_eq!(h.phase, PhaseFunction::HenyeyGreenstein { g: 0.7 });
    let outside = s.interfaces[s.shapes[0].interface as usize]
        .exterior
        .unwrap();
    let h = homogeneous(&s.media[outside as usize]);
    assert_eq!(h.sigma_t, Color::new(2.0, 3.0, 4.0));
    assert_eq!(h.albedo, Color::new(0.5, 2.0 / 3.0, 0.75));
    assert_eq!(h.phase, PhaseFunction::Isotropic);
    assert!(s.shapes[0].null);

    // Mitsuba's defaults (σt 1, albedo 0.75, hg's g 0.8); the camera's and a light's medium.
    let text = scene_with(
        r#"        <ref name="medium" id="air"/>"#,
        r#"    <medium type="homogeneous" id="air"><phase type="hg"/></medium>
    <emitter type="spot"><ref name="medium" id="air"/></emitter>"#,
    );
    let s = loads(&d, &text);
    assert_eq!(s.media.len(), 1);
    assert_eq!(s.camera_medium, Some(0));
    let h = homogeneous(&s.media[0]);
    assert_eq!((h.sigma_t, h.albedo), (Color::ONE, Color::splat(0.75)));
    assert_eq!(h.phase, PhaseFunction::HenyeyGreenstein { g: 0.8 });
    assert_eq!(s.light_media.iter().filter(|m| **m == Some(0)).count(), 1);

    // heterogeneous over a grid file (3 channels) and a constvolume albedo.
    let values: Vec<f32> = (0..24).map(|i| i as f32 * 0.1).collect();
    std::fs::write(d.join("sigma.vol"), vol_bytes([2, 2, 2], 3, &values)).unwrap();
    let text = scene_xml(
        r#"    <shape type="cube">
        <bsdf type="null"/>
        <medium name="interior" type="heterogeneous">
            <volume name="sigma_t" type="gridvolume">
                <string name="filename" value="sigma.vol"/>
                <transform name="to_world"><translate x="-0.5" y="-0.5" z="-0.5"/></transform>
            </volume>
            <volume name="albedo" type="constvolume"><rgb name="value" value="0.9"/></volume>
            <float name="scale" value="3"/>
        </medium>
    </shape>"#,
    );
    let s = loads(&d, &text);
    assert_eq!(s.media.len(), 1);
    let Medium::Grid(g) = &s.media[0] else {
        panic!("a grid medium")
    };
    // The sample at local (0.25, 0.25, 0.25) is value 0 (channels 0, 1, 2) times the scale.
    let p = lt_core::math::Vec3::splat(-0.25) - s.origin;
    let want = Color::new(0.0, 0.1, 0.2) * 3.0;
    assert!(
        (g.sigma_t(p) - want).abs().max_element() < 1e-6,
        "{}",
        g.sigma_t(p)
    );
    assert_eq!(g.albedo(p), Color::splat(0.9));
    assert!(s.source_files.iter().any(|f| f.ends_with("sigma.vol")));
}

#[test]
fn xml_bad_media_give_one_clear_error() {
    let d = dir("bad");
    let medium = |params: &str| {
        scene_xml(&format!(
            "    <medium type=\"homogeneous\" id=\"m\">\n{params}\n    </medium>"
        ))
    };
    let cases: [(&str, &str, &[&str]); 6] = [
        (
            "        <rgb name=\"sigma_t\" value=\"1, -1, 1\"/>",
            "sigma_t",
            &["`sigma_t` of medium `homogeneous` must not be negative"],
        ),
        (
            "        <float name=\"sigma_t\" value=\"inf\"/>",
            "sigma_t",
            &["sigma_t"],
        ),
        (
            "        <rgb name=\"albedo\" value=\"0.5, 1.2, 0.5\"/>",
            "albedo",
            &["`albedo` of medium `homogeneous` must be at most 1"],
        ),
        (
            "        <float name=\"scale\" value=\"-1\"/>",
            "<medium",
            &["medium `homogeneous`: scale = -1 must be finite and non-negative"],
        ),
        (
            "        <phase type=\"hg\"><float name=\"g\" value=\"1\"/></phase>",
            "<phase",
            &["g = 1 must lie strictly between -1 and 1"],
        ),
        (
            "        <float name=\"sigma_a\" value=\"1\"/>\n        <float name=\"albedo\" value=\"1\"/>",
            "<medium",
            &["sigma_t and albedo, or sigma_a and sigma_s"],
        ),
    ];
    for (params, at, needles) in cases {
        let text = medium(params);
        fails(&d, &text, line_of(&text, at), needles);
    }
    let text = medium("        <float name=\"density\" value=\"1\"/>");
    fails(
        &d,
        &text,
        line_of(&text, "density"),
        &["parameter `density` of medium `homogeneous` is not supported"],
    );

    // A medium referenced but not defined.
    let text = scene_xml(
        "    <shape type=\"sphere\">\n        <ref name=\"interior\" id=\"smoke\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "smoke"),
        &["reference to an undefined id `smoke`"],
    );
    // A medium under a name no shape reads.
    let text = scene_xml(
        "    <medium type=\"homogeneous\" id=\"m\"/>\n    <shape type=\"sphere\">\n        <ref name=\"inside\" id=\"m\"/>\n    </shape>",
    );
    fails(
        &d,
        &text,
        line_of(&text, "inside"),
        &["must be named `interior` or `exterior`"],
    );
    // An interior medium in an open surface: a rectangle, a disk, an open mesh.
    for shape in ["rectangle", "disk", "cylinder"] {
        let text = scene_xml(&format!(
            "    <medium type=\"homogeneous\" id=\"m\"/>\n    <shape type=\"{shape}\">\n        <ref name=\"interior\" id=\"m\"/>\n    </shape>"
        ));
        fails(
            &d,
            &text,
            line_of(&text, "<shape"),
            &["has an interior medium but is not closed"],
        );
    }
    // A cube minus its last face: open; a closed cube with an exterior medium only is fine.
    let mut obj =
        String::from("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n");
    let faces = [
        "1 4 3 2", "5 6 7 8", "1 2 6 5", "2 3 7 6", "3 4 8 7", "4 1 5 8",
    ];
    for f in &faces[..5] {
        obj += &format!("f {f}\n");
    }
    std::fs::write(d.join("open.obj"), &obj).unwrap();
    obj += &format!("f {}\n", faces[5]);
    std::fs::write(d.join("closed.obj"), &obj).unwrap();
    let mesh = |file: &str, name: &str| {
        scene_xml(&format!(
            "    <medium type=\"homogeneous\" id=\"m\"/>\n    <shape type=\"obj\">\n        <string name=\"filename\" value=\"{file}\"/>\n        <ref name=\"{name}\" id=\"m\"/>\n    </shape>"
        ))
    };
    let text = mesh("open.obj", "interior");
    fails(
        &d,
        &text,
        line_of(&text, "<shape"),
        &["not closed (4 of its 17 edges are not shared by exactly two triangles)"],
    );
    loads(&d, &mesh("closed.obj", "interior"));
    loads(&d, &mesh("open.obj", "exterior"));

    // Grid files: truncated, inconsistent, albedo above 1, missing.
    let grid = |file: &str, name: &str| {
        scene_xml(&format!(
            "    <medium type=\"heterogeneous\" id=\"m\">\n        <volume name=\"{name}\" type=\"gridvolume\">\n            <string name=\"filename\" value=\"{file}\"/>\n        </volume>\n    </medium>"
        ))
    };
    let good = vol_bytes([2, 2, 2], 1, &[0.5; 8]);
    std::fs::write(d.join("short.vol"), &good[..good.len() - 4]).unwrap();
    let mut long = good.clone();
    long.extend([0; 4]);
    std::fs::write(d.join("long.vol"), &long).unwrap();
    std::fs::write(d.join("bright.vol"), vol_bytes([2, 2, 2], 1, &[1.5; 8])).unwrap();
    std::fs::write(d.join("negative.vol"), vol_bytes([2, 2, 2], 1, &[-1.0; 8])).unwrap();
    let cases: [(&str, &str, &str, &[&str]); 5] = [
        (
            "short.vol",
            "sigma_t",
            "filename",
            &["malformed volume grid file", "truncated"],
        ),
        (
            "long.vol",
            "sigma_t",
            "filename",
            &["malformed volume grid file", "inconsistent"],
        ),
        (
            "bright.vol",
            "albedo",
            "<medium",
            &["albedo", "must lie in [0, 1]"],
        ),
        (
            "negative.vol",
            "sigma_t",
            "<medium",
            &["sigma_t", "non-negative"],
        ),
        ("none.vol", "sigma_t", "filename", &["none.vol"]),
    ];
    for (file, name, at, needles) in cases {
        let text = grid(file, name);
        fails(&d, &text, line_of(&text, at), needles);
    }
    let text = scene_xml("    <medium type=\"fog\"/>");
    fails(
        &d,
        &text,
        line_of(&text, "fog"),
        &["medium `fog` is not supported (lt reads homogeneous, heterogeneous)"],
    );
}

/// Every scene of Mitsuba's media suite loads, with its media where the file puts them.
#[test]
fn xml_mitsubas_media_suite_loads() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../shared/mitsuba-render-tests/tests/scenes/participating_media");
    if !dir.is_dir() {
        assert!(
            std::env::var("LT_REQUIRE_MITSUBA_SUITE").as_deref() != Ok("1"),
            "LT_REQUIRE_MITSUBA_SUITE=1 but {} is missing",
            dir.display()
        );
        eprintln!("skipped: no Mitsuba render-test suite at {}", dir.display());
        return;
    }
    // Scene, number of media, each shape in order: I has an interior medium, N is null.
    let expected = [
        ("hetero_sigmat_albedo_volpath", 1, "- IN -"),
        ("hetero_sigmat_volpath", 1, "- IN -"),
        ("hetero_spectral_sigmat_no_scattering_volpath", 1, "- IN -"),
        ("hetero_spectral_sigmat_volpathmis", 1, "- IN -"),
        ("homo_area_light_volpath", 1, "- IN I -"),
        ("homo_dielectric_envmap_volpath", 1, "I I"),
        ("homo_emitter_inside_medium_volpath", 1, "- I I - -"),
        ("homo_null_envmap_volpath", 1, "- IN IN"),
        ("homo_obj_inside_medium_volpath", 1, "- I I - -"),
        ("homo_roughdielectric_spot_volpath", 1, "I I"),
        ("homo_spectral_sigmat_volpathmis", 1, "- IN IN"),
        ("surf_area_light_volpath", 0, "- - - -"),
    ];
    let files = std::fs::read_dir(&dir).unwrap().filter(|f| {
        let p = f.as_ref().unwrap().path();
        p.extension().is_some_and(|e| e == "xml")
    });
    assert_eq!(files.count(), expected.len());
    for (name, media, shapes) in expected {
        let path = dir.join(format!("test_{name}.xml"));
        let (s, _) = load_scene_with(&path, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(s.media.len(), media, "{name}");
        let got: Vec<String> = (0..s.shapes.len())
            .map(|i| {
                let mut k = if interior(&s, i).is_some() { "I" } else { "-" }.to_string();
                if s.shapes[i].null {
                    k += "N";
                }
                k
            })
            .collect();
        assert_eq!(got.join(" "), shapes, "{name}");
    }
}
