//! The Embree ray core (`--ray-core embree`, built when `build.rs` finds Embree 3): Intel's
//! Embree traverses its own BVH and tests triangles (a parallelogram is given as its two
//! triangles) in its SIMD kernels; spheres, disks, cylinders and sdf voxels are Embree user
//! geometry tested by lt's own routines. Embree's triangle test only proposes: a filter runs lt's
//! own test of the primitive (from the ray's true origin, within (0, t_max)) and rejects what it
//! misses — without it a ray leaving a surface, offset by its rounding bound, was hit again by its
//! own triangle at t ≈ 0 (veach-bidir rendered 7 % dark). The distance reported is lt's own, so
//! hit points and their rounding bounds are those of the portable cores; what can differ is which
//! primitive wins an exact tie and a grazing hit Embree's test rounds away (tests in `accel.rs`).
//!
//! Only `rtcIntersect1`/`rtcOccluded1` are called, so every callback sees one ray (N = 1), whose
//! layout is then `RTCRayHit`'s (Embree 3 API reference, "RTCIntersectFunctionN").

use super::primitive::{PrimHit, Primitive};
use super::ray::Ray;
use super::triangle::ShearedRay;
use crate::math::Vec3;
use obvhs::Boundable;
use std::ffi::c_void;

/// The C API of Embree 3.13 (`rtcore_*.h`), only what this core calls.
#[allow(non_camel_case_types, dead_code)]
mod ffi {
    use std::ffi::{c_char, c_int, c_uint, c_void};

    pub type Device = *mut c_void;
    pub type Scene = *mut c_void;
    pub type Geometry = *mut c_void;

    pub const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
    pub const GEOMETRY_TYPE_USER: c_uint = 120;
    pub const BUFFER_TYPE_INDEX: c_uint = 0;
    pub const BUFFER_TYPE_VERTEX: c_uint = 1;
    pub const FORMAT_UINT3: c_uint = 0x5003;
    pub const FORMAT_FLOAT3: c_uint = 0x9003;
    pub const BUILD_QUALITY_HIGH: c_uint = 2;
    /// No culling of tests by arithmetic shortcuts: watertight triangle tests.
    pub const SCENE_FLAG_ROBUST: c_uint = 1 << 2;
    pub const INVALID_GEOMETRY_ID: c_uint = u32::MAX;

    #[repr(C, align(16))]
    pub struct Ray {
        pub org: [f32; 3],
        pub tnear: f32,
        pub dir: [f32; 3],
        pub time: f32,
        pub tfar: f32,
        pub mask: c_uint,
        pub id: c_uint,
        pub flags: c_uint,
    }

    #[repr(C, align(16))]
    pub struct Hit {
        pub ng: [f32; 3],
        pub u: f32,
        pub v: f32,
        pub prim_id: c_uint,
        pub geom_id: c_uint,
        pub inst_id: [c_uint; 1],
    }

    #[repr(C)]
    pub struct RayHit {
        pub ray: Ray,
        pub hit: Hit,
    }

    #[repr(C)]
    pub struct IntersectContext {
        pub flags: c_uint,
        pub filter: *const c_void,
        pub inst_id: [c_uint; 1],
    }

    #[repr(C, align(16))]
    pub struct Bounds {
        pub lower: [f32; 3],
        pub align0: f32,
        pub upper: [f32; 3],
        pub align1: f32,
    }

    #[repr(C)]
    pub struct BoundsArgs {
        pub user: *mut c_void,
        pub prim_id: c_uint,
        pub time_step: c_uint,
        pub bounds_o: *mut Bounds,
    }

    #[repr(C)]
    pub struct IntersectArgs {
        pub valid: *mut c_int,
        pub user: *mut c_void,
        pub prim_id: c_uint,
        pub context: *mut IntersectContext,
        pub rayhit: *mut RayHit,
        pub n: c_uint,
        pub geom_id: c_uint,
    }

    #[repr(C)]
    pub struct FilterArgs {
        pub valid: *mut c_int,
        pub user: *mut c_void,
        pub context: *mut IntersectContext,
        pub ray: *mut Ray,
        pub hit: *mut Hit,
        pub n: c_uint,
    }

    #[repr(C)]
    pub struct OccludedArgs {
        pub valid: *mut c_int,
        pub user: *mut c_void,
        pub prim_id: c_uint,
        pub context: *mut IntersectContext,
        pub ray: *mut Ray,
        pub n: c_uint,
        pub geom_id: c_uint,
    }

    pub type BoundsFn = unsafe extern "C" fn(*const BoundsArgs);
    pub type IntersectFn = unsafe extern "C" fn(*const IntersectArgs);
    pub type OccludedFn = unsafe extern "C" fn(*const OccludedArgs);
    pub type FilterFn = unsafe extern "C" fn(*const FilterArgs);

