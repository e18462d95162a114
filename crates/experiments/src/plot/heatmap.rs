//! A table of positive numbers drawn as a heat map (SVG and PNG): one coloured cell per value,
//! colour by log₁₀ of the value on a sequential palette (viridis' anchors, dark = small), the
//! value printed in the cell. A value that is not finite and positive is a grey cell marked "—".

use super::{font, register_font, with_suffix, FONT};
use crate::image_io::{write_atomic, write_atomic_with};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::path::Path;

pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Column and row names, left to right and top to bottom.
    pub columns: Vec<String>,
    pub rows: Vec<String>,
    /// `values[row][column]`.
    pub values: Vec<Vec<f64>>,
}

const SIZE: (u32, u32) = (900, 560);

/// Viridis at 0, ¼, ½, ¾, 1.
const PALETTE: [(f64, f64, f64); 5] = [
    (68.0, 1.0, 84.0),
    (59.0, 82.0, 139.0),
    (33.0, 145.0, 140.0),
    (94.0, 201.0, 98.0),
    (253.0, 231.0, 37.0),
];

fn colour(t: f64) -> RGBColor {
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x.floor() as usize).min(3);
    let f = x - i as f64;
    let (a, b) = (PALETTE[i], PALETTE[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Writes `study_dir/<stem>.svg` and `.png` and returns the manifest's figure.
pub fn write_heatmap_figure(
    study_dir: &Path,
    stem: &str,
    h: &HeatMap,
    caption: &str,
) -> Result<crate::manifest::Figure, String> {
    register_font();
    let base = study_dir.join(stem);
    let svg_path = with_suffix(&base, "svg");
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, SIZE).into_drawing_area();
        draw(&root, h).map_err(|e| format!("{}: {e}", svg_path.display()))?;
        root.present()
            .map_err(|e| format!("{}: {e}", svg_path.display()))?;
    }
    let svg = svg.replace(
        &format!("font-family=\"{FONT}\""),
        &format!("font-family=\"{FONT}, Verdana, Arial, sans-serif\""),
    );
    write_atomic(&svg_path, svg.as_bytes())?;
    let png_path = with_suffix(&base, "png");
    let (w, hh) = SIZE;
    let mut rgb = vec![0u8; (w * hh * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, SIZE).into_drawing_area();
        draw(&root, h).map_err(|e| format!("{}: {e}", png_path.display()))?;
        root.present()
            .map_err(|e| format!("{}: {e}", png_path.display()))?;
    }
    let img = image::RgbImage::from_raw(w, hh, rgb).expect("buffer matches size");
    write_atomic_with(&png_path, |tmp| {
        img.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| format!("cannot write PNG {}: {e}", png_path.display()))
    })?;
    Ok(crate::manifest::Figure {
        title: h.title.clone(),
        caption: caption.into(),
        svg: format!("{stem}.svg"),
        png: format!("{stem}.png"),
    })
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    h: &HeatMap,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    root.fill(&WHITE)?;
    let centred = |size: f64| font(size).pos(Pos::new(HPos::Center, VPos::Center));
    let (w, hh) = root.dim_in_pixel();
    let (w, hh) = (w as i32, hh as i32);
    root.draw(&Text::new(h.title.clone(), (w / 2, 24), centred(22.0)))?;
    let logs: Vec<f64> = h
        .values
        .iter()
        .flatten()
        .filter(|v| v.is_finite() && **v > 0.0)
        .map(|v| v.log10())
        .collect();
    let lo = logs.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let span = if hi > lo { hi - lo } else { 1.0 };
    let (left, top, right, bottom) = (130, 60, w - 40, hh - 90);
    let nc = h.columns.len().max(1) as i32;
    let nr = h.rows.len().max(1) as i32;
    let (cw, ch) = ((right - left) / nc, (bottom - top) / nr);
    for (r, line) in h.values.iter().enumerate() {
        for (c, &v) in line.iter().enumerate() {
            let (x0, y0) = (left + c as i32 * cw, top + r as i32 * ch);
            let (fill, text, ink) = if v.is_finite() && v > 0.0 {
                let t = (v.log10() - lo) / span;
                let ink = if t > 0.6 { BLACK } else { WHITE };
                (colour(t), super::format_number(v), ink)
            } else {
                (RGBColor(200, 200, 200), "—".to_string(), BLACK)
            };
            root.draw(&Rectangle::new(
                [(x0, y0), (x0 + cw - 2, y0 + ch - 2)],
                fill.filled(),
            ))?;
            root.draw(&Text::new(
                text,
                (x0 + cw / 2, y0 + ch / 2),
                centred(18.0).color(&ink),
            ))?;
        }
    }
    for (c, name) in h.columns.iter().enumerate() {
        let x = left + c as i32 * cw + cw / 2;
        root.draw(&Text::new(name.clone(), (x, bottom + 18), centred(17.0)))?;
    }
    for (r, name) in h.rows.iter().enumerate() {
        let y = top + r as i32 * ch + ch / 2;
        root.draw(&Text::new(name.clone(), (left / 2, y), centred(17.0)))?;
    }
    root.draw(&Text::new(
        h.x_label.clone(),
        ((left + right) / 2, bottom + 50),
        centred(18.0),
    ))?;
    root.draw(&Text::new(
        h.y_label.clone(),
        (left / 2, top - 20),
        centred(16.0),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::colour;

    #[test]
    fn palette_ends_are_viridis_ends() {
        assert_eq!(colour(0.0), plotters::style::RGBColor(68, 1, 84));
        assert_eq!(colour(1.0), plotters::style::RGBColor(253, 231, 37));
        assert_eq!(colour(-3.0), colour(0.0));
    }
}
