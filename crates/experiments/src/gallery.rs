//! What a gallery needs from images: sRGB previews, nearest-neighbour enlarged crops, and a crop
//! chosen where the estimates differ most from the reference. `write_gallery` does all three
//! and returns the manifest entry `lt report` shows.
//!
//! A gallery is committed with the results, so its images are what weighs: the page shows JPEG
//! previews at full resolution (`PREVIEW_QUALITY`: the committed renders weigh 6.6× less than as
//! PNGs, 12.1 MB for 79.9 MB, each pixel's noise still seen), and the lossless PNGs and enlarged
//! crops go to the study's `full/` folder, which git ignores (`FULL_DIR`).

use crate::image_io::{srgb_encode, write_atomic_with, write_png_preview};
use crate::manifest::{Crop, Gallery, GalleryImage};
use lt_estimators::Image;
use std::path::{Path, PathBuf};

/// How much a crop PNG is enlarged (nearest neighbour: pixels stay square and sharp).
pub const CROP_SCALE: u32 = 4;

/// JPEG quality of the committed previews.
pub const PREVIEW_QUALITY: u8 = 75;

/// The sub-folder of a study's folder that holds its full-size, lossless gallery images (not
/// committed: `.gitignore`).
pub const FULL_DIR: &str = "full";

/// Where the lossless copy of `rel` (a file relative to `study_dir`) goes.
pub fn full_path(study_dir: &Path, rel: &str) -> PathBuf {
    study_dir.join(FULL_DIR).join(rel)
}

/// An 8-bit sRGB image (clamped to [0, 1], no tone curve).
fn srgb8(img: &Image) -> image::RgbImage {
    let bytes: Vec<u8> = img
        .data
        .iter()
        .flat_map(|p| p.map(|v| (srgb_encode(v) * 255.0).round() as u8))
        .collect();
    image::RgbImage::from_raw(img.width as u32, img.height as u32, bytes)
        .expect("buffer matches size")
}

/// Writes an 8-bit sRGB image as a JPEG of `PREVIEW_QUALITY`, atomically, creating the parent
/// folder.
pub fn write_jpeg(path: &Path, rgb: &image::RgbImage) -> Result<(), String> {
    create_parent(path)?;
    write_atomic_with(path, |tmp| {
        let file = std::fs::File::create(tmp)
            .map_err(|e| format!("cannot create {}: {e}", tmp.display()))?;
        let mut out = std::io::BufWriter::new(file);
        image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, PREVIEW_QUALITY)
            .encode_image(rgb)
            .map_err(|e| format!("cannot write JPEG {}: {e}", path.display()))?;
        std::io::Write::flush(&mut out).map_err(|e| format!("cannot write {}: {e}", path.display()))
    })
}

/// Writes `img` as the gallery's preview: an sRGB JPEG (see `write_jpeg`).
pub fn write_srgb_jpeg(path: &Path, img: &Image) -> Result<(), String> {
    write_jpeg(path, &srgb8(img))
}

/// Writes `img` as an 8-bit sRGB PNG (clamped to [0, 1], no tone curve), atomically, creating
/// the parent folder.
pub fn write_srgb_png(path: &Path, img: &Image) -> Result<(), String> {
    create_parent(path)?;
    write_png_preview(path, img)
}

/// Writes the `crop` of `img`, each pixel enlarged to `scale`×`scale`, as an sRGB PNG.
pub fn write_crop_png(path: &Path, img: &Image, crop: Crop, scale: u32) -> Result<(), String> {
    check_crop(img, crop).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    if scale == 0 {
        return Err(format!("cannot write {}: scale 0", path.display()));
    }
    create_parent(path)?;
    let (w, h) = (crop.w * scale, crop.h * scale);
    let buf = image::RgbImage::from_fn(w, h, |x, y| {
        let p = img.get((crop.x + x / scale) as usize, (crop.y + y / scale) as usize);
        image::Rgb(p.map(|v| (srgb_encode(v) * 255.0).round() as u8))
    });
    write_atomic_with(path, |tmp| {
        buf.save_with_format(tmp, image::ImageFormat::Png)
            .map_err(|e| format!("cannot write PNG {}: {e}", path.display()))
    })
}

