//! Validated construction of media parameters. Each check returns a message naming the parameter
//! and what is wrong with it; the scene loaders prefix it with the file and line.

use super::{Homogeneous, PhaseFunction};
use crate::math::Color;

/// σ (an extinction, absorption or scattering coefficient, per unit length): finite and ≥ 0 in
/// every channel.
pub fn check_sigma(name: &str, c: Color) -> Result<Color, String> {
    match channel_where(c, |v| v.is_finite() && v >= 0.0) {
        None => Ok(c),
        Some(k) => Err(format!(
            "{name} = {} must be finite and non-negative (channel {k} is {})",
            show(c),
            c[k]
        )),
    }
}

/// A single-scattering albedo: in [0, 1] in every channel.
pub fn check_albedo(name: &str, c: Color) -> Result<Color, String> {
    match channel_where(c, |v| (0.0..=1.0).contains(&v)) {
        None => Ok(c),
        Some(k) => Err(format!(
            "{name} = {} must lie in [0, 1] (channel {k} is {})",
            show(c),
            c[k]
        )),
    }
}

/// Mitsuba's `scale` of a medium's σ: finite and ≥ 0.
pub fn check_scale(scale: f32) -> Result<f32, String> {
    if scale.is_finite() && scale >= 0.0 {
        Ok(scale)
    } else {
        Err(format!("scale = {scale} must be finite and non-negative"))
    }
}

impl PhaseFunction {
    /// Ok when the parameters are in range (HG's g in (−1, 1)).
    pub fn check(&self) -> Result<(), String> {
        match *self {
            PhaseFunction::Isotropic => Ok(()),
            PhaseFunction::HenyeyGreenstein { g } => {
                PhaseFunction::henyey_greenstein(g).map(|_| ())
            }
        }
    }
}

impl Homogeneous {
    /// Mitsuba's `homogeneous` given σt and albedo: σt·scale, albedo as is.
    pub fn new(
        sigma_t: Color,
        albedo: Color,
        scale: f32,
        phase: PhaseFunction,
    ) -> Result<Homogeneous, String> {
        let sigma_t = check_sigma("sigma_t", sigma_t)?;
        let albedo = check_albedo("albedo", albedo)?;
        let scale = check_scale(scale)?;
        phase.check()?;
        check_sigma("sigma_t × scale", sigma_t * scale).map(|sigma_t| Homogeneous {
            sigma_t,
            albedo,
            phase,
        })
    }

    /// Mitsuba's `homogeneous` given σa and σs: σt = σa + σs, albedo σs/σt (0 where σt = 0).
    pub fn from_absorption(
        sigma_a: Color,
        sigma_s: Color,
        scale: f32,
        phase: PhaseFunction,
    ) -> Result<Homogeneous, String> {
        let sigma_a = check_sigma("sigma_a", sigma_a)?;
        let sigma_s = check_sigma("sigma_s", sigma_s)?;
        let sigma_t = sigma_a + sigma_s;
        let albedo = Color::select(sigma_t.cmpgt(Color::ZERO), sigma_s / sigma_t, Color::ZERO);
        // σs/σt can round above 1 when σa is a few ulps of σs.
        Homogeneous::new(sigma_t, albedo.min(Color::ONE), scale, phase)
    }
}

fn channel_where(c: Color, ok: impl Fn(f32) -> bool) -> Option<usize> {
    (0..3).find(|&k| !ok(c[k]))
}

fn show(c: Color) -> String {
    format!("({}, {}, {})", c.x, c.y, c.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ISO: PhaseFunction = PhaseFunction::Isotropic;

    #[test]
    fn refuses_bad_parameters_with_a_message_naming_them() {
        let one = Color::ONE;
        let cases: [(Result<Homogeneous, String>, &str); 7] = [
            (
                Homogeneous::new(Color::new(1.0, -0.5, 1.0), one, 1.0, ISO),
                "sigma_t",
            ),
            (
                Homogeneous::new(Color::new(1.0, f32::NAN, 1.0), one, 1.0, ISO),
                "channel 1",
            ),
            (
                Homogeneous::new(Color::splat(f32::INFINITY), one, 1.0, ISO),
                "finite",
            ),
            (
                Homogeneous::new(one, Color::new(0.5, 1.01, 0.5), 1.0, ISO),
                "albedo",
            ),
            (
                Homogeneous::new(one, Color::splat(-0.1), 1.0, ISO),
                "[0, 1]",
            ),
            (Homogeneous::new(one, one, -2.0, ISO), "scale"),
            (
                Homogeneous::new(one, one, 1.0, PhaseFunction::HenyeyGreenstein { g: 1.0 }),
                "between -1 and 1",
            ),
        ];
        for (i, (r, needle)) in cases.into_iter().enumerate() {
            let e = r.expect_err(&format!("case {i} must be refused"));
            assert!(e.contains(needle), "case {i}: {e:?} lacks {needle:?}");
        }
        assert!(
            Homogeneous::from_absorption(one, Color::splat(-1.0), 1.0, ISO)
                .unwrap_err()
                .contains("sigma_s")
        );
        // σ × scale overflowing to ∞ is refused too.
        assert!(Homogeneous::new(Color::splat(3e38), one, 10.0, ISO).is_err());
    }

    #[test]
    fn builds_what_mitsuba_builds() {
        let h = Homogeneous::new(Color::new(1.0, 2.0, 0.0), Color::splat(0.5), 2.0, ISO).unwrap();
        assert_eq!(h.sigma_t, Color::new(2.0, 4.0, 0.0));
        assert_eq!(h.albedo, Color::splat(0.5));
        let h = Homogeneous::from_absorption(
            Color::new(1.0, 0.0, 0.0),
            Color::new(1.0, 2.0, 0.0),
            1.0,
            ISO,
        )
        .unwrap();
        assert_eq!(h.sigma_t, Color::new(2.0, 2.0, 0.0));
        assert_eq!(h.albedo, Color::new(0.5, 1.0, 0.0));
    }
}
