//! The scene: shapes in one BVH, materials, lights and the camera, plus the queries integrators
//! make (closest hit; visibility in `visibility.rs`). Scenes are assembled with `SceneBuilder`: by
//! the file readers of `lt-scene-io` (TOML, Mitsuba XML) or in code by tests.

mod builder;
mod hit;
mod media;
pub mod ray_stats;
mod translated;
mod visibility;

pub use crate::light::LightDesc;
pub use crate::shape::{MeshAttribute, ShapeGeometry, TriangleMesh};
pub use builder::SceneBuilder;
pub use hit::SurfaceHit;
pub use media::{
    ConnectionFlight, Crossing, MediumInterface, MediumPiece, SegmentCrossing,
    MAX_MEDIUM_INTERFACES,
};
pub use visibility::{ConnectionEnd, ShadowRay};

use crate::bsdf::Material;
use crate::camera::Camera;
use crate::geometry::packet::PACKET;
use crate::geometry::{Accel, Ray};
use crate::light::{Light, LightSampler};
use crate::math::Vec3;

/// Integrator-independent render settings a scene file may carry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Longest path in segments, camera ray included (Mitsuba 3's convention):
    /// 1 = emitters seen directly, 2 = direct lighting, …
    pub max_depth: u32,
    /// Russian roulette starts after this many segments.
    pub rr_depth: u32,
    /// Default samples per pixel when the command line gives none.
    pub spp: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            max_depth: 8,
            rr_depth: 5,
            spp: 64,
        }
    }
}

/// One shape as the user described it, after transforms, in the scene's internal coordinates
/// (world − `Scene::origin`).
#[derive(Clone, Debug)]
pub struct Shape {
    pub geometry: ShapeGeometry,
    pub material: u32,
    /// Index into `Scene::lights` when the shape emits.
    pub light: Option<u32>,
    /// Flips the geometric (and shading) normal: emission and inside/outside follow it.
    pub flip_normals: bool,
    /// The mesh attribute (index into the mesh's `attributes`) the shape's material reads, if
    /// any: only then does a hit compute one.
    pub attribute: Option<u32>,
    /// A hit computes texture coordinates only when something reads them: the material
    /// (`Material::reads_uv`) or a textured emission. Others keep uv zero, and skip its cost.
    pub reads_uv: bool,
    /// `Material::needs_tangent`, asked once here instead of at every hit.
    pub needs_tangent: bool,
    /// The media inside and outside the shape: an index into `Scene::interfaces` (0: none).
    pub interface: u16,
    /// The shape is a `null` boundary (`Material::Null`, resolved once at build): it only
    /// separates media; a media-aware walk passes through it without making a vertex.
    pub null: bool,
}

pub struct Scene {
    /// The world position of the internal origin. Every position the scene holds or returns —
    /// shapes, point lights, the camera eye, the bounding sphere, hit points, path vertices, and
    /// the points its queries take — is internal: world − `origin`. Add it back to report a
    /// world position. Directions are the same in both.
    pub origin: Vec3,
    pub camera: Camera,
    pub settings: RenderSettings,
    pub materials: Vec<Material>,
    /// `Material::is_delta` of each material, asked once at build: connections ask it of every
    /// vertex of every technique (O(k²) per path), and through wrappers it recurses.
    pub delta_materials: Vec<bool>,
    pub shapes: Vec<Shape>,
    pub lights: Vec<Light>,
    pub light_sampler: LightSampler,
    /// Lights at infinity (sun, environment) that a ray escaping the scene can see.
    pub infinite_lights: Vec<u32>,
    /// Bounding sphere of the geometry (centre, radius): distant lights emit over its disk.
    pub bounding_sphere: (Vec3, f32),
    /// The files the scene was read from, the scene file first, then every mesh it names in file
    /// order: what a content hash of the scene must cover. Empty for scenes built in code.
    pub source_files: Vec<std::path::PathBuf>,
    /// Participating media, indexed by `MediumId` (empty for a scene without media).
    pub media: Vec<crate::medium::Medium>,
    /// The distinct (interior, exterior) pairs of the shapes; entry 0 is (none, none).
    pub interfaces: Vec<MediumInterface>,
    /// For each medium m, the index of the pair (m, m) in `interfaces`: what a surface vertex on
    /// a shape that names no media carries when a walk reached it inside m (empty without media).
    pub within_medium: Vec<u16>,
    /// The medium the camera sits in.
    pub camera_medium: Option<crate::medium::MediumId>,
    /// The medium each light emits into (an area light: its shape's exterior, the side its
    /// normal faces; a light at infinity: none).
    pub light_media: Vec<Option<crate::medium::MediumId>>,
    /// True when any medium is referenced by a shape, the camera or a light: every media query
    /// is behind this one flag, so a scene without media does no extra work.
    pub has_media: bool,
    pub(crate) accel: Accel,
}

impl Scene {
    /// The closest surface the ray hits.
    #[inline]
    /// The ray core alone (no hit record): what `lt bench` times as raw traversal.
    pub fn accel(&self) -> &Accel {
        &self.accel
    }

    pub fn intersect(&self, ray: &Ray) -> Option<SurfaceHit> {
        ray_stats::count_closest();
        let h = self.accel.intersect(ray)?;
        Some(SurfaceHit::new(self, ray, h))
    }

    /// `intersect` of each ray of a packet whose `active` flag is set (`None` on the others),
    /// through the ray core's packet query (`geometry::packet`).
    pub fn intersect_packet(
        &self,
        rays: &[Ray; PACKET],
        active: &[bool; PACKET],
    ) -> [Option<SurfaceHit>; PACKET] {
        for _ in active.iter().filter(|&&a| a) {
            ray_stats::count_closest();
        }
        let hits = self.accel.intersect_packet(rays, active);
        std::array::from_fn(|i| hits[i].map(|h| SurfaceHit::new(self, &rays[i], h)))
    }

    pub fn material(&self, id: u32) -> &Material {
        &self.materials[id as usize]
    }

    /// `material(id).is_delta()`, from the table built with the scene.
    #[inline]
    pub fn material_is_delta(&self, id: u32) -> bool {
        self.delta_materials[id as usize]
    }

    /// Number of primitives (for benchmarks and reports).
    pub fn primitive_count(&self) -> usize {
        self.accel.primitive_count()
    }

    /// Which ray core answers this scene's queries ("bvh", "flat (avx512)", …; `--ray-core`).
    pub fn ray_core(&self) -> String {
        self.accel.describe()
    }
}