/// The `w`×`h` rectangle (clamped to the image) where the estimates differ most from the
/// reference: the window maximising Σ over items and pixels of the squared difference of the
/// sRGB-encoded values (what a reader sees, so a bright firefly counts no more than a visible
/// blotch). Windows are tried on a grid of step max(1, size/8); the first best one in row-major
/// order wins, so the choice is deterministic. With no items, or identical images, the centre.
pub fn pick_crop(reference: &Image, items: &[&Image], w: u32, h: u32) -> Result<Crop, String> {
    let (iw, ih) = (reference.width, reference.height);
    if iw == 0 || ih == 0 {
        return Err("crop: empty reference".into());
    }
    if let Some(bad) = items.iter().find(|i| !i.same_size(reference)) {
        return Err(format!(
            "crop: reference is {iw}x{ih}, an item is {}x{}",
            bad.width, bad.height
        ));
    }
    let cw = (w.max(1) as usize).min(iw);
    let ch = (h.max(1) as usize).min(ih);
    let centre = Crop {
        x: ((iw - cw) / 2) as u32,
        y: ((ih - ch) / 2) as u32,
        w: cw as u32,
        h: ch as u32,
    };
    // Summed-area table of the per-pixel error, (iw+1)×(ih+1).
    let stride = iw + 1;
    let mut sat = vec![0.0f64; stride * (ih + 1)];
    for y in 0..ih {
        let mut row = 0.0;
        for x in 0..iw {
            let r = reference.get(x, y);
            let mut e = 0.0;
            for item in items {
                let t = item.get(x, y);
                for c in 0..3 {
                    let d = srgb_encode(t[c]) - srgb_encode(r[c]);
                    e += d * d;
                }
            }
            row += e;
            sat[(y + 1) * stride + x + 1] = sat[y * stride + x + 1] + row;
        }
    }
    let window = |x: usize, y: usize| {
        sat[(y + ch) * stride + x + cw] - sat[y * stride + x + cw] - sat[(y + ch) * stride + x]
            + sat[y * stride + x]
    };
    let (sx, sy) = ((cw / 8).max(1), (ch / 8).max(1));
    let mut best: Option<(f64, usize, usize)> = None;
    let mut y = 0;
    while y + ch <= ih {
        let mut x = 0;
        while x + cw <= iw {
            let e = window(x, y);
            if best.is_none_or(|(b, _, _)| e > b) {
                best = Some((e, x, y));
            }
            x += sx;
        }
        y += sy;
    }
    match best {
        Some((e, x, y)) if e > 0.0 => Ok(Crop {
            x: x as u32,
            y: y as u32,
            w: cw as u32,
            h: ch as u32,
        }),
        _ => Ok(centre),
    }
}

/// One image of a gallery: its label, a note under it, and the file stem (relative to the study
/// folder, e.g. "gallery/cornell-box/pt") its PNGs are written under.
pub struct Entry<'a> {
    pub label: &'a str,
    pub note: String,
    pub image: &'a Image,
    pub stem: String,
}

/// Writes every image as the preview `study_dir/<stem>.jpg` and the lossless
/// `study_dir/full/<stem>.png`, and, when `crop_size` is given, picks the crop (`pick_crop` over
/// all items, a square of that many pixels) and writes each image's `full/<stem>.crop.png`
/// enlarged ×`CROP_SCALE`. Returns the manifest's gallery (the previews, relative to
/// `study_dir`).
pub fn write_gallery(
    study_dir: &Path,
    title: &str,
    caption: &str,
    reference: &Entry,
    items: &[Entry],
    crop_size: Option<u32>,
) -> Result<Gallery, String> {
    let crop = match crop_size {
        Some(s) => {
            let imgs: Vec<&Image> = items.iter().map(|e| e.image).collect();
            Some(pick_crop(reference.image, &imgs, s, s)?)
        }
        None => None,
    };
    let mut write = |e: &Entry| -> Result<GalleryImage, String> {
        let preview = format!("{}.jpg", e.stem);
        write_srgb_jpeg(&study_dir.join(&preview), e.image)?;
        write_srgb_png(&full_path(study_dir, &format!("{}.png", e.stem)), e.image)?;
        if let Some(c) = crop {
            let crop_png = full_path(study_dir, &format!("{}.crop.png", e.stem));
            write_crop_png(&crop_png, e.image, c, CROP_SCALE)?;
        }
        Ok(GalleryImage {
            label: e.label.into(),
            image: preview,
            note: e.note.clone(),
        })
    };
    let reference_image = write(reference)?;
    let items = items
        .iter()
        .map(&mut write)
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Gallery {
        title: title.into(),
        caption: caption.into(),
        reference: reference_image,
        items,
        crop,
    })
}

