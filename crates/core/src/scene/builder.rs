//! Assembling a scene in code: the loader and the tests both go through this one path, so a scene
//! built by hand is checked and indexed exactly like one read from a file.

use super::{MediumInterface, RenderSettings, Scene, Shape, MAX_MEDIUM_INTERFACES};
use crate::bsdf::Material;
use crate::camera::Camera;
use crate::geometry::quad::Parallelogram;
use crate::geometry::quadric;
use crate::geometry::sdf::SdfVoxel;
use crate::geometry::{Accel, Primitive};
use crate::light::{Light, LightDesc, LightSampler};
use crate::math::{Color, Vec3};
use crate::medium::{Medium, MediumId};
use crate::shape::{ShapeGeometry, TriangleMesh};
use crate::texture::Texture;
use std::collections::{HashMap, HashSet};

/// Triangles of a mesh as BVH primitives; consecutive pairs that split a parallelogram (quads,
/// cube faces, quads triangulated from OBJ) become one analytic parallelogram.
fn push_mesh_primitives(m: &TriangleMesh, shape: u32, prims: &mut Vec<Primitive>) {
    let mut i = 0;
    while i < m.indices.len() {
        if i + 1 < m.indices.len() && m.triangle_area(i) > 0.0 && m.triangle_area(i + 1) > 0.0 {
            if let Some(q) = Parallelogram::from_triangle_pair(m.triangle(i), m.triangle(i + 1)) {
                prims.push(Primitive::Quad {
                    q,
                    shape,
                    index: i as u32,
                });
                i += 2;
                continue;
            }
        }
        if m.triangle_area(i) > 0.0 {
            prims.push(Primitive::Triangle {
                p: m.triangle(i),
                shape,
                index: i as u32,
            });
        }
        i += 1;
    }
}

/// The world point a scene is recentred on: per axis, the centre of the geometry's bounding box
/// (mesh vertices, spheres), so a scene far from the world origin keeps the precision it would
/// have at the origin (at 1e4 an f32 coordinate has ~1e-3 absolute rounding, which BDPT's
/// geometry factors between nearby vertices cannot absorb).
///
/// An axis whose centre is within two bounding-box diagonals of 0 keeps 0: its coordinates are
/// already of the scene's own size, and scenes modelled around the origin stay bit for bit as
/// given. Beyond that, every box coordinate p lies within a factor of 2 of the f32 centre c, so
/// p − c is exact (Sterbenz): the recentred geometry is the input geometry, merely moved. (The
/// eye and point lights, outside the box, may round once, by at most half an ulp of their
/// distance to c.)
fn scene_origin(shapes: &[(ShapeGeometry, u32, Option<Texture>, bool)]) -> Vec3 {
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for (geometry, ..) in shapes {
        match geometry {
            ShapeGeometry::Mesh(m) => {
                for &p in &m.positions {
                    (lo, hi) = (lo.min(p), hi.max(p));
                }
            }
            &ShapeGeometry::Sphere { center, radius }
            | &ShapeGeometry::RotatedSphere { center, radius, .. } => {
                (lo, hi) = (lo.min(center - radius), hi.max(center + radius));
            }
            ShapeGeometry::Disk { to_world } => {
                let (a, b) = quadric::disk_bounds(to_world);
                (lo, hi) = (lo.min(a), hi.max(b));
            }
            ShapeGeometry::Cylinder { to_world } => {
                let (a, b) = quadric::cylinder_bounds(to_world);
                (lo, hi) = (lo.min(a), hi.max(b));
            }
            ShapeGeometry::SdfGrid { to_world, .. } => {
                for i in 0..8 {
                    let c = Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32);
                    let p = to_world.point(c);
                    (lo, hi) = (lo.min(p), hi.max(p));
                }
            }
        }
    }
    let center = 0.5 * lo + 0.5 * hi;
    let diagonal = (hi - lo).length();
    if !center.is_finite() || !diagonal.is_finite() {
        return Vec3::ZERO;
    }
    Vec3::select(
        center.abs().cmpgt(Vec3::splat(2.0 * diagonal)),
        center,
        Vec3::ZERO,
    )
}

pub struct SceneBuilder {
    camera: Camera,
    settings: RenderSettings,
    materials: Vec<Material>,
    shapes: Vec<(ShapeGeometry, u32, Option<Texture>, bool)>,
    lights: Vec<LightDesc>,
    /// Set by a loader that recentred in f64 itself (`set_origin`).
    origin: Option<Vec3>,
    media: Vec<Medium>,
    /// Per shape, parallel to `shapes`.
    shape_media: Vec<MediumInterface>,
    /// Per light description, parallel to `lights`.
    light_media: Vec<Option<MediumId>>,
    camera_medium: Option<MediumId>,
}

