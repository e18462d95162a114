//! The page itself: study sections from manifests, with the inline CSS and scripts beside this
//! file (`page.css`, `page.js`, `selfcheck.js`).

use super::escape::{esc, url};
use super::markdown;
use super::overview;
use super::StudyDir;
use crate::manifest::{Crop, Figure, Gallery, GalleryImage, Manifest, Table};
use std::fmt::Write;
use std::path::Path;

const CSS: &str = include_str!("page.css");
const PAGE_JS: &str = include_str!("page.js");
const SELFCHECK_JS: &str = include_str!("selfcheck.js");

/// The id of the hidden `<pre>` the self-check writes its JSON into.
pub const SELFCHECK_ID: &str = "lt-selfcheck";

/// How many `<img>` elements the page shows for the manifest `m` of study folder `dir` (not
/// counting images its summary's Markdown shows): one per figure; per gallery the wipe stage's
/// two, the zoom's two, and one thumbnail each for the reference and every item; the compact
/// table's thumbnails (`overview`) instead of the galleries it opens on demand.
pub fn images_in_page(m: &Manifest, dir: &Path) -> usize {
    let shown: usize = m
        .galleries
        .iter()
        .filter(|g| !overview::on_demand(m, g))
        .map(|g| 5 + g.items.len())
        .sum();
    let table = match overview::of_study(dir, m) {
        Some(Ok(o)) => overview::images(&o),
        _ => 0,
    };
    m.figures.len() + shown + table
}

/// The `<img>` elements the compact table's rows add once opened (`index.html#exercise` opens
/// them all): the galleries of the scenes whose full-size images exist under `dir`.
pub fn images_when_opened(m: &Manifest, dir: &Path) -> usize {
    match overview::of_study(dir, m) {
        Some(Ok(o)) => overview::images_when_opened(dir, m, &o),
        _ => 0,
    }
}

/// Every file a manifest names (relative to its study folder) that must be there: the full-size
/// galleries the compact table opens on demand are left out.
pub fn files_named(m: &Manifest) -> Vec<&str> {
    let mut out: Vec<&str> = Vec::new();
    if !m.summary.is_empty() {
        out.push(&m.summary);
    }
    for f in &m.figures {
        out.push(&f.svg);
        out.push(&f.png);
    }
    for t in &m.tables {
        if !t.csv.is_empty() {
            out.push(&t.csv);
        }
    }
    for g in m.galleries.iter().filter(|g| !overview::on_demand(m, g)) {
        out.push(&g.reference.image);
        out.extend(g.items.iter().map(|i| i.image.as_str()));
    }
    out
}

/// An id made of `[a-z0-9-]` from any text.
fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') {
            out.push('-');
        }
    }
    out.trim_matches('-').to_string()
}

