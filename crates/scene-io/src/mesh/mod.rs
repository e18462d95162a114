//! Mesh files: Wavefront OBJ (the TOML and XML paths share one reader) and PLY.

pub(crate) mod obj;
pub(crate) mod ply;