    extern "C" {
        pub fn rtcNewDevice(config: *const c_char) -> Device;
        pub fn rtcReleaseDevice(device: Device);
        pub fn rtcGetDeviceError(device: Device) -> c_uint;
        pub fn rtcNewScene(device: Device) -> Scene;
        pub fn rtcSetSceneFlags(scene: Scene, flags: c_uint);
        pub fn rtcSetSceneBuildQuality(scene: Scene, quality: c_uint);
        pub fn rtcCommitScene(scene: Scene);
        pub fn rtcReleaseScene(scene: Scene);
        pub fn rtcNewGeometry(device: Device, kind: c_uint) -> Geometry;
        pub fn rtcSetNewGeometryBuffer(
            geometry: Geometry,
            kind: c_uint,
            slot: c_uint,
            format: c_uint,
            byte_stride: usize,
            count: usize,
        ) -> *mut c_void;
        pub fn rtcSetGeometryUserPrimitiveCount(geometry: Geometry, count: c_uint);
        pub fn rtcSetGeometryUserData(geometry: Geometry, ptr: *mut c_void);
        pub fn rtcSetGeometryBoundsFunction(geometry: Geometry, f: BoundsFn, user: *mut c_void);
        pub fn rtcSetGeometryIntersectFunction(geometry: Geometry, f: IntersectFn);
        pub fn rtcSetGeometryOccludedFunction(geometry: Geometry, f: OccludedFn);
        pub fn rtcSetGeometryIntersectFilterFunction(geometry: Geometry, f: FilterFn);
        pub fn rtcSetGeometryOccludedFilterFunction(geometry: Geometry, f: FilterFn);
        pub fn rtcCommitGeometry(geometry: Geometry);
        pub fn rtcAttachGeometryByID(scene: Scene, geometry: Geometry, id: c_uint);
        pub fn rtcReleaseGeometry(geometry: Geometry);
        pub fn rtcIntersect1(scene: Scene, context: *mut IntersectContext, rayhit: *mut RayHit);
        pub fn rtcOccluded1(scene: Scene, context: *mut IntersectContext, ray: *mut Ray);
    }

    impl IntersectContext {
        /// `rtcInitIntersectContext` (a header-inline function in C): incoherent rays, no filter.
        pub fn new() -> IntersectContext {
            IntersectContext {
                flags: 0,
                filter: std::ptr::null(),
                inst_id: [INVALID_GEOMETRY_ID],
            }
        }
    }
}

/// Embree's geometry ids: every triangle in one mesh, every other primitive in one user geometry.
const TRIANGLES: u32 = 0;
const USER: u32 = 1;

/// What the callbacks read: every primitive, and lt's index of each Embree primitive.
struct Lookup {
    prims: Box<[Primitive]>,
    /// Of each Embree triangle (two per parallelogram).
    triangle_owner: Vec<u32>,
    /// Of each user primitive.
    user_owner: Vec<u32>,
}

/// One query's context: Embree's, extended (it hands the callbacks the pointer it was given, so
/// they read the rest) with what lt's own tests take.
#[repr(C)]
struct Query {
    ctx: ffi::IntersectContext,
    sheared: ShearedRay,
    o: Vec3,
    d: Vec3,
    t_max: f32,
}

impl Query {
    fn new(ray: &Ray, sheared: &ShearedRay) -> Query {
        Query {
            ctx: ffi::IntersectContext::new(),
            sheared: *sheared,
            o: ray.o,
            d: ray.d,
            t_max: ray.t_max,
        }
    }
}

/// An Embree device and committed scene over a list of primitives.
pub struct EmbreeScene {
    device: ffi::Device,
    scene: ffi::Scene,
    /// Kept alive (and unmoved, being boxed) for the callbacks, which hold a pointer to it.
    lookup: Box<Lookup>,
}

// SAFETY: a committed Embree scene is read-only and Embree documents rtcIntersect1/rtcOccluded1 as
// safe to call from any number of threads at once; nothing here is mutated after `new`.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: both handles came from Embree in `new` and are released once, scene first.
        unsafe {
            ffi::rtcReleaseScene(self.scene);
            ffi::rtcReleaseDevice(self.device);
        }
    }
}

unsafe extern "C" fn user_bounds(args: *const ffi::BoundsArgs) {
    // SAFETY: Embree passes valid arguments and the user pointer given in `new`.
    let a = unsafe { &*args };
    let look = unsafe { &*(a.user as *const Lookup) };
    let b = look.prims[look.user_owner[a.prim_id as usize] as usize].aabb();
    let out = unsafe { &mut *a.bounds_o };
    out.lower = [b.min.x, b.min.y, b.min.z];
    out.upper = [b.max.x, b.max.y, b.max.z];
}

