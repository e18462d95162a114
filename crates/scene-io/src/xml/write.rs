//! One of our TOML scenes as Mitsuba 3 XML (`lt convert`), wherever Mitsuba can express it: the
//! scene is loaded (so everything is checked as for rendering), then written from its file's own
//! description. Materials, media, lights and textures are printed from the plugin tree the
//! loader builds them from (`toml_scene::tree`, `print`), so this file knows none of their
//! parameters; the integrator, the sensor and the shapes are written here — rectangles and cubes
//! as `rectangle`/`cube` with the exact `to_world` the loader built, meshes as `obj` files
//! referenced relative to the output, spheres as `sphere`. Numbers are written as the shortest
//! decimal that reads back to the same value, so toml → xml → load gives the same scene bit for
//! bit.
//!
//! Refused: the `sun` light (Mitsuba 3 has no distant light of finite solid angle; a
//! directional light or an environment map would change the image, so nothing is approximated).

use super::doc::Elem;
use super::print::{escape, map_filenames, print};
use crate::error::Ctx;
use crate::toml_scene::schema::{SceneFile, ShapeDef, TextureDef, S};
use crate::toml_scene::tree;
use crate::transform::shape_matrix;
use crate::SceneError;
use lt_core::camera::{FilterShape, Lens};
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
    let loaded = crate::toml_scene::load_scene_str(&text, scene)?;
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
    let mut x = String::new();
    let name = scene
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let _ = writeln!(x, "<?xml version=\"1.0\" encoding=\"utf-8\"?>");
    let _ = writeln!(
        x,
        "<!-- {} as Mitsuba 3 XML, written by `lt convert` (render it with Mitsuba's `scalar_rgb` or `llvm_ad_rgb` variant). -->",
        esc(&name)
    );
    let _ = writeln!(x, "<scene version=\"3.0.0\">");
    let s = loaded.settings;
    let _ = writeln!(
        x,
        "    <integrator type=\"path\">\n        <integer name=\"max_depth\" value=\"{}\"/>\n        <integer name=\"rr_depth\" value=\"{}\"/>\n    </integrator>",
        s.max_depth, s.rr_depth
    );
    // Camera: the look-at as written (f32, as the loader reads it).
    let c = file.camera.get_ref();
    let v = |a: &[f64; 3]| {
        let f = a.map(|x| x as f32);
        format!("{}, {}, {}", f[0], f[1], f[2])
    };
    let up =
        c.up.as_ref()
            .map(|u| *u.get_ref())
            .unwrap_or([0.0, 1.0, 0.0]);
    let axis = match c.fov_axis.map_or(lt_core::camera::FovAxis::X, Into::into) {
        lt_core::camera::FovAxis::X => "x",
        lt_core::camera::FovAxis::Y => "y",
        lt_core::camera::FovAxis::Smaller => "smaller",
        lt_core::camera::FovAxis::Larger => "larger",
    };
    let [w, h] = *c.resolution.get_ref();
    let cam = &loaded.camera;
    let kind = match cam.lens() {
        Lens::Pinhole => "perspective",
        Lens::ThinLens { .. } => "thinlens",
        Lens::Orthographic { .. } => "orthographic",
    };
    let mut media: Vec<_> = file.media.iter().collect();
    media.sort_by_key(|(_, d)| d.span().start);
    for (name, def) in media {
        x.push_str(&printed(&ctx, tree::medium(&ctx, name, def)?, 1, out_dir));
    }
    let _ = writeln!(x, "    <sensor type=\"{kind}\">");
    if let Some(m) = &c.medium {
        x.push_str(&printed(
            &ctx,
            tree::reference("medium", m.get_ref(), m.span()),
            2,
            out_dir,
        ));
    }
    if let Some(fov) = &c.fov {
        let _ = writeln!(
            x,
            "        <float name=\"fov\" value=\"{}\"/>",
            *fov.get_ref() as f32
        );
        let _ = writeln!(x, "        <string name=\"fov_axis\" value=\"{axis}\"/>");
    }
    if let Lens::ThinLens {
        aperture_radius,
        focus_distance,
    } = cam.lens()
    {
        let _ = writeln!(
            x,
            "        <float name=\"aperture_radius\" value=\"{aperture_radius}\"/>\n        <float name=\"focus_distance\" value=\"{focus_distance}\"/>"
        );
    }
    let ppo = cam.principal_point_offset();
    if ppo != lt_core::Vec2::ZERO {
        let _ = writeln!(
            x,
            "        <float name=\"principal_point_offset_x\" value=\"{}\"/>\n        <float name=\"principal_point_offset_y\" value=\"{}\"/>",
            ppo.x, ppo.y
        );
    }
    let scale = match cam.lens() {
        Lens::Orthographic { half_width } => {
            format!("\n            <scale x=\"{half_width}\" y=\"{half_width}\"/>")
        }
        _ => String::new(),
    };
    let _ = writeln!(
        x,
        "        <transform name=\"to_world\">{scale}\n            <lookat origin=\"{}\" target=\"{}\" up=\"{}\"/>\n        </transform>",
        v(c.eye.get_ref()),
        v(c.target.get_ref()),
        v(&up)
    );
    let _ = writeln!(
        x,
        "        <sampler type=\"independent\">\n            <integer name=\"sample_count\" value=\"{}\"/>\n        </sampler>",
        s.spp
    );
    let _ = writeln!(
        x,
        "        <film type=\"hdrfilm\">\n            <integer name=\"width\" value=\"{w}\"/>\n            <integer name=\"height\" value=\"{h}\"/>\n            {}\n        </film>\n    </sensor>",
        rfilter_xml(cam.filter().shape())
    );
    // Materials and media, in file order, printed from the plugin tree the loader builds them
    // from (so the writer knows no material's or medium's parameters).
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(_, d)| d.span().start);
    for (name, def) in materials {
        x.push_str(&printed(&ctx, tree::material(&ctx, name, def)?, 1, out_dir));
    }
    for def in &file.shapes {
        let d = def.get_ref();
        x.push_str(&shape(&ctx, d, out_dir, &v)?);
    }
    // Lights printed from the tree the loader builds them from (a sun was refused above).
    for l in &file.lights {
        let e = tree::with_medium(tree::light(&ctx, l)?, l.get_ref());
        x.push_str(&printed(&ctx, e, 1, out_dir));
    }
    x.push_str("</scene>\n");
    Ok(x)
}

