//! Rays, primitives and the acceleration structure.

pub mod accel;
#[cfg(lt_embree)]
pub mod embree;
pub mod flat;
pub mod packet;
pub mod primitive;
pub mod quad;
pub mod quadric;
pub mod ray;
pub mod sdf;
pub mod segment_hits;
pub mod soa;
pub mod sphere;
pub mod triangle;
pub mod triangle_pack;
pub mod wide;

pub use accel::{set_ray_core, Accel, RayCore};
pub use primitive::{PrimHit, Primitive};
pub use ray::{offset_ray_origin, Ray, SHADOW_EPSILON};
