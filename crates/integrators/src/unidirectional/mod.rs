//! Estimators that trace from one end only: `pt` (camera paths with next-event estimation and
//! BSDF sampling under MIS), `pt-bsdf` (BSDF sampling alone) and `light` (light paths splatted
//! to the lens).

pub mod light;
pub mod light_lanes;
pub mod light_params;
pub mod pt;
pub mod pt_bsdf;
pub mod pt_lanes;
