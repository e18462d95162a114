//! Gather radii of the photon-mapping family, shared by them and owned by none: where the initial
//! radius comes from and how it shrinks.
//!
//! **Convention.** The initial radius r₀ is relative to the pixel footprint at the visible point
//! (`radius_px`, the default, 2 footprints) or to the scene's bounding-sphere diameter
//! (`radius_scene`), or absolute in scene units (`radius`) only on request. It shrinks by
//! Knaus & Zwicker's global schedule (2011, eq. 20) by default — r²ᵢ₊₁ = r²ᵢ (i + α)/(i + 1), the
//! same for every point, so r²ᵢ ∝ i^(α−1) — or by Hachisuka et al.'s per-point update (2008,
//! eqs. 5–8) with `radius_update = local`: r² ← r² (N + αM)/(N + M), N ← N + αM after a pass that
//! gathered M photons. With r² ∝ N^(α−1), variance falls as N^−α and bias as N^(α−1): MSE ∝
//! N^−min(α, 2−2α), best at α = 2/3 (Knaus & Zwicker 2011; Kaplanyan & Dachsbacher 2013).

use crate::density::visible::VisiblePoint;
use crate::params::ParamReader;
use lt_core::Scene;

/// Where r₀ comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InitialRadius {
    /// This many pixel footprints at the visible point.
    Pixels(f32),
    /// This fraction of the scene's bounding-sphere diameter.
    Scene(f32),
    /// Scene units.
    Absolute(f32),
}

/// The default r₀: two pixel footprints.
pub const DEFAULT_RADIUS_PX: f32 = 2.0;

impl InitialRadius {
    /// Reads `radius_px`, `radius_scene` and `radius` (at most one of them).
    pub fn read(r: &ParamReader, who: &str) -> Result<InitialRadius, String> {
        let px = r.get::<f32>("radius_px")?;
        let scene = r.get::<f32>("radius_scene")?;
        let abs = r.get::<f32>("radius")?;
        let given: Vec<InitialRadius> = [
            px.map(InitialRadius::Pixels),
            scene.map(InitialRadius::Scene),
            abs.map(InitialRadius::Absolute),
        ]
        .into_iter()
        .flatten()
        .collect();
        let chosen = match given.as_slice() {
            [] => InitialRadius::Pixels(DEFAULT_RADIUS_PX),
            [one] => *one,
            _ => {
                return Err(format!(
                    "{who}: give one of radius_px, radius_scene and radius, not several"
                ))
            }
        };
        let v = match chosen {
            InitialRadius::Pixels(v) | InitialRadius::Scene(v) | InitialRadius::Absolute(v) => v,
        };
        if !(v > 0.0 && v.is_finite()) {
            return Err(format!(
                "{who}: the radius must be a positive number, got {v}"
            ));
        }
        Ok(chosen)
    }

    /// r₀ at a visible point.
    #[inline]
    pub fn at(self, scene: &Scene, vp: &VisiblePoint) -> f32 {
        match self {
            InitialRadius::Pixels(k) => k * vp.footprint,
            InitialRadius::Scene(f) => f * 2.0 * scene.bounding_sphere.1,
            InitialRadius::Absolute(r) => r,
        }
    }

    /// A warning when an absolute radius is far from the pixel footprint it is meant to resemble
    /// (`mean_footprint` over a pass's visible points): outside 1/4 … 16 footprints, the estimate
    /// is either noise or blur.
    pub fn warning(self, mean_footprint: f64) -> Option<String> {
        let InitialRadius::Absolute(r) = self else {
            return None;
        };
        let ratio = r as f64 / mean_footprint;
        (!(0.25..=16.0).contains(&ratio)).then(|| {
            format!(
                "radius = {r} is {ratio:.3} mean pixel footprints ({mean_footprint:.3e}); \
                 radius_px is the footprint-relative alternative"
            )
        })
    }

    pub fn describe(self) -> String {
        match self {
            InitialRadius::Pixels(k) => format!("{k} pixel footprints"),
            InitialRadius::Scene(f) => format!("{f} × scene diameter"),
            InitialRadius::Absolute(r) => format!("{r} scene units"),
        }
    }
}

/// How radii shrink from pass to pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Update {
    /// Knaus & Zwicker's schedule, the same for every point.
    Global,
    /// Hachisuka et al.'s per-point (per-pixel) statistics.
    Local,
    /// vcm's pure power law r²ᵢ = r²₁ i^(α−1) (`connect_merge`, as in SmallVCM), the same for
    /// every point: lets the radius study run vcm's merging schedule at frozen points.
    Power,
}

impl Update {
    pub fn parse(s: &str) -> Result<Update, String> {
        match s {
            "global" => Ok(Update::Global),
            "local" => Ok(Update::Local),
            "power" => Ok(Update::Power),
            _ => Err(format!(
                "unknown radius_update '{s}' (known: global, local, power)"
            )),
        }
    }
}

/// Reads `alpha` (default 2/3), which must lie in (0, 1].
pub fn read_alpha(r: &ParamReader, who: &str) -> Result<f64, String> {
    let a = r.get::<f64>("alpha")?.unwrap_or(2.0 / 3.0);
    if !(a > 0.0 && a <= 1.0) {
        return Err(format!("{who}: alpha must be in (0, 1], got {a}"));
    }
    Ok(a)
}

/// r²ᵢ / r²₁ of vcm's schedule for pass i (1-based): i^(α−1).
pub fn power_scale2(pass: u32, alpha: f64) -> f64 {
    (pass as f64).powf(alpha - 1.0)
}

/// r²ᵢ / r²₁ of the global schedule for pass i (1-based): Π_{j<i} (j + α)/(j + 1).
pub fn global_scale2(pass: u32, alpha: f64) -> f64 {
    (1..pass).fold(1.0, |s, j| s * (j as f64 + alpha) / (j as f64 + 1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn global_schedule_follows_its_power_law() {
        // r²ᵢ ∝ i^(α−1) asymptotically: Π (j+α)/(j+1) = Γ(i+α)/(Γ(1+α) Γ(i+1)) ~ i^(α−1)/Γ(1+α).
        for alpha in [0.3, 2.0 / 3.0, 0.9] {
            let (a, b) = (global_scale2(1000, alpha), global_scale2(8000, alpha));
            let slope = (b / a).ln() / 8f64.ln();
            assert!(
                (slope - (alpha - 1.0)).abs() < 1e-3,
                "α {alpha}: slope {slope}"
            );
        }
        assert_eq!(global_scale2(1, 0.5), 1.0);
        assert_eq!(global_scale2(2, 0.5), 0.75);
        assert_eq!(global_scale2(5, 1.0), 1.0);
    }
}
