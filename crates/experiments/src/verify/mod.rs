//! Verification tools: programs that hold the integrators to an independent answer.
//!
//! - `mis_check`: `lt mis-check`, every MIS weight against the path-space oracle.
//! - `strategies`: Veach's path pyramid (`lt render --strategies`), bdpt's image split by (s, t).
//! - `mitsuba_suite`: Mitsuba 3's render-test suite, judged with lt's own standard errors.

pub mod mis_check;
pub mod mitsuba_suite;
pub mod strategies;