/// The page, led by the findings when given.
pub fn page(studies: &[StudyDir], findings: Option<&[super::findings::Finding]>) -> String {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    h.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    // The self-check first, so it sees every error after it.
    let _ = writeln!(h, "<script>\n{SELFCHECK_JS}</script>");
    h.push_str("<title>lt — light transport studies</title>\n");
    let _ = writeln!(h, "<style>\n{CSS}</style>\n</head>\n<body>");
    h.push_str("<header>\n<h1>Light transport studies</h1>\n");
    h.push_str(
        "<p class=\"lede\">What <code>lt study</code> measured: every estimator's error against \
         samples and time, bias and variance, radius shrinkage, equal-time galleries and error \
         per path length. Written by <code>lt report</code> from each study's \
         <code>manifest.json</code>.</p>\n",
    );
    if studies.is_empty() {
        h.push_str(
            "<p class=\"warn\">No study results here yet: run <code>lt study all</code>.</p>\n",
        );
    } else {
        h.push_str("<nav><ol>\n");
        for s in studies {
            let title = match &s.manifest {
                Ok(m) => m.title.clone(),
                Err(_) => s.folder.clone(),
            };
            let scale = match &s.manifest {
                Ok(m) => format!(" <span class=\"scale\">{}</span>", esc(&m.scale)),
                Err(_) => " <span class=\"scale bad\">unreadable</span>".into(),
            };
            let _ = writeln!(
                h,
                "<li><a href=\"#study-{}\">{}</a>{scale}</li>",
                slug(&s.folder),
                esc(&title)
            );
        }
        h.push_str("</ol></nav>\n");
    }
    h.push_str("</header>\n<main>\n");
    if let Some(fs) = findings {
        h.push_str("<section class=\"study\" id=\"findings\">\n<h2>Findings</h2>\n");
        h.push_str(
            "<p class=\"meta\">Each with its figure and the number that proves it (95 % \
             intervals from independent runs), read from the studies' CSVs below.</p>\n",
        );
        for (i, f) in fs.iter().enumerate() {
            let svg = url(f.folder, &format!("{}.svg", f.figure));
            let _ = writeln!(
                h,
                "<h3>{}. {}</h3>\n<figure class=\"chart\">\n<a href=\"#study-{}\"><img \
                 src=\"{svg}\" alt=\"{}\" width=\"960\" height=\"600\"></a>\n<figcaption>{}\
                 </figcaption>\n</figure>",
                i + 1,
                esc(f.title),
                slug(f.folder),
                esc(f.title),
                markdown::render(&f.text, "")
            );
        }
        h.push_str("</section>\n");
    }
    for s in studies {
        study(&mut h, s);
    }
    h.push_str("</main>\n");
    let _ = writeln!(h, "<pre id=\"{SELFCHECK_ID}\" hidden>pending</pre>");
    let _ = writeln!(h, "<script>\n{PAGE_JS}</script>\n</body>\n</html>");
    h
}

fn study(h: &mut String, s: &StudyDir) {
    let id = slug(&s.folder);
    let _ = writeln!(h, "<section class=\"study\" id=\"study-{id}\">");
    let m = match &s.manifest {
        Ok(m) => m,
        Err(e) => {
            let _ = writeln!(
                h,
                "<h2>{}</h2>\n<p class=\"warn\">{}</p>\n</section>",
                esc(&s.folder),
                esc(e)
            );
            return;
        }
    };
    let _ = writeln!(
        h,
        "<h2>{} <span class=\"scale\">{} scale</span></h2>",
        esc(&m.title),
        esc(&m.scale)
    );
    // The lecture's slides are no study: their manifests come from a script.
    let made_by = if super::SLIDES.contains(&m.study.as_str()) {
        super::SLIDES_SCRIPT.to_string()
    } else {
        format!("lt study {}", m.study)
    };
    let _ = writeln!(
        h,
        "<p class=\"meta\"><code>{}</code> · folder <a href=\"{}\">{}/</a></p>",
        esc(&made_by),
        url(&s.folder, ""),
        esc(&s.folder)
    );
    match &s.summary {
        Ok(md) if !md.trim().is_empty() => {
            let _ = writeln!(
                h,
                "<div class=\"summary\">\n{}</div>",
                markdown::render(without_title(md, &m.title), &url(&s.folder, ""))
            );
        }
        Ok(_) => {}
        Err(e) => {
            let _ = writeln!(h, "<p class=\"warn\">{}</p>", esc(e));
        }
    }
    if !m.figures.is_empty() {
        h.push_str("<div class=\"figures\">\n");
        for f in &m.figures {
            figure(h, &s.folder, f);
        }
        h.push_str("</div>\n");
    }
    let compact = match &s.overview {
        Some(Ok(o)) => Some(o),
        Some(Err(e)) => {
            let _ = writeln!(h, "<p class=\"warn\">{}</p>", esc(e));
            None
        }
        None => None,
    };
    for t in &m.tables {
        match compact {
            // The compact table stands for the long one (its CSV is linked from it).
            Some(o) if t.csv == crate::study::equal_time::GALLERIES_CSV => {
                overview::write(h, &s.folder, &format!("g-{id}-scene"), m, o, &gallery);
            }
            _ => table(h, &s.folder, t),
        }
    }
    for (i, g) in m.galleries.iter().enumerate() {
        if compact.is_none() || !overview::on_demand(m, g) {
            gallery(h, &s.folder, &format!("g-{id}-{i}"), g);
        }
    }
    h.push_str("</section>\n");
}

