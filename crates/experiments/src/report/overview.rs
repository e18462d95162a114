//! The equal-time study as one compact table: a row per scene, a column per integrator, each
//! cell the image's error against the scene's reference and the CPU time it took at the scene's
//! shared CPU budget, over a small committed thumbnail. Numbers come from the study's own CSV
//! (`equal_time::GALLERIES_CSV`, its "equal time" rows). The full-size galleries are not
//! committed: each row holds its scene's galleries in a `<template>` that the page opens when
//! the images exist locally, and the command that makes them (`equal_time::regenerate`).

use super::escape::{esc, url};
use crate::manifest::{Gallery, Manifest};
use crate::study::equal_time::{self, thumb, GALLERIES_CSV};
use std::collections::HashMap;
use std::fmt::Write;
use std::path::Path;

/// One scene × integrator at equal time.
#[derive(Debug, PartialEq)]
pub struct Cell {
    pub passes: String,
    pub cpu_seconds: String,
    /// The error as the CSV prints it, and as a number (NaN when it is no number, e.g. "—").
    pub error_text: String,
    pub error: f64,
}

#[derive(Debug, PartialEq)]
pub struct Row {
    pub scene: String,
    /// The CPU-time budget every integrator of the scene got (pt's time for the equal-samples
    /// passes).
    pub budget: String,
    /// By column (`Overview::integrators`); None where the CSV has no such row.
    pub cells: Vec<Option<Cell>>,
}

impl Row {
    /// The column of the smallest error (the first on a tie); None when no error is a number.
    pub fn best(&self) -> Option<usize> {
        let mut best: Option<(usize, f64)> = None;
        for (k, c) in self.cells.iter().enumerate() {
            if let Some(c) = c {
                if c.error.is_finite() && best.is_none_or(|(_, e)| c.error < e) {
                    best = Some((k, c.error));
                }
            }
        }
        best.map(|(k, _)| k)
    }
}

#[derive(Debug, PartialEq)]
pub struct Overview {
    /// "relMSE" when the CSV has it, else "MSE" (tables written before it was recorded).
    pub metric: &'static str,
    /// "CPU s", or "s" in tables written before budgets were CPU time (their "seconds").
    pub time_unit: &'static str,
    /// In the CSV's order of first appearance; rows likewise.
    pub integrators: Vec<String>,
    pub rows: Vec<Row>,
}

/// The equal-time rows of the study's CSV (`rows`, as `findings::csv` reads `file`) as the
/// compact table. Errors name the file, the row (1 = the header) and the problem: a missing
/// column, a scene × integrator given twice, integrators of one scene with different budgets.
pub fn from_rows(rows: &[HashMap<String, String>], file: &str) -> Result<Overview, String> {
    let has = |c: &str| rows.first().is_some_and(|r| r.contains_key(c));
    let metric = if has("relMSE") { "relMSE" } else { "MSE" };
    // Tables written before budgets were CPU time name their columns "seconds", "budget s".
    let (time, budget_col, time_unit) = if has("seconds") {
        ("seconds", "budget s", "s")
    } else {
        ("CPU s", "budget CPU s", "CPU s")
    };
    let mut out = Overview {
        metric,
        time_unit,
        integrators: Vec::new(),
        rows: Vec::new(),
    };
    for (k, r) in rows.iter().enumerate() {
        let line = k + 2;
        let get = |c: &str| {
            r.get(c)
                .map(|v| v.trim())
                .ok_or_else(|| format!("{file}: row {line} has no column `{c}`"))
        };
        if get("comparison")? != "equal time" {
            continue;
        }
        let (scene, integrator, budget) = (get("scene")?, get("integrator")?, get(budget_col)?);
        let column = match out.integrators.iter().position(|i| i == integrator) {
            Some(c) => c,
            None => {
                out.integrators.push(integrator.to_string());
                out.integrators.len() - 1
            }
        };
        let at = match out.rows.iter().position(|row| row.scene == scene) {
            Some(a) => a,
            None => {
                out.rows.push(Row {
                    scene: scene.to_string(),
                    budget: budget.to_string(),
                    cells: Vec::new(),
                });
                out.rows.len() - 1
            }
        };
        let row = &mut out.rows[at];
        if row.budget != budget {
            return Err(format!(
                "{file}: row {line}: {scene}'s {integrator} had a budget of {budget} {time_unit}, \
                 the scene's other integrators {} {time_unit}: not an equal-time comparison",
                row.budget
            ));
        }
        if row.cells.len() <= column {
            row.cells.resize_with(column + 1, || None);
        }
        if row.cells[column].is_some() {
            return Err(format!(
                "{file}: row {line}: {scene} × {integrator} at equal time a second time"
            ));
        }
        let error_text = get(metric)?.to_string();
        row.cells[column] = Some(Cell {
            passes: get("passes")?.to_string(),
            cpu_seconds: get(time)?.to_string(),
            error: error_text.parse().unwrap_or(f64::NAN),
            error_text,
        });
    }
    let n = out.integrators.len();
    for row in &mut out.rows {
        row.cells.resize_with(n, || None);
    }
    Ok(out)
}

