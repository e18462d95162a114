//! Values written in the XML: numbers, colours, vectors and `to_world` transforms (`matrix`,
//! `lookat`, `translate`, `rotate`, `scale`, applied in document order: each later one acts on
//! the result of the earlier ones). Transforms are composed in f64 and rounded to f32 once, like
//! the TOML path, with exact sines and cosines at multiples of 90°.

use super::doc::{Doc, Elem};
use crate::SceneError;
use glam::{DMat3, DMat4, DVec3};

/// A number as Mitsuba writes it (surrounding spaces allowed).
pub(super) fn number(doc: &Doc, e: &Elem, s: &str, what: &str) -> Result<f64, SceneError> {
    let t = s.trim();
    match t.parse::<f64>() {
        Ok(x) if x.is_finite() && (x as f32).is_finite() => Ok(x),
        Ok(_) => Err(doc.err(e, format!("{what}: `{t}` is not a finite number"))),
        Err(_) => Err(doc.err(e, format!("{what}: `{t}` is not a number"))),
    }
}

/// A list of numbers separated by commas and/or spaces.
pub(super) fn numbers(doc: &Doc, e: &Elem, s: &str, what: &str) -> Result<Vec<f64>, SceneError> {
    s.split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .map(|w| number(doc, e, w, what))
        .collect()
}

/// The attribute `key`, required.
pub(super) fn need<'e>(doc: &Doc, e: &'e Elem, key: &str) -> Result<&'e str, SceneError> {
    e.attr(key)
        .ok_or_else(|| doc.err(e, format!("<{}> needs a `{key}` attribute", e.tag)))
}

/// Rejects attributes the element does not take.
pub(super) fn only_attrs(doc: &Doc, e: &Elem, allowed: &[&str]) -> Result<(), SceneError> {
    for (k, _) in &e.attrs {
        if !allowed.contains(&k.as_str()) {
            return Err(doc.err(e, format!("<{}> does not take the attribute `{k}`", e.tag)));
        }
    }
    Ok(())
}

/// Three numbers from `value="x y z"` / `value="x, y, z"`, or from `x`, `y`, `z` attributes
/// (each defaulting to `default`).
pub(super) fn triple(
    doc: &Doc,
    e: &Elem,
    default: f64,
    what: &str,
) -> Result<[f64; 3], SceneError> {
    if let Some(v) = e.attr("value") {
        if ["x", "y", "z"].iter().any(|k| e.attr(k).is_some()) {
            return Err(doc.err(e, format!("{what}: give `value` or `x`/`y`/`z`, not both")));
        }
        let n = numbers(doc, e, v, what)?;
        return match n[..] {
            [a] if e.tag == "scale" => Ok([a; 3]),
            [a, b, c] => Ok([a, b, c]),
            _ => Err(doc.err(
                e,
                format!("{what}: expected 3 numbers, got {} in `{v}`", n.len()),
            )),
        };
    }
    let mut out = [default; 3];
    for (slot, k) in out.iter_mut().zip(["x", "y", "z"]) {
        if let Some(v) = e.attr(k) {
            *slot = number(doc, e, v, what)?;
        }
    }
    Ok(out)
}

/// A parsed `<transform>`: its composed matrix and, when it is one `lookat` alone, the look-at
/// itself (a camera then takes eye, target and up exactly as written).
#[derive(Clone, Debug)]
pub(super) struct Xform {
    pub m: DMat4,
    pub lookat: Option<[DVec3; 3]>,
}