fn shape(
    ctx: &Ctx,
    d: &ShapeDef,
    out_dir: &Path,
    v: &dyn Fn(&[f64; 3]) -> String,
) -> Result<String, SceneError> {
    let mut x = String::new();
    let matrix = |x: &mut String| -> Result<(), SceneError> {
        let (m, _) = shape_matrix(ctx, d)?;
        let rows: Vec<String> = (0..4)
            .map(|r| {
                let row = m.row(r);
                format!("{} {} {} {}", row.x, row.y, row.z, row.w)
            })
            .collect();
        let _ = writeln!(
            x,
            "        <transform name=\"to_world\">\n            <matrix value=\"{}\"/>\n        </transform>",
            rows.join("  ")
        );
        Ok(())
    };
    match d.kind.get_ref().as_str() {
        "quad" | "cube" => {
            let t = if d.kind.get_ref() == "quad" {
                "rectangle"
            } else {
                "cube"
            };
            let _ = writeln!(x, "    <shape type=\"{t}\">");
            matrix(&mut x)?;
        }
        "mesh" => {
            let file = d
                .file
                .as_ref()
                .map(|f| f.get_ref().clone())
                .unwrap_or_default();
            let abs = ctx.base_dir.join(&file);
            let rel = relative(&abs, out_dir);
            let _ = writeln!(x, "    <shape type=\"obj\">");
            let _ = writeln!(
                x,
                "        <string name=\"filename\" value=\"{}\"/>",
                esc(&rel.to_string_lossy())
            );
            // Without normals on every vertex our meshes shade flat; Mitsuba would compute
            // smooth vertex normals, so ask it for face normals then.
            let mesh =
                crate::mesh::obj::load_obj(ctx, d.file.as_ref().expect("checked by the load"))?;
            if mesh.normals.is_none() {
                let _ = writeln!(x, "        <boolean name=\"face_normals\" value=\"true\"/>");
            }
            matrix(&mut x)?;
        }
        "sphere" => {
            let c = d.center.as_ref().map(|c| *c.get_ref()).unwrap_or_default();
            let r = d.radius.as_ref().map(|r| *r.get_ref()).unwrap_or(1.0);
            let _ = writeln!(x, "    <shape type=\"sphere\">");
            let _ = writeln!(x, "        <point name=\"center\" value=\"{}\"/>", v(&c));
            let _ = writeln!(x, "        <float name=\"radius\" value=\"{}\"/>", r as f32);
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!("shape type `{other}` has no Mitsuba counterpart"),
            ))
        }
    }
    if d.flip_normals {
        let _ = writeln!(x, "        <boolean name=\"flip_normals\" value=\"true\"/>");
    }
    let _ = writeln!(x, "        <ref id=\"{}\"/>", esc(d.material.get_ref()));
    if let Some(e) = &d.emission {
        let c = e.get_ref().0;
        if c.iter().any(|&k| k as f32 > 0.0) {
            let _ = writeln!(
                x,
                "        <emitter type=\"area\">\n            <rgb name=\"radiance\" value=\"{}\"/>\n        </emitter>",
                v(&c)
            );
        }
    }
    if let Some(t) = &d.emission_texture {
        let _ = write!(
            x,
            "        <emitter type=\"area\">\n{}        </emitter>\n",
            texture_xml(ctx, t, "radiance", out_dir, 3)?
        );
    }
    for (m, side) in [(&d.interior, "interior"), (&d.exterior, "exterior")] {
        if let Some(m) = m {
            x.push_str(&printed(
                ctx,
                tree::reference(side, m.get_ref(), m.span()),
                2,
                out_dir,
            ));
        }
    }
    x.push_str("    </shape>\n");
    Ok(x)
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