unsafe extern "C" fn user_intersect(args: *const ffi::IntersectArgs) {
    // SAFETY: as above; N = 1 (only rtcIntersect1 is called), so `rayhit` is an RTCRayHit.
    let a = unsafe { &*args };
    if a.n != 1 || unsafe { *a.valid } == 0 {
        return;
    }
    let look = unsafe { &*(a.user as *const Lookup) };
    let rh = unsafe { &mut *a.rayhit };
    let (o, d) = (Vec3::from(rh.ray.org), Vec3::from(rh.ray.dir));
    let p = &look.prims[look.user_owner[a.prim_id as usize] as usize];
    let t = p.intersect(&ShearedRay::UNUSED, o, d, rh.ray.tfar);
    if t < rh.ray.tfar {
        rh.ray.tfar = t;
        rh.hit.prim_id = a.prim_id;
        rh.hit.geom_id = a.geom_id;
        rh.hit.inst_id = unsafe { (*a.context).inst_id };
    }
}

unsafe extern "C" fn user_occluded(args: *const ffi::OccludedArgs) {
    // SAFETY: as above; `ray` is an RTCRay. Embree marks an occluded ray by tfar = −∞.
    let a = unsafe { &*args };
    if a.n != 1 || unsafe { *a.valid } == 0 {
        return;
    }
    let look = unsafe { &*(a.user as *const Lookup) };
    let r = unsafe { &mut *a.ray };
    let (o, d) = (Vec3::from(r.org), Vec3::from(r.dir));
    let p = &look.prims[look.user_owner[a.prim_id as usize] as usize];
    if p.intersect(&ShearedRay::UNUSED, o, d, r.tfar).is_finite() {
        r.tfar = f32::NEG_INFINITY;
    }
}

/// Embree's triangle hit stands only if lt's own test of the primitive hits within (0, t_max).
unsafe extern "C" fn triangle_filter(args: *const ffi::FilterArgs) {
    // SAFETY: as above; N = 1, so `hit` is an RTCHit; the context is the `Query` this file
    // passed to rtcIntersect1/rtcOccluded1.
    let a = unsafe { &*args };
    if a.n != 1 || unsafe { *a.valid } == 0 {
        return;
    }
    let look = unsafe { &*(a.user as *const Lookup) };
    let q = unsafe { &*(a.context as *const Query) };
    let hit = unsafe { &*a.hit };
    let p = &look.prims[look.triangle_owner[hit.prim_id as usize] as usize];
    if !p.intersect(&q.sheared, q.o, q.d, q.t_max).is_finite() {
        unsafe { *a.valid = 0 };
    }
}

