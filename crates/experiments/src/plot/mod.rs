//! Charts the studies draw, written as SVG and PNG with the font that ships in the repository
//! (no system fonts). The studies describe a chart; this module alone knows plotters.
//!
//! - Axes are linear or log₁₀ (`log_x`, `log_y`). A log axis is drawn as a linear axis over
//!   log₁₀ of the data with its own ticks: decades (and 2…9 between them as light lines), or
//!   1-2-5 steps when less than two decades are in view.
//! - Points that are not finite, or not positive on a log axis, are skipped (a skipped point
//!   breaks the line); a chart with nothing left to draw still writes both files, saying
//!   "no data". Nothing here panics on data.
//! - An error bar is drawn for each point with a finite `y_interval`; on a log y axis a
//!   non-positive lower end (a bias² interval that includes 0) runs to the bottom of the plot.
//! - Colours are the Okabe–Ito palette (colour-blind safe, ordered so neighbours differ in
//!   lightness) and each measured series also gets its own marker shape, so the series stay
//!   apart in grayscale. A `Style::Fitted` series is a dashed line without markers, in the colour
//!   of the measured series whose name is the longest prefix of its own name ("pt" → "pt fit"),
//!   or the next colour when there is none.
//! - The legend sits in a column right of the plot, so it never covers data.
//! - Text is DejaVu Sans (`assets/fonts/`), embedded and registered with plotters' `ab_glyph`
//!   backend; the SVG names the same family with generic fall-backs for viewers without it.
//!
//! `chart`: what a study describes; `axis`: ranges, ticks and tick labels; `look`: each series'
//! colour, marker and dash; this file draws them.

mod axis;
mod chart;
pub mod heatmap;
mod look;

pub use axis::{format_number, format_power};
pub use chart::{Chart, Series, Style};

use crate::image_io::{write_atomic, write_atomic_with};
use axis::{Axis, Ticked};
use look::{looks, Marker};
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use plotters::style::FontStyle;
use std::path::{Path, PathBuf};
use std::sync::Once;

/// Pixel size of both the PNG and the SVG canvas.
pub const CHART_SIZE: (u32, u32) = (960, 600);

/// The family name the embedded font is registered under (and the SVG asks for).
const FONT: &str = "DejaVu Sans";
static FONT_BYTES: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

fn register_font() {
    REGISTER.call_once(|| {
        // The file is part of the source tree: it parses or the build is broken.
        if plotters::style::register_font(FONT, FontStyle::Normal, FONT_BYTES).is_err() {
            panic!("assets/fonts/DejaVuSans.ttf is not a font");
        }
    });
}

/// A series in plotted units: runs of drawable points (a skipped point ends a run) and error
/// bars (x, low, high), low None when it runs to the bottom of the plot.
struct Prepared {
    runs: Vec<Vec<(f64, f64)>>,
    bars: Vec<(f64, Option<f64>, f64)>,
}

fn prepare(chart: &Chart) -> Vec<Prepared> {
    chart
        .series
        .iter()
        .map(|s| {
            let mut runs: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
            let mut bars = Vec::new();
            for (i, &(x, y)) in s.points.iter().enumerate() {
                let px = Axis::to_plot(chart.log_x, x);
                let py = Axis::to_plot(chart.log_y, y);
                match (px, py) {
                    (Some(px), Some(py)) => {
                        runs.last_mut().expect("one run at least").push((px, py));
                        if let Some(&(lo, hi)) = s.y_interval.get(i) {
                            if let Some(phi) = Axis::to_plot(chart.log_y, hi) {
                                if lo.is_finite() && lo <= hi {
                                    let plo = Axis::to_plot(chart.log_y, lo);
                                    bars.push((px, plo, phi));
                                }
                            }
                        }
                    }
                    _ => {
                        if !runs.last().expect("one run at least").is_empty() {
                            runs.push(Vec::new());
                        }
                    }
                }
            }
            runs.retain(|r| !r.is_empty());
            Prepared { runs, bars }
        })
        .collect()
}