/// The summary without a first line "# <title>" (the section's heading already says it).
fn without_title<'a>(md: &'a str, title: &str) -> &'a str {
    let rest = md.trim_start();
    let (first, tail) = rest.split_once('\n').unwrap_or((rest, ""));
    if first.trim_end().strip_prefix("# ").map(str::trim) == Some(title.trim()) {
        tail
    } else {
        md
    }
}

fn figure(h: &mut String, folder: &str, f: &Figure) {
    let svg = url(folder, &f.svg);
    let png = url(folder, &f.png);
    let _ = writeln!(
        h,
        "<figure class=\"chart\">\n<a href=\"{png}\"><img src=\"{svg}\" alt=\"{}\" width=\"960\" \
         height=\"600\"></a>\n<figcaption><strong>{}</strong> {} <span class=\"links\">\
         <a href=\"{png}\">PNG</a> · <a href=\"{svg}\">SVG</a></span></figcaption>\n</figure>",
        esc(&f.title),
        esc(&f.title),
        esc(&f.caption)
    );
}

/// Whether a cell reads as a number (right-aligned): starts with a sign, digit or point and
/// has a digit.
fn numeric(cell: &str) -> bool {
    let t = cell.trim();
    t.chars()
        .next()
        .is_some_and(|c| c.is_ascii_digit() || "+-−.".contains(c))
        && t.chars().any(|c| c.is_ascii_digit())
}

