//! A rigidly translated copy of a scene: the robustness check that results do not depend on where
//! the scene sits in floating-point space (large coordinates leave fewer bits for the geometry).

use super::{LightDesc, Scene, SceneBuilder, ShapeGeometry, TriangleMesh};
use crate::light::Light;
use crate::math::Vec3;

impl Scene {
    /// The scene with eye, every shape and every point light moved by `offset` (rounded once to
    /// f32 per vertex, as a loader `translate` would). Distant lights are unchanged.
    pub fn translated(&self, offset: Vec3) -> Scene {
        let mut camera = self.camera.clone();
        camera.eye += offset;
        let mut b = SceneBuilder::new(camera, self.settings);
        for m in &self.materials {
            b.add_material(m.clone());
        }
        for s in &self.shapes {
            let geometry = match &s.geometry {
                ShapeGeometry::Mesh(m) => ShapeGeometry::Mesh(TriangleMesh {
                    positions: m.positions.iter().map(|&p| p + offset).collect(),
                    ..m.clone()
                }),
                &ShapeGeometry::Sphere { center, radius } => ShapeGeometry::Sphere {
                    center: center + offset,
                    radius,
                },
            };
            let emission = s.light.and_then(|l| match &self.lights[l as usize] {
                Light::Area(a) => Some(a.emission),
                _ => None,
            });
            b.add_shape(geometry, s.material, emission, s.flip_normals);
        }
        // Area lights come first (one per emitting shape, as the builder makes them); the rest
        // are re-described so the builder orders them the same way.
        for l in &self.lights {
            match l {
                Light::Area(_) => {}
                Light::Point(p) => b.add_light(LightDesc::Point {
                    position: p.position + offset,
                    intensity: p.intensity,
                }),
                Light::Sun(s) => b.add_light(LightDesc::Sun {
                    direction: s.direction,
                    solid_angle: s.solid_angle,
                    radiance: s.radiance,
                }),
                Light::Environment(e) => b.add_light(LightDesc::Environment {
                    radiance: e.radiance,
                }),
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
        let s = b.build();
        let off = Vec3::new(1e3, -2e3, 5e2);
        let t = s.translated(off);
        assert_eq!(t.camera.eye, s.camera.eye + off);
        assert_eq!(t.lights.len(), 2);
        assert!(matches!(&t.lights[1], Light::Point(p) if p.position == Vec3::Y + off));
        assert!(
            matches!(t.shapes[1].geometry, ShapeGeometry::Sphere { center, .. } if center == Vec3::X + off)
        );
        assert!(t.shapes[1].flip_normals && t.shapes[0].light == Some(0));
        let (lo, hi) = t.accel.bounds();
        assert_eq!(lo, Vec3::new(-1.0, -1.0, -0.5) + off);
        assert_eq!(hi, Vec3::new(1.5, 1.0, 0.5) + off);
    }
}
