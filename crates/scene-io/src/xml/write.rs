//! One of our TOML scenes as Mitsuba 3 XML (`lt convert`), wherever Mitsuba can express it: the
//! scene is loaded (so everything is checked as for rendering), then its plugin tree — the one
//! the loader builds the scene from (`toml_scene::plugins`) — is printed (`print`), so this file
//! knows no plugin's parameters. Only lt's own tree properties are put in Mitsuba's words: an
//! orthographic sensor's `half_width` becomes a `to_world` scale before its look-at, and a mesh's
//! `missing_normals = "flat"` becomes `face_normals` when the file has no normals (Mitsuba would
//! compute smooth ones) and is dropped otherwise. File names are made relative to the output.
//! Numbers are written as the shortest decimal that reads back to the same value, so toml → xml
//! → load gives the same scene bit for bit.
//!
//! Refused: the `sun` light (Mitsuba 3 has no distant light of finite solid angle; a
//! directional light or an environment map would change the image, so nothing is approximated).

use super::doc::Elem;
use super::print::{escape, map_filenames, print};
use crate::error::Ctx;
use crate::toml_scene::schema::SceneFile;
use crate::toml_scene::tree::{boolean, elem};
use crate::SceneError;
use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};

/// The XML text of the TOML scene at `scene`, with mesh paths relative to `out_dir` (the
/// directory the XML will be written to).
pub fn to_mitsuba_xml(scene: &Path, out_dir: &Path) -> Result<String, SceneError> {
    let text = std::fs::read_to_string(scene).map_err(|e| SceneError {
        file: scene.display().to_string(),
        line: None,
        column: None,
        message: format!("cannot read the scene file: {e}"),
    })?;
    if scene
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("xml"))
    {
        return Err(SceneError {
            file: scene.display().to_string(),
            line: None,
            column: None,
            message: "this is already an XML scene (lt convert reads our TOML scenes)".into(),
        });
    }
    // Everything checked exactly as for rendering.
    crate::toml_scene::load_scene_str(&text, scene)?;
    let ctx = Ctx {
        file: scene.display().to_string(),
        text: &text,
        base_dir: scene.parent().map(Path::to_path_buf).unwrap_or_default(),
    };
    let file: SceneFile =
        toml::from_str(&text).map_err(|e| ctx.whole(e.message().trim_end().to_string()))?;
    for l in &file.lights {
        let d = l.get_ref();
        if d.kind.get_ref() == "sun" {
            return Err(ctx.at(
                d.kind.span(),
                "Mitsuba 3 has no sun of finite solid angle (its `directional` is a delta in \
                 direction, its `sunsky` a sky model): this scene cannot be written as Mitsuba \
                 XML without changing its image, and lt convert does not approximate",
            ));
        }
    }
    let name = scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut x = String::new();
    let _ = writeln!(x, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        x,
        "<!-- {} as Mitsuba 3 XML, written by `lt convert` (render it with Mitsuba's `scalar_rgb` or `llvm_ad_rgb` variant). -->",
        escape(&name)
    );
    let _ = writeln!(x, "<scene version=\"3.0.0\">");
    for mut e in crate::toml_scene::plugins(&ctx, &file)? {
        in_mitsubas_words(&ctx, &mut e)?;
        x.push_str(&printed(&ctx, e, 1, out_dir));
    }
    x.push_str("</scene>\n");
    Ok(x)
}

/// The child property of `e` named `name`, removed, with its value.
fn take(e: &mut Elem, name: &str) -> Option<(usize, Elem)> {
    let i = e
        .children
        .iter()
        .position(|c| c.attr("name") == Some(name))?;
    Some((i, e.children.remove(i)))
}

/// lt's own properties of a top-level plugin as Mitsuba writes the same thing.
fn in_mitsubas_words(ctx: &Ctx, e: &mut Elem) -> Result<(), SceneError> {
    if e.tag == "sensor" {
        if let Some((_, hw)) = take(e, "half_width") {
            // Mitsuba's orthographic film spans [-1, 1] in x, scaled by to_world.
            let v = hw.attr("value").unwrap_or("1").to_string();
            let scale = elem("scale", &[("x", &v), ("y", &v)], hw.range);
            if let Some(t) = e.children.iter_mut().find(|c| c.tag == "transform") {
                t.children.insert(0, scale);
            }
        }
    }
    if e.tag == "shape" {
        if let Some((i, m)) = take(e, "missing_normals") {
            let file = e
                .children
                .iter()
                .find(|c| c.attr("name") == Some("filename"))
                .expect("a mesh has its filename");
            let spanned = toml::Spanned::new(
                file.range.clone(),
                file.attr("value").unwrap_or_default().to_string(),
            );
            let mesh = crate::mesh::obj::load_obj(ctx, &spanned)?;
            if mesh.normals.is_none() && m.attr("value") == Some("flat") {
                e.children.insert(i, boolean("face_normals", true, m.range));
            }
        }
    }
    Ok(())
}

/// `path` relative to `dir` when both resolve (else `path` made absolute).
fn relative(path: &Path, dir: &Path) -> PathBuf {
    let (Ok(p), Ok(d)) = (path.canonicalize(), dir.canonicalize()) else {
        return std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    };
    let pc: Vec<Component> = p.components().collect();
    let dc: Vec<Component> = d.components().collect();
    let common = pc.iter().zip(&dc).take_while(|(a, b)| a == b).count();
    let mut out = PathBuf::new();
    for _ in common..dc.len() {
        out.push("..");
    }
    for c in &pc[common..] {
        out.push(c);
    }
    out
}

/// A tree element as XML text at `depth`, its file names relative to `out_dir`.
fn printed(ctx: &Ctx, mut e: Elem, depth: usize, out_dir: &Path) -> String {
    let base = ctx.base_dir.clone();
    map_filenames(&mut e, &|f| {
        relative(&base.join(f), out_dir)
            .to_string_lossy()
            .into_owned()
    });
    let mut x = String::new();
    print(&e, depth, &mut x);
    x
}