/// Writes `stem.svg` and `stem.png` and returns both paths (svg, png).
pub fn write_chart(stem: &Path, chart: &Chart) -> Result<(PathBuf, PathBuf), String> {
    register_font();
    let svg_path = with_suffix(stem, "svg");
    let png_path = with_suffix(stem, "png");
    if let Some(dir) = stem.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    }
    let prepared = prepare(chart);

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, CHART_SIZE).into_drawing_area();
        draw(&root, chart, &prepared).map_err(|e| format!("{}: {e}", svg_path.display()))?;
        root.present()
            .map_err(|e| format!("{}: {e}", svg_path.display()))?;
    }
    let svg = svg.replace(
        &format!("font-family=\"{FONT}\""),
        &format!("font-family=\"{FONT}, Verdana, Arial, sans-serif\""),
    );
    write_atomic(&svg_path, svg.as_bytes())?;

    let (w, h) = CHART_SIZE;
    let mut rgb = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, CHART_SIZE).into_drawing_area();
        draw(&root, chart, &prepared).map_err(|e| format!("{}: {e}", png_path.display()))?;
        root.present()
            .map_err(|e| format!("{}: {e}", png_path.display()))?;
    }
    let img = image::RgbImage::from_raw(w, h, rgb).expect("buffer matches size");
    write_atomic_with(&png_path, |tmp| {
        img.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| format!("cannot write PNG {}: {e}", png_path.display()))
    })?;
    Ok((svg_path, png_path))
}

/// Writes `study_dir/<stem>.svg` and `.png` (`stem` relative to the study folder, e.g.
/// "mse_spp" or "plots/mse_spp") and returns the manifest's figure: the chart's title, the
/// caption, and both paths relative to `study_dir`.
pub fn write_figure(
    study_dir: &Path,
    stem: &str,
    chart: &Chart,
    caption: &str,
) -> Result<crate::manifest::Figure, String> {
    write_chart(&study_dir.join(stem), chart)?;
    Ok(crate::manifest::Figure {
        title: chart.title.clone(),
        caption: caption.into(),
        svg: format!("{stem}.svg"),
        png: format!("{stem}.png"),
    })
}

/// `stem` with `.ext` appended (a stem may contain dots: "mse.spp" → "mse.spp.svg").
fn with_suffix(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

fn font(size: f64) -> TextStyle<'static> {
    (FONT, size).into_font().color(&BLACK)
}

