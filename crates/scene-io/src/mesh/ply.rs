//! PLY meshes (ASCII and binary, either byte order) through `ply-rs-bw`: vertex `x y z`, optional
//! `nx ny nz` (kept as shading normals), and faces as `vertex_indices` (or `vertex_index`) lists,
//! fan-triangulated. Errors point at the scene's `filename`. Any other scalar properties become
//! mesh attributes under Mitsuba's names: `<p>_0`, `<p>_1`, `<p>_2` (or a lone `<p>`) of the
//! vertices give `vertex_<p>`, of the faces `face_<p>` (one or three channels).

use crate::error::Ctx;
use crate::SceneError;
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::scene::{MeshAttribute, TriangleMesh};
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use toml::Spanned;

pub(crate) fn load_ply(ctx: &Ctx, file: &Spanned<String>) -> Result<TriangleMesh, SceneError> {
    let (path, bytes) = ctx.read_mesh(file)?;
    let shown = path.display();
    let bad = |msg: String| ctx.at(file.span(), format!("malformed PLY file {shown}: {msg}"));
    let parsed = std::panic::catch_unwind(|| {
        Parser::<DefaultElement>::new().read_ply(&mut bytes.as_slice())
    });
    let ply = match parsed {
        Ok(Ok(p)) => p,
        Ok(Err(e)) => return Err(bad(e.to_string())),
        Err(_) => return Err(bad("the PLY reader failed on it".into())),
    };
    let Some(vertices) = ply.payload.get("vertex") else {
        return Err(bad("it has no `vertex` element".into()));
    };
    let scalar = |v: &DefaultElement, k: &str| v.get(k).and_then(Property::to_f32_lossy);
    let mut positions = Vec::with_capacity(vertices.len());
    let mut normals = Some(Vec::with_capacity(vertices.len()));
    let mut uvs = Some(Vec::with_capacity(vertices.len()));
    for (i, v) in vertices.iter().enumerate() {
        let (Some(x), Some(y), Some(z)) = (scalar(v, "x"), scalar(v, "y"), scalar(v, "z")) else {
            return Err(bad(format!("vertex {i} lacks a numeric x, y or z")));
        };
        positions.push(Vec3::new(x, y, z));
        match (scalar(v, "nx"), scalar(v, "ny"), scalar(v, "nz")) {
            (Some(a), Some(b), Some(c)) => {
                if let Some(ns) = &mut normals {
                    ns.push(Vec3::new(a, b, c));
                }
            }
            _ => normals = None,
        }
        // Texture coordinates under any of the names PLY writers use, as stored: Mitsuba flips v
        // for OBJ files only (checked on the suite's various_shapes, whose PLY, OBJ and
        // serialized rectangles carry the same texture).
        let uv = [("u", "v"), ("s", "t"), ("texture_u", "texture_v")]
            .iter()
            .find_map(|(a, b)| Some((scalar(v, a)?, scalar(v, b)?)));
        match uv {
            Some((a, b)) => {
                if let Some(t) = &mut uvs {
                    t.push(Vec2::new(a, b));
                }
            }
            None => uvs = None,
        }
    }
    let n = positions.len();
    let mut indices = Vec::new();
    // How many triangles each face was split into (face attributes are copied to each).
    let mut splits = Vec::new();
    let faces = ply.payload.get("face").map(Vec::as_slice).unwrap_or(&[]);
    for (i, f) in faces.iter().enumerate() {
        let Some(list) = f.get("vertex_indices").or_else(|| f.get("vertex_index")) else {
            return Err(bad(format!("face {i} has no vertex_indices list")));
        };
        let idx: Vec<i64> = match list {
            Property::ListChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListInt(v) => v.iter().map(|&x| x as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|&x| x as i64).collect(),
            _ => {
                return Err(bad(format!(
                    "face {i}: vertex_indices is not a list of integers"
                )))
            }
        };
        if idx.len() < 3 {
            return Err(bad(format!("face {i} has fewer than 3 vertices")));
        }
        if let Some(&k) = idx.iter().find(|&&k| k < 0 || k as usize >= n) {
            return Err(bad(format!(
                "face {i}: vertex index {k} is out of range (0..{n})"
            )));
        }
        for j in 1..idx.len() - 1 {
            indices.push([idx[0] as u32, idx[j] as u32, idx[j + 1] as u32]);
        }
        splits.push(idx.len() - 2);
    }
    let mut attributes = Vec::new();
    const VERTEX_KNOWN: &[&str] = &[
        "x",
        "y",
        "z",
        "nx",
        "ny",
        "nz",
        "u",
        "v",
        "s",
        "t",
        "texture_u",
        "texture_v",
    ];
    for (element, items, prefix) in [
        ("vertex", vertices.as_slice(), "vertex"),
        ("face", faces, "face"),
    ] {
        let Some(def) = ply.header.elements.get(element) else {
            continue;
        };
        let names: Vec<&str> = def
            .properties
            .keys()
            .map(String::as_str)
            .filter(|k| !VERTEX_KNOWN.contains(k) && !k.starts_with("vertex_ind"))
            .collect();
        for (base, channels) in attribute_groups(&names) {
            let mut values = Vec::with_capacity(items.len());
            for (i, item) in items.iter().enumerate() {
                let mut c = [0.0f32; 3];
                for (slot, k) in c.iter_mut().zip(&channels) {
                    *slot = scalar(item, k).ok_or_else(|| {
                        bad(format!("{element} {i}: property `{k}` is not a number"))
                    })?;
                }
                if !c.iter().all(|x| x.is_finite()) {
                    return Err(bad(format!("{element} {i}: `{base}` is NaN or infinite")));
                }
                let c = if channels.len() == 1 {
                    Color::splat(c[0])
                } else {
                    Color::from_array(c)
                };
                if element == "face" {
                    values.extend(std::iter::repeat_n(c, splits[i]));
                } else {
                    values.push(c);
                }
            }
            attributes.push(MeshAttribute {
                name: format!("{prefix}_{base}"),
                per_face: element == "face",
                values,
            });
        }
    }
    if indices.is_empty() {
        return Err(bad("it has no faces".into()));
    }
    if positions.iter().any(|p| !p.is_finite()) {
        return Err(bad("a vertex position is NaN or infinite".into()));
    }
    if normals
        .as_ref()
        .is_some_and(|ns| ns.iter().any(|v| !v.is_finite()))
    {
        return Err(bad("a vertex normal is NaN or infinite".into()));
    }
    Ok(TriangleMesh {
        positions,
        normals,
        uvs,
        indices,
        attributes,
    })
}