/// The compact table of a study folder, when its manifest is the equal-time study's and its
/// CSV is there; why not, when the CSV cannot be read.
pub fn of_study(dir: &Path, m: &Manifest) -> Option<Result<Overview, String>> {
    if !has_overview(m) {
        return None;
    }
    let path = dir.join(GALLERIES_CSV);
    Some(super::findings::csv(&path).and_then(|rows| from_rows(&rows, &path.display().to_string())))
}

/// Whether the report shows `m` through the compact table.
pub fn has_overview(m: &Manifest) -> bool {
    m.study == equal_time::NAME && m.tables.iter().any(|t| t.csv == GALLERIES_CSV)
}

/// Whether `g` is one of a scene's full-size galleries (under `gallery/`, not committed), which
/// the compact table opens on demand.
pub fn on_demand(m: &Manifest, g: &Gallery) -> bool {
    has_overview(m) && g.reference.image.starts_with("gallery/")
}

/// The on-demand galleries of `scene`.
fn scene_galleries<'a>(m: &'a Manifest, scene: &str) -> Vec<&'a Gallery> {
    let prefix = format!("{}/", equal_time::gallery_dir(scene));
    m.galleries
        .iter()
        .filter(|g| on_demand(m, g) && g.reference.image.starts_with(&prefix))
        .collect()
}

/// `<img>` elements the table shows: a thumbnail per scene and per cell.
pub fn images(o: &Overview) -> usize {
    o.rows
        .iter()
        .map(|r| 1 + r.cells.iter().flatten().count())
        .sum()
}

/// `<img>` elements the rows add once opened, counting only scenes whose full-size reference
/// exists under `dir` (the others show how to make them).
pub fn images_when_opened(dir: &Path, m: &Manifest, o: &Overview) -> usize {
    o.rows
        .iter()
        .map(|r| scene_galleries(m, &r.scene))
        .filter(|gs| {
            gs.first()
                .is_some_and(|g| dir.join(&g.reference.image).is_file())
        })
        .flat_map(|gs| gs.into_iter().map(|g| 5 + g.items.len()))
        .sum()
}