impl SceneBuilder {
    pub fn new(camera: Camera, settings: RenderSettings) -> SceneBuilder {
        SceneBuilder {
            camera,
            settings,
            materials: Vec::new(),
            shapes: Vec::new(),
            lights: Vec::new(),
            origin: None,
            media: Vec::new(),
            shape_media: Vec::new(),
            light_media: Vec::new(),
            camera_medium: None,
        }
    }

    /// Returns the medium's id for shapes, the camera and lights to refer to.
    pub fn add_medium(&mut self, m: Medium) -> MediumId {
        self.media.push(m);
        (self.media.len() - 1) as MediumId
    }

    /// The medium the camera sits in.
    pub fn set_camera_medium(&mut self, medium: Option<MediumId>) {
        self.camera_medium = medium;
    }

    /// The media inside and outside the shape added last (Mitsuba's `interior`/`exterior`; the
    /// exterior is the side its normal faces, after `flip_normals`).
    pub fn set_last_shape_media(&mut self, media: MediumInterface) {
        if let Some(last) = self.shape_media.last_mut() {
            *last = media;
        }
    }

    /// `add_light` for a light that sits in a medium (a point or spot light inside fog).
    pub fn add_light_in_medium(&mut self, light: LightDesc, medium: Option<MediumId>) {
        self.lights.push(light);
        self.light_media.push(medium);
    }

    /// Declares every position given (shapes, point lights, the camera eye) to be world − `origin`
    /// already: a file loader that subtracted the origin in f64 before its one rounding to f32
    /// (`lt-scene-io`'s `WorldBuilder`). `build` then keeps the geometry exactly as given.
    pub fn set_origin(&mut self, origin: Vec3) {
        self.origin = Some(origin);
    }

    /// Returns the material's id for `add_shape`.
    pub fn add_material(&mut self, m: Material) -> u32 {
        self.materials.push(m);
        (self.materials.len() - 1) as u32
    }

    /// `emission`, when given, makes the shape a one-sided area light on its normal side.
    pub fn add_shape(
        &mut self,
        geometry: ShapeGeometry,
        material: u32,
        emission: Option<Color>,
        flip_normals: bool,
    ) {
        let radiance = emission.map(Texture::Constant);
        self.add_emitting_shape(geometry, material, radiance, flip_normals);
    }

    /// `add_shape` with the emitted radiance a texture over the shape's uv (Mitsuba's area
    /// emitter with a textured `radiance`); a constant texture is the plain area light.
    pub fn add_emitting_shape(
        &mut self,
        geometry: ShapeGeometry,
        material: u32,
        radiance: Option<Texture>,
        flip_normals: bool,
    ) {
        self.shapes
            .push((geometry, material, radiance, flip_normals));
        self.shape_media.push(MediumInterface::default());
    }

    pub fn add_light(&mut self, light: LightDesc) {
        self.add_light_in_medium(light, None);
    }

    /// [`SceneBuilder::try_build`] for scenes that cannot fail it (code building a scene within
    /// its limits); panics with `try_build`'s message otherwise.
    pub fn build(self) -> Scene {
        self.try_build()
            .unwrap_or_else(|m| panic!("SceneBuilder::build: {m}"))
    }

