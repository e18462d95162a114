//! Bidirectional path tracing: `bdpt` (one light subpath per camera sample, every strategy
//! (s, t)) and `lvc-bdpt` (connections to vertices drawn from a cache of the pass's light
//! subpaths). Both run the camera loop of `crate::subpath::camera_loop` with their own policy.

pub mod bdpt;
pub mod lvc_bdpt;
