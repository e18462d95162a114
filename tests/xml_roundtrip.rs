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