type DrawResult<E> = Result<(), DrawingAreaErrorKind<E>>;

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &Chart,
    prepared: &[Prepared],
) -> DrawResult<DB::ErrorType> {
    root.fill(&WHITE)?;
    let xs = prepared
        .iter()
        .flat_map(|p| p.runs.iter().flatten().map(|&(x, _)| x));
    let ys = prepared.iter().flat_map(|p| {
        p.runs.iter().flatten().map(|&(_, y)| y).chain(
            p.bars
                .iter()
                .flat_map(|&(_, lo, hi)| lo.into_iter().chain([hi])),
        )
    });
    let (x_axis, y_axis) = match (
        Axis::covering(chart.log_x, xs),
        Axis::covering(chart.log_y, ys),
    ) {
        (Some(x), Some(y)) => (x, y),
        _ => return draw_empty(root, chart),
    };

    let looks = looks(&chart.series);
    let legend: Vec<usize> = (0..chart.series.len())
        .filter(|&i| !prepared[i].runs.is_empty() && !chart.series[i].name.is_empty())
        .collect();
    let legend_font = if legend.len() > 16 { 14.0 } else { 18.0 };
    let row = legend_font * 1.5;
    let (w, _) = root.dim_in_pixel();
    // The legend column is at most a third of the chart; a name wider than that wraps at spaces
    // onto further rows rather than running off the image.
    let measure = |t: &str| {
        root.estimate_text_size(t, &font(legend_font))
            .map(|(w, _)| w)
            .unwrap_or(0)
    };
    let names: Vec<Vec<String>> = legend
        .iter()
        .map(|&i| wrap_label(&chart.series[i].name, w / 3 - 60, &measure))
        .collect();
    let text_w = names
        .iter()
        .flatten()
        .map(|l| measure(l))
        .max()
        .unwrap_or(0);
    let legend_w = if legend.is_empty() {
        10
    } else {
        (text_w + 60).clamp(120, w / 3)
    };
    let (plot_area, legend_area) = root.split_horizontally(w - legend_w);

    let mut cc = ChartBuilder::on(&plot_area)
        .caption(&chart.title, font(26.0))
        .margin(12)
        .x_label_area_size(64)
        .y_label_area_size(100)
        .build_cartesian_2d(Ticked::new(&x_axis), Ticked::new(&y_axis))?;
    let x_fmt = x_axis.labeller(&x_axis.ticks().0);
    let y_fmt = y_axis.labeller(&y_axis.ticks().0);
    cc.configure_mesh()
        .x_desc(&chart.x_label)
        .y_desc(&chart.y_label)
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .label_style(font(18.0))
        .axis_desc_style(font(20.0))
        .bold_line_style(RGBColor(200, 200, 200))
        .light_line_style(RGBColor(236, 236, 236))
        .draw()?;

    let floor = y_axis.lo;
    for (p, look) in prepared.iter().zip(&looks) {
        let style = ShapeStyle::from(&look.color).stroke_width(2);
        for run in &p.runs {
            if look.dashed {
                cc.draw_series(std::iter::once(DashedPathElement::new(
                    run.iter().copied(),
                    10,
                    6,
                    style,
                )))?;
            } else if run.len() > 1 {
                cc.draw_series(std::iter::once(PathElement::new(run.clone(), style)))?;
            }
        }
        let thin = ShapeStyle::from(&look.color).stroke_width(1);
        for &(x, lo, hi) in &p.bars {
            let lo = lo.unwrap_or(floor);
            cc.draw_series(std::iter::once(PathElement::new(
                vec![(x, lo), (x, hi)],
                thin,
            )))?;
            // Caps: short horizontal strokes in pixels, whatever the axis.
            for y in [lo, hi] {
                cc.draw_series(std::iter::once(
                    EmptyElement::at((x, y)) + PathElement::new(vec![(-4, 0), (4, 0)], thin),
                ))?;
            }
        }
        if let Some((marker, filled)) = look.marker {
            for run in &p.runs {
                cc.draw_series(
                    run.iter()
                        .map(|&pt| EmptyElement::at(pt) + marker_shape(marker, filled, look.color)),
                )?;
            }
        }
    }

    // The legend column: a line sample (with the marker) and the name per series.
    let (_, lh) = legend_area.dim_in_pixel();
    let rows: usize = names.iter().map(Vec::len).sum();
    let top = ((lh as f64 - row * rows as f64) / 2.0).max(40.0) as i32;
    let mut used = 0;
    for (j, &i) in legend.iter().enumerate() {
        let look = looks[i];
        let y = top + (row * used as f64) as i32;
        used += names[j].len();
        let style = ShapeStyle::from(&look.color).stroke_width(2);
        if look.dashed {
            legend_area.draw(&DashedPathElement::new([(4, y), (40, y)], 7, 4, style))?;
        } else {
            legend_area.draw(&PathElement::new(vec![(4, y), (40, y)], style))?;
        }
        if let Some((marker, filled)) = look.marker {
            legend_area
                .draw(&(EmptyElement::at((22, y)) + marker_shape(marker, filled, look.color)))?;
        }
        for (k, line) in names[j].iter().enumerate() {
            legend_area.draw(&Text::new(
                line.clone(),
                (48, y - (legend_font * 0.6) as i32 + (row * k as f64) as i32),
                font(legend_font),
            ))?;
        }
    }
    Ok(())
}

/// `name` in lines no wider than `max_w` (as `measure` says), broken at spaces; a single word
/// wider than that keeps a line of its own. Joined by spaces, the lines are the name.
pub fn wrap_label(name: &str, max_w: u32, measure: &dyn Fn(&str) -> u32) -> Vec<String> {
    let mut lines: Vec<String> = Vec::new();
    for word in name.split(' ') {
        match lines.last_mut() {
            Some(l) if measure(&format!("{l} {word}")) <= max_w => {
                l.push(' ');
                l.push_str(word);
            }
            _ => lines.push(word.to_string()),
        }
    }
    lines
}

