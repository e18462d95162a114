//! Every shipped scene Mitsuba can express survives toml → xml (`lt convert`) → load unchanged:
//! the same camera rays, settings, origin, geometry, materials and lights, bit for bit (the
//! writer prints each f32 as the shortest decimal that reads back to it and the XML loader
//! rounds to f32 once, as the TOML loader does). A scene with a finite-cone sun is refused by
//! name: Mitsuba 3 has no such light.

use lt_core::{Scene, Vec2};
use lt_scene_io::{load_scene, load_scene_with, LoadOptions};
use lt_tests::{scenes_dir, shipped_scene_names};
use std::path::PathBuf;

fn assert_same(name: &str, a: &Scene, b: &Scene) {
    assert_eq!(a.settings, b.settings, "{name}: settings");
    assert_eq!(a.origin, b.origin, "{name}: origin");
    assert_eq!(
        a.bounding_sphere, b.bounding_sphere,
        "{name}: bounding sphere"
    );
    assert_eq!(
        a.primitive_count(),
        b.primitive_count(),
        "{name}: primitives"
    );
    assert_eq!(
        format!("{:?}", a.materials),
        format!("{:?}", b.materials),
        "{name}: materials"
    );
    assert_eq!(
        format!("{:?}", a.shapes),
        format!("{:?}", b.shapes),
        "{name}: shapes"
    );
    assert_eq!(
        format!("{:?}", a.lights),
        format!("{:?}", b.lights),
        "{name}: lights"
    );
    assert_eq!(a.infinite_lights, b.infinite_lights, "{name}");
    let (ca, cb) = (&a.camera, &b.camera);
    assert_eq!((ca.width, ca.height), (cb.width, cb.height), "{name}");
    assert_eq!(
        (ca.lens(), ca.filter().shape(), ca.principal_point_offset()),
        (cb.lens(), cb.filter().shape(), cb.principal_point_offset()),
        "{name}: lens, pixel filter, principal point"
    );
    for j in 0..=6 {
        for i in 0..=6 {
            let r = Vec2::new(
                ca.width as f32 * i as f32 / 6.0,
                ca.height as f32 * j as f32 / 6.0,
            );
            let (ra, rb) = (ca.generate_ray(r), cb.generate_ray(r));
            assert_eq!((ra.o, ra.d), (rb.o, rb.d), "{name}: camera ray at {r}");
        }
    }
}

fn has_sun(toml: &std::path::Path) -> bool {
    std::fs::read_to_string(toml)
        .unwrap()
        .lines()
        .any(|l| l.replace(' ', "").starts_with("type=\"sun\""))
}