/// The table's HTML; `gallery` writes one gallery's markup (`html::gallery`).
pub fn write(
    h: &mut String,
    folder: &str,
    id: &str,
    m: &Manifest,
    o: &Overview,
    gallery: &dyn Fn(&mut String, &str, &str, &Gallery),
) {
    let csv = url(folder, GALLERIES_CSV);
    let _ = writeln!(
        h,
        "<div class=\"table overview\">\n<h3>Every scene at equal CPU time</h3>\n<p \
         class=\"caption\">Rows: scenes; columns: integrators. Each cell: the image after the \
         scene's CPU-time budget (the time <code>pt</code> took for its equal-samples passes; \
         each integrator ran round(budget / its time per pass) passes), its <b>{metric}</b> \
         against the scene's reference (bold: the row's lowest), its passes and the seconds it \
         took ({unit}{old}). \
         One run (seed 1) per cell, so no interval: the convergence study's independent runs \
         give the intervals. The thumbnails are {tw} px; a click on a row opens its full-size \
         comparison when its images exist locally — they are not committed, the row says how \
         to make them. <span class=\"links\"><a href=\"{csv}\">CSV</a></span></p>",
        metric = o.metric,
        unit = o.time_unit,
        old = if o.time_unit == "s" {
            ": this table predates CPU-time budgets and records seconds as measured then"
        } else {
            ""
        },
        tw = equal_time::THUMB_WIDTH,
    );
    h.push_str("<div class=\"scroll\"><table>\n<thead><tr><th>scene, reference</th>");
    for i in &o.integrators {
        let _ = write!(h, "<th>{}</th>", esc(i));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for (k, r) in o.rows.iter().enumerate() {
        let s = esc(&r.scene);
        let _ = write!(
            h,
            "<tr class=\"scene\" tabindex=\"0\" aria-expanded=\"false\" title=\"open the \
             full-size comparison\"><th><img src=\"{}\" alt=\"{s}, reference\"><b>{s}</b>\
             <small>budget {} {}</small></th>",
            url(folder, &thumb(&r.scene, "reference")),
            esc(&r.budget),
            o.time_unit
        );
        let best = r.best();
        for (c, cell) in r.cells.iter().enumerate() {
            let Some(cell) = cell else {
                h.push_str("<td>—</td>");
                continue;
            };
            let i = &o.integrators[c];
            let class = if best == Some(c) { " best" } else { "" };
            let _ = write!(
                h,
                "<td class=\"cell{class}\"><img src=\"{}\" alt=\"{s}, {}\"><span \
                 class=\"err\">{}</span><small>{} passes, {} s</small></td>",
                url(folder, &thumb(&r.scene, &format!("time-{i}"))),
                esc(i),
                esc(&cell.error_text),
                esc(&cell.passes),
                esc(&cell.cpu_seconds),
            );
        }
        h.push_str("</tr>\n");
        let galleries = scene_galleries(m, &r.scene);
        let command = equal_time::regenerate_command(&m.scale, &r.scene);
        let _ = write!(
            h,
            "<tr class=\"detail\" hidden><td colspan=\"{}\"><p class=\"ondemand\">The \
             full-size images of {s} are not committed. <code>{}</code> makes them (under \
             <code>{}/</code>) at the pass counts above; then a click on the row opens them \
             here.</p>",
            o.integrators.len() + 1,
            esc(&command),
            esc(&url(folder, &equal_time::gallery_dir(&r.scene)))
        );
        if let Some(first) = galleries.first() {
            let _ = write!(
                h,
                "<template data-probe=\"{}\">",
                url(folder, &first.reference.image)
            );
            for (j, g) in galleries.iter().enumerate() {
                gallery(h, folder, &format!("{id}-{k}-{j}"), g);
            }
            h.push_str("</template><div class=\"opened\"></div>");
        }
        h.push_str("</td></tr>\n");
    }
    h.push_str("</tbody>\n</table></div>\n</div>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(csv: &str) -> Vec<HashMap<String, String>> {
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        lines
            .map(|l| {
                header
                    .iter()
                    .map(|h| h.to_string())
                    .zip(l.split(',').map(String::from))
                    .collect()
            })
            .collect()
    }

    const HEAD: &str = "scene,comparison,integrator,passes,CPU s,budget CPU s,wall s,MSE";

    #[test]
    fn equal_time_rows_become_scenes_by_integrators() {
        let csv = format!(
            "{HEAD}\n\
             box,equal samples,pt,16,2.1,2.1,2.6,1e-3\n\
             box,equal time,pt,16,1.7,2.1,2.7,1.91e-3\n\
             box,equal time,bdpt,4,1.9,2.1,2.7,2.55e-3\n\
             box,equal time,light,13,1.9,2.1,2.9,1.14e-3\n\
             sds,equal time,pt,16,0.75,0.841,1.2,0.474\n\
             sds,equal time,light,26,0.65,0.841,1.4,—\n"
        );
        let o = from_rows(&rows(&csv), "g.csv").unwrap();
        assert_eq!((o.metric, o.time_unit), ("MSE", "CPU s"));
        assert_eq!(o.integrators, ["pt", "bdpt", "light"]);
        assert_eq!(o.rows.len(), 2);
        let (b, s) = (&o.rows[0], &o.rows[1]);
        assert_eq!((b.scene.as_str(), b.budget.as_str()), ("box", "2.1"));
        let pt = b.cells[0].as_ref().unwrap();
        assert_eq!((pt.passes.as_str(), pt.error), ("16", 1.91e-3));
        assert_eq!(b.best(), Some(2), "light's 1.14e-3 is the box's lowest");
        assert!(s.cells[1].is_none(), "sds has no bdpt row");
        assert_eq!(s.best(), Some(0), "a dash is no number and never the best");
        assert_eq!(images(&o), 2 + 3 + 2);
        // relMSE is shown when the CSV records it.
        let csv = format!("{HEAD},relMSE\nbox,equal time,pt,16,1.7,2.1,2.7,1e-3,0.5\n");
        let o = from_rows(&rows(&csv), "g.csv").unwrap();
        assert_eq!(
            (o.metric, o.rows[0].cells[0].as_ref().unwrap().error),
            ("relMSE", 0.5)
        );
        // An older table: "seconds" and "budget s".
        let csv = "scene,comparison,integrator,passes,seconds,budget s,MSE\nbox,equal time,pt,16,5.4,2.2,4e-3\n";
        let o = from_rows(&rows(csv), "g.csv").unwrap();
        assert_eq!((o.time_unit, o.rows[0].budget.as_str()), ("s", "2.2"));
        // Bad tables are refused, naming the file and row.
        let twice = format!("{HEAD}\nbox,equal time,pt,16,1,2,2,1\nbox,equal time,pt,8,1,2,2,1\n");
        let e = from_rows(&rows(&twice), "g.csv").unwrap_err();
        assert!(
            e.starts_with("g.csv: row 3:") && e.contains("second time"),
            "{e}"
        );
        let budgets =
            format!("{HEAD}\nbox,equal time,pt,16,1,2,2,1\nbox,equal time,vcm,2,1,3,2,1\n");
        let e = from_rows(&rows(&budgets), "g.csv").unwrap_err();
        assert!(
            e.contains("row 3") && e.contains("not an equal-time"),
            "{e}"
        );
        let e = from_rows(&rows("scene,comparison\nbox,equal time\n"), "g.csv").unwrap_err();
        assert_eq!(e, "g.csv: row 2 has no column `integrator`");
    }
}