/// Properties grouped into attributes as Mitsuba names them: `<p>_0`, `<p>_1`, `<p>_2` form one
/// three-channel attribute `<p>`, a lone `<p>_0` or `<p>` a one-channel one; other channel counts
/// are not attributes a texture can read, and are left out.
fn attribute_groups<'a>(names: &[&'a str]) -> Vec<(String, Vec<&'a str>)> {
    let mut groups: Vec<(String, Vec<&'a str>)> = Vec::new();
    for &name in names {
        let base = match name.rsplit_once('_') {
            Some((b, d)) if !d.is_empty() && d.bytes().all(|c| c.is_ascii_digit()) => b,
            _ => name,
        };
        match groups.iter_mut().find(|(b, _)| b == base) {
            Some((_, ks)) => ks.push(name),
            None => groups.push((base.to_string(), vec![name])),
        }
    }
    groups.retain(|(_, ks)| ks.len() == 1 || ks.len() == 3);
    for (_, ks) in &mut groups {
        // Channels in the order of their suffix digits.
        ks.sort_by_key(|k| k.rsplit_once('_').and_then(|(_, d)| d.parse::<u32>().ok()));
    }
    groups
}

#[cfg(test)]
mod tests {
    use super::attribute_groups;

    #[test]
    fn properties_group_into_mitsuba_attributes() {
        let g = attribute_groups(&[
            "color_2", "color_0", "weight_0", "color_1", "pair_0", "pair_1", "tag",
        ]);
        let names: Vec<(&str, Vec<&str>)> =
            g.iter().map(|(b, k)| (b.as_str(), k.clone())).collect();
        assert_eq!(
            names,
            vec![
                ("color", vec!["color_0", "color_1", "color_2"]),
                ("weight", vec!["weight_0"]),
                ("tag", vec!["tag"]),
            ]
        );
    }
}
