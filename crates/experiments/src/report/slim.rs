//! `lt report --slim`: re-encodes a results folder's rendered PNGs as the committed previews the
//! gallery writer now makes (`gallery::write_jpeg`), moving each lossless PNG — and a gallery's
//! enlarged crops — into its study's `full/` folder, which git ignores. Renders are the gallery
//! images a manifest names and the images a folder's Markdown embeds; charts (a PNG with its SVG
//! beside it) stay lossless PNGs, re-encoded at the best compression. Manifests and Markdown links are rewritten to the previews, so
//! running it twice changes nothing the second time.

use crate::gallery::{full_path, write_jpeg, FULL_DIR};
use crate::image_io::write_atomic;
use crate::manifest::{Manifest, MANIFEST_FILE};
use std::path::{Path, PathBuf};

/// Folders of a results folder that are caches or a scale's own tree, never committed.
const SKIPPED: [&str; 3] = ["cache", "references", "quick"];

/// What a slimming did.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Slimmed {
    /// PNGs re-encoded as JPEG previews (their PNG moved to `full/`).
    pub previews: usize,
    /// Enlarged crops moved to `full/`.
    pub crops: usize,
    /// Bytes of the PNGs replaced, and of the previews that replaced them.
    pub png_bytes: u64,
    pub jpeg_bytes: u64,
    /// Charts re-encoded smaller (lossless), and the bytes that saved.
    pub charts: usize,
    pub chart_bytes_saved: u64,
    /// Thumbnails of the equal-time study's compact table made from its full-size previews.
    pub thumbs: usize,
}

/// Slims every study folder of `results` (see the module docs).
pub fn slim(results: &Path) -> Result<Slimmed, String> {
    let mut done = Slimmed::default();
    let entries = std::fs::read_dir(results)
        .map_err(|e| format!("cannot read results folder {}: {e}", results.display()))?;
    let mut dirs: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| !SKIPPED.iter().any(|s| n == *s))
        })
        .collect();
    dirs.sort();
    for dir in dirs {
        if dir.join(MANIFEST_FILE).is_file() {
            slim_manifest(&dir, &mut done)?;
            thumbs_from_previews(&dir, &mut done)?;
        }
        for md in markdown_files(&dir)? {
            slim_markdown(&dir, &md, &mut done)?;
        }
        move_crops(&dir, &dir, &mut done)?;
        for chart in charts(&dir)? {
            recompress(&chart, &mut done)?;
        }
    }
    Ok(done)
}

