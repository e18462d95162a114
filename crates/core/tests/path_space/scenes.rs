//! Scenes and statistics shared by the path-space tests.

use lt_core::bsdf::{Dielectric, Diffuse, Glossy, Material, Mirror};
use lt_core::camera::{Camera, FovAxis};
use lt_core::math::{Color, Mat4, Vec3};
use lt_core::scene::{LightDesc, RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::Scene;

/// A parallelogram centred at `c` spanned by the half-edges `u`, `v`; its normal is u × v.
pub fn quad(c: Vec3, u: Vec3, v: Vec3) -> ShapeGeometry {
    let n = u.cross(v).normalize();
    let m = Mat4::from_cols(u.extend(0.0), v.extend(0.0), n.extend(0.0), c.extend(1.0));
    ShapeGeometry::Mesh(TriangleMesh::unit_rectangle().transformed(&m))
}

fn diffuse(b: &mut SceneBuilder, albedo: f32) -> u32 {
    b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(albedo),
    }))
}

/// Variations of the Cornell-like box.
#[derive(Clone, Copy, Debug, Default)]
pub struct BoxConfig {
    /// Tilts the floor's shading normals away from its geometric normal (differently at each
    /// corner), so radiance and importance transport differ.
    pub bumpy_floor: bool,
    /// Adds a glass sphere and a tilted glass cube (IOR 1.5) and makes the back wall a GGX
    /// conductor (α = 0.3).
    pub glass_and_glossy: bool,
}

/// A Cornell-like box [-1,1]³ open towards +z: diffuse walls, a quad light under the ceiling, a
/// dimmer one on the back wall (so light selection pmfs are not 1) and a mirror block.
pub fn cornell(cfg: BoxConfig) -> Scene {
    let cam = Camera::look_at(
        Vec3::new(0.0, 0.0, 3.9),
        Vec3::ZERO,
        Vec3::Y,
        39.3,
        FovAxis::X,
        32,
        24,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam, RenderSettings::default());
    let white = diffuse(&mut b, 0.7);
    let red = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::new(0.6, 0.1, 0.1),
    }));
    let black = diffuse(&mut b, 0.0);
    let mirror = b.add_material(Material::Mirror(Mirror {
        reflectance: Color::splat(0.9),
    }));
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    let mut floor = quad(-y, z, x); // normal +y
    if let (true, ShapeGeometry::Mesh(m)) = (cfg.bumpy_floor, &mut floor) {
        let tilt = [
            Vec3::new(0.4, 1.0, 0.1),
            Vec3::new(-0.3, 1.0, 0.3),
            Vec3::new(0.1, 1.0, -0.5),
            Vec3::new(0.0, 1.0, 0.2),
        ];
        m.normals = Some(tilt.iter().map(|n| n.normalize()).collect());
    }
    b.add_shape(floor, white, None, false);
    b.add_shape(quad(y, x, z), white, None, false); // ceiling, normal −y
    let back = if cfg.glass_and_glossy {
        b.add_material(Material::Glossy(Glossy {
            reflectance: Color::new(0.8, 0.7, 0.5),
            roughness: 0.3,
        }))
    } else {
        white
    };
    b.add_shape(quad(-z, x, y), back, None, false); // back, normal +z
    if cfg.glass_and_glossy {
        let glass = b.add_material(Material::Dielectric(Dielectric { ior: 1.5 }));
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::new(-0.4, -0.6, 0.2),
                radius: 0.35,
            },
            glass,
            None,
            false,
        );
        let cube = Mat4::from_translation(Vec3::new(-0.45, 0.35, -0.4))
            * Mat4::from_rotation_x(0.6)
            * Mat4::from_rotation_y(0.7)
            * Mat4::from_scale(Vec3::splat(0.2));
        b.add_shape(
            ShapeGeometry::Mesh(TriangleMesh::unit_cube().transformed(&cube)),
            glass,
            None,
            false,
        );
        // A spherical emitter in view: next-event estimation samples its visible cone, light
        // tracing its whole area, so the two densities of x0 differ (k = 1 tells them apart).
        b.add_shape(
            ShapeGeometry::Sphere {
                center: Vec3::new(0.55, 0.45, 0.2),
                radius: 0.12,
            },
            white,
            Some(Color::splat(4.0)),
            false,
        );
    }
    b.add_shape(quad(-x, y, z), red, None, false); // left, normal +x
    b.add_shape(quad(x, z, y), white, None, false); // right, normal −x
    b.add_shape(
        quad(Vec3::new(0.0, 0.99, 0.0), 0.3 * x, 0.3 * z),
        black,
        Some(Color::splat(12.0)),
        false,
    );
    b.add_shape(
        quad(Vec3::new(-0.5, 0.5, -0.99), 0.2 * x, 0.1 * y),
        black,
        Some(Color::new(3.0, 5.0, 8.0)),
        false,
    );
    let block = Mat4::from_translation(Vec3::new(0.35, -0.6, -0.3))
        * Mat4::from_rotation_y(0.4)
        * Mat4::from_scale(Vec3::splat(0.35));
    b.add_shape(
        ShapeGeometry::Mesh(TriangleMesh::unit_cube().transformed(&block)),
        mirror,
        None,
        false,
    );
    b.build()
}