/// A marker centred on (0, 0) in pixels.
fn marker_shape<DB: DrawingBackend>(
    marker: Marker,
    filled: bool,
    color: RGBColor,
) -> DynElement<'static, DB, (i32, i32)> {
    let style = if filled {
        ShapeStyle::from(&color).filled()
    } else {
        ShapeStyle::from(&color).stroke_width(2)
    };
    const R: i32 = 5;
    match marker {
        Marker::Circle => Circle::new((0, 0), R, style).into_dyn(),
        Marker::Square => Rectangle::new([(-R + 1, -R + 1), (R - 1, R - 1)], style).into_dyn(),
        Marker::Triangle => {
            let pts = vec![(0, -R - 1), (R + 1, R - 1), (-R - 1, R - 1), (0, -R - 1)];
            if filled {
                Polygon::new(pts, style).into_dyn()
            } else {
                PathElement::new(pts, style).into_dyn()
            }
        }
        Marker::Diamond => {
            let pts = vec![
                (0, -R - 1),
                (R + 1, 0),
                (0, R + 1),
                (-R - 1, 0),
                (0, -R - 1),
            ];
            if filled {
                Polygon::new(pts, style).into_dyn()
            } else {
                PathElement::new(pts, style).into_dyn()
            }
        }
    }
}

