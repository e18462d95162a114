//! The path-space core shared by every integrator: geometry, sampling, materials, lights, the
//! camera, scenes, and path vertices with their pdfs in area measure.

pub mod bsdf;
pub mod camera;
pub mod geometry;
pub mod keyed_pcg;
pub mod light;
pub mod math;
pub mod measure;
pub mod medium;
pub mod path;
pub mod primary_space;
pub mod sampling;
pub mod scene;
pub mod shape;
pub mod spatial;
pub mod testing;
pub mod texture;

pub use math::{Color, Vec2, Vec3};
pub use scene::Scene;
