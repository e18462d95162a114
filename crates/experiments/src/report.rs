//! `lt report`: one self-contained page, `RESULTS/index.html`, from the studies' manifests
//! (`manifest::Manifest`): per study its Markdown summary, figures (the SVG shown, the PNG
//! linked), tables (with their CSV) and galleries, where a reader wipes or flips between the
//! reference and an estimate and sees a chosen crop enlarged. CSS and JavaScript are inline,
//! images are linked relatively (the results folder can be moved or served as it is), and
//! nothing is fetched from the network.
//!
//! The page carries a hidden self-check (`report/selfcheck.js`, the first script to run): it
//! counts window errors, unhandled rejections and `console.error` calls, waits for the page's
//! images, and writes a JSON line into `<pre id="lt-selfcheck" hidden>` — what
//! `crates/experiments/tests/report_browser.rs` reads from Chromium's dumped DOM.

mod escape;
pub mod findings;
mod html;
mod markdown;
pub mod overview;
pub mod slim;

use crate::image_io::write_atomic;
use crate::manifest::{Manifest, MANIFEST_FILE};
use crate::study::registry::STUDIES;
use std::path::{Path, PathBuf};

pub use html::{images_in_page, images_when_opened, SELFCHECK_ID};

/// The page's file name inside the results folder.
pub const INDEX_FILE: &str = "index.html";

/// The lecture's slides (`crates/experiments/scripts/slides_manifests.py` writes their
/// manifests), in the order the page shows them.
const SLIDES: [&str; 2] = ["seed-slides", "sppm-slides"];

/// What writes the slides' manifests (from their committed renders and tables).
const SLIDES_SCRIPT: &str = "python3 crates/experiments/scripts/slides_manifests.py";

/// One study folder as the page shows it: its manifest, or why it could not be read.
pub struct StudyDir {
    /// The folder's name inside the results folder (what links are relative to).
    pub folder: String,
    pub manifest: Result<Manifest, String>,
    /// The summary's Markdown, or why there is none to show.
    pub summary: Result<String, String>,
    /// The equal-time study's compact table (`overview`), or why it could not be read.
    pub overview: Option<Result<overview::Overview, String>>,
}

/// Every sub-folder of `results` holding a manifest, in report order: the studies' table order
/// (`study::registry::STUDIES`, the lecture's slides after the figures), then any other folder
/// by name.
pub fn find_studies(results: &Path) -> Result<Vec<StudyDir>, String> {
    let entries = std::fs::read_dir(results)
        .map_err(|e| format!("cannot read results folder {}: {e}", results.display()))?;
    let mut folders: Vec<String> = Vec::new();
    for entry in entries {
        let entry = entry.map_err(|e| format!("cannot read {}: {e}", results.display()))?;
        let path = entry.path();
        if path.is_dir() && path.join(MANIFEST_FILE).is_file() {
            if let Some(name) = path.file_name().and_then(|n| n.to_str()) {
                folders.push(name.to_string());
            }
        }
    }
    // The lecture's slides right after the field's figures, which they sit beside.
    let rank = |f: &str| {
        let study = |name: &str| STUDIES.iter().position(|s| s.name == name);
        match SLIDES.iter().position(|s| *s == f) {
            Some(k) => (study("figures").unwrap_or(STUDIES.len()), 1 + k),
            None => (study(f).unwrap_or(STUDIES.len()), 0),
        }
    };
    folders.sort_by(|a, b| rank(a).cmp(&rank(b)).then_with(|| a.cmp(b)));
    Ok(folders
        .into_iter()
        .map(|folder| {
            let dir = results.join(&folder);
            let manifest = Manifest::read(&dir);
            let summary = match &manifest {
                Ok(m) if m.summary.is_empty() => Ok(String::new()),
                Ok(m) => {
                    let p = dir.join(&m.summary);
                    std::fs::read_to_string(&p)
                        .map_err(|e| format!("cannot read {}: {e}", p.display()))
                }
                Err(_) => Ok(String::new()),
            };
            let overview = match &manifest {
                Ok(m) => overview::of_study(&dir, m),
                Err(_) => None,
            };
            StudyDir {
                folder,
                manifest,
                summary,
                overview,
            }
        })
        .collect())
}

/// Writes `results/index.html` (atomically) and returns its path. Problems a reader should see
/// — an unreadable manifest or summary, a file a manifest names but the folder lacks — are
/// shown on the page and printed as warnings; they do not stop the page from being written.
pub fn write_report(results: &Path) -> Result<PathBuf, String> {
    let studies = find_studies(results)?;
    for s in &studies {
        let dir = results.join(&s.folder);
        match &s.manifest {
            Err(e) => eprintln!("warning: {e}"),
            Ok(m) => {
                for f in html::files_named(m) {
                    if !dir.join(f).is_file() {
                        eprintln!(
                            "warning: {} names {f}, which {} lacks",
                            dir.join(MANIFEST_FILE).display(),
                            dir.display()
                        );
                    }
                }
            }
        }
        if let Err(e) = &s.summary {
            eprintln!("warning: {e}");
        }
        if let Some(Err(e)) = &s.overview {
            eprintln!("warning: {e}");
        }
    }
    // The findings lead the page (and are written as findings.md) when the studies' CSVs exist.
    let findings = match findings::findings(results) {
        Ok(f) => {
            write_atomic(
                &results.join("findings.md"),
                findings::markdown(&f).as_bytes(),
            )?;
            Some(f)
        }
        Err(_) => None,
    };
    let page = html::page(&studies, findings.as_deref());
    let path = results.join(INDEX_FILE);
    write_atomic(&path, page.as_bytes())?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn studies_in_report_order_and_broken_ones_shown() {
        let dir = std::env::temp_dir().join(format!("lt-report-order-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for name in ["zeta", "per-length", "alpha", "convergence", "equal-time"] {
            let d = dir.join(name);
            std::fs::create_dir_all(&d).unwrap();
            let mut m = Manifest::new(name, &format!("Study {name}"), "test");
            if name == "alpha" {
                m.summary = "missing.md".into();
            }
            m.write(&d).unwrap();
        }
        std::fs::create_dir_all(dir.join("broken")).unwrap();
        std::fs::write(dir.join("broken").join(MANIFEST_FILE), "{").unwrap();
        std::fs::create_dir_all(dir.join("not-a-study")).unwrap();
        let found = find_studies(&dir).unwrap();
        let names: Vec<&str> = found.iter().map(|s| s.folder.as_str()).collect();
        assert_eq!(
            names,
            [
                "convergence",
                "equal-time",
                "per-length",
                "alpha",
                "broken",
                "zeta"
            ]
        );
        let page = std::fs::read_to_string(write_report(&dir).unwrap()).unwrap();
        assert!(page.contains("missing.md"), "the missing summary is named");
        assert!(
            page.contains("broken/manifest.json"),
            "the broken manifest is named"
        );
        let order: Vec<usize> = names
            .iter()
            .map(|n| page.find(&format!("id=\"study-{n}\"")).unwrap())
            .collect();
        assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:?}");
        assert!(write_report(&dir.join("nowhere")).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
