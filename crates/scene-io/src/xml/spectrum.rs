//! Spectra turned into linear sRGB exactly as Mitsuba 3's RGB variants do when they load a
//! scene (its RGB reference images depend on this conversion, so it is not an approximation):
//!
//! - wavelength:value pairs: the spectrum, linear between its samples and zero outside them, is
//!   sampled at 1000 evenly spaced wavelengths spanning 360–830 nm (both ends included) against
//!   the tabulated CIE 1931 colour-matching functions (`cie_table`) — weighted by the D65
//!   illuminant except inside an emitter —, the sum scaled by the step (470/1000 nm) and the
//!   ȳ normalisation, then taken from XYZ to linear sRGB; negative channels become 0, and a
//!   bounded parameter (a reflectance) is clamped to [0, 1];
//! - one value v: a reflectance or other non-emitter parameter is v in every channel; inside an
//!   emitter it is the equal-energy spectrum, XYZ = (v, v, v), in sRGB (pinkish, not grey).

use super::cie_table::{CIE_D65, CIE_MAX, CIE_MIN, CIE_XYZ, CIE_Y_NORMALIZATION};

/// Wavelength samples of Mitsuba's conversion.
const STEPS: usize = 1000;

/// XYZ → linear sRGB (D65 white), the matrix Mitsuba uses.
const XYZ_TO_SRGB: [[f64; 3]; 3] = [
    [3.240479, -1.537150, -0.498535],
    [-0.969256, 1.875991, 0.041556],
    [0.055648, -0.204043, 1.057311],
];

/// How a spectral parameter converts (Mitsuba decides by where the parameter is).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum SpectrumUse {
    /// A reflectance: D65-weighted, clamped to [0, 1].
    Bounded,
    /// Another surface parameter (a conductor's η and k): D65-weighted, clamped below at 0.
    Unbounded,
    /// Inside an emitter: unweighted, clamped below at 0.
    Emission,
}

/// "400:0.1, 500:0.5, …" as (wavelength, value) pairs, wavelengths increasing.
pub(super) fn parse_pairs(s: &str) -> Result<Vec<(f64, f64)>, String> {
    let mut out: Vec<(f64, f64)> = Vec::new();
    for item in s.split(',').map(str::trim).filter(|w| !w.is_empty()) {
        let Some((a, b)) = item.split_once(':') else {
            return Err(format!("`{item}` is not wavelength:value"));
        };
        let (Ok(l), Ok(v)) = (a.trim().parse::<f64>(), b.trim().parse::<f64>()) else {
            return Err(format!("`{item}` is not a pair of numbers"));
        };
        if !l.is_finite() || !v.is_finite() {
            return Err(format!("`{item}` is not finite"));
        }
        if out.last().is_some_and(|&(p, _)| !(l > p)) {
            return Err(format!("wavelengths must increase (`{item}`)"));
        }
        out.push((l, v));
    }
    if out.len() < 2 {
        return Err("a spectrum needs at least two wavelength:value pairs".into());
    }
    Ok(out)
}

/// A table at whole nanometres from CIE_MIN, linear between knots (l within the table).
fn table<const N: usize, T: Copy>(t: &[T; N], l: f64, get: impl Fn(T) -> f64) -> f64 {
    let x = (l - CIE_MIN).clamp(0.0, (N - 1) as f64);
    let i = (x as usize).min(N - 2);
    let u = x - i as f64;
    get(t[i]) * (1.0 - u) + get(t[i + 1]) * u
}

/// The pairs' linear interpolant at l (l within their range).
fn interpolate(pairs: &[(f64, f64)], l: f64) -> f64 {
    let k = pairs
        .partition_point(|&(w, _)| w <= l)
        .clamp(1, pairs.len() - 1);
    let ((l0, v0), (l1, v1)) = (pairs[k - 1], pairs[k]);
    v0 + (v1 - v0) * (l - l0) / (l1 - l0)
}

fn xyz_to_srgb(xyz: [f64; 3]) -> [f64; 3] {
    XYZ_TO_SRGB.map(|row| row[0] * xyz[0] + row[1] * xyz[1] + row[2] * xyz[2])
}