    /// Indexes the scene, recentred on `scene_origin` of its geometry: every shape, positioned light
    /// and the camera eye are stored as world − origin (see `Scene::origin`); directions (sun,
    /// directional light, environment, shading normals) are unchanged. Errs when the shapes name
    /// more distinct (interior, exterior) media pairs than [`MAX_MEDIUM_INTERFACES`] allows.
    pub fn try_build(mut self) -> Result<Scene, String> {
        // Checked before any work: a refused scene costs nothing.
        // Each medium also gets the pair (m, m): the interface of a surface vertex on a shape that
        // names no media, reached inside m (`Scene::interface_within`).
        let within = (0..self.media.len() as MediumId).map(|m| MediumInterface {
            interior: Some(m),
            exterior: Some(m),
        });
        let pairs: HashSet<MediumInterface> = self
            .shape_media
            .iter()
            .copied()
            .chain(within)
            .chain([MediumInterface::default()])
            .collect();
        if pairs.len() > MAX_MEDIUM_INTERFACES {
            return Err(too_many_interfaces(pairs.len()));
        }
        let origin = self.origin.unwrap_or_else(|| scene_origin(&self.shapes));
        if self.origin.is_none() && origin != Vec3::ZERO {
            for (geometry, ..) in &mut self.shapes {
                match geometry {
                    ShapeGeometry::Mesh(m) => m.positions.iter_mut().for_each(|p| *p -= origin),
                    ShapeGeometry::Sphere { center, .. }
                    | ShapeGeometry::RotatedSphere { center, .. } => *center -= origin,
                    ShapeGeometry::Disk { to_world }
                    | ShapeGeometry::Cylinder { to_world }
                    | ShapeGeometry::SdfGrid { to_world, .. } => to_world.t -= origin,
                }
            }
            for light in &mut self.lights {
                if let Some(position) = light.position_mut() {
                    *position -= origin;
                }
            }
            self.camera.eye -= origin;
        }
        let mut shapes = Vec::with_capacity(self.shapes.len());
        let mut lights = Vec::new();
        let mut light_media = Vec::new();
        let mut prims = Vec::new();
        let mut interfaces = vec![MediumInterface::default()];
        let mut interface_index = HashMap::from([(MediumInterface::default(), 0u16)]);
        for ((geometry, material, emission, flip_normals), media) in
            self.shapes.into_iter().zip(self.shape_media)
        {
            let shape_id = shapes.len() as u32;
            match &geometry {
                ShapeGeometry::Mesh(m) => push_mesh_primitives(m, shape_id, &mut prims),
                &ShapeGeometry::Sphere { center, radius }
                | &ShapeGeometry::RotatedSphere { center, radius, .. } => {
                    prims.push(Primitive::Sphere {
                        center,
                        radius,
                        shape: shape_id,
                    })
                }
                ShapeGeometry::Disk { to_world } => prims.push(Primitive::Disk {
                    to_object: to_world.inverse(),
                    shape: shape_id,
                }),
                ShapeGeometry::Cylinder { to_world } => prims.push(Primitive::Cylinder {
                    to_object: to_world.inverse(),
                    shape: shape_id,
                }),
                ShapeGeometry::SdfGrid { grid, to_world } => {
                    for v in grid.surface_voxels() {
                        prims.push(Primitive::SdfVoxel {
                            voxel: SdfVoxel::new(grid, v, to_world),
                            shape: shape_id,
                        });
                    }
                }
            }
            let textured_light = matches!(&emission, Some(e) if !matches!(e, Texture::Constant(_)));
            let light = emission.map(|e| {
                lights.push(Light::area(shape_id, &geometry, &e, flip_normals));
                light_media.push(media.exterior);
                (lights.len() - 1) as u32
            });
            // In order of first use; fits in u16 (checked above).
            let interface = *interface_index.entry(media).or_insert_with(|| {
                interfaces.push(media);
                (interfaces.len() - 1) as u16
            });
            // A missing attribute reads as zero (the loaders report it first).
            let attribute = match (
                &geometry,
                self.materials[material as usize].mesh_attribute(),
            ) {
                (ShapeGeometry::Mesh(m), Some(name)) => m.attribute_index(name),
                _ => None,
            };
            let m = &self.materials[material as usize];
            shapes.push(Shape {
                reads_uv: m.reads_uv() || textured_light,
                needs_tangent: m.needs_tangent(),
                geometry,
                material,
                light,
                flip_normals,
                attribute,
                interface,
                null: matches!(m, Material::Null(_)),
            });
        }
        let accel = Accel::build(prims);
        let (lo, hi) = accel.bounds();
        let center = 0.5 * (lo + hi);
        let radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE);
        let bounding_sphere = (center, radius);
        let mut infinite_lights = Vec::new();
        for (desc, medium) in self.lights.into_iter().zip(self.light_media) {
            let light = Light::from_desc(&desc);
            if light.is_infinite() {
                infinite_lights.push(lights.len() as u32);
            }
            lights.push(light);
            light_media.push(if desc_is_infinite(&lights) {
                None
            } else {
                medium
            });
        }
        let has_media = self.camera_medium.is_some()
            || interfaces.len() > 1
            || light_media.iter().any(Option::is_some);
        let within_medium = if has_media {
            (0..self.media.len() as MediumId)
                .map(|m| {
                    let both = MediumInterface {
                        interior: Some(m),
                        exterior: Some(m),
                    };
                    *interface_index.entry(both).or_insert_with(|| {
                        interfaces.push(both);
                        (interfaces.len() - 1) as u16
                    })
                })
                .collect()
        } else {
            Vec::new()
        };
        let light_sampler = LightSampler::new(&lights, bounding_sphere);
        let scene = Scene {
            origin,
            camera: self.camera,
            settings: self.settings,
            delta_materials: self.materials.iter().map(Material::is_delta).collect(),
            materials: self.materials,
            shapes,
            lights,
            light_sampler,
            infinite_lights,
            bounding_sphere,
            source_files: Vec::new(),
            media: self.media,
            interfaces,
            within_medium,
            camera_medium: self.camera_medium,
            light_media,
            has_media,
            accel,
        };
        Ok(scene)
    }
}

fn too_many_interfaces(pairs: usize) -> String {
    format!(
        "the shapes name {} distinct (interior, exterior) media pairs, each medium's (m, m) \
         included; at most {} are supported",
        pairs - 1,
        MAX_MEDIUM_INTERFACES - 1
    )
}

/// True when the light pushed last sits at infinity (it emits into no medium).
fn desc_is_infinite(lights: &[Light]) -> bool {
    lights.last().is_some_and(Light::is_infinite)
}
