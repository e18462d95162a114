//! The checks Mitsuba applies to `principled` / `principledthin` parameters, shared by the XML
//! and the TOML reader so both refuse the same values with the same words.

/// A principled scalar in [0, max] (1 for all but `diff_trans`, whose range is 0–2).
pub fn scalar_in_range(name: &str, x: f64, max: f32) -> Result<f32, String> {
    if (0.0..=max as f64).contains(&x) {
        Ok(x as f32)
    } else {
        Err(format!("`{name}` must lie in [0, {max}], got {x}"))
    }
}

/// principled's η from `eta` or `specular` (one quantity: Mitsuba refuses both; specular 0.5 by
/// default). A transmitting lobe moves η = 1 (specular 0) off the index-matched interface, as
/// Mitsuba does. `eta_key` is how the file names η (`eta` in XML, `ior` in TOML).
pub fn principled_eta(
    eta: Option<f64>,
    specular: Option<f64>,
    has_spec_trans: bool,
    eta_key: &str,
) -> Result<f32, String> {
    use lt_core::bsdf::Principled;
    match (eta, specular) {
        (Some(_), Some(_)) => Err(format!(
            "give `{eta_key}` or `specular`, not both (they set one quantity)"
        )),
        (Some(x), None) if x > 0.0 && x.is_finite() => Ok(if has_spec_trans && x == 1.0 {
            1.001
        } else {
            x as f32
        }),
        (Some(x), None) => Err(format!("`{eta_key}` must be a positive number, got {x}")),
        (None, specular) => {
            let s = specular.unwrap_or(0.5);
            if !(0.0..1.0 / 0.08).contains(&s) {
                return Err(format!("`specular` must lie in [0, 12.5), got {s}"));
            }
            let s = if has_spec_trans && s == 0.0 {
                1e-3
            } else {
                s as f32
            };
            Ok(Principled::eta_from_specular(s))
        }
    }
}

/// principledthin's η (1.5 by default): positive and finite.
pub fn thin_eta(eta: Option<f64>, eta_key: &str) -> Result<f32, String> {
    match eta {
        None => Ok(1.5),
        Some(x) if x > 0.0 && x.is_finite() => Ok(x as f32),
        Some(x) => Err(format!("`{eta_key}` must be a positive number, got {x}")),
    }
}