fn table(h: &mut String, folder: &str, t: &Table) {
    h.push_str("<div class=\"table\">\n");
    let _ = write!(h, "<h3>{}</h3>", esc(&t.title));
    if !t.caption.is_empty() || !t.csv.is_empty() {
        h.push_str("<p class=\"caption\">");
        h.push_str(&esc(&t.caption));
        if !t.csv.is_empty() {
            let _ = write!(
                h,
                " <span class=\"links\"><a href=\"{}\">CSV</a></span>",
                url(folder, &t.csv)
            );
        }
        h.push_str("</p>");
    }
    h.push_str("\n<div class=\"scroll\"><table>\n<thead><tr>");
    for c in &t.columns {
        let _ = write!(h, "<th>{}</th>", esc(c));
    }
    h.push_str("</tr></thead>\n<tbody>\n");
    for row in &t.rows {
        h.push_str("<tr>");
        for cell in row {
            let class = if numeric(cell) { " class=\"num\"" } else { "" };
            let _ = write!(h, "<td{class}>{}</td>", esc(cell));
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</tbody>\n</table></div>\n</div>\n");
}

fn gallery(h: &mut String, folder: &str, id: &str, g: &Gallery) {
    let reference = url(folder, &g.reference.image);
    // With no items the reference stands in for the estimate.
    let first: &GalleryImage = g.items.first().unwrap_or(&g.reference);
    let first_src = url(folder, &first.image);
    let crop = g
        .crop
        .map(|Crop { x, y, w, h }| format!(" data-crop=\"{x},{y},{w},{h}\""))
        .unwrap_or_default();
    let _ = writeln!(
        h,
        "<div class=\"gallery\" id=\"{id}\"{crop} tabindex=\"0\">\n<h3>{}</h3>",
        esc(&g.title)
    );
    if !g.caption.is_empty() {
        let _ = writeln!(h, "<p class=\"caption\">{}</p>", esc(&g.caption));
    }
    let _ = writeln!(
        h,
        "<div class=\"controls\">\
         <span class=\"modes\" role=\"group\" aria-label=\"compare by\">\
         <button type=\"button\" class=\"mode on\" data-mode=\"wipe\">Wipe</button>\
         <button type=\"button\" class=\"mode\" data-mode=\"flip\">Flip</button></span>\
         <input type=\"range\" class=\"wipe\" min=\"0\" max=\"100\" step=\"0.1\" value=\"50\" \
         aria-label=\"wipe position\">\
         <button type=\"button\" class=\"toggle\" hidden>Show reference</button>\
         <span class=\"hint\">drag: wipe · click: move the crop (shift-click when flipping) · \
         F: flip · ←/→: next estimate</span>\
         </div>"
    );
    let _ = writeln!(
        h,
        "<div class=\"viewer\">\n<div class=\"stage\">\
         <img class=\"ref\" src=\"{reference}\" alt=\"{ra}\">\
         <img class=\"est\" src=\"{first_src}\" alt=\"{fa}\">\
         <div class=\"divider\"></div><div class=\"cropbox\"></div>\
         <span class=\"tag left\">{rl}</span><span class=\"tag right\">{fl}</span></div>",
        ra = esc(&g.reference.label),
        fa = esc(&first.label),
        rl = esc(&g.reference.label),
        fl = esc(&first.label),
    );
    let _ = writeln!(
        h,
        "<div class=\"zoom\">\
         <figure><div class=\"crop\"><img class=\"zref\" src=\"{reference}\" alt=\"{ra} crop\">\
         </div><figcaption>{rl}</figcaption></figure>\
         <figure><div class=\"crop\"><img class=\"zest\" src=\"{first_src}\" alt=\"{fa} crop\">\
         </div><figcaption class=\"zlabel\">{fl}</figcaption></figure>\
         <p class=\"zbar\"><button type=\"button\" class=\"zsize\" data-f=\"0.5\" \
         title=\"smaller crop, larger zoom\">+</button><button type=\"button\" \
         class=\"zsize\" data-f=\"2\" title=\"larger crop, smaller zoom\">−</button> \
         <span class=\"zinfo\"></span></p></div>\n</div>",
        ra = esc(&g.reference.label),
        fa = esc(&first.label),
        rl = esc(&g.reference.label),
        fl = esc(&first.label),
    );
    h.push_str("<div class=\"thumbs\">\n");
    let _ = writeln!(
        h,
        "<figure class=\"thumb reference\"><img src=\"{reference}\" alt=\"{}\">\
         <figcaption><b>{}</b><small>{}</small></figcaption></figure>",
        esc(&g.reference.label),
        esc(&g.reference.label),
        esc(&g.reference.note)
    );
    for (i, item) in g.items.iter().enumerate() {
        let src = url(folder, &item.image);
        let on = if i == 0 { " on" } else { "" };
        let _ = writeln!(
            h,
            "<button type=\"button\" class=\"thumb item{on}\" data-src=\"{src}\" \
             data-label=\"{l}\" data-note=\"{n}\"><img src=\"{src}\" alt=\"{l}\">\
             <b>{l}</b><small>{n}</small></button>",
            l = esc(&item.label),
            n = esc(&item.note)
        );
    }
    h.push_str("</div>\n</div>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slugs_and_titles() {
        assert_eq!(slug("Per length (k ≤ 5)"), "per-length-k-5");
        assert_eq!(
            without_title("# Convergence\n\nText\n", "Convergence"),
            "\nText\n"
        );
        assert_eq!(
            without_title("# Other\nText", "Convergence"),
            "# Other\nText"
        );
        assert_eq!(without_title("# Convergence", "Convergence"), "");
        assert!(numeric("1.2e-3") && numeric("−0.98 ± 0.02") && !numeric("pt") && !numeric("-"));
    }
}