/// What lights the analytic plane scene.
#[derive(Clone, Copy, Debug)]
pub enum PlaneLight {
    /// A downward-facing square of half-size `half` at height 1 above the origin, radiance `le`.
    Quad { half: f32, le: f32 },
    /// A point light at height 1 above the origin.
    Point { intensity: f32 },
    /// A sun towards `dir` of solid angle `omega`.
    Sun {
        dir: Vec3,
        omega: f32,
        radiance: f32,
    },
    /// A directional light (a delta in direction) towards `dir` of irradiance `irradiance`, and
    /// optionally a second one, (direction, irradiance), so that light selection pmfs are not 1.
    Directional {
        dir: Vec3,
        irradiance: f32,
        second: Option<(Vec3, f32)>,
    },
}

pub const PLANE_ALBEDO: f32 = 0.5;

/// A diffuse square (half-size 2, normal +y, through the origin) seen by a camera from above.
pub fn plane(light: PlaneLight) -> Scene {
    let cam = Camera::look_at(
        Vec3::new(0.0, 0.6, 2.5),
        Vec3::ZERO,
        Vec3::Y,
        40.0,
        FovAxis::X,
        32,
        24,
    )
    .unwrap();
    let mut b = SceneBuilder::new(cam, RenderSettings::default());
    let white = diffuse(&mut b, PLANE_ALBEDO);
    let black = diffuse(&mut b, 0.0);
    b.add_shape(
        quad(Vec3::ZERO, 2.0 * Vec3::Z, 2.0 * Vec3::X),
        white,
        None,
        false,
    );
    match light {
        PlaneLight::Quad { half, le } => {
            let g = quad(Vec3::Y, half * Vec3::X, half * Vec3::Z);
            b.add_shape(g, black, Some(Color::splat(le)), false);
        }
        PlaneLight::Point { intensity } => b.add_light(LightDesc::Point {
            position: Vec3::Y,
            intensity: Color::splat(intensity),
        }),
        PlaneLight::Sun {
            dir,
            omega,
            radiance,
        } => b.add_light(LightDesc::Sun {
            direction: dir,
            solid_angle: omega,
            radiance: Color::splat(radiance),
        }),
        PlaneLight::Directional {
            dir,
            irradiance,
            second,
        } => {
            for (d, e) in std::iter::once((dir, irradiance)).chain(second) {
                b.add_light(LightDesc::Directional {
                    direction: d.normalize(),
                    irradiance: Color::splat(e),
                });
            }
        }
    }
    b.build()
}

/// Exact irradiance at `x` (normal +y) from the plane scene's light, ignoring occlusion (none
/// occludes the plane). Quad: Lambert's polygon formula E = Le/2 · Σ Θ_i (n · û_i);
/// point: I cos/d²; sun: E = L ∫_cone cos dω = L π sin²θmax (n · d) for a cone above the
/// horizon; directional: E (n · d) for each light above the horizon.
pub fn plane_irradiance(light: PlaneLight, x: Vec3) -> f64 {
    let n = Vec3::Y.as_dvec3();
    match light {
        PlaneLight::Quad { half, le } => {
            let h = half as f64;
            let corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
                .map(|(a, c)| glam::DVec3::new(a, 1.0, c) - x.as_dvec3());
            let mut sum = 0.0;
            for i in 0..4 {
                let (a, b) = (corners[i].normalize(), corners[(i + 1) % 4].normalize());
                sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(a.cross(b).normalize());
            }
            le as f64 * 0.5 * sum.abs()
        }
        PlaneLight::Point { intensity } => {
            let d = Vec3::Y.as_dvec3() - x.as_dvec3();
            intensity as f64 * n.dot(d).max(0.0) / d.length().powi(3)
        }
        PlaneLight::Sun {
            dir,
            omega,
            radiance,
        } => {
            let h = omega as f64 / (2.0 * std::f64::consts::PI);
            radiance as f64
                * std::f64::consts::PI
                * h
                * (2.0 - h)
                * n.dot(dir.normalize().as_dvec3())
        }
        PlaneLight::Directional {
            dir,
            irradiance,
            second,
        } => std::iter::once((dir, irradiance))
            .chain(second)
            .map(|(d, e)| e as f64 * n.dot(d.normalize().as_dvec3()).max(0.0))
            .sum(),
    }
}

/// Running mean and standard error of i.i.d. samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct Stats {
    n: u64,
    sum: f64,
    sum2: f64,
}

impl Stats {
    pub fn add(&mut self, x: f64) {
        self.n += 1;
        self.sum += x;
        self.sum2 += x * x;
    }
    pub fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }
    pub fn se(&self) -> f64 {
        let m = self.mean();
        ((self.sum2 / self.n as f64 - m * m).max(0.0) / (self.n as f64 - 1.0)).sqrt()
    }
}

/// z score of the difference of two independent estimates (or of one against an exact value).
pub fn z(a: (f64, f64), b: (f64, f64)) -> f64 {
    (a.0 - b.0) / (a.1 * a.1 + b.1 * b.1).sqrt()
}

/// Relative agreement of two non-negative numbers.
pub fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()) || (a == 0.0 && b == 0.0)
}