pub(super) fn transform(doc: &Doc, t: &Elem) -> Result<Xform, SceneError> {
    let mut m = DMat4::IDENTITY;
    let mut lookat = None;
    for (i, c) in t.children.iter().enumerate() {
        let what = format!(
            "<{}> in transform `{}`",
            c.tag,
            t.attr("name").unwrap_or("")
        );
        let step = match c.tag.as_str() {
            "matrix" => {
                only_attrs(doc, c, &["value"])?;
                let v = need(doc, c, "value")?;
                let n = numbers(doc, c, v, &what)?;
                match n.len() {
                    16 => {
                        let rows: [[f64; 4]; 4] =
                            std::array::from_fn(|r| std::array::from_fn(|k| n[4 * r + k]));
                        DMat4::from_cols_array_2d(&rows).transpose()
                    }
                    9 => {
                        let rows: [[f64; 3]; 3] =
                            std::array::from_fn(|r| std::array::from_fn(|k| n[3 * r + k]));
                        DMat4::from_mat3(DMat3::from_cols_array_2d(&rows).transpose())
                    }
                    k => {
                        return Err(doc.err(
                            c,
                            format!("{what}: a matrix needs 16 numbers (4×4, row by row), got {k}"),
                        ))
                    }
                }
            }
            "translate" => {
                only_attrs(doc, c, &["value", "x", "y", "z"])?;
                DMat4::from_translation(DVec3::from_array(triple(doc, c, 0.0, &what)?))
            }
            "scale" => {
                only_attrs(doc, c, &["value", "x", "y", "z"])?;
                DMat4::from_scale(DVec3::from_array(triple(doc, c, 1.0, &what)?))
            }
            "rotate" => {
                only_attrs(doc, c, &["value", "x", "y", "z", "angle"])?;
                let axis = DVec3::from_array(triple(doc, c, 0.0, &what)?);
                let angle = number(doc, c, need(doc, c, "angle")?, &what)?;
                if axis.length_squared() == 0.0 {
                    return Err(doc.err(c, format!("{what}: the rotation axis is the zero vector")));
                }
                DMat4::from_mat3(rotation(axis.normalize(), angle))
            }
            "lookat" => {
                only_attrs(doc, c, &["origin", "target", "up"])?;
                let v3 = |k: &str| -> Result<DVec3, SceneError> {
                    let n = numbers(doc, c, need(doc, c, k)?, &what)?;
                    match n[..] {
                        [a, b, cc] => Ok(DVec3::new(a, b, cc)),
                        _ => Err(doc.err(c, format!("{what}: `{k}` needs 3 numbers"))),
                    }
                };
                let (o, target) = (v3("origin")?, v3("target")?);
                let up = match c.attr("up") {
                    Some(_) => v3("up")?,
                    None => any_perpendicular(target - o),
                };
                let dir = target - o;
                if !(dir.length() > 0.0) {
                    return Err(doc.err(c, format!("{what}: origin and target coincide")));
                }
                let left = up.cross(dir);
                if !(left.length() > 1e-9 * up.length() * dir.length()) {
                    return Err(doc.err(c, format!("{what}: `up` is parallel to the viewing direction (or zero)")));
                }
                if i == 0 && t.children.len() == 1 {
                    lookat = Some([o, target, up]);
                }
                let dir = dir.normalize();
                let left = left.normalize();
                let new_up = dir.cross(left);
                DMat4::from_cols(
                    left.extend(0.0),
                    new_up.extend(0.0),
                    dir.extend(0.0),
                    o.extend(1.0),
                )
            }
            other => {
                return Err(doc.err(
                    c,
                    format!("<{other}> is not a transform step (expected matrix, lookat, translate, rotate or scale)"),
                ))
            }
        };
        m = step * m;
    }
    if !m.is_finite() {
        return Err(doc.err(t, "the transform has a NaN or infinite entry"));
    }
    let last = m.row(3);
    if (last - glam::DVec4::new(0.0, 0.0, 0.0, 1.0))
        .abs()
        .max_element()
        > 0.0
    {
        return Err(doc.err(
            t,
            "the transform must be affine: its last row must be 0 0 0 1",
        ));
    }
    Ok(Xform { m, lookat })
}

/// Some unit vector perpendicular to `d` (Mitsuba picks an arbitrary up when a lookat has none).
fn any_perpendicular(d: DVec3) -> DVec3 {
    let d = d.normalize_or_zero();
    let a = if d.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
    d.cross(a).normalize_or_zero()
}

/// Rodrigues' rotation about a unit axis, counter-clockwise by `deg` degrees.
pub(super) fn rotation(a: DVec3, deg: f64) -> DMat3 {
    let (s, c) = sin_cos_deg(deg);
    let k = DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    );
    let outer = DMat3::from_cols(a * a.x, a * a.y, a * a.z);
    DMat3::IDENTITY * c + k * s + outer * (1.0 - c)
}

/// Exact at multiples of 90°.
fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r % 90.0 == 0.0 {
        return [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][(r / 90.0) as usize % 4];
    }
    deg.to_radians().sin_cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xml_rotation_is_right_handed_and_exact_at_quarter_turns() {
        assert_eq!(rotation(DVec3::X, 90.0) * DVec3::Y, DVec3::Z);
        let v = rotation(DVec3::Z, 30.0) * DVec3::X;
        assert!((v - DVec3::new(0.75f64.sqrt(), 0.5, 0.0)).length() < 1e-15);
    }
}