#[test]
fn xml_every_expressible_shipped_scene_round_trips() {
    let out = std::env::temp_dir().join(format!("lt-xml-roundtrip-{}", std::process::id()));
    std::fs::create_dir_all(&out).unwrap();
    let (mut converted, mut refused) = (Vec::new(), Vec::new());
    for name in shipped_scene_names() {
        let toml = scenes_dir().join(format!("{name}.toml"));
        let xml = out.join(format!("{name}.xml"));
        let args = lt_experiments::commands::convert::ConvertArgs {
            scene: toml.clone(),
            output: xml.clone(),
        };
        match lt_experiments::commands::convert::run(&args) {
            Err(e) => {
                assert!(has_sun(&toml), "{name}: refused without a sun: {e}");
                assert!(e.contains("no sun of finite solid angle"), "{name}: {e}");
                assert!(!xml.exists(), "{name}: a refused conversion wrote a file");
                refused.push(name);
                continue;
            }
            Ok(()) => assert!(!has_sun(&toml), "{name} has a sun but was converted"),
        }
        let a = load_scene(&toml).unwrap();
        let (b, report) = load_scene_with(&xml, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{name}: the converted XML does not load: {e}"));
        assert!(report.substitutions.is_empty(), "{name}: {report:?}");
        assert!(report.ignored.is_empty(), "{name}: {report:?}");
        assert_same(&name, &a, &b);
        // The same mesh files, referenced from the XML's folder.
        let canon = |v: &[PathBuf]| -> Vec<PathBuf> {
            v.iter().map(|p| p.canonicalize().unwrap()).collect()
        };
        assert_eq!(b.source_files[0], xml);
        assert_eq!(
            canon(&a.source_files[1..]),
            canon(&b.source_files[1..]),
            "{name}: meshes"
        );
        converted.push(name);
    }
    eprintln!("converted {converted:?}; refused (sun) {refused:?}");
    assert!(converted.len() >= 10, "{converted:?}");
    assert!(
        converted.iter().any(|n| n == "cornell-mesh-light"),
        "the mesh scene converts"
    );
    assert!(
        !refused.is_empty(),
        "a shipped scene with a sun exists and is refused"
    );
    let _ = std::fs::remove_dir_all(&out);
}

/// A `.vol` grid: header (version 3, f32), resolution, channels, unit bounding box, values.
fn vol_bytes(res: [i32; 3], values: &[f32]) -> Vec<u8> {
    let mut b = b"VOL\x03".to_vec();
    for v in [1, res[0], res[1], res[2], 1] {
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

/// Media in TOML (`[media]`, shapes' interior/exterior, the camera's and a light's medium, a
/// `null` material, a grid, an HG phase) build the same scene as the same media written by hand
/// in Mitsuba XML, and as the XML `lt convert` writes from the TOML.
const MEDIA_TOML: &str = r#"
[camera]
eye = [0.0, 1.0, 4.0]
target = [0.0, 1.0, 0.0]
fov = 40.0
resolution = [32, 24]
medium = "fog"

[render]
max_depth = 6

[materials.white]
type = "diffuse"
albedo = 0.7

[materials.boundary]
type = "null"

[media.fog]
type = "homogeneous"
sigma_a = [0.01, 0.02, 0.03]
sigma_s = 0.05
phase = { type = "isotropic" }

[media.smoke]
type = "heterogeneous"
sigma_t_volume = { file = "density.vol", to_world = [[2.0, 0.0, 0.0, -1.0], [0.0, 2.0, 0.0, 0.0], [0.0, 0.0, 2.0, -1.0], [0.0, 0.0, 0.0, 1.0]] }
albedo = [0.9, 0.8, 0.7]
scale = 3.0
phase = { type = "hg", g = 0.7 }

[[shapes]]
type = "quad"
material = "white"
to_world = [[4.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, -4.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
exterior = "fog"

[[shapes]]
type = "sphere"
center = [0.0, 1.0, 0.0]
radius = 0.75
material = "boundary"
interior = "smoke"
exterior = "fog"

[[lights]]
type = "point"
position = [0.0, 3.0, 1.0]
intensity = 10.0
medium = "fog"
"#;

const MEDIA_XML: &str = r#"<scene version="3.0.0">
    <integrator type="volpath">
        <integer name="max_depth" value="6"/>
    </integrator>
    <bsdf type="twosided" id="white">
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
    </bsdf>
    <bsdf type="null" id="boundary"/>
    <medium type="homogeneous" id="fog">
        <rgb name="sigma_a" value="0.01, 0.02, 0.03"/>
        <rgb name="sigma_s" value="0.05"/>
        <phase type="isotropic"/>
    </medium>
    <medium type="heterogeneous" id="smoke">
        <volume type="gridvolume" name="sigma_t">
            <string name="filename" value="density.vol"/>
            <transform name="to_world">
                <scale value="2"/>
                <translate x="-1" y="0" z="-1"/>
            </transform>
        </volume>
        <rgb name="albedo" value="0.9, 0.8, 0.7"/>
        <float name="scale" value="3"/>
        <phase type="hg"><float name="g" value="0.7"/></phase>
    </medium>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <string name="fov_axis" value="x"/>
        <transform name="to_world"><lookat origin="0, 1, 4" target="0, 1, 0" up="0, 1, 0"/></transform>
        <ref name="medium" id="fog"/>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="32"/>
            <integer name="height" value="24"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world">
            <matrix value="4 0 0 0  0 0 1 0  0 -4 0 0  0 0 0 1"/>
        </transform>
        <ref id="white"/>
        <ref name="exterior" id="fog"/>
    </shape>
    <shape type="sphere">
        <point name="center" value="0, 1, 0"/>
        <float name="radius" value="0.75"/>
        <ref id="boundary"/>
        <ref name="interior" id="smoke"/>
        <ref name="exterior" id="fog"/>
    </shape>
    <emitter type="point">
        <point name="position" value="0, 3, 1"/>
        <rgb name="intensity" value="10"/>
        <ref name="medium" id="fog"/>
    </emitter>
</scene>
"#;

#[test]
fn xml_toml_media_scene_builds_as_its_xml_twin() {
    let dir = std::env::temp_dir().join(format!("lt-toml-media-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let density: Vec<f32> = (0..27).map(|i| 0.1 + 0.05 * i as f32).collect();
    std::fs::write(dir.join("density.vol"), vol_bytes([3, 3, 3], &density)).unwrap();
    let toml = dir.join("media.toml");
    std::fs::write(&toml, MEDIA_TOML).unwrap();
    let twin = dir.join("media.xml");
    std::fs::write(&twin, MEDIA_XML).unwrap();
    let converted = dir.join("converted.xml");
    lt_experiments::commands::convert::run(&lt_experiments::commands::convert::ConvertArgs {
        scene: toml.clone(),
        output: converted.clone(),
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let a = load_scene(&toml).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.media.len(), 2);
    assert!(a.camera_medium.is_some() && a.light_media == [a.camera_medium]);
    for (what, xml) in [("the XML twin", &twin), ("the converted XML", &converted)] {
        let (b, _) =
            load_scene_with(xml, &LoadOptions::default()).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_same(what, &a, &b);
        assert_eq!(a.media, b.media, "{what}: media");
        assert_eq!(a.interfaces, b.interfaces, "{what}: interfaces");
        assert_eq!(
            (a.camera_medium, &a.light_media),
            (b.camera_medium, &b.light_media),
            "{what}: camera and light media"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
