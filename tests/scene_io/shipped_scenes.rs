//! Every scene in `scenes/` loads, and each is what its comments say it is.

use lt_core::bsdf::Material;
use lt_core::geometry::quad::Parallelogram;
use lt_core::geometry::Ray;
use lt_core::light::{Light, SunLight};
use lt_core::math::{Color, Vec3, PI};
use lt_core::scene::{ShapeGeometry, SurfaceHit};
use lt_core::Scene;
use lt_scene_io::load_scene;
use std::path::PathBuf;

const SCENES: [&str; 11] = [
    "cornell-box",
    "cornell-small-light",
    "cornell-glass-light",
    "cornell-point-caustic",
    "cornell-mesh-light",
    "cornell-env",
    "sun-room",
    "caustic-sds",
    "veach-mis",
    "veach-door",
    "cornell-directional",
];

fn scenes_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes"))
}

fn load(name: &str) -> Scene {
    let path = scenes_dir().join(format!("{name}.toml"));
    load_scene(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Σ over area lights of area × emission: the emitted power is π times this.
fn area_times_emission(s: &Scene) -> Color {
    s.lights
        .iter()
        .filter_map(|l| {
            if let Light::Area(a) = l {
                Some(a.area * a.emission)
            } else {
                None
            }
        })
        .sum()
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

/// Directions over the whole sphere (a Fibonacci lattice), for watertightness checks.
fn sphere_directions(n: usize) -> impl Iterator<Item = Vec3> {
    let golden = PI * (3.0 - 5f32.sqrt());
    (0..n).map(move |i| {
        let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

#[test]
fn every_scene_loads() {
    let mut found: Vec<String> = std::fs::read_dir(scenes_dir())
        .unwrap()
        .filter_map(|e| {
            e.ok()?
                .path()
                .file_name()?
                .to_str()?
                .strip_suffix(".toml")
                .map(str::to_string)
        })
        .collect();
    found.sort();
    for name in SCENES {
        assert!(
            found.iter().any(|f| f == name),
            "scenes/{name}.toml is missing"
        );
    }
    for name in &found {
        let s = load(name);
        assert!(!s.lights.is_empty(), "{name} has no light");
        if name.starts_with("smallvcm-") {
            // SmallVCM's own defaults: 512², path length 10 (segments, as our max_depth).
            assert_eq!((s.camera.width, s.camera.height), (512, 512), "{name}");
            assert_eq!(s.settings.max_depth, 10, "{name}");
        } else if name == "point-plane" || name == "point-plane-pinhole" {
            // One plane under a point light: every path is light → plane → camera, so the
            // radius-shrinkage study's exact answer holds at any depth; 2 says so.
            assert_eq!(s.settings.max_depth, 2, "{name}");
        } else {
            assert!(
                s.camera.width <= 256 && s.camera.height <= 256,
                "{name} is larger than 256²"
            );
            assert_eq!(s.settings.max_depth, 8, "{name}");
        }
    }
}

#[test]
fn area_lights_face_the_scene() {
    for name in SCENES {
        let s = load(name);
        let center = s.bounding_sphere.0;
        for l in &s.lights {
            if let Light::Area(a) = l {
                if let ShapeGeometry::Mesh(_) = s.shapes[a.shape as usize].geometry {
                    let n = mesh_normal(&s, a.shape);
                    assert!(
                        n.dot(center - mesh_center(&s, a.shape)) > 0.0,
                        "{name}: light {} faces away from the scene",
                        a.shape
                    );
                }
            }
        }
    }
}

#[test]
fn cornell_box_has_mitsubas_numbers() {
    let s = load("cornell-box");
    assert_eq!(s.shapes.len(), 8);
    assert_eq!(s.lights.len(), 1);
    let Light::Area(light) = &s.lights[0] else {
        panic!("the light is not an area light")
    };
    // to_world columns of the light rectangle: 0.23 x and 0.19 along z, so 0.46 x 0.38.
    assert!(
        close(light.area, 0.46 * 0.38, 1e-6),
        "light area {}",
        light.area
    );
    assert_eq!(light.emission, Vec3::new(18.387, 13.9873, 6.75357));
    let n = mesh_normal(&s, light.shape);
    assert!(
        (n - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6,
        "light normal {n}"
    );
    assert!((mesh_center(&s, light.shape) - Vec3::new(0.0, 0.99, 0.01)).length() < 1e-6);
    assert!((s.camera.eye - Vec3::new(0.0, 0.0, 3.9)).length() < 1e-6);
    assert!((s.camera.forward() - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
    assert_eq!((s.camera.width, s.camera.height), (256, 256));
    let Material::Diffuse(white) = s.material(s.shapes[light.shape as usize].material) else {
        panic!("the light is not white diffuse")
    };
    assert_eq!(white.albedo, Vec3::new(0.885809, 0.698859, 0.666422));
    // The red wall (x = -1) is on the image's left, the green one on its right.
    let red = s.camera.project(Vec3::new(-0.99, 0.0, 0.0)).unwrap().raster;
    let green = s.camera.project(Vec3::new(0.99, 0.0, 0.0)).unwrap().raster;
    assert!(
        red.x < 128.0 && green.x > 128.0,
        "red at {red}, green at {green}"
    );
    let red_hit = s
        .intersect(&s.camera.generate_ray(lt_core::Vec2::new(5.5, 128.5)))
        .unwrap();
    let Material::Diffuse(d) = s.material(red_hit.material) else {
        panic!()
    };
    assert_eq!(
        d.albedo,
        Vec3::new(0.570068, 0.0430135, 0.0443706),
        "the left edge shows the red wall"
    );
}

#[test]
fn cornell_small_light_has_the_same_power() {
    let big = load("cornell-box");
    let small = load("cornell-small-light");
    let (pb, ps) = (area_times_emission(&big), area_times_emission(&small));
    for k in 0..3 {
        assert!(close(pb[k], ps[k], 1e-5), "{pb} vs {ps}");
    }
    let Light::Area(l) = &small.lights[0] else {
        panic!()
    };
    assert!(close(l.area, 0.46 * 0.38 / 25.0, 1e-5));
}

#[test]
fn cornell_glass_light_is_a_sphere_in_a_glass_shell() {
    let s = load("cornell-glass-light");
    assert_eq!(s.lights.len(), 1, "the sphere is the only light");
    let Light::Area(l) = &s.lights[0] else {
        panic!()
    };
    let ShapeGeometry::Sphere { center, radius } = s.shapes[l.shape as usize].geometry else {
        panic!("the light is not a sphere")
    };
    let shells: Vec<_> = s
        .shapes
        .iter()
        .filter(|sh| matches!(s.material(sh.material), Material::Dielectric(d) if d.ior == 1.5))
        .map(|sh| match sh.geometry {
            ShapeGeometry::Sphere {
                center: c,
                radius: r,
            } => (c, r, sh.flip_normals),
            _ => panic!("glass that is not a sphere"),
        })
        .collect();
    assert_eq!(shells.len(), 2);
    for &(c, r, flipped) in &shells {
        assert_eq!(c, center, "the shell is concentric with the light");
        assert!(r > radius);
        assert_eq!(flipped, r < 0.2, "only the inner surface is flipped");
    }
    // Same emitted power as cornell-box (within the rounding of the radiance in the file).
    let (pg, pb) = (
        area_times_emission(&s),
        area_times_emission(&load("cornell-box")),
    );
    for k in 0..3 {
        assert!(close(pg[k], pb[k], 1e-4), "{pg} vs {pb}");
    }
}

#[test]
fn sun_room_is_lit_by_the_sun_alone() {
    let s = load("sun-room");
    assert_eq!(s.lights.len(), 1);
    let Light::Sun(sun) = &s.lights[0] else {
        panic!("the light is not a sun")
    };
    assert_eq!(sun.solid_angle, 6.87e-5);
    let expect = SunLight::radiance_from_irradiance(Color::new(5.0, 4.7, 4.2), 6.87e-5);
    assert!((sun.radiance - expect).length() <= 1e-6 * expect.length());
    assert!(
        s.shapes.iter().all(|sh| sh.light.is_none()),
        "no emissive shapes"
    );
    // The sunlit patch on the floor is in view and lit: sun -> window -> floor.
    let patch = Vec3::new(0.8, 0.0, -0.45);
    assert!(s.camera.project(patch).is_some());
    assert!(s.visible_between(s.camera.eye, patch + Vec3::new(0.0, 1e-3, 0.0)));
    let to_sun = patch + sun.direction * 10.0;
    assert!(
        s.visible_between(patch + Vec3::new(0.0, 1e-3, 0.0), to_sun),
        "the patch sees the sun"
    );
}

#[test]
fn sun_room_is_closed_but_for_the_window() {
    let s = load("sun-room");
    let middle = Vec3::new(0.0, 1.25, 0.0);
    for (i, _) in s.shapes.iter().enumerate() {
        let i = i as u32;
        assert!(
            mesh_normal(&s, i).dot(middle - mesh_center(&s, i)) > 0.0,
            "wall {i} faces out of the room"
        );
    }
    for eye in [
        s.camera.eye,
        Vec3::new(0.0, 1.25, 0.0),
        Vec3::new(1.9, 0.1, 2.9),
    ] {
        for d in sphere_directions(20000) {
            if s.intersect(&Ray::new(eye, d)).is_some() {
                continue;
            }
            // An escaping ray must leave through the window: x = 2, y 1..2, z -0.75..0.75.
            assert!(d.x > 0.0, "ray {d} from {eye} escapes through a crack");
            let p = eye + d * ((2.0 - eye.x) / d.x);
            assert!(
                (1.0..=2.0).contains(&p.y) && (-0.75..=0.75).contains(&p.z),
                "ray {d} from {eye} escapes at {p}"
            );
        }
    }
}

#[test]
fn cornell_directional_is_lit_by_one_directional_light_through_the_skylight() {
    let s = load("cornell-directional");
    assert_eq!(s.lights.len(), 1);
    let Light::Directional(d) = &s.lights[0] else {
        panic!("the light is not directional: {:?}", s.lights[0])
    };
    assert!((d.direction - Vec3::new(0.5, 1.0, -0.1).normalize()).length() < 1e-6);
    assert_eq!(d.irradiance, Color::new(10.0, 9.0, 7.5));
    assert!(
        s.shapes.iter().all(|sh| sh.light.is_none()),
        "no emissive shapes"
    );
    // Lit through the skylight and in view: the red wall (x = -1, normal +x), the floor beside
    // it and the large box's right face; shaded by the large box: the floor behind it.
    let lit = |p: Vec3, n: Vec3| {
        let q = p + n * 1e-3;
        s.visible_between(q, q + d.direction * 10.0)
    };
    let seen = |p: Vec3, n: Vec3| {
        s.camera.project(p).is_some() && s.visible_between(s.camera.eye, p + n * 1e-3)
    };
    for (p, n) in [
        (Vec3::new(-1.0, -0.5, 0.2), Vec3::X),
        (Vec3::new(-0.8, -1.0, 0.5), Vec3::Y),
    ] {
        assert!(lit(p, n) && seen(p, n), "{p} should be sunlit and in view");
    }
    assert!(
        !lit(Vec3::new(-0.9, -1.0, -0.6), Vec3::Y),
        "behind the large box"
    );
    assert!(!lit(Vec3::new(0.6, -1.0, 0.0), Vec3::Y), "outside the beam");
    // Closed but for the skylight (x, z in -0.5..0.5 at y = 1) and the open front (z = 1).
    for eye in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.9, -0.9, -0.9)] {
        for dir in sphere_directions(20000) {
            if s.intersect(&Ray::new(eye, dir)).is_some() {
                continue;
            }
            let through = |t: f32| eye + dir * t;
            let sky = dir.y > 0.0 && {
                let p = through((1.0 - eye.y) / dir.y);
                p.x.abs() <= 0.5 && p.z.abs() <= 0.5
            };
            let front = dir.z > 0.0 && {
                let p = through((1.0 - eye.z) / dir.z);
                p.x.abs() <= 1.0 && p.y.abs() <= 1.0
            };
            assert!(sky || front, "ray {dir} from {eye} escapes through a crack");
        }
    }
}

#[test]
fn caustic_is_seen_only_in_the_mirror() {
    let s = load("caustic-sds");
    let caustic = Vec3::new(0.8, 0.0, 0.0);
    assert!(
        s.camera.project(caustic).is_none(),
        "the caustic must be out of the direct view"
    );
    // Through the mirror (z = -2.5) its image is at z = -5: the camera ray there hits the mirror,
    // and the reflected ray reaches the caustic unobstructed.
    let image = Vec3::new(caustic.x, caustic.y, -5.0 - caustic.z);
    assert!(
        s.camera.project(image).is_some(),
        "the caustic's mirror image is in frame"
    );
    let d = (image - s.camera.eye).normalize();
    let hit = s
        .intersect(&Ray::new(s.camera.eye, d))
        .expect("the camera ray hits the mirror");
    assert!(matches!(s.material(hit.material), Material::Mirror(_)));
    assert!((hit.p.z + 2.5).abs() < 1e-4);
    assert!(s.visible_between(
        hit.p + Vec3::new(0.0, 0.0, 1e-3),
        caustic + Vec3::new(0.0, 1e-3, 0.0)
    ));
    let glass = s
        .shapes
        .iter()
        .filter(|sh| matches!(s.material(sh.material), Material::Dielectric(_)))
        .count();
    assert_eq!(glass, 1);
}

#[test]
fn veach_mis_lights_have_equal_power() {
    let s = load("veach-mis");
    let mut radii = Vec::new();
    for l in &s.lights {
        let Light::Area(a) = l else { panic!() };
        let ShapeGeometry::Sphere { center, radius } = s.shapes[a.shape as usize].geometry else {
            panic!()
        };
        if center.y == 0.0 {
            radii.push(radius);
            assert!(
                close(a.emission.x * radius * radius, 1.0, 2e-4),
                "L r² = {}",
                a.emission.x * radius * radius
            );
            assert!(
                s.camera.project(center).is_some(),
                "light at {center} is out of frame"
            );
        }
    }
    assert_eq!(radii, vec![0.0333, 0.1, 0.3, 0.9]);
    let rough: Vec<f32> = s
        .materials
        .iter()
        .filter_map(|m| {
            if let Material::Glossy(g) = m {
                Some(g.roughness)
            } else {
                None
            }
        })
        .collect();
    assert_eq!(rough.len(), 4);
}

#[test]
fn veach_door_light_reaches_the_dark_room_only_by_bouncing() {
    let s = load("veach-door");
    assert_eq!(s.lights.len(), 1);
    let Light::Area(lamp) = &s.lights[0] else {
        panic!()
    };
    let lc = mesh_center(&s, lamp.shape);
    assert!(lc.x > 0.0, "the lamp is in the far room");
    assert!(s.camera.eye.x < 0.0, "the camera is in the dark room");
    // Closed: every ray from the camera hits something.
    for d in sphere_directions(20000) {
        assert!(
            s.intersect(&Ray::new(s.camera.eye, d)).is_some(),
            "ray {d} escapes"
        );
    }
    // No straight line joins the lamp to the dark room, but the door is open (the far room's
    // walls are visible from the dark room through the gap).
    let mut through_gap = 0;
    for i in 0..9 {
        for j in 0..9 {
            let l = lc + Vec3::new(-0.45 + 0.1125 * i as f32, -0.01, -0.45 + 0.1125 * j as f32);
            for x in [-3.9f32, -3.0, -2.0, -1.0, -0.2] {
                for y in [0.05f32, 0.5, 1.0, 1.5, 2.0, 2.45] {
                    for z in [-2.4f32, -1.5, -0.5, 0.3, 0.6, 1.0, 1.5, 2.4] {
                        assert!(
                            !s.visible_between(l, Vec3::new(x, y, z)),
                            "lamp point {l} sees ({x}, {y}, {z})"
                        );
                    }
                }
            }
        }
    }
    // The gap opens sideways (the door's free edge is in the dark room), so it joins the far
    // room's north side (z > 0.5) to the dark room's south side (z < 0.5).
    for i in 0..40 {
        for j in 0..40 {
            let a = Vec3::new(-3.9 + 0.085 * i as f32, 1.0, -2.4);
            let b = Vec3::new(0.5 + 0.085 * j as f32, 1.0, 2.4);
            through_gap += s.visible_between(a, b) as usize;
        }
    }
    assert!(through_gap > 0, "no line of sight through the door gap");
}

/// Snell refraction of the unit direction `d` at a surface whose unit normal `n` faces against
/// `d`; `eta` = ior of the side `d` comes from / ior of the other side. None on total reflection.
fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    (k >= 0.0).then(|| (eta * d + (eta * cos_i - k.sqrt()) * n).normalize())
}

/// Follows a ray through every dielectric it meets (refraction only, no reflection) to the first
/// non-dielectric surface.
fn trace_through_glass(s: &Scene, origin: Vec3, mut d: Vec3) -> Option<SurfaceHit> {
    let mut hit = s.intersect(&Ray::new(origin, d))?;
    for _ in 0..8 {
        let Material::Dielectric(glass) = s.material(hit.material) else {
            return Some(hit);
        };
        let entering = d.dot(hit.ng) < 0.0;
        let (n, eta) = if entering {
            (hit.ng, 1.0 / glass.ior)
        } else {
            (-hit.ng, glass.ior)
        };
        d = refract(d, n, eta)?;
        hit = s.intersect(&hit.spawn_ray(d))?;
    }
    None
}

#[test]
fn cornell_point_caustic_focuses_the_point_light_onto_the_floor_in_view() {
    let s = load("cornell-point-caustic");
    assert_eq!(s.lights.len(), 1);
    let Light::Point(light) = &s.lights[0] else {
        panic!("the light is not a point light")
    };
    assert!(
        s.shapes.iter().all(|sh| sh.light.is_none()),
        "no emissive shapes"
    );
    // Power 4 pi I = cornell-box's light power pi A L.
    let pb = PI * area_times_emission(&load("cornell-box"));
    let pp = 4.0 * PI * light.intensity;
    for k in 0..3 {
        assert!(close(pp[k], pb[k], 1e-5), "{pp} vs {pb}");
    }
    let glass: Vec<(Vec3, f32)> = s
        .shapes
        .iter()
        .filter(|sh| matches!(s.material(sh.material), Material::Dielectric(d) if d.ior == 1.5))
        .map(|sh| match sh.geometry {
            ShapeGeometry::Sphere { center, radius } => (center, radius),
            _ => panic!("glass that is not a sphere"),
        })
        .collect();
    assert_eq!(glass.len(), 1, "one glass ball");
    let (c, r) = glass[0];
    assert!(
        light.position.y < 1.0 && light.position.y > c.y + r,
        "the light is above the ball"
    );
    // The ray through the ball's centre goes straight on and lands on the floor, in view.
    let axis = (c - light.position).normalize();
    let focus = trace_through_glass(&s, light.position, axis)
        .expect("the axial ray reaches a surface")
        .p;
    assert!(
        (focus.y + 1.0).abs() < 1e-4,
        "the axial ray lands at {focus}, not on the floor"
    );
    let lift = Vec3::new(0.0, 1e-3, 0.0);
    for dx in [-0.1f32, 0.0, 0.1] {
        for dz in [-0.1f32, 0.0, 0.1] {
            let p = focus + Vec3::new(dx, 0.0, dz);
            let proj = s.camera.project(p).expect("the caustic is in frame");
            assert!(
                (0.0..s.camera.width as f32).contains(&proj.raster.x)
                    && (0.0..s.camera.height as f32).contains(&proj.raster.y)
            );
            assert!(
                s.visible_between(s.camera.eye, p + lift),
                "the camera does not see the caustic at {p}"
            );
        }
    }
    // Rays from the light spread uniformly over the cone towards the ball: most land within 0.1
    // of the axis point, a disk 1/13 of the area of the ball's shadow (radius ~0.36).
    let cos_max = (1.0 - r * r / (c - light.position).length_squared()).sqrt();
    let frame = lt_core::math::Frame::from_z(axis);
    let (mut near, mut total) = (0usize, 0usize);
    for i in 0..64 {
        for j in 0..64 {
            let cos_t = 1.0 - (1.0 - cos_max) * (i as f32 + 0.5) / 64.0 * 0.95;
            let sin_t = (1.0 - cos_t * cos_t).sqrt();
            let phi = 2.0 * PI * (j as f32 + 0.5) / 64.0;
            let d = frame.to_world(Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t));
            let Some(hit) = trace_through_glass(&s, light.position, d) else {
                continue;
            };
            total += 1;
            near += ((hit.p - focus).length() < 0.1) as usize;
        }
    }
    assert_eq!(
        total,
        64 * 64,
        "every ray through the ball reaches a surface"
    );
    assert!(
        near as f32 > 0.4 * total as f32,
        "only {near} of {total} rays land near {focus}"
    );
    // The light sees most of the floor; the ball shadows the caustic's surroundings.
    let mut lit = 0;
    let n = 39;
    for i in 0..n {
        for j in 0..n {
            let p = Vec3::new(
                -0.95 + 1.9 * i as f32 / (n - 1) as f32,
                -1.0,
                -0.95 + 1.9 * j as f32 / (n - 1) as f32,
            );
            let seen = s.visible_between(light.position, p + lift);
            lit += seen as usize;
            if (p - focus).length() < 0.25 {
                assert!(!seen, "{p} is in the ball's shadow, but the light sees it");
            }
        }
    }
    assert!(
        lit as f32 > 0.6 * (n * n) as f32,
        "the light sees only {lit} of {} floor points",
        n * n
    );
}

#[test]
fn cornell_mesh_light_is_an_unmerged_triangle_fan_with_cornell_box_power() {
    let s = load("cornell-mesh-light");
    let base = load("cornell-box");
    assert_eq!(s.lights.len(), 1);
    let Light::Area(light) = &s.lights[0] else {
        panic!("the light is not an area light")
    };
    let ShapeGeometry::Mesh(m) = &s.shapes[light.shape as usize].geometry else {
        panic!("the light is not a mesh")
    };
    assert_eq!(m.indices.len(), 8, "an octagonal fan of 8 triangles");
    for i in 0..8 {
        let [a, b, c] = m.triangle(i);
        let n = (b - a).cross(c - a).normalize();
        assert!(
            (n - Vec3::new(0.0, -1.0, 0.0)).length() < 1e-6,
            "triangle {i} normal {n}"
        );
        assert!([a, b, c].iter().all(|p| (p.y - 0.99).abs() < 1e-6));
    }
    // No two consecutive triangles split a parallelogram, so the builder keeps all 8 (cornell-box
    // has the same shapes with a one-quad light).
    for i in 0..7 {
        assert!(
            Parallelogram::from_triangle_pair(m.triangle(i), m.triangle(i + 1)).is_none(),
            "triangles {i} and {} form a parallelogram",
            i + 1
        );
    }
    assert_eq!(s.primitive_count(), base.primitive_count() - 1 + 8);
    assert!(
        close(light.area, 0.21875, 1e-6),
        "light area {}",
        light.area
    );
    assert!((mesh_center(&s, light.shape) - Vec3::new(0.0, 0.99, 0.01)).length() < 1e-6);
    let (pm, pb) = (area_times_emission(&s), area_times_emission(&base));
    for k in 0..3 {
        assert!(close(pm[k], pb[k], 1e-5), "{pm} vs {pb}");
    }
}

#[test]
fn cornell_env_is_lit_only_through_the_open_front() {
    let s = load("cornell-env");
    assert_eq!(s.lights.len(), 1);
    let Light::Environment(env) = &s.lights[0] else {
        panic!("the light is not an environment")
    };
    assert_eq!(env.radiance, Vec3::ONE);
    assert_eq!(s.infinite_lights, vec![0]);
    assert!(
        s.shapes.iter().all(|sh| sh.light.is_none()),
        "no emissive shapes"
    );
    assert!(s.camera.eye.z > 1.0, "the camera is in front of the box");
    for eye in [
        Vec3::ZERO,
        Vec3::new(0.5, 0.5, -0.5),
        Vec3::new(-0.5, 0.0, 0.5),
        Vec3::new(0.9, -0.9, -0.9),
    ] {
        assert!(
            s.intersect(&Ray::new(eye, Vec3::new(0.0, 0.0, 1.0)))
                .is_none(),
            "a ray from {eye} towards +z does not escape"
        );
        let mut escaped = 0;
        for d in sphere_directions(20000) {
            if s.intersect(&Ray::new(eye, d)).is_some() {
                continue;
            }
            escaped += 1;
            // An escaping ray leaves through the front: z = 1, x and y in [-1, 1].
            assert!(d.z > 0.0, "ray {d} from {eye} escapes through a crack");
            let p = eye + d * ((1.0 - eye.z) / d.z);
            assert!(
                p.x.abs() <= 1.0 + 1e-5 && p.y.abs() <= 1.0 + 1e-5,
                "ray {d} from {eye} escapes at {p}"
            );
        }
        if eye == Vec3::ZERO {
            // From the centre the opening is one face of the cube: 1/6 of the sphere, less what
            // the small box hides.
            let f = escaped as f32 / 20000.0;
            assert!(f > 0.14 && f < 1.0 / 6.0 + 0.005, "escaping fraction {f}");
        }
    }
}

/// `cornell-rough-glass` hides its thin-glass pane (a delta BSDF) behind the rough slab, so that
/// no camera ray's first hit is a delta surface and light tracing sees every path the camera
/// does (the premise of its per-depth agreement test). Checked on a 4×4 grid per pixel at the
/// full 256² resolution.
#[test]
fn cornell_rough_glass_shows_no_delta_surface_to_the_camera() {
    let s = load("cornell-rough-glass");
    let (mut rough, mut pane) = (0usize, 0usize);
    for py in 0..s.camera.height {
        for px in 0..s.camera.width {
            for k in 0..16 {
                let raster = lt_core::math::Vec2::new(
                    px as f32 + (k % 4) as f32 / 4.0 + 0.125,
                    py as f32 + (k / 4) as f32 / 4.0 + 0.125,
                );
                let Some(hit) = s.intersect(&s.camera.generate_ray(raster)) else {
                    continue;
                };
                let m = s.material(hit.material);
                assert!(
                    !m.is_delta(),
                    "pixel ({px}, {py}) sees a delta surface first: {m:?}"
                );
                rough += matches!(m, Material::RoughDielectric(_)) as usize;
            }
        }
    }
    // The pane is there, and the camera sees it through the slab.
    for sh in &s.shapes {
        pane += matches!(s.material(sh.material), Material::ThinDielectric(_)) as usize;
    }
    assert!(
        rough > 0 && pane == 1,
        "rough glass hits {rough}, panes {pane}"
    );
}
