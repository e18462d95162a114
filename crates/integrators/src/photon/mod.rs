//! Photon mapping: `pm` (one photon map, a fixed radius or k nearest), `ppm` and `sppm`
//! (progressive: visible points and shrinking radii across passes). Their photon maps, visible
//! points and radius schedules are in `crate::density`.

pub mod pm;
pub mod ppm;
pub mod sppm;
