//! What every study writes and how: a folder per study, CSV tables, charts through
//! `crate::plot`, the Markdown summary and the manifest `lt report` reads.

use super::Scale;
use crate::manifest::{Figure, Manifest, Table};
use crate::plot::{write_chart, Chart};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

static FILMS: Mutex<Option<HashMap<PathBuf, (u32, u32)>>> = Mutex::new(None);

/// The film a scene is rendered at in a study: the scale's width, the scene's aspect ratio.
pub fn film(scale: &Scale, scene: &Path) -> Result<(u32, u32), String> {
    let mut films = FILMS.lock().unwrap();
    let map = films.get_or_insert_with(HashMap::new);
    let size = match map.get(scene) {
        Some(s) => *s,
        None => {
            let s = crate::scene_load::load(scene).map_err(|e| e.to_string())?;
            let size = (s.camera.width, s.camera.height);
            map.insert(scene.to_path_buf(), size);
            size
        }
    };
    Ok(scale.resolution(size))
}

/// A confidence level as a percentage: 95, 99.9.
pub fn pct(confidence: f64) -> String {
    num(confidence * 100.0)
}

/// A scene's name: its file's stem, or its folder's name for a Mitsuba scene kept as
/// `<name>/scene.xml` (Bitterli's scenes), whose stems would all be `scene`.
pub fn stem(path: &Path) -> String {
    let file = path
        .file_stem()
        .map(|s| s.to_string_lossy().to_string())
        .unwrap_or_default();
    match path.parent().and_then(|d| d.file_name()) {
        Some(dir) if file == "scene" => dir.to_string_lossy().to_string(),
        _ => file,
    }
}

/// A number as the tables print it: 3 significant digits, scientific outside [0.01, 1000).
/// A fitted slope's table cells against a predicted one: measured, "[lo, hi]", "difference ±
/// half-width" and whether the interval holds the prediction; the error and dashes when the
/// slope could not be fitted.
pub fn slope_cells(
    slope: &Result<lt_estimators::Jackknifed, String>,
    against: f64,
) -> (String, String, String, String) {
    match slope {
        Ok(j) => (
            num(j.estimate),
            format!("[{}, {}]", num(j.interval.lo), num(j.interval.hi)),
            format!(
                "{} ± {}",
                num(j.estimate - against),
                num(j.interval.hi - j.estimate)
            ),
            if j.interval.contains(against) {
                "yes"
            } else {
                "no"
            }
            .to_string(),
        ),
        Err(e) => ("—".into(), e.clone(), "—".into(), "—".into()),
    }
}

pub fn num(v: f64) -> String {
    if !v.is_finite() {
        return "—".into();
    }
    let a = v.abs();
    if a == 0.0 || (1e-2..1e3).contains(&a) {
        format!("{:.3}", v)
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{v:.2e}")
    }
}

/// A study's folder, manifest and summary under construction.
pub struct StudyOutput {
    pub dir: PathBuf,
    pub manifest: Manifest,
    pub summary: String,
}

impl StudyOutput {
    pub fn new(
        dir: PathBuf,
        study: &str,
        title: &str,
        scale: &Scale,
    ) -> Result<StudyOutput, String> {
        std::fs::create_dir_all(&dir)
            .map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
        let mut manifest = Manifest::new(study, title, scale.name);
        manifest.summary = "summary.md".into();
        Ok(StudyOutput {
            dir,
            manifest,
            summary: format!("# {title}\n\n"),
        })
    }

    pub fn para(&mut self, text: &str) {
        self.summary.push_str(text.trim());
        self.summary.push_str("\n\n");
    }

    /// Writes `name.csv` and adds the table to the manifest and (when `in_summary`) the summary.
    pub fn table(
        &mut self,
        name: &str,
        title: &str,
        caption: &str,
        columns: &[&str],
        rows: Vec<Vec<String>>,
        in_summary: bool,
    ) -> Result<(), String> {
        if let Some(r) = rows.iter().find(|r| r.len() != columns.len()) {
            return Err(format!(
                "table {name}: a row has {} cells for {} columns: {r:?}",
                r.len(),
                columns.len()
            ));
        }
        let mut csv = columns.join(",");
        csv.push('\n');
        for r in &rows {
            let cells: Vec<String> = r
                .iter()
                .map(|c| {
                    if c.contains([',', '"', '\n']) {
                        format!("\"{}\"", c.replace('"', "\"\""))
                    } else {
                        c.clone()
                    }
                })
                .collect();
            csv.push_str(&cells.join(","));
            csv.push('\n');
        }
        let file = format!("{name}.csv");
        crate::image_io::write_atomic(&self.dir.join(&file), csv.as_bytes())?;
        if in_summary {
            let _ = write!(self.summary, "**{title}.** {caption}\n\n");
            let _ = writeln!(self.summary, "| {} |", columns.join(" | "));
            let _ = writeln!(self.summary, "|{}", "---|".repeat(columns.len()));
            for r in &rows {
                let _ = writeln!(self.summary, "| {} |", r.join(" | "));
            }
            self.summary.push('\n');
        }
        self.manifest.tables.push(Table {
            title: title.into(),
            caption: caption.into(),
            csv: file,
            columns: columns.iter().map(|c| c.to_string()).collect(),
            rows,
        });
        Ok(())
    }

    /// Writes `name.svg` and `name.png` and adds the figure to the manifest.
    pub fn chart(&mut self, name: &str, chart: &Chart, caption: &str) -> Result<(), String> {
        write_chart(&self.dir.join(name), chart)?;
        self.manifest.figures.push(Figure {
            title: chart.title.clone(),
            caption: caption.into(),
            svg: format!("{name}.svg"),
            png: format!("{name}.png"),
        });
        Ok(())
    }

    pub fn finish(mut self) -> Result<(), String> {
        let _ = writeln!(
            self.summary,
            "_Scale `{}`; code version `{}`. Every number here is recomputed from cached renders by \
             rerunning the study._",
            self.manifest.scale,
            crate::cache::CODE_VERSION
        );
        crate::image_io::write_atomic(&self.dir.join("summary.md"), self.summary.as_bytes())?;
        self.manifest.write(&self.dir)?;
        Ok(())
    }
}