fn draw_empty<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &Chart,
) -> DrawResult<DB::ErrorType> {
    let (w, h) = root.dim_in_pixel();
    let centred = |size: f64| {
        font(size).pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Center,
        ))
    };
    root.draw(&Text::new(
        chart.title.clone(),
        (w as i32 / 2, 40),
        centred(22.0),
    ))?;
    root.draw(&Text::new(
        "no data".to_string(),
        (w as i32 / 2, h as i32 / 2),
        centred(28.0).color(&RGBColor(120, 120, 120)),
    ))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::axis::log_ticks;
    use super::*;

    fn tmp(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("lt-plot-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn measured(name: &str, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.into(),
            points,
            y_interval: Vec::new(),
            style: Style::Measured,
        }
    }

    fn png_size(path: &Path) -> (u32, u32) {
        let img = image::open(path).unwrap();
        (img.width(), img.height())
    }

    #[test]
    fn long_legend_names_wrap_to_the_legend_column() {
        // 10 px per character: a 40-px column takes four characters a line.
        let measure = |t: &str| 10 * t.chars().count() as u32;
        let name = "K&Z's model at these N, ppm's schedule (exact)";
        let lines = wrap_label(name, 160, &measure);
        assert!(lines.len() > 1, "{lines:?}");
        assert!(lines.iter().all(|l| measure(l) <= 160), "{lines:?}");
        assert_eq!(lines.join(" "), name);
        assert_eq!(wrap_label("pt", 160, &measure), ["pt"]);
        assert_eq!(
            wrap_label("unbreakable-word", 40, &measure),
            ["unbreakable-word"]
        );
    }

    #[test]
    fn writes_both_files_with_legend_and_error_bars() {
        let d = tmp("full");
        let n: Vec<f64> = (0..8).map(|i| 2f64.powi(i)).collect();
        let mut pt = measured("pt", n.iter().map(|&n| (n, 0.1 / n)).collect());
        pt.y_interval = n.iter().map(|&n| (0.08 / n, 0.12 / n)).collect();
        let fit = Series {
            name: "pt fit, slope −1.00".into(),
            points: vec![(1.0, 0.1), (128.0, 0.1 / 128.0)],
            y_interval: vec![],
            style: Style::Fitted,
        };
        let chart = Chart {
            title: "MSE against spp".into(),
            x_label: "spp".into(),
            y_label: "MSE".into(),
            log_x: true,
            log_y: true,
            series: vec![
                pt,
                fit,
                measured("bdpt", n.iter().map(|&n| (n, 0.05 / n)).collect()),
            ],
        };
        let (svg, png) = write_chart(&d.join("mse"), &chart).unwrap();
        assert_eq!(svg, d.join("mse.svg"));
        assert_eq!(png, d.join("mse.png"));
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg"), "{}", &text[..40.min(text.len())]);
        for word in ["MSE against spp", "pt fit, slope −1.00", "bdpt", "spp"] {
            assert!(text.contains(word), "svg lacks {word}");
        }
        assert!(text.contains("DejaVu Sans"));
        assert_eq!(png_size(&png), CHART_SIZE);
        let f = write_figure(&d, "plots/again", &chart, "caption").unwrap();
        assert_eq!(
            (f.svg.as_str(), f.png.as_str()),
            ("plots/again.svg", "plots/again.png")
        );
        assert_eq!(f.title, "MSE against spp");
        assert!(d.join("plots/again.svg").is_file() && d.join("plots/again.png").is_file());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn bad_points_are_skipped_and_empty_charts_say_so() {
        let d = tmp("bad");
        let chart = Chart {
            title: "nothing drawable".into(),
            x_label: "x".into(),
            y_label: "y".into(),
            log_x: true,
            log_y: true,
            series: vec![
                measured(
                    "a",
                    vec![(0.0, 1.0), (-1.0, 2.0), (f64::NAN, 1.0), (1.0, -3.0)],
                ),
                measured("b", vec![(1.0, f64::INFINITY)]),
                measured("c", vec![]),
            ],
        };
        let (svg, png) = write_chart(&d.join("empty"), &chart).unwrap();
        assert!(std::fs::read_to_string(&svg).unwrap().contains("no data"));
        assert_eq!(png_size(&png), CHART_SIZE);

        // The same points on linear axes: the finite ones are drawn, NaN/inf skipped.
        let mut lin = chart.clone();
        lin.log_x = false;
        lin.log_y = false;
        lin.series[0].y_interval = vec![(f64::NAN, 1.0), (3.0, 1.0), (0.0, 0.0), (-4.0, -2.0)];
        let (svg, _) = write_chart(&d.join("lin"), &lin).unwrap();
        assert!(!std::fs::read_to_string(&svg).unwrap().contains("no data"));

        // One point, zero span on both axes.
        let one = Chart {
            series: vec![measured("one", vec![(3.0, 3.0)])],
            ..chart.clone()
        };
        let (svg, _) = write_chart(&d.join("one"), &one).unwrap();
        assert!(!std::fs::read_to_string(&svg).unwrap().contains("no data"));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn log_ticks_are_decades_or_one_two_five() {
        let (bold, light) = log_ticks(-3.2, 0.1);
        assert_eq!(bold, vec![-3.0, -2.0, -1.0, 0.0]);
        assert!(light.len() >= 8 * 3);
        let (bold, _) = log_ticks(0.05, 0.9); // 1.12 … 7.9
        let vals: Vec<f64> = bold.iter().map(|v| 10f64.powf(*v)).collect();
        assert_eq!(vals.len(), 2, "{vals:?}");
        assert!((vals[0] - 2.0).abs() < 1e-9 && (vals[1] - 5.0).abs() < 1e-9);
        // Narrower than a factor of two: linear steps, still more than one tick.
        let (bold, _) = log_ticks(0.0, 0.1);
        assert!(bold.len() >= 2, "{bold:?}");
    }

    #[test]
    fn numbers_read_well() {
        assert_eq!(format_number(0.001), "0.001");
        assert_eq!(format_number(250.0), "250");
        assert_eq!(format_number(0.5), "0.5");
        assert_eq!(format_number(1e-5), "10⁻⁵");
        assert_eq!(format_number(2e-5), "2×10⁻⁵");
        assert_eq!(format_number(-0.25), "−0.25");
        assert_eq!(format_number(1e6), "10⁶");
        assert_eq!(format_power(0.001), "10⁻³");
        assert_eq!(format_power(0.00099999), "10⁻³");
        assert_eq!(format_power(0.5), "5×10⁻¹");
        let axis = Axis {
            log: true,
            lo: -4.2,
            hi: -0.9,
        };
        let label = axis.labeller(&axis.ticks().0);
        assert_eq!(label(&-2.0), "10⁻²");
        let axis = Axis { lo: -2.2, ..axis };
        assert_eq!(axis.labeller(&axis.ticks().0)(&-2.0), "0.01");
    }

    #[test]
    fn fitted_lines_take_their_measured_colour() {
        let s = vec![
            measured("pt", vec![]),
            measured("ppm", vec![]),
            Series {
                name: "ppm fit".into(),
                points: vec![],
                y_interval: vec![],
                style: Style::Fitted,
            },
            Series {
                name: "predicted".into(),
                points: vec![],
                y_interval: vec![],
                style: Style::Fitted,
            },
        ];
        let l = looks(&s);
        assert_eq!(l[2].color, l[1].color);
        assert_ne!(l[3].color, l[0].color);
        assert_ne!(l[3].color, l[1].color);
        assert!(l[2].dashed && l[2].marker.is_none());
    }
}
