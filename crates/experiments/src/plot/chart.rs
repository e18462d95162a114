//! What a study says of a chart: its series, axes and labels.

/// How a series is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Style {
    /// Measured points joined by a line, with error bars where given.
    Measured,
    /// A fitted or predicted line, dashed, no markers.
    Fitted,
}

#[derive(Clone, Debug)]
pub struct Series {
    pub name: String,
    /// (x, y) points; non-finite or (on a log axis) non-positive points are skipped.
    pub points: Vec<(f64, f64)>,
    /// Per point, the (low, high) of its confidence interval, or empty for none.
    pub y_interval: Vec<(f64, f64)>,
    pub style: Style,
}

#[derive(Clone, Debug)]
pub struct Chart {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub log_x: bool,
    pub log_y: bool,
    pub series: Vec<Series>,
}
