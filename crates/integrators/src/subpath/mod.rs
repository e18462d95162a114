//! Subpaths and their joins, owned by no integrator: the walks (`walk`; through media
//! `media_walk`, with the steps every media walk shares in `media_step`), a light vertex joined to
//! the lens, next-event estimation and shadow-ray joins (`connect`), the one bidirectional camera
//! loop (`camera_loop`) and the MIS weight of a strategy from stored densities: the O(k) chain
//! (`strategy_weight`), the oracle, and the O(1) per-vertex recursion (`recursive_weight`).

pub mod camera_loop;
pub mod connect;
pub mod media_step;
pub mod media_walk;
pub mod recursive_weight;
pub mod strategy_weight;
pub mod walk;
