//! `lt mis-check`: samples paths with an integrator's own code (through its `Recorder` hooks) and
//! holds the MIS weights it applied to the from-scratch oracle of `lt_core::path`.
//!
//! - `pt_bdpt`: pt's, bdpt's and lvc-bdpt's weights (connection techniques; lvc-bdpt's counted
//!   n_conn = N / L̄ times, `connection_count`), and bdpt's (lvc-bdpt's) replayed for every
//!   technique of the path.
//! - `vcm_bpm`: vcm's and bpm's (connections and merges), and their recursion replayed.
//! - `tolerance`: how far a weight may stray from the oracle's.
//! - `report`: the one report both checkers fill, a row per path length.

pub mod pt_bdpt;
pub mod report;
pub mod tolerance;
pub mod vcm_bpm;
