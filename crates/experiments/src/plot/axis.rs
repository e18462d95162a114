//! Axes: linear or log₁₀ ranges covering the data, their ticks (decades with light 2…9 lines, or
//! 1-2-5 steps) and tick labels.

use plotters::coord::ranged1d::{DefaultFormatting, KeyPointHint};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// One axis: whether it is log₁₀, and the range drawn (in plotted units: log₁₀ of the data on
/// a log axis).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Axis {
    pub(super) log: bool,
    pub(super) lo: f64,
    pub(super) hi: f64,
}

impl Axis {
    /// Data value → plotted value, or None when it cannot be drawn on this axis.
    pub(super) fn to_plot(log: bool, v: f64) -> Option<f64> {
        if !v.is_finite() {
            None
        } else if log {
            if v > 0.0 {
                Some(v.log10())
            } else {
                None
            }
        } else {
            Some(v)
        }
    }

    /// The range covering `values` (plotted units) with a 5 % margin; None when empty.
    pub(super) fn covering(log: bool, values: impl Iterator<Item = f64>) -> Option<Axis> {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in values {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        if !(lo <= hi) {
            return None;
        }
        let span = hi - lo;
        let pad = if span > 0.0 {
            0.05 * span
        } else if log {
            0.5
        } else {
            (lo.abs() * 0.1).max(1.0)
        };
        Some(Axis {
            log,
            lo: lo - pad,
            hi: hi + pad,
        })
    }

    /// (bold ticks with labels, light ticks), in plotted units.
    pub(super) fn ticks(&self) -> (Vec<f64>, Vec<f64>) {
        if self.log {
            log_ticks(self.lo, self.hi)
        } else {
            (linear_ticks(self.lo, self.hi), Vec::new())
        }
    }

    /// Tick labels for `ticks` (plotted units). On a log axis whose ticks leave the range
    /// plain decimals cover, every label is written m×10ᵉ, so one axis reads one way.
    pub(super) fn labeller(&self, ticks: &[f64]) -> impl Fn(&f64) -> String {
        let log = self.log;
        let powers = log
            && ticks
                .iter()
                .any(|&t| !(1e-3..1e5).contains(&10f64.powf(t).abs()));
        move |&v: &f64| {
            if !log {
                format_number(v)
            } else if powers {
                format_power(10f64.powf(v))
            } else {
                format_number(10f64.powf(v))
            }
        }
    }
}

/// Ticks at 1, 2 or 5 × 10ᵏ, about six across [lo, hi].
pub(super) fn linear_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    if !(span > 0.0) || !span.is_finite() {
        return vec![lo];
    }
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * mag);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last)
        .map(|i| {
            let v = i as f64 * step;
            // Snap values that should be 0 (−1e-17 and the like).
            if v.abs() < step * 1e-9 {
                0.0
            } else {
                v
            }
        })
        .collect()
}

/// Log₁₀ ticks over [lo, hi] (exponents): every decade (every 2nd, 3rd… when there are many)
/// with 2…9 as light ticks; with less than two decades in view, 1-2-5 bold and the rest light.
pub(super) fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let (d0, d1) = (lo.floor() as i64, hi.ceil() as i64);
    let inside = |v: f64| v >= lo - 1e-12 && v <= hi + 1e-12;
    let decades = hi - lo;
    let (mut bold, mut light) = (Vec::new(), Vec::new());
    if decades >= 2.0 {
        let every = ((decades / 8.0).ceil() as i64).max(1);
        for d in d0..=d1 {
            let v = d as f64;
            if inside(v) && d.rem_euclid(every) == 0 {
                bold.push(v);
            } else if inside(v) {
                light.push(v);
            }
            if every == 1 {
                for m in 2..=9 {
                    let w = v + (m as f64).log10();
                    if inside(w) {
                        light.push(w);
                    }
                }
            }
        }
    } else {
        for d in d0..=d1 {
            for m in 1..=9 {
                let w = d as f64 + (m as f64).log10();
                if !inside(w) {
                    continue;
                }
                if m == 1 || m == 2 || m == 5 || decades < 0.5 {
                    bold.push(w);
                } else {
                    light.push(w);
                }
            }
        }
        if bold.len() < 2 {
            // Less than a factor of 2 in view: fall back to linear steps in the data.
            let lin = linear_ticks(10f64.powf(lo), 10f64.powf(hi));
            bold = lin
                .into_iter()
                .filter(|v| *v > 0.0)
                .map(f64::log10)
                .collect();
            light.clear();
        }
    }
    (bold, light)
}

/// A linear coordinate over plotted units with our own ticks (plotters' `WithKeyPoints` over
/// f64 takes no label formatter).
pub(super) struct Ticked {
    inner: RangedCoordf64,
    bold: Vec<f64>,
    light: Vec<f64>,
}

impl Ticked {
    pub(super) fn new(axis: &Axis) -> Ticked {
        let (bold, light) = axis.ticks();
        Ticked {
            inner: (axis.lo..axis.hi).into(),
            bold,
            light,
        }
    }
}

impl Ranged for Ticked {
    type ValueType = f64;
    type FormatOption = DefaultFormatting;

    fn range(&self) -> std::ops::Range<f64> {
        self.inner.range()
    }

    fn map(&self, value: &f64, limit: (i32, i32)) -> i32 {
        self.inner.map(value, limit)
    }

    fn key_points<Hint: KeyPointHint>(&self, hint: Hint) -> Vec<f64> {
        if hint.weight().allow_light_points() {
            self.light.clone()
        } else {
            self.bold.clone()
        }
    }
}

/// A tick label: plain decimals between 10⁻³ and 10⁵, else m×10ᵉ with superscripts.
pub fn format_number(v: f64) -> String {
    if v == 0.0 {
        return "0".into();
    }
    if !v.is_finite() {
        return format!("{v}");
    }
    let a = v.abs();
    if (1e-3..1e5).contains(&a) {
        // Enough decimals for 3 significant digits, trailing zeros dropped.
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        return s.replace('-', "−");
    }
    format_power(v)
}

/// m×10ᵉ with a superscript exponent ("10⁻³" when m is 1).
pub fn format_power(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format_number(v);
    }
    // Rounding: 9.9996e-4 must read 10⁻³, not 10×10⁻⁴.
    let mut e = v.abs().log10().floor() as i32;
    if (v.abs() / 10f64.powi(e) * 100.0).round() >= 1000.0 {
        e += 1;
    }
    let m = v / 10f64.powi(e);
    let exp = superscript(e);
    let ms = format!("{m:.2}");
    let ms = ms
        .trim_end_matches('0')
        .trim_end_matches('.')
        .replace('-', "−");
    match ms.as_str() {
        "1" => format!("10{exp}"),
        "−1" => format!("−10{exp}"),
        _ => format!("{ms}×10{exp}"),
    }
}

pub(super) fn superscript(e: i32) -> String {
    const DIGITS: [char; 10] = ['⁰', '¹', '²', '³', '⁴', '⁵', '⁶', '⁷', '⁸', '⁹'];
    let mut s = String::new();
    if e < 0 {
        s.push('⁻');
    }
    for c in e.unsigned_abs().to_string().chars() {
        s.push(DIGITS[c.to_digit(10).unwrap_or(0) as usize]);
    }
    s
}
