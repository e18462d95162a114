//! The twins of SmallVCM's four `--report` scenes (`scenes/smallvcm-*.toml`) keep SmallVCM's
//! numbers (its src/scene.hxx, `LoadCornellBox`): camera, box, balls and lights; and no camera ray
//! sees a back face, where SmallVCM's one-sided surfaces and our two-sided ones would differ.

use lt_core::bsdf::Material;
use lt_core::light::Light;
use lt_core::math::{Color, Vec3, PI};
use lt_core::scene::ShapeGeometry;
use lt_core::Scene;
use lt_scene_io::load_scene;
use std::path::PathBuf;

fn load(name: &str) -> Scene {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes"))
        .join(format!("{name}.toml"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

/// Normal of the first triangle of a mesh shape (quads: the quad's normal).
fn mesh_normal(s: &Scene, shape: u32) -> Vec3 {
    let ShapeGeometry::Mesh(m) = &s.shapes[shape as usize].geometry else {
        panic!("shape {shape} is not a mesh")
    };
    let [a, b, c] = m.triangle(0);
    (b - a).cross(c - a).normalize()
}

fn mesh_center(s: &Scene, shape: u32) -> Vec3 {
    let ShapeGeometry::Mesh(m) = &s.shapes[shape as usize].geometry else {
        panic!("shape {shape} is not a mesh")
    };
    m.positions.iter().copied().sum::<Vec3>() / m.positions.len() as f32
}

/// The twins of SmallVCM's `--report` scenes (its src/scene.hxx, `LoadCornellBox`).
const SMALLVCM_TWINS: [&str; 4] = [
    "smallvcm-spheres-sun",
    "smallvcm-mirror-ball",
    "smallvcm-spheres-point",
    "smallvcm-spheres-background",
];

fn spheres(s: &Scene) -> Vec<(Vec3, f32, &Material)> {
    s.shapes
        .iter()
        .filter_map(|sh| match sh.geometry {
            ShapeGeometry::Sphere { center, radius } => {
                Some((center, radius, s.material(sh.material)))
            }
            _ => None,
        })
        .collect()
}

#[test]
fn smallvcm_twins_have_smallvcms_camera_box_and_balls() {
    for name in SMALLVCM_TWINS {
        let s = load(name);
        assert!((s.camera.eye - Vec3::new(-0.0439815, -4.12529, 0.222539)).length() < 1e-6);
        let forward = Vec3::new(0.00688625, 0.998505, -0.0542161).normalize();
        assert!((s.camera.forward() - forward).length() < 1e-5, "{name}");
        // SmallVCM's image right is forward x up = +x: its green wall (x = -1.27) on the left.
        let green = s.camera.project(Vec3::new(-1.2, 0.5, 0.0)).unwrap().raster;
        let red = s.camera.project(Vec3::new(1.2, 0.5, 0.0)).unwrap().raster;
        assert!(green.x < 256.0 && red.x > 256.0, "{name}: {green} {red}");
        // SmallVCM's diffuse and Phong surfaces are one-sided (black from behind), ours are
        // two-sided: that changes nothing as long as no camera ray sees a back face.
        for i in 0..64 {
            for j in 0..64 {
                let raster = lt_core::Vec2::new(4.0 + 8.0 * i as f32, 4.0 + 8.0 * j as f32);
                let ray = s.camera.generate_ray(raster);
                let hit = s
                    .intersect(&ray)
                    .unwrap_or_else(|| panic!("{name}: the camera sees past the box at {raster}"));
                if !matches!(s.material(hit.material), Material::Dielectric(_)) {
                    assert!(
                        hit.ng.dot(ray.d) < 0.0,
                        "{name}: back face seen at {raster}"
                    );
                }
            }
        }
        let balls = spheres(&s);
        if name == "smallvcm-mirror-ball" {
            assert_eq!(balls.len(), 1);
            let (c, r, m) = balls[0];
            assert!((c - Vec3::new(0.00973, 0.02453, -0.48002)).length() < 1e-5);
            assert_eq!(r, 0.8);
            assert!(matches!(m, Material::Mirror(_)));
        } else {
            assert_eq!(balls.len(), 2, "{name}");
            for (c, r, m) in balls {
                assert_eq!(r, 0.5);
                assert!((c.y - 0.02453).abs() < 1e-5 && (c.z + 0.78002).abs() < 1e-5);
                match m {
                    Material::Mirror(_) => assert!((c.x + 0.53885).abs() < 1e-5),
                    Material::Dielectric(d) => {
                        assert_eq!(d.ior, 1.6);
                        assert!((c.x - 0.55831).abs() < 1e-5);
                    }
                    _ => panic!("{name}: a ball that is neither mirror nor glass"),
                }
            }
        }
    }
}

#[test]
fn smallvcm_twins_have_smallvcms_lights() {
    let s = load("smallvcm-mirror-ball");
    assert_eq!(s.lights.len(), 1);
    let Light::Area(l) = &s.lights[0] else {
        panic!("the light is not the light box's bottom")
    };
    assert!(close(l.area, 0.25, 1e-5), "area {}", l.area);
    assert_eq!(l.emission, Color::splat(25.033298));
    assert!((mesh_normal(&s, l.shape) - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
    assert!((mesh_center(&s, l.shape) - Vec3::new(0.0, 0.0, 1.26002)).length() < 1e-6);
    let Material::Diffuse(d) = s.material(s.shapes[l.shape as usize].material) else {
        panic!()
    };
    assert_eq!(d.albedo, Color::ZERO, "SmallVCM's emitters reflect nothing");

    let s = load("smallvcm-spheres-point");
    assert_eq!(s.lights.len(), 1);
    let Light::Point(p) = &s.lights[0] else {
        panic!("not a point light")
    };
    assert_eq!(p.position, Vec3::new(0.0, -0.5, 1.0));
    assert!(close(p.intensity.x * 4.0 * PI, 70.0, 1e-6), "70 W");
    assert_eq!(s.shapes.len(), 7, "five walls and two balls: no light box");

    let s = load("smallvcm-spheres-sun");
    assert_eq!(s.lights.len(), 1);
    let Light::Directional(d) = &s.lights[0] else {
        panic!("not a directional light")
    };
    // SmallVCM's DirectionalLight(-1, 1.5, -1) is the direction light travels; ours points back.
    assert!((d.direction - Vec3::new(1.0, -1.5, 1.0).normalize()).length() < 1e-6);
    assert_eq!(
        d.irradiance,
        Color::new(10.0, 4.0, 0.0),
        "(0.5, 0.2, 0) x 20"
    );
    assert_eq!(
        s.shapes.len(),
        12,
        "five walls, five light-box faces, two balls"
    );
    assert!(s.shapes.iter().all(|sh| sh.light.is_none()), "no emitter");

    let s = load("smallvcm-spheres-background");
    assert_eq!(s.lights.len(), 1);
    let Light::Environment(e) = &s.lights[0] else {
        panic!("not an environment")
    };
    let sky = Color::new(135.0, 206.0, 250.0) / 255.0;
    assert!((e.radiance - sky).length() < 1e-6);
    assert_eq!(
        s.shapes.len(),
        12,
        "five walls, five light-box faces, two balls"
    );
}
