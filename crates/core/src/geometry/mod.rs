//! Rays, primitives and the acceleration structure.

pub mod accel;
pub mod quad;
pub mod ray;
pub mod sphere;
pub mod triangle;

pub use accel::{Accel, PrimHit, Primitive};
pub use ray::{offset_ray_origin, Ray, SHADOW_EPSILON};
