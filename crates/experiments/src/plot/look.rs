//! How each series is drawn: the Okabe–Ito colour, marker and dash of every series in order.

use super::chart::{Series, Style};
use plotters::style::RGBColor;

/// Okabe & Ito's colour-blind-safe palette (yellow left out: unreadable on white), ordered so
/// that consecutive colours differ in lightness as well as hue.
pub(super) const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),   // blue
    RGBColor(213, 94, 0),    // vermillion
    RGBColor(0, 158, 115),   // bluish green
    RGBColor(0, 0, 0),       // black
    RGBColor(230, 159, 0),   // orange
    RGBColor(204, 121, 167), // reddish purple
    RGBColor(86, 180, 233),  // sky blue
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Marker {
    Circle,
    Square,
    Triangle,
    Diamond,
}

pub(super) const MARKERS: [Marker; 4] = [
    Marker::Circle,
    Marker::Square,
    Marker::Triangle,
    Marker::Diamond,
];

/// How one series is drawn: colour, marker (measured only), whether filled, dashed.
#[derive(Clone, Copy, Debug)]
pub(super) struct Look {
    pub(super) color: RGBColor,
    pub(super) marker: Option<(Marker, bool)>,
    pub(super) dashed: bool,
}

/// Looks for every series, in order (see the module comment for the rules).
pub(super) fn looks(series: &[Series]) -> Vec<Look> {
    let mut next = 0usize;
    let mut measured: Vec<(usize, &str, usize)> = Vec::new(); // (series, name, colour index)
    let mut out = Vec::with_capacity(series.len());
    for (i, s) in series.iter().enumerate() {
        match s.style {
            Style::Measured => {
                let k = next;
                next += 1;
                measured.push((i, &s.name, k));
                // Markers cycle faster than colours and go hollow on the second round of
                // colours, so (colour, marker, fill) stays distinct for 56 series.
                let marker = MARKERS[k % MARKERS.len()];
                let filled = (k / PALETTE.len()).is_multiple_of(2);
                out.push(Look {
                    color: PALETTE[k % PALETTE.len()],
                    marker: Some((marker, filled)),
                    dashed: false,
                });
            }
            Style::Fitted => {
                let parent = measured
                    .iter()
                    .filter(|(_, name, _)| !name.is_empty() && s.name.starts_with(name))
                    .max_by_key(|(_, name, _)| name.len());
                let k = match parent {
                    Some(&(_, _, k)) => k,
                    None => {
                        next += 1;
                        next - 1
                    }
                };
                out.push(Look {
                    color: PALETTE[k % PALETTE.len()],
                    marker: None,
                    dashed: true,
                });
            }
        }
    }
    out
}
