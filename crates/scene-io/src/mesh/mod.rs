//! Mesh files: Wavefront OBJ (the TOML and XML paths share one reader), PLY and Mitsuba's
//! serialized format; Mitsuba's `.vol` grids (for `sdfgrid`).

mod le_bytes;
pub(crate) mod obj;
pub(crate) mod ply;
pub(crate) mod serialized;
pub(crate) mod vol;