fn esc(s: &str) -> String {
    escape(s)
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

/// A TOML texture as Mitsuba's `<texture name=…>` (through the tree).
fn texture_xml(
    ctx: &Ctx,
    t: &S<TextureDef>,
    name: &str,
    out_dir: &Path,
    depth: usize,
) -> Result<String, SceneError> {
    Ok(printed(ctx, tree::texture(ctx, t, name)?, depth, out_dir))
}

/// Mitsuba's `<rfilter>` of a pixel filter, with its parameters.
fn rfilter_xml(shape: FilterShape) -> String {
    let f =
        |name: &str, v: f32| format!("\n                <float name=\"{name}\" value=\"{v}\"/>");
    let (kind, params) = match shape {
        FilterShape::Box { radius } => ("box", f("radius", radius)),
        FilterShape::Tent { radius } => ("tent", f("radius", radius)),
        FilterShape::Gaussian { stddev } => ("gaussian", f("stddev", stddev)),
        FilterShape::Mitchell { b, c } => ("mitchell", f("B", b) + &f("C", c)),
        FilterShape::CatmullRom => ("catmullrom", String::new()),
        FilterShape::Lanczos { lobes } => (
            "lanczos",
            format!("\n                <integer name=\"lobes\" value=\"{lobes}\"/>"),
        ),
    };
    if shape == FilterShape::default() {
        return "<rfilter type=\"box\"/>".into();
    }
    format!("<rfilter type=\"{kind}\">{params}\n            </rfilter>")
}
