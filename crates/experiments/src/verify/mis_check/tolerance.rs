//! How far an integrator's MIS weight may stray from the oracle's, for `lt mis-check`: the
//! relative mismatch, the fixed floor τ and a path's condition κ (see `pt_bdpt` and `vcm_bpm`).

use lt_core::path::Path;

/// Default tolerance of check (a), relative (see the module docs and `lt mis-check --help`).
pub const DEFAULT_TOLERANCE: f64 = 1e-3;
/// Tolerance of check (b), absolute on Σ w − 1 (f64 arithmetic on consistent densities for bdpt;
/// two complementary f32 weights for pt).
pub const SUM_TOLERANCE: f64 = 1e-6;
/// Stricter levels of (a) whose exceedances the table counts, for the record.
pub const STRICT_LEVELS: [f64; 3] = [1e-4, 1e-5, 1e-6];

/// Relative difference |a − b| / max(|a|, |b|) (0 when both are 0; NaN counts as 1).
pub fn relative(a: f64, b: f64) -> f64 {
    if a == b {
        return 0.0;
    }
    let r = (a - b).abs() / a.abs().max(b.abs());
    if r.is_nan() {
        1.0
    } else {
        r
    }
}

/// How far the oracle's densities can stray from the walk's on this path: `Path::condition`.
pub fn condition(path: &Path) -> f64 {
    path.condition()
}

/// The tolerance of (a) for a path of condition `kappa`: `tolerance`, or κ when larger.
pub fn path_tolerance(tolerance: f64, kappa: f64) -> f64 {
    tolerance.max(kappa)
}
