//! Verification tools: programs that hold the integrators to an independent answer.
//!
//! - `mis_check`: `lt mis-check`, every MIS weight against the path-space oracle.

pub mod mis_check;
