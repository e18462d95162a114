//! The one rounding to f32. Both loaders describe the scene in f64 world coordinates — numbers
//! parsed in f64, transforms composed and applied in f64 — and `WorldBuilder::build` picks the
//! scene's origin in f64 and rounds every position once, as world − origin. A scene translated
//! far from the world origin is therefore the same scene to the last bit of its f32 geometry:
//! rounding a far world coordinate first (at 1e4 an f32 has ~1e-3 absolute spacing) would have
//! moved every vertex by up to that much, growing or shrinking lights by a measurable fraction.

use crate::SceneError;
use glam::{DMat3, DMat4, DVec3};
use lt_core::bsdf::Material;
use lt_core::camera::{Camera, FovAxis};
use lt_core::light::LightDesc;
use lt_core::math::Vec3;
use lt_core::medium::{Medium, MediumId};
use lt_core::scene::{
    MediumInterface, RenderSettings, Scene, SceneBuilder, ShapeGeometry, TriangleMesh,
    MAX_MEDIUM_INTERFACES,
};
use lt_core::shape::Affine;
use lt_core::texture::Texture;
use std::collections::HashSet;

/// Largest world coordinate a scene may hold. f32 products of two coordinates (squared distances,
/// cross products for areas and normals) overflow beyond ~1.8e19; keep a margin of ten.
pub const MAX_COORDINATE: f64 = 1e18;

/// A triangle mesh placed in the world, positions in f64.
#[derive(Clone, Debug)]
pub struct WorldMesh {
    pub positions: Vec<DVec3>,
    /// Unit shading normals (directions need no recentring; they are rounded once here).
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates: no transform touches them.
    pub uvs: Option<Vec<lt_core::math::Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Mesh attributes: no transform touches them.
    pub attributes: Vec<lt_core::scene::MeshAttribute>,
}

impl WorldMesh {
    /// `local` (object space, as read from its file) under the object-to-world matrix `m`: points
    /// by `m`, normals by its inverse transpose, all in f64. A mirroring `m` turns the winding
    /// inside out, so triangles are flipped back to keep normals where the file put them.
    pub fn place(local: &TriangleMesh, m: &DMat4) -> WorldMesh {
        let positions = local
            .positions
            .iter()
            .map(|p| m.transform_point3(p.as_dvec3()))
            .collect();
        let normals = local.normals.as_ref().map(|ns| {
            let nm = DMat3::from_mat4(*m).inverse().transpose();
            ns.iter()
                .map(|n| (nm * n.as_dvec3()).normalize_or_zero().as_vec3())
                .collect()
        });
        let mut indices = local.indices.clone();
        if m.determinant() < 0.0 {
            indices.iter_mut().for_each(|t| t.swap(1, 2));
        }
        WorldMesh {
            positions,
            normals,
            uvs: local.uvs.clone(),
            indices,
            attributes: local.attributes.clone(),
        }
    }

