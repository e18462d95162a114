//! The schema of `results/<study>/manifest.json`: what a study wrote (its summary, figures,
//! tables and galleries) and what `lt report` reads. Every path in it is relative to the study's
//! own folder, so a results folder can be moved or published as it is.

use crate::image_io::write_atomic;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The file name every study writes into its folder.
pub const MANIFEST_FILE: &str = "manifest.json";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Manifest {
    /// The study's name, as `lt study NAME` spells it (also its folder name).
    pub study: String,
    pub title: String,
    /// "quick" | "full" | "test".
    pub scale: String,
    /// Markdown file name in the study folder, e.g. "summary.md" (empty: none).
    pub summary: String,
    pub figures: Vec<Figure>,
    pub tables: Vec<Table>,
    pub galleries: Vec<Gallery>,
}

/// A chart written by `plot::write_chart`; `svg` and `png` are relative to the study folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    pub title: String,
    pub caption: String,
    pub svg: String,
    pub png: String,
}

/// A table shown in the report; `csv` (relative to the study folder) holds the same numbers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Table {
    pub title: String,
    pub caption: String,
    pub csv: String,
    pub columns: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

/// A reference image and the estimates a reader compares with it (flip, wipe, zoomed crop).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gallery {
    pub title: String,
    pub caption: String,
    pub reference: GalleryImage,
    pub items: Vec<GalleryImage>,
    /// A rectangle in image pixels worth zooming into (see `gallery::pick_crop`).
    pub crop: Option<Crop>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GalleryImage {
    pub label: String,
    /// The sRGB image the page shows (a JPEG preview, `gallery::write_gallery`; a PNG in
    /// manifests written before it), relative to the study folder.
    #[serde(alias = "png")]
    pub image: String,
    /// A short line under the image, e.g. "MSE 1.2e-3, 30 s".
    pub note: String,
}

/// A rectangle in image pixels: top-left (x, y), width w, height h.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Crop {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl Table {
    /// Writes the table as CSV to `study_dir/<self.csv>` (atomically; fields holding a comma,
    /// quote or line break are quoted, quotes doubled), creating the parent folder.
    pub fn write_csv(&self, study_dir: &Path) -> Result<PathBuf, String> {
        let path = study_dir.join(&self.csv);
        if let Some(d) = path.parent() {
            std::fs::create_dir_all(d)
                .map_err(|e| format!("cannot create {}: {e}", d.display()))?;
        }
        let mut text = String::new();
        for row in std::iter::once(&self.columns).chain(&self.rows) {
            let fields: Vec<String> = row.iter().map(|f| csv_field(f)).collect();
            text.push_str(&fields.join(","));
            text.push('\n');
        }
        write_atomic(&path, text.as_bytes())?;
        Ok(path)
    }
}

fn csv_field(f: &str) -> String {
    if f.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", f.replace('"', "\"\""))
    } else {
        f.to_string()
    }
}

impl Manifest {
    /// A manifest with no figures, tables or galleries yet.
    pub fn new(study: &str, title: &str, scale: &str) -> Manifest {
        Manifest {
            study: study.into(),
            title: title.into(),
            scale: scale.into(),
            summary: String::new(),
            figures: Vec::new(),
            tables: Vec::new(),
            galleries: Vec::new(),
        }
    }

    /// `dir/manifest.json`.
    pub fn path(dir: &Path) -> PathBuf {
        dir.join(MANIFEST_FILE)
    }

    /// Writes `dir/manifest.json` atomically (pretty-printed JSON); returns its path.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, String> {
        let path = Manifest::path(dir);
        let mut json = serde_json::to_string_pretty(self)
            .map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
        json.push('\n');
        write_atomic(&path, json.as_bytes())?;
        Ok(path)
    }

    /// Reads `dir/manifest.json`; errors name the file.
    pub fn read(dir: &Path) -> Result<Manifest, String> {
        let path = Manifest::path(dir);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
        serde_json::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Manifest {
        let mut m = Manifest::new("convergence", "Convergence", "test");
        m.summary = "summary.md".into();
        m.figures.push(Figure {
            title: "MSE against spp".into(),
            caption: "log-log".into(),
            svg: "mse_spp.svg".into(),
            png: "mse_spp.png".into(),
        });
        m.tables.push(Table {
            title: "Efficiency".into(),
            caption: String::new(),
            csv: "efficiency.csv".into(),
            columns: vec!["integrator".into(), "1/(MSE·s)".into()],
            rows: vec![vec!["pt".into(), "12.5".into()]],
        });
        m.galleries.push(Gallery {
            title: "cornell-box".into(),
            caption: String::new(),
            reference: GalleryImage {
                label: "reference".into(),
                image: "ref.jpg".into(),
                note: String::new(),
            },
            items: vec![GalleryImage {
                label: "pt".into(),
                image: "pt.jpg".into(),
                note: "MSE 1e-3".into(),
            }],
            crop: Some(Crop {
                x: 8,
                y: 16,
                w: 32,
                h: 32,
            }),
        });
        m
    }

    #[test]
    fn round_trip() {
        let dir = std::env::temp_dir().join(format!("lt-manifest-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = sample();
        let path = m.write(&dir).unwrap();
        assert_eq!(path, dir.join(MANIFEST_FILE));
        assert_eq!(Manifest::read(&dir).unwrap(), m);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn manifests_written_before_the_previews_still_read() {
        let old = r#"{"label": "pt", "png": "g/pt.png", "note": ""}"#;
        let i: GalleryImage = serde_json::from_str(old).unwrap();
        assert_eq!(i.image, "g/pt.png");
    }

    #[test]
    fn tables_write_quoted_csv() {
        let dir = std::env::temp_dir().join(format!("lt-manifest-csv-{}", std::process::id()));
        let t = Table {
            title: "t".into(),
            caption: String::new(),
            csv: "sub/t.csv".into(),
            columns: vec!["name".into(), "value".into()],
            rows: vec![
                vec!["a, b".into(), "1".into()],
                vec!["say \"hi\"".into(), "2".into()],
            ],
        };
        let path = t.write_csv(&dir).unwrap();
        assert_eq!(
            std::fs::read_to_string(path).unwrap(),
            "name,value\n\"a, b\",1\n\"say \"\"hi\"\"\",2\n"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn errors_name_the_file() {
        let dir = std::env::temp_dir().join(format!("lt-manifest-bad-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = Manifest::read(&dir).unwrap_err();
        assert!(e.contains("manifest.json"), "{e}");
        std::fs::write(dir.join(MANIFEST_FILE), "{\"study\": 3}").unwrap();
        let e = Manifest::read(&dir).unwrap_err();
        assert!(e.contains("manifest.json"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