/// The charts under `dir`: PNGs with their SVG beside them (`plot::write_chart` writes both).
fn charts(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries =
            std::fs::read_dir(&d).map_err(|e| format!("cannot read {}: {e}", d.display()))?;
        for p in entries.flatten().map(|e| e.path()) {
            if p.is_dir() && p != dir.join(FULL_DIR) {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "png") && p.with_extension("svg").is_file()
            {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

/// Re-encodes a PNG losslessly at the encoder's best compression (the image crate's default is
/// its fastest), keeping the smaller file.
fn recompress(png: &Path, done: &mut Slimmed) -> Result<(), String> {
    use image::codecs::png::{CompressionType, FilterType, PngEncoder};
    let img = image::open(png).map_err(|e| format!("cannot read {}: {e}", png.display()))?;
    let mut bytes = Vec::new();
    img.write_with_encoder(PngEncoder::new_with_quality(
        &mut bytes,
        CompressionType::Best,
        FilterType::Adaptive,
    ))
    .map_err(|e| format!("cannot encode {}: {e}", png.display()))?;
    let before = size(png);
    if (bytes.len() as u64) < before {
        write_atomic(png, &bytes)?;
        done.charts += 1;
        done.chart_bytes_saved += before - bytes.len() as u64;
    }
    Ok(())
}

/// The manifest's gallery images as previews.
fn slim_manifest(dir: &Path, done: &mut Slimmed) -> Result<(), String> {
    let mut m = Manifest::read(dir)?;
    let mut changed = false;
    for g in &mut m.galleries {
        for i in std::iter::once(&mut g.reference).chain(g.items.iter_mut()) {
            if let Some(jpg) = preview_of(dir, &i.image, done)? {
                i.image = jpg;
                changed = true;
            }
        }
    }
    if changed {
        m.write(dir)?;
    }
    Ok(())
}

/// The compact table's thumbnails (`equal_time::thumb`: every scene's reference and equal-time
/// images), made from the full-size previews where they are missing: what moves a folder
/// written before the table to it, so its previews need not be committed.
fn thumbs_from_previews(dir: &Path, done: &mut Slimmed) -> Result<(), String> {
    use crate::study::equal_time::{thumb, write_thumb};
    let m = Manifest::read(dir)?;
    for g in m
        .galleries
        .iter()
        .filter(|g| super::overview::on_demand(&m, g))
    {
        for image in std::iter::once(&g.reference).chain(&g.items) {
            let rel = Path::new(&image.image);
            let (Some(scene), Some(what)) = (
                rel.parent()
                    .and_then(|p| p.file_name())
                    .and_then(|s| s.to_str()),
                rel.file_stem().and_then(|s| s.to_str()),
            ) else {
                continue;
            };
            let out = dir.join(thumb(scene, what));
            let wanted = what == "reference" || what.starts_with("time-");
            if !wanted || out.is_file() || !dir.join(rel).is_file() {
                continue;
            }
            let rgb = image::open(dir.join(rel))
                .map_err(|e| format!("cannot read {}: {e}", dir.join(rel).display()))?
                .into_rgb8();
            write_thumb(&out, &rgb)?;
            done.thumbs += 1;
        }
    }
    Ok(())
}

/// The images `md` embeds (`![…](x.png)`, relative to its folder) as previews, its links
/// rewritten; charts (an SVG beside the PNG) left alone.
fn slim_markdown(dir: &Path, md: &Path, done: &mut Slimmed) -> Result<(), String> {
    let text =
        std::fs::read_to_string(md).map_err(|e| format!("cannot read {}: {e}", md.display()))?;
    let base = md.parent().unwrap_or(dir);
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(at) = rest.find("](") {
        let (head, tail) = rest.split_at(at + 2);
        out.push_str(head);
        let end = tail.find(')').unwrap_or(tail.len());
        let target = &tail[..end];
        let is_chart = base.join(target).with_extension("svg").is_file();
        let rel_to_dir = base.join(target);
        let local = rel_to_dir.strip_prefix(dir).ok().and_then(|p| p.to_str());
        match local.filter(|_| target.ends_with(".png") && !is_chart) {
            Some(rel) => match preview_of(dir, rel, done)? {
                Some(_) => out.push_str(&format!("{}.jpg", target.trim_end_matches(".png"))),
                None => out.push_str(target),
            },
            None => out.push_str(target),
        }
        rest = &tail[end..];
    }
    out.push_str(rest);
    if out != text {
        write_atomic(md, out.as_bytes())?;
    }
    Ok(())
}

/// Writes `dir/<rel without .png>.jpg` from `dir/<rel>` and moves the PNG to `full/`; the
/// preview's name, or `None` when `rel` is no PNG or is gone (already slimmed).
fn preview_of(dir: &Path, rel: &str, done: &mut Slimmed) -> Result<Option<String>, String> {
    let Some(stem) = rel.strip_suffix(".png") else {
        return Ok(None);
    };
    let png = dir.join(rel);
    let jpg_rel = format!("{stem}.jpg");
    if !png.is_file() {
        // Already slimmed through another link to it, or gone.
        let slimmed = dir.join(&jpg_rel).is_file() && full_path(dir, rel).is_file();
        return Ok(slimmed.then_some(jpg_rel));
    }
    let rgb = image::open(&png)
        .map_err(|e| format!("cannot read {}: {e}", png.display()))?
        .into_rgb8();
    let jpg = dir.join(&jpg_rel);
    write_jpeg(&jpg, &rgb)?;
    done.previews += 1;
    done.png_bytes += size(&png);
    done.jpeg_bytes += size(&jpg);
    move_into(&png, &full_path(dir, rel))?;
    Ok(Some(jpg_rel))
}

/// Every `*.crop.png` under `here` (not in `full/`) moved to the same place under `dir/full/`.
fn move_crops(dir: &Path, here: &Path, done: &mut Slimmed) -> Result<(), String> {
    let entries =
        std::fs::read_dir(here).map_err(|e| format!("cannot read {}: {e}", here.display()))?;
    for p in entries.flatten().map(|e| e.path()) {
        if p.is_dir() {
            if p != dir.join(FULL_DIR) {
                move_crops(dir, &p, done)?;
            }
        } else if p.to_string_lossy().ends_with(".crop.png") {
            let rel = p.strip_prefix(dir).expect("under dir");
            move_into(&p, &dir.join(FULL_DIR).join(rel))?;
            done.crops += 1;
        }
    }
    Ok(())
}

/// The Markdown files under `dir`, `full/` left out.
fn markdown_files(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let entries =
            std::fs::read_dir(&d).map_err(|e| format!("cannot read {}: {e}", d.display()))?;
        for p in entries.flatten().map(|e| e.path()) {
            if p.is_dir() && p != dir.join(FULL_DIR) {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                out.push(p);
            }
        }
    }
    out.sort();
    Ok(out)
}

fn move_into(from: &Path, to: &Path) -> Result<(), String> {
    if let Some(parent) = to.parent() {
        std::fs::create_dir_all(parent)
            .map_err(|e| format!("cannot create {}: {e}", parent.display()))?;
    }
    std::fs::rename(from, to)
        .map_err(|e| format!("cannot move {} to {}: {e}", from.display(), to.display()))
}

fn size(p: &Path) -> u64 {
    std::fs::metadata(p).map(|m| m.len()).unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::manifest::{Gallery, GalleryImage};

    fn png(path: &Path) {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        image::RgbImage::from_fn(8, 4, |x, y| image::Rgb([x as u8 * 30, y as u8 * 60, 7]))
            .save(path)
            .unwrap();
    }

    #[test]
    fn renders_become_previews_and_charts_stay() {
        let results = std::env::temp_dir().join(format!("lt-slim-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&results);
        let study = results.join("equal-time");
        for f in ["g/ref.png", "g/pt.png", "g/pt.crop.png", "chart.png"] {
            png(&study.join(f));
        }
        std::fs::write(study.join("chart.svg"), "<svg/>").unwrap();
        let image = |label: &str, f: &str| GalleryImage {
            label: label.into(),
            image: f.into(),
            note: String::new(),
        };
        let mut m = Manifest::new("equal-time", "Equal time", "test");
        m.galleries.push(Gallery {
            title: "g".into(),
            caption: String::new(),
            reference: image("reference", "g/ref.png"),
            items: vec![image("pt", "g/pt.png")],
            crop: None,
        });
        m.write(&study).unwrap();
        let notes = results.join("slides");
        png(&notes.join("a/pt.png"));
        png(&notes.join("plot.png"));
        std::fs::write(notes.join("plot.svg"), "<svg/>").unwrap();
        std::fs::write(
            notes.join("README.md"),
            "![pt](a/pt.png) and ![plot](plot.png), [link](README.md)\n",
        )
        .unwrap();
        std::fs::write(notes.join("table.md"), "![again](a/pt.png)\n").unwrap();

        let done = slim(&results).unwrap();
        assert_eq!((done.previews, done.crops), (3, 1), "{done:?}");
        let chart = image::open(study.join("chart.png")).unwrap().into_rgb8();
        assert_eq!(
            chart.get_pixel(7, 3).0,
            [210, 180, 7],
            "charts stay lossless"
        );
        let m = Manifest::read(&study).unwrap();
        assert_eq!(m.galleries[0].reference.image, "g/ref.jpg");
        assert_eq!(m.galleries[0].items[0].image, "g/pt.jpg");
        for f in [
            "g/ref.jpg",
            "g/pt.jpg",
            "chart.png",
            "full/g/pt.png",
            "full/g/pt.crop.png",
        ] {
            assert!(study.join(f).is_file(), "{f}");
        }
        assert!(!study.join("g/pt.png").exists() && !study.join("g/pt.crop.png").exists());
        let md = std::fs::read_to_string(notes.join("README.md")).unwrap();
        assert_eq!(
            md,
            "![pt](a/pt.jpg) and ![plot](plot.png), [link](README.md)\n"
        );
        assert_eq!(
            std::fs::read_to_string(notes.join("table.md")).unwrap(),
            "![again](a/pt.jpg)\n"
        );
        assert!(notes.join("full/a/pt.png").is_file() && notes.join("plot.png").is_file());
        // Twice: nothing left to do.
        assert_eq!(slim(&results).unwrap(), Slimmed::default());
        std::fs::remove_dir_all(&results).unwrap();
    }
}
