//! Density estimation, shared by the photon family and the VCM family: photon batches and maps
//! (`photons`), camera paths to their first non-delta vertex (`visible`), the progressive
//! state of `ppm` and `sppm` (`progressive`) and the radius convention and schedules (`radius`).

pub mod photons;
pub mod progressive;
pub mod radius;
pub mod surface_merge;
pub mod visible;