fn clamped(rgb: [f64; 3], usage: SpectrumUse) -> [f64; 3] {
    match usage {
        SpectrumUse::Bounded => rgb.map(|v| v.clamp(0.0, 1.0)),
        _ => rgb.map(|v| v.max(0.0)),
    }
}

/// Linear sRGB of wavelength:value pairs (see the module docs).
pub(super) fn pairs_to_rgb(pairs: &[(f64, f64)], usage: SpectrumUse) -> [f64; 3] {
    let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
    let mut xyz = [0.0f64; 3];
    for i in 0..STEPS {
        let l = CIE_MIN + (i as f64 / (STEPS - 1) as f64) * (CIE_MAX - CIE_MIN);
        if l < first || l > last {
            continue;
        }
        let mut w = interpolate(pairs, l);
        if usage != SpectrumUse::Emission {
            w *= table(&CIE_D65, l, |v| v as f64);
        }
        for (k, c) in xyz.iter_mut().enumerate() {
            *c += w * table(&CIE_XYZ, l, |r| r[k] as f64);
        }
    }
    let scale = (CIE_MAX - CIE_MIN) / STEPS as f64 * CIE_Y_NORMALIZATION;
    clamped(xyz_to_srgb(xyz.map(|c| c * scale)), usage)
}

/// Linear sRGB of a constant spectrum (see the module docs).
pub(super) fn constant_to_rgb(v: f64, usage: SpectrumUse) -> [f64; 3] {
    match usage {
        SpectrumUse::Emission => clamped(xyz_to_srgb([v; 3]), usage),
        _ => [v; 3],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(ours: [f64; 3], theirs: [f64; 3]) {
        for k in 0..3 {
            // Mitsuba sums its 1000 samples in f32 (rounding grows like √1000 · 2⁻²⁴ ≈ 2e-6)
            // and its figures are printed to 6 digits; the analytic fit this replaced was 1e-2 off.
            assert!(
                (ours[k] - theirs[k]).abs() <= 1e-5 * theirs[k].abs().max(0.1),
                "{ours:?} vs Mitsuba {theirs:?}"
            );
        }
    }

    /// Mitsuba 3.9.1's own figures (`scalar_rgb`, read back with `mi.traverse` from a loaded
    /// diffuse reflectance, area-emitter radiance or conductor η).
    #[test]
    fn xml_spectrum_to_rgb_is_mitsubas() {
        let p = |s| parse_pairs(s).unwrap();
        use SpectrumUse::*;
        let three = p("400:0.1, 500:0.5, 600:0.9");
        close(
            pairs_to_rgb(&three, Bounded),
            [0.223602, 0.711799, 0.274743],
        );
        close(
            pairs_to_rgb(&three, Emission),
            [0.276843, 0.688619, 0.240435],
        );
        let four = p("400:0.2, 500:0.5, 600:0.8, 700:0.9");
        close(pairs_to_rgb(&four, Bounded), [0.880858, 0.631926, 0.321875]);
        close(pairs_to_rgb(&four, Emission), [1.0364, 0.602968, 0.283548]);
        let flat = p("400:0.78, 500:0.78, 600:0.78, 700:0.78");
        close(pairs_to_rgb(&flat, Bounded), [0.776367, 0.77981, 0.776029]);
        let light = p("400:0, 500:8, 600:15.6, 700:18.4");
        close(pairs_to_rgb(&light, Emission), [20.7108, 10.8546, 2.77115]);
        // Out of gamut: a reflectance is clamped to [0, 1], a conductor's η only below.
        let wild = p("400:0.2, 500:1.5, 600:0.8");
        close(pairs_to_rgb(&wild, Bounded), [0.0, 1.0, 0.880733]);
        close(pairs_to_rgb(&wild, Unbounded), [0.0, 1.29492, 0.880733]);
        close(
            constant_to_rgb(0.5, Emission),
            [0.602397, 0.474146, 0.454458],
        );
        close(constant_to_rgb(0.5, Bounded), [0.5; 3]);
        close(constant_to_rgb(0.789, Unbounded), [0.789; 3]);
    }
}