impl EmbreeScene {
    /// Builds Embree's structures over `prims` (high build quality, robust tests). None when
    /// Embree cannot start a device or reports an error (the caller falls back to the BVH).
    pub fn new(prims: &[Primitive]) -> Option<EmbreeScene> {
        let mut vertices: Vec<[f32; 3]> = Vec::new();
        let mut triangles: Vec<[u32; 3]> = Vec::new();
        let mut triangle_owner = Vec::new();
        let mut user_owner = Vec::new();
        for (i, p) in prims.iter().enumerate() {
            let base = vertices.len() as u32;
            match *p {
                Primitive::Triangle { p, .. } => {
                    vertices.extend(p.map(|v| v.to_array()));
                    triangles.push([base, base + 1, base + 2]);
                    triangle_owner.push(i as u32);
                }
                Primitive::Quad { q, .. } => {
                    let c = [q.p0, q.p0 + q.e1, q.p0 + q.e1 + q.e2, q.p0 + q.e2];
                    vertices.extend(c.map(|v| v.to_array()));
                    triangles.push([base, base + 1, base + 2]);
                    triangles.push([base, base + 2, base + 3]);
                    triangle_owner.extend([i as u32; 2]);
                }
                _ => user_owner.push(i as u32),
            }
        }
        let lookup = Box::new(Lookup {
            prims: prims.into(),
            triangle_owner,
            user_owner,
        });
        let ptr = &*lookup as *const Lookup as *mut c_void;
        // SAFETY: each call gets handles Embree returned and buffers of the sizes it was asked
        // for; the geometries are released after attaching (the scene holds its own reference).
        unsafe {
            let device = ffi::rtcNewDevice(std::ptr::null());
            if device.is_null() {
                return None;
            }
            let scene = ffi::rtcNewScene(device);
            ffi::rtcSetSceneFlags(scene, ffi::SCENE_FLAG_ROBUST);
            ffi::rtcSetSceneBuildQuality(scene, ffi::BUILD_QUALITY_HIGH);
            if !triangles.is_empty() {
                let g = ffi::rtcNewGeometry(device, ffi::GEOMETRY_TYPE_TRIANGLE);
                let vb = ffi::rtcSetNewGeometryBuffer(
                    g,
                    ffi::BUFFER_TYPE_VERTEX,
                    0,
                    ffi::FORMAT_FLOAT3,
                    12,
                    vertices.len(),
                ) as *mut [f32; 3];
                let ib = ffi::rtcSetNewGeometryBuffer(
                    g,
                    ffi::BUFFER_TYPE_INDEX,
                    0,
                    ffi::FORMAT_UINT3,
                    12,
                    triangles.len(),
                ) as *mut [u32; 3];
                if !vb.is_null() && !ib.is_null() {
                    std::ptr::copy_nonoverlapping(vertices.as_ptr(), vb, vertices.len());
                    std::ptr::copy_nonoverlapping(triangles.as_ptr(), ib, triangles.len());
                }
                ffi::rtcSetGeometryUserData(g, ptr);
                ffi::rtcSetGeometryIntersectFilterFunction(g, triangle_filter);
                ffi::rtcSetGeometryOccludedFilterFunction(g, triangle_filter);
                ffi::rtcCommitGeometry(g);
                ffi::rtcAttachGeometryByID(scene, g, TRIANGLES);
                ffi::rtcReleaseGeometry(g);
            }
            if !lookup.user_owner.is_empty() {
                let g = ffi::rtcNewGeometry(device, ffi::GEOMETRY_TYPE_USER);
                ffi::rtcSetGeometryUserPrimitiveCount(g, lookup.user_owner.len() as u32);
                ffi::rtcSetGeometryUserData(g, ptr);
                ffi::rtcSetGeometryBoundsFunction(g, user_bounds, ptr);
                ffi::rtcSetGeometryIntersectFunction(g, user_intersect);
                ffi::rtcSetGeometryOccludedFunction(g, user_occluded);
                ffi::rtcCommitGeometry(g);
                ffi::rtcAttachGeometryByID(scene, g, USER);
                ffi::rtcReleaseGeometry(g);
            }
            ffi::rtcCommitScene(scene);
            let built = EmbreeScene {
                device,
                scene,
                lookup,
            };
            (ffi::rtcGetDeviceError(device) == 0).then_some(built)
        }
    }

    fn embree_ray(ray: &Ray) -> ffi::Ray {
        ffi::Ray {
            org: ray.o.to_array(),
            tnear: 0.0,
            dir: ray.d.to_array(),
            time: 0.0,
            tfar: ray.t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    /// Closest hit within (0, t_max): the primitive Embree finds, at lt's own distance to it.
    #[inline]
    pub fn closest(&self, prims: &[Primitive], ray: &Ray, sheared: &ShearedRay) -> Option<PrimHit> {
        let mut rh = ffi::RayHit {
            ray: Self::embree_ray(ray),
            hit: ffi::Hit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: ffi::INVALID_GEOMETRY_ID,
                geom_id: ffi::INVALID_GEOMETRY_ID,
                inst_id: [ffi::INVALID_GEOMETRY_ID],
            },
        };
        let mut q = Query::new(ray, sheared);
        // SAFETY: a committed scene, a valid context and ray-hit (16-byte aligned by its type).
        unsafe { ffi::rtcIntersect1(self.scene, &mut q.ctx, &mut rh) };
        let (geom, id) = (rh.hit.geom_id, rh.hit.prim_id as usize);
        let (prim, t) = match geom {
            TRIANGLES => {
                let prim = self.lookup.triangle_owner[id];
                let own = prims[prim as usize].intersect(sheared, ray.o, ray.d, ray.t_max);
                (prim, if own.is_finite() { own } else { rh.ray.tfar })
            }
            // The user callbacks already report lt's own distance.
            USER => (self.lookup.user_owner[id], rh.ray.tfar),
            _ => return None,
        };
        Some(PrimHit { t, prim })
    }

    /// True when anything blocks the ray within (0, t_max).
    #[inline]
    pub fn occluded(&self, ray: &Ray, sheared: &ShearedRay) -> bool {
        let mut r = Self::embree_ray(ray);
        let mut q = Query::new(ray, sheared);
        // SAFETY: as in `closest`.
        unsafe { ffi::rtcOccluded1(self.scene, &mut q.ctx, &mut r) };
        r.tfar == f32::NEG_INFINITY
    }
}
