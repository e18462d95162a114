//! Wavefront OBJ meshes through tobj (triangulated; vertex normals kept when every vertex has
//! one). A light pre-check of `v`/`vn`/`vt`/`f` lines names the OBJ line of a malformed file,
//! which tobj's errors do not.

use crate::error::Ctx;
use crate::toml_scene::schema::S;
use crate::SceneError;
use lt_core::math::{Vec2, Vec3};
use lt_core::scene::TriangleMesh;

/// Loads `file` (relative to the scene file). Errors point at the scene's `file` key.
pub fn load_obj(ctx: &Ctx, file: &S<String>) -> Result<TriangleMesh, SceneError> {
    let (path, bytes) = ctx.read_mesh(file)?;
    let shown = path.display();
    let text = String::from_utf8(bytes).map_err(|e| {
        ctx.at(
            file.span(),
            format!("cannot read mesh file {shown}: not UTF-8 text: {e}"),
        )
    })?;
    let bad = |msg: String| ctx.at(file.span(), format!("malformed OBJ file {shown}: {msg}"));
    if let Some((line, what)) = precheck(&text) {
        return Err(bad(format!("line {line}: {what}")));
    }
    // Which fields exist depends on tobj's features, hence the struct update.
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let parsed = std::panic::catch_unwind(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
    });
    let models = match parsed {
        Ok(Ok((models, _materials))) => models,
        Ok(Err(e)) => return Err(bad(e.to_string())),
        Err(_) => return Err(bad("the OBJ reader failed on it".into())),
    };
    let mut mesh = TriangleMesh {
        normals: Some(Vec::new()),
        uvs: Some(Vec::new()),
        ..Default::default()
    };
    for m in &models {
        let m = &m.mesh;
        let base = mesh.positions.len() as u32;
        let p: Vec<Vec3> = m
            .positions
            .chunks_exact(3)
            .map(|c| Vec3::new(c[0], c[1], c[2]))
            .collect();
        if m.normals.len() == m.positions.len() {
            if let Some(ns) = &mut mesh.normals {
                ns.extend(
                    m.normals
                        .chunks_exact(3)
                        .map(|c| Vec3::new(c[0], c[1], c[2])),
                );
            }
        } else {
            mesh.normals = None;
        }
        // Texture coordinates with v flipped, Mitsuba's default for OBJ (`flip_tex_coords`):
        // OBJ puts v = 0 at the image's bottom, Mitsuba's textures at its top row.
        if 2 * p.len() == m.texcoords.len() {
            if let Some(uvs) = &mut mesh.uvs {
                uvs.extend(
                    m.texcoords
                        .chunks_exact(2)
                        .map(|c| Vec2::new(c[0], 1.0 - c[1])),
                );
            }
        } else {
            mesh.uvs = None;
        }
        mesh.positions.extend(p);
        mesh.indices.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [base + t[0], base + t[1], base + t[2]]),
        );
    }
    if mesh.indices.is_empty() {
        return Err(bad("it has no faces".into()));
    }
    if mesh.positions.iter().any(|p| !p.is_finite()) {
        return Err(bad("a vertex position is NaN or infinite".into()));
    }
    if mesh
        .normals
        .as_ref()
        .is_some_and(|ns| ns.iter().any(|n| !n.is_finite()))
    {
        return Err(bad("a vertex normal is NaN or infinite".into()));
    }
    Ok(mesh)
}

/// The first line that tobj would reject or that holds a bad index, with the reason.
fn precheck(text: &str) -> Option<(usize, String)> {
    let (mut nv, mut nt, mut nn) = (0i64, 0i64, 0i64);
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next().unwrap_or("");
        let args: Vec<&str> = words.collect();
        let floats = |min: usize, max: usize| {
            args.len() >= min && args.len() <= max && args.iter().all(|w| w.parse::<f32>().is_ok())
        };
        let problem = match key {
            "v" if !floats(3, 7) => Some("a vertex needs 3 numbers".to_string()),
            "vn" if !floats(3, 3) => Some("a normal needs 3 numbers".to_string()),
            "vt" if !floats(1, 3) => Some("a texture coordinate needs 1 to 3 numbers".to_string()),
            "f" => face_problem(&args, nv, nt, nn),
            _ => None,
        };
        if problem.is_some() {
            return problem.map(|p| (i + 1, format!("{p}: `{}`", line.trim())));
        }
        match key {
            "v" => nv += 1,
            "vt" => nt += 1,
            "vn" => nn += 1,
            _ => {}
        }
    }
    None
}

fn face_problem(args: &[&str], nv: i64, nt: i64, nn: i64) -> Option<String> {
    if args.len() < 3 {
        return Some("a face needs at least 3 vertices".into());
    }
    for a in args {
        for (k, part) in a.split('/').enumerate() {
            if part.is_empty() && k > 0 {
                continue;
            }
            let Some(&count) = [nv, nt, nn].get(k) else {
                return Some(format!("`{a}` has too many `/`"));
            };
            let Ok(idx) = part.parse::<i64>() else {
                return Some(format!("`{part}` is not an index"));
            };
            let ok = if idx > 0 {
                idx <= count
            } else {
                idx < 0 && -idx <= count
            };
            if !ok {
                let what = ["vertex", "texture coordinate", "normal"][k];
                return Some(format!(
                    "{what} index {idx} is out of range (1..={count} defined so far)"
                ));
            }
        }
    }
    None
}