fn check_crop(img: &Image, c: Crop) -> Result<(), String> {
    let fits = c.w > 0
        && c.h > 0
        && (c.x as usize + c.w as usize) <= img.width
        && (c.y as usize + c.h as usize) <= img.height;
    if fits {
        Ok(())
    } else {
        Err(format!(
            "crop {}x{} at ({}, {}) outside the {}x{} image",
            c.w, c.h, c.x, c.y, img.width, img.height
        ))
    }
}

fn create_parent(path: &Path) -> Result<(), String> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(d) => {
            std::fs::create_dir_all(d).map_err(|e| format!("cannot create {}: {e}", d.display()))
        }
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: usize, h: usize, v: f64) -> Image {
        Image::from_fn(w, h, |_, _| [v; 3])
    }

    #[test]
    fn crop_lands_on_the_error() {
        let r = flat(64, 48, 0.25);
        let mut a = r.clone();
        let mut b = r.clone();
        // A blotch at (40..48, 8..16) in one item, a weaker one elsewhere in the other.
        for y in 8..16 {
            for x in 40..48 {
                a.data[y * 64 + x] = [0.9; 3];
            }
        }
        for y in 30..34 {
            for x in 4..8 {
                b.data[y * 64 + x] = [0.4; 3];
            }
        }
        let c = pick_crop(&r, &[&a, &b], 8, 8).unwrap();
        assert_eq!((c.x, c.y, c.w, c.h), (40, 8, 8, 8));
        // Deterministic, and clamped to the image.
        assert_eq!(pick_crop(&r, &[&a, &b], 8, 8).unwrap(), c);
        let big = pick_crop(&r, &[&a], 100, 100).unwrap();
        assert_eq!((big.x, big.y, big.w, big.h), (0, 0, 64, 48));
        // No difference anywhere: the centre.
        let c = pick_crop(&r, &[&r], 16, 16).unwrap();
        assert_eq!((c.x, c.y), (24, 16));
        assert!(pick_crop(&r, &[&flat(8, 8, 0.0)], 4, 4).is_err());
    }

    #[test]
    fn crop_png_is_enlarged_nearest_neighbour() {
        let dir = std::env::temp_dir().join(format!("lt-gallery-{}", std::process::id()));
        let img = Image::from_fn(10, 6, |x, y| [x as f64 / 9.0, y as f64 / 5.0, 0.0]);
        let crop = Crop {
            x: 2,
            y: 1,
            w: 3,
            h: 2,
        };
        let path = dir.join("sub").join("c.png");
        write_crop_png(&path, &img, crop, 4).unwrap();
        let png = image::open(&path).unwrap().into_rgb8();
        assert_eq!(png.dimensions(), (12, 8));
        let expect = |x: usize, y: usize| {
            img.get(x, y)
                .map(|v| (srgb_encode(v) * 255.0).round() as u8)
        };
        assert_eq!(png.get_pixel(0, 0).0, expect(2, 1));
        assert_eq!(png.get_pixel(3, 3).0, expect(2, 1));
        assert_eq!(png.get_pixel(4, 0).0, expect(3, 1));
        assert_eq!(png.get_pixel(11, 7).0, expect(4, 2));
        let outside = Crop { x: 8, ..crop };
        assert!(write_crop_png(&dir.join("bad.png"), &img, outside, 4).is_err());

        let g = write_gallery(
            &dir,
            "t",
            "",
            &Entry {
                label: "reference",
                note: String::new(),
                image: &img,
                stem: "g/ref".into(),
            },
            &[Entry {
                label: "pt",
                note: "MSE 0".into(),
                image: &img,
                stem: "g/pt".into(),
            }],
            Some(4),
        )
        .unwrap();
        assert_eq!(g.items[0].image, "g/pt.jpg");
        for f in ["g/ref.jpg", "g/pt.jpg"] {
            assert!(dir.join(f).is_file(), "{f}");
        }
        for f in ["g/ref.png", "g/pt.png", "g/ref.crop.png", "g/pt.crop.png"] {
            assert!(full_path(&dir, f).is_file(), "{f}");
            assert!(!dir.join(f).exists(), "{f} beside the preview");
        }
        // The preview is the image: same size, and within JPEG's error of its sRGB values.
        let preview = image::open(dir.join("g/pt.jpg")).unwrap().into_rgb8();
        assert_eq!(preview.dimensions(), (10, 6));
        let lossless = image::open(full_path(&dir, "g/pt.png"))
            .unwrap()
            .into_rgb8();
        let worst = preview
            .pixels()
            .zip(lossless.pixels())
            .flat_map(|(a, b)| (0..3).map(move |c| (a[c] as i32 - b[c] as i32).abs()))
            .max()
            .unwrap();
        assert!(worst <= 24, "JPEG preview off by {worst}/255");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
