//! `scenes/xml/cornell-box.xml` (Mitsuba 3's `cornell_box()` written by hand as XML, each
//! to_world as the translate/rotate/scale steps cornell_box() composes) is the scene
//! `scenes/cornell-box.toml` holds as Mitsuba's f32 matrices: the same primitives, materials,
//! lights, settings and camera rays within f32 rounding, and the same image within standard
//! errors.
//!
//! Float tolerance: the TOML's matrices are Mitsuba's, built in f32 (cos 90° = −4.37e-8, sines
//! and cosines of 17° and 18.25° rounded once per entry); the XML's are composed in f64 with exact
//! quarter turns and rounded once. Each matrix entry therefore differs by at most an f32 rounding
//! of a number ≤ 1 plus Mitsuba's −4.37e-8 residue, and a vertex (three products and a
//! translation, coordinates ≤ 1) by at most 8 · 2⁻²⁴ ≈ 4.8e-7 — the bound held here.

use lt_core::light::Light;
use lt_core::scene::ShapeGeometry;
use lt_core::Scene;
use lt_estimators::agreement::agreement_t;
use lt_integrators::IntegratorParams;
use lt_scene_io::{load_scene, load_scene_with, LoadOptions};
use lt_tests::{render_blocks, scenes_dir};
use std::path::PathBuf;

const VERTEX_TOLERANCE: f32 = 8.0 / (1u32 << 24) as f32;

fn xml_path() -> PathBuf {
    scenes_dir().join("xml/cornell-box.xml")
}

fn load(path: &std::path::Path) -> Scene {
    load_scene(path).unwrap_or_else(|e| panic!("{e}"))
}

/// Largest coordinate difference between the two scenes' shapes (asserting that everything
/// else about them is identical).
fn max_vertex_difference(a: &Scene, b: &Scene) -> f32 {
    assert_eq!(a.shapes.len(), b.shapes.len());
    assert_eq!(a.primitive_count(), b.primitive_count());
    let mut worst = 0.0f32;
    for (i, (sa, sb)) in a.shapes.iter().zip(&b.shapes).enumerate() {
        // Mitsuba's `diffuse` is one-sided (lt's FrontDiffuse), the TOML's two-sided: the same
        // BSDF on the walls' fronts, the side the camera and light see (the images are compared
        // in `xml_cornell_box_renders_the_toml_image`).
        let one_sided = |m: &lt_core::bsdf::Material| {
            format!("{m:?}").replace("FrontDiffuse(FrontDiffuse", "Diffuse(Diffuse")
        };
        assert_eq!(
            one_sided(a.material(sa.material)),
            one_sided(b.material(sb.material)),
            "shape {i}: material"
        );
        assert_eq!(sa.light.is_some(), sb.light.is_some(), "shape {i}: emits");
        assert_eq!(sa.flip_normals, sb.flip_normals, "shape {i}");
        match (&sa.geometry, &sb.geometry) {
            (ShapeGeometry::Mesh(ma), ShapeGeometry::Mesh(mb)) => {
                assert_eq!(ma.indices, mb.indices, "shape {i}: triangles");
                assert_eq!(ma.normals.is_some(), mb.normals.is_some(), "shape {i}");
                for (p, q) in ma.positions.iter().zip(&mb.positions) {
                    worst = worst.max((*p - *q).abs().max_element());
                }
            }
            (ShapeGeometry::Sphere { .. }, ShapeGeometry::Sphere { .. }) => {
                unreachable!("the Cornell box has no spheres")
            }
            _ => panic!("shape {i}: different kinds of geometry"),
        }
    }
    worst
}

#[test]
fn xml_cornell_box_is_the_toml_scene() {
    let toml = load(&scenes_dir().join("cornell-box.toml"));
    let (xml, report) = load_scene_with(&xml_path(), &LoadOptions::default()).unwrap();
    assert!(report.substitutions.is_empty(), "{report:?}");
    assert_eq!(toml.settings, xml.settings);
    assert_eq!(toml.origin, xml.origin);
    // The one light: same shape, radiance and (within the vertex tolerance) area; its sampling
    // pieces are the light's mesh, compared with the geometry below.
    assert_eq!(toml.lights.len(), 1);
    assert_eq!(xml.lights.len(), 1);
    let (Light::Area(la), Light::Area(lb)) = (&toml.lights[0], &xml.lights[0]) else {
        panic!("the Cornell box's light is an area light")
    };
    assert_eq!((la.shape, la.emission), (lb.shape, lb.emission));
    assert!((la.area - lb.area).abs() <= 4.0 * VERTEX_TOLERANCE * la.area.sqrt());
    let worst = max_vertex_difference(&toml, &xml);
    eprintln!("largest vertex difference {worst:.3e} (bound {VERTEX_TOLERANCE:.3e})");
    assert!(worst <= VERTEX_TOLERANCE, "vertices differ by {worst}");
    // The camera: the same rays (both are the same look-at, so exactly the same).
    let (ca, cb) = (&toml.camera, &xml.camera);
    assert_eq!((ca.width, ca.height), (cb.width, cb.height));
    for j in 0..=8 {
        for i in 0..=8 {
            let r = lt_core::math::Vec2::new(32.0 * i as f32, 32.0 * j as f32);
            let (ra, rb) = (ca.generate_ray(r), cb.generate_ray(r));
            assert_eq!(ra.o, rb.o);
            assert!(
                (ra.d - rb.d).abs().max_element() <= 2.0 * f32::EPSILON,
                "{r}"
            );
        }
    }
    assert_eq!(xml.source_files, vec![xml_path()]);
}

/// The two files render the same image: pt on each, independent seeds, 8×8-pixel blocks at
/// 64×64, two-sample z per block and channel, Šidák-corrected to a 1e-3 false-alarm rate over
/// all of them. A control with the red wall's reflectance 10 % lower must fail the same test, so
/// the test can see a difference of that size.
#[test]
fn xml_cornell_box_renders_the_toml_image() {
    let small = |mut s: Scene| {
        s.camera = s.camera.with_resolution(64, 64);
        s
    };
    let toml = small(load(&scenes_dir().join("cornell-box.toml")));
    let xml = small(load(&xml_path()));
    let passes = 256;
    let (r1, a) = render_blocks(&toml, "pt", IntegratorParams::default(), passes, 21, 8);
    let (r2, b) = render_blocks(&xml, "pt", IntegratorParams::default(), passes, 22, 8);
    assert_eq!(r1.invalid_samples + r2.invalid_samples, 0);
    let same = agreement_t(&a, &b, 1e-3);
    eprintln!("toml vs xml: {same}");
    assert!(same.passed(), "toml vs xml: {same}");

    let text = std::fs::read_to_string(xml_path()).unwrap();
    let darker = text.replace(
        "0.570068, 0.0430135, 0.0443706",
        "0.5130612, 0.03871215, 0.03993354",
    );
    assert_ne!(darker, text);
    let dir = std::env::temp_dir().join(format!("lt-xml-cornell-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let control_path = dir.join("darker-red.xml");
    std::fs::write(&control_path, darker).unwrap();
    let control = small(load(&control_path));
    let (_, c) = render_blocks(&control, "pt", IntegratorParams::default(), passes, 22, 8);
    let differ = agreement_t(&a, &c, 1e-3);
    eprintln!("toml vs xml with a 10 % darker red wall: {differ}");
    assert!(!differ.passed(), "the control should fail: {differ}");
    let _ = std::fs::remove_dir_all(&dir);
}
