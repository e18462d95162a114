//! Rays, primitives and the acceleration structure.

pub mod accel;
pub mod flat;
pub mod quad;
pub mod ray;
pub mod sphere;
pub mod triangle;

pub use accel::{set_ray_core, Accel, PrimHit, Primitive, RayCore};
pub use ray::{offset_ray_origin, Ray, SHADOW_EPSILON};
