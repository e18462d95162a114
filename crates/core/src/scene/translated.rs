//! A rigidly translated copy of a scene: the robustness check that results do not depend on where
//! the scene sits in floating-point space (large coordinates leave fewer bits for the geometry).

use super::{LightDesc, Scene, SceneBuilder, ShapeGeometry, TriangleMesh};
use crate::geometry::quadric::Affine;
use crate::light::Light;
use crate::math::Vec3;

impl Scene {
    /// The scene with eye, every shape and every positioned light (point, spot, projector) moved by `offset` in world
    /// coordinates (rounded once to f32 per vertex, as a loader `translate` would), then rebuilt,
    /// so recentred on its own `origin`. Distant lights are unchanged.
    pub fn translated(&self, offset: Vec3) -> Scene {
        // Internal + origin is the world position (exactly, for geometry: see `scene_origin`).
        let moved = |p: Vec3| (p + self.origin) + offset;
        let mut camera = self.camera.clone();
        camera.eye = moved(camera.eye);
        let mut b = SceneBuilder::new(camera, self.settings);
        for m in &self.materials {
            b.add_material(m.clone());
        }
        for s in &self.shapes {
            let geometry = match &s.geometry {
                ShapeGeometry::Mesh(m) => ShapeGeometry::Mesh(TriangleMesh {
                    positions: m.positions.iter().map(|&p| moved(p)).collect(),
                    ..m.clone()
                }),
                &ShapeGeometry::RotatedSphere {
                    center,
                    radius,
                    rotation,
                } => ShapeGeometry::RotatedSphere {
                    center: moved(center),
                    radius,
                    rotation,
                },
                &ShapeGeometry::Sphere { center, radius } => ShapeGeometry::Sphere {
                    center: moved(center),
                    radius,
                },
                &ShapeGeometry::Disk { to_world } => ShapeGeometry::Disk {
                    to_world: Affine::new(to_world.m, moved(to_world.t)),
                },
                &ShapeGeometry::Cylinder { to_world } => ShapeGeometry::Cylinder {
                    to_world: Affine::new(to_world.m, moved(to_world.t)),
                },
                ShapeGeometry::SdfGrid { grid, to_world } => ShapeGeometry::SdfGrid {
                    grid: grid.clone(),
                    to_world: Affine::new(to_world.m, moved(to_world.t)),
                },
            };
            let radiance = s.light.and_then(|l| match &self.lights[l as usize] {
                Light::Area(a) => Some(a.radiance()),
                _ => None,
            });
            b.add_emitting_shape(geometry, s.material, radiance, s.flip_normals);
        }
        // Area lights come first (one per emitting shape, as the builder makes them); the rest
        // are re-described so the builder orders them the same way.
        for l in &self.lights {
            match l {
                Light::Area(_) => {}
                Light::Point(p) => b.add_light(LightDesc::Point {
                    position: moved(p.position),
                    intensity: p.intensity,
                }),
                Light::Spot(l) => b.add_light(LightDesc::Spot {
                    position: moved(l.position),
                    to_world: l.to_world,
                    intensity: l.intensity,
                    texture: l.texture.clone(),
                    cutoff: l.cutoff,
                    beam_width: l.beam_width,
                }),
                Light::Projector(l) => b.add_light(LightDesc::Projector {
                    position: moved(l.position),
                    to_world: l.to_world,
                    irradiance: l.irradiance.clone(),
                    scale: l.scale,
                    tan_half: l.tan_half,
                }),
                Light::Sun(s) => b.add_light(LightDesc::Sun {
                    direction: s.direction,
                    solid_angle: s.solid_angle,
                    radiance: s.radiance,
                }),
                Light::Directional(d) => b.add_light(LightDesc::Directional {
                    direction: d.direction,
                    irradiance: d.irradiance,
                }),
                Light::Environment(e) => b.add_light(LightDesc::Environment {
                    radiance: e.radiance,
                }),
                Light::EnvironmentMap(e) => {
                    b.add_light(LightDesc::EnvironmentMap { map: e.map.clone() })
                }
            }
        }
        b.build()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bsdf::{Diffuse, Material};
    use crate::camera::{Camera, FovAxis};
    use crate::math::Color;
    use crate::scene::RenderSettings;

    #[test]
    fn translation_moves_geometry_eye_and_point_lights_only() {
        let cam =
            Camera::look_at(Vec3::Z * 3.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 8, 8).unwrap();
        let mut b = SceneBuilder::new(cam, RenderSettings::default());
        let m = b.add_material(Material::Diffuse(Diffuse {
            albedo: Color::splat(0.5),
        }));
        b.add_shape(
            ShapeGeometry::Mesh(TriangleMesh::unit_rectangle()),
            m,
            Some(Color::ONE),
            false,
        );
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::X,
                radius: 0.5,
            },
            m,
            None,
            true,
        );
        b.add_light(LightDesc::Point {
            position: Vec3::Y,
            intensity: Color::ONE,
        });
        let to_light = Vec3::new(0.6, 0.8, 0.0);
        b.add_light(LightDesc::Directional {
            direction: to_light,
            irradiance: Color::splat(2.0),
        });
        let s = b.build();
        // Modelled around the world origin: kept as given.
        assert_eq!(s.origin, Vec3::ZERO);
        let off = Vec3::new(1e3, -2e3, 5e2);
        let t = s.translated(off);
        // Recentred on the centre of the moved geometry's box, (-1, -1, -0.5)…(1.5, 1, 0.5) + off.
        assert_eq!(t.origin, Vec3::new(0.25, 0.0, 0.0) + off);
        let world = |p: Vec3| p + t.origin;
        assert_eq!(world(t.camera.eye), s.camera.eye + off);
        assert_eq!(t.lights.len(), 3);
        assert!(matches!(&t.lights[1], Light::Point(p) if world(p.position) == Vec3::Y + off));
        // A direction is not a position: the directional light is unchanged.
        assert!(matches!(&t.lights[2], Light::Directional(d)
            if d.direction == to_light.normalize() && d.irradiance == Color::splat(2.0)));
        assert!(
            matches!(t.shapes[1].geometry, ShapeGeometry::Sphere { center, .. } if world(center) == Vec3::X + off)
        );
        assert!(t.shapes[1].flip_normals && t.shapes[0].light == Some(0));
        // Internally the box is centred, and the bounding sphere with it.
        let (lo, hi) = t.accel.bounds();
        assert_eq!(lo, Vec3::new(-1.25, -1.0, -0.5));
        assert_eq!(hi, Vec3::new(1.25, 1.0, 0.5));
        assert_eq!(t.bounding_sphere.0, Vec3::ZERO);
        // Translating back rebuilds the original, on the world origin again.
        let back = t.translated(-off);
        assert_eq!(back.origin, Vec3::ZERO);
        assert_eq!(back.camera.eye, s.camera.eye);
        assert_eq!(back.accel.bounds(), s.accel.bounds());
    }

    #[test]
    fn a_translated_scene_is_internally_the_centred_scene() {
        // Vertices on a 1/8 grid, so the 1e4 offset moves them exactly and the comparison can be
        // exact: the far scene must be stored exactly as the same scene built around its centre.
        let cam =
            Camera::look_at(Vec3::Z * 3.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 8, 8).unwrap();
        let build = |shift: Vec3| {
            let mut c = cam.clone();
            c.eye += shift;
            let mut b = SceneBuilder::new(c, RenderSettings::default());
            let m = b.add_material(Material::Diffuse(Diffuse {
                albedo: Color::splat(0.5),
            }));
            let mesh = TriangleMesh::unit_cube().transformed(&glam::Mat4::from_translation(
                Vec3::new(0.5, 0.25, -0.125) + shift,
            ));
            b.add_shape(ShapeGeometry::Mesh(mesh), m, None, true);
            b.add_light(LightDesc::Point {
                position: Vec3::new(0.5, 0.75, 0.0) + shift,
                intensity: Color::ONE,
            });
            b.build()
        };
        let near = build(Vec3::ZERO);
        let far = build(Vec3::splat(1e4));
        assert_eq!(near.origin, Vec3::ZERO);
        assert_eq!(far.origin, Vec3::new(0.5, 0.25, -0.125) + 1e4);
        let centred = |p: Vec3| p - Vec3::new(0.5, 0.25, -0.125);
        assert_eq!(far.camera.eye, centred(near.camera.eye));
        let (ShapeGeometry::Mesh(a), ShapeGeometry::Mesh(b)) =
            (&near.shapes[0].geometry, &far.shapes[0].geometry)
        else {
            unreachable!()
        };
        assert!(a
            .positions
            .iter()
            .zip(&b.positions)
            .all(|(&p, &q)| centred(p) == q));
        assert!(
            matches!((&near.lights[0], &far.lights[0]), (Light::Point(p), Light::Point(q)) if centred(p.position) == q.position)
        );
        assert_eq!(far.bounding_sphere.0, Vec3::ZERO);
        assert_eq!(far.bounding_sphere.1, near.bounding_sphere.1);
    }
}