    /// Total area in f64 (a mesh of only degenerate triangles has none).
    pub fn area(&self) -> f64 {
        self.indices
            .iter()
            .map(|&[a, b, c]| {
                let [a, b, c] = [a, b, c].map(|i| self.positions[i as usize]);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum()
    }

    /// The first position outside ±`MAX_COORDINATE` (or not finite), if any.
    pub fn out_of_range(&self) -> Option<DVec3> {
        self.positions.iter().copied().find(|p| !in_range(*p))
    }
}

/// True when every coordinate is finite and within ±`MAX_COORDINATE`.
pub fn in_range(p: DVec3) -> bool {
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// One-line message for a position `in_range` rejects.
pub fn out_of_range_message(what: &str, p: DVec3) -> String {
    format!(
        "{what} reaches {p:?} in world coordinates: every coordinate must be finite and within \
         ±{MAX_COORDINATE:e} (f32 distances and areas overflow beyond)"
    )
}

#[derive(Clone, Debug)]
pub enum WorldGeometry {
    Mesh(WorldMesh),
    Sphere {
        center: DVec3,
        radius: f64,
        /// The rotation (orthonormal, object to world) of its `to_world`, when not the identity:
        /// uv and tangents follow it (`ShapeGeometry::RotatedSphere`).
        rotation: Option<DMat3>,
    },
    /// Mitsuba's disk: the unit disk under this object-to-world map (`ShapeGeometry::Disk`).
    Disk {
        to_world: DMat4,
    },
    /// Mitsuba's open cylinder: the unit cylinder under this map (`ShapeGeometry::Cylinder`).
    Cylinder {
        to_world: DMat4,
    },
    /// Mitsuba's `sdfgrid`: the grid's unit cube under this map (`ShapeGeometry::SdfGrid`).
    SdfGrid {
        grid: std::sync::Arc<lt_core::shape::SdfGrid>,
        to_world: DMat4,
    },
}

/// The world box of the unit disk at height `z` under `m`: per axis, the centre ± √(m_i0² + m_i1²).
fn disk_box(m: &DMat4, z: f64) -> (DVec3, DVec3) {
    let c = m.transform_point3(DVec3::new(0.0, 0.0, z));
    let (x, y) = (m.x_axis.truncate(), m.y_axis.truncate());
    let e = (x * x + y * y).map(f64::sqrt);
    (c - e, c + e)
}

/// The scene's affine map from a world one, translation recentred (subtracted in f64).
fn local_affine(m: &DMat4, origin: DVec3) -> Affine {
    Affine::new(
        DMat3::from_mat4(*m).as_mat3(),
        (m.w_axis.truncate() - origin).as_vec3(),
    )
}

struct WorldShape {
    geometry: WorldGeometry,
    material: u32,
    /// The emitted radiance (a constant or a texture over the shape's uv) when it is a light.
    radiance: Option<Texture>,
    flip_normals: bool,
    media: MediumInterface,
}

/// A medium made once the origin is known (a grid's `to_world` is recentred); the error names the
/// medium's place in the file.
pub type MediumAt = Box<dyn Fn(DVec3) -> Result<Medium, SceneError>>;

/// The scene as the loaders describe it, before the one rounding. Mirrors `SceneBuilder`.
pub struct WorldBuilder {
    settings: RenderSettings,
    materials: Vec<Material>,
    shapes: Vec<WorldShape>,
    /// Lights not made of shapes, each with its world position in f64 when it has one.
    lights: Vec<(LightDesc, Option<DVec3>, Option<MediumId>)>,
    media: Vec<MediumAt>,
    camera_medium: Option<MediumId>,
    /// The distinct media pairs the shapes name besides (none, none).
    media_pairs: HashSet<MediumInterface>,
}

impl WorldBuilder {
    pub fn new(settings: RenderSettings) -> WorldBuilder {
        WorldBuilder {
            settings,
            materials: Vec::new(),
            shapes: Vec::new(),
            lights: Vec::new(),
            media: Vec::new(),
            camera_medium: None,
            media_pairs: HashSet::new(),
        }
    }

    /// A medium, made by `make` from the scene's origin at `build`; returns its id.
    pub fn add_medium(&mut self, make: MediumAt) -> MediumId {
        self.media.push(make);
        (self.media.len() - 1) as MediumId
    }

    pub fn set_camera_medium(&mut self, medium: Option<MediumId>) {
        self.camera_medium = medium;
    }

    /// The media inside and outside the shape added last; errs when the pair is one more than
    /// a scene may hold (`MAX_MEDIUM_INTERFACES`), for the loader to place at the shape.
    pub fn set_last_shape_media(&mut self, media: MediumInterface) -> Result<(), String> {
        if media != MediumInterface::default()
            && self.media_pairs.insert(media)
            && self.media_pairs.len() >= MAX_MEDIUM_INTERFACES
        {
            return Err(format!(
                "this shape's (interior, exterior) media pair is the {}th distinct one; a scene \
                 holds at most {}",
                self.media_pairs.len(),
                MAX_MEDIUM_INTERFACES - 1
            ));
        }
        if let Some(s) = self.shapes.last_mut() {
            s.media = media;
        }
        Ok(())
    }

    /// The medium the light added last sits in.
    pub fn set_last_light_medium(&mut self, medium: Option<MediumId>) {
        if let Some(l) = self.lights.last_mut() {
            l.2 = medium;
        }
    }

    /// Returns the material's id for `add_shape`.
    pub fn material(&self, id: u32) -> &Material {
        &self.materials[id as usize]
    }

    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// A shape, emitting `radiance` (a constant or a texture over its uv) when given.
    pub fn add_shape(
        &mut self,
        geometry: WorldGeometry,
        material: u32,
        radiance: Option<Texture>,
        flip_normals: bool,
    ) {
        self.shapes.push(WorldShape {
            geometry,
            material,
            radiance,
            flip_normals,
            media: MediumInterface::default(),
        });
    }

    /// A light without a position (sun, directional, environment).
    pub fn add_light(&mut self, light: LightDesc) {
        self.lights.push((light, None, None));
    }

    /// A light with a position (point, spot, projector: `LightDesc::position_mut`) placed at a
    /// world position given in f64; the position in `light` is replaced.
    pub fn add_light_at(&mut self, light: LightDesc, position: DVec3) {
        self.lights.push((light, Some(position), None));
    }

    /// The scene's origin, rounded once per position, indexed. `camera` makes the camera from its
    /// world description given the origin (it subtracts the origin from its eye and target in
    /// f64); a loader calls it once with `DVec3::ZERO` beforehand so that a degenerate camera is
    /// reported in file order.
    pub fn build(
        self,
        camera: impl FnOnce(DVec3) -> Result<Camera, SceneError>,
    ) -> Result<Scene, SceneError> {
        let origin = self.origin();
        let mut b = SceneBuilder::new(camera(origin)?, self.settings);
        b.set_origin(origin.as_vec3());
        for m in self.materials {
            b.add_material(m);
        }
        for make in &self.media {
            b.add_medium(make(origin)?);
        }
        b.set_camera_medium(self.camera_medium);
        let local = |p: DVec3| (p - origin).as_vec3();
        for s in self.shapes {
            let geometry = match s.geometry {
                WorldGeometry::Mesh(m) => ShapeGeometry::Mesh(TriangleMesh {
                    positions: m.positions.into_iter().map(local).collect(),
                    normals: m.normals,
                    uvs: m.uvs,
                    indices: m.indices,
                    attributes: m.attributes,
                }),
                WorldGeometry::Sphere {
                    center,
                    radius,
                    rotation: None,
                } => ShapeGeometry::Sphere {
                    center: local(center),
                    radius: radius as f32,
                },
                WorldGeometry::Sphere {
                    center,
                    radius,
                    rotation: Some(r),
                } => ShapeGeometry::RotatedSphere {
                    center: local(center),
                    radius: radius as f32,
                    rotation: r.as_mat3(),
                },
                WorldGeometry::Disk { to_world } => ShapeGeometry::Disk {
                    to_world: local_affine(&to_world, origin),
                },
                WorldGeometry::Cylinder { to_world } => ShapeGeometry::Cylinder {
                    to_world: local_affine(&to_world, origin),
                },
                WorldGeometry::SdfGrid { grid, to_world } => ShapeGeometry::SdfGrid {
                    grid,
                    to_world: local_affine(&to_world, origin),
                },
            };
            b.add_emitting_shape(geometry, s.material, s.radiance, s.flip_normals);
            if s.media != MediumInterface::default() {
                b.set_last_shape_media(s.media);
            }
        }
        for (mut light, at, medium) in self.lights {
            if let (Some(position), Some(p)) = (light.position_mut(), at) {
                *position = local(p);
            }
            b.add_light_in_medium(light, medium);
        }
        // The pairs were counted as the shapes were added (`set_last_shape_media`).
        b.try_build().map_err(|message| SceneError {
            file: String::new(),
            line: None,
            column: None,
            message,
        })
    }

    /// Per axis, the centre of the geometry's bounding box when it lies more than two box
    /// diagonals from 0, else 0 (a scene modelled around the origin keeps its coordinates as
    /// given). Rounded to f32, so that `Scene::origin` holds it exactly and world − origin is
    /// computed from the same number the scene reports.
    fn origin(&self) -> DVec3 {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for s in &self.shapes {
            match &s.geometry {
                WorldGeometry::Mesh(m) => {
                    for &p in &m.positions {
                        (lo, hi) = (lo.min(p), hi.max(p));
                    }
                }
                &WorldGeometry::Sphere { center, radius, .. } => {
                    (lo, hi) = (lo.min(center - radius), hi.max(center + radius));
                }
                WorldGeometry::Disk { to_world } => {
                    let (a, b) = disk_box(to_world, 0.0);
                    (lo, hi) = (lo.min(a), hi.max(b));
                }
                WorldGeometry::Cylinder { to_world } => {
                    for z in [0.0, 1.0] {
                        let (a, b) = disk_box(to_world, z);
                        (lo, hi) = (lo.min(a), hi.max(b));
                    }
                }
                WorldGeometry::SdfGrid { to_world, .. } => {
                    for i in 0..8 {
                        let c =
                            DVec3::new((i & 1) as f64, (i >> 1 & 1) as f64, (i >> 2 & 1) as f64);
                        let p = to_world.transform_point3(c);
                        (lo, hi) = (lo.min(p), hi.max(p));
                    }
                }
            }
        }
        let center = 0.5 * (lo + hi);
        let diagonal = (hi - lo).length();
        if !center.is_finite() || !diagonal.is_finite() {
            return DVec3::ZERO;
        }
        let far = center.abs().cmpgt(DVec3::splat(2.0 * diagonal));
        DVec3::select(far, center, DVec3::ZERO).as_vec3().as_dvec3()
    }
}

/// A camera as a file describes it, in world coordinates (f64), made once the origin is known.
#[derive(Clone, Copy, Debug)]
pub struct LookAt {
    pub eye: DVec3,
    pub target: DVec3,
    /// A direction: needs no recentring.
    pub up: DVec3,
    pub fov_deg: f32,
    pub fov_axis: FovAxis,
    pub width: u32,
    pub height: u32,
}

impl LookAt {
    /// The camera with its eye and target as world − `origin`, subtracted in f64 and rounded once.
    pub fn at(&self, origin: DVec3) -> Result<Camera, String> {
        Camera::look_at(
            (self.eye - origin).as_vec3(),
            (self.target - origin).as_vec3(),
            self.up.as_vec3(),
            self.fov_deg,
            self.fov_axis,
            self.width,
            self.height,
        )
    }
}
