//! Shape transforms: Mitsuba's `to_world` matrix, or `scale`, then `rotate`, then `translate`.
//! Composed and applied in f64 (`world.rs` rounds each position once), so quads and cubes placed
//! with round numbers meet exactly at shared edges (rotations by multiples of 90° use exact sines
//! and cosines).

use crate::error::Ctx;
use crate::toml_scene::schema::{ShapeDef, S};
use crate::SceneError;
use glam::{DMat3, DMat4, DVec3};

/// The shape's object-to-world matrix (identity when it gives no transform keys), with the span a
/// degenerate-transform error should point at (`to_world` or `scale`, else the shape's `type`).
pub fn shape_matrix(
    ctx: &Ctx,
    def: &ShapeDef,
) -> Result<(DMat4, std::ops::Range<usize>), SceneError> {
    if let Some(m) = &def.to_world {
        let trs = [
            def.translate.as_ref().map(S::span),
            def.rotate.as_ref().map(S::span),
            def.scale.as_ref().map(S::span),
        ];
        if let Some(span) = trs.into_iter().flatten().next() {
            return Err(ctx.at(
                span,
                "give either `to_world` or `translate`/`rotate`/`scale`, not both",
            ));
        }
        let rows = m.get_ref();
        if rows.iter().flatten().any(|v| !v.is_finite()) {
            return Err(ctx.at(m.span(), "`to_world` has a NaN or infinite entry"));
        }
        if rows[3] != [0.0, 0.0, 0.0, 1.0] {
            return Err(ctx.at(
                m.span(),
                "`to_world` must be affine: its last row must be [0, 0, 0, 1]",
            ));
        }
        // Rows as written, acting on column vectors (Mitsuba's convention).
        return Ok((DMat4::from_cols_array_2d(rows).transpose(), m.span()));
    }
    let mut m = DMat4::IDENTITY;
    let mut span = def.kind.span();
    if let Some(s) = &def.scale {
        let v = s.get_ref().0;
        if v.iter().any(|x| !x.is_finite()) {
            return Err(ctx.at(s.span(), "`scale` has a NaN or infinite entry"));
        }
        m = DMat4::from_scale(DVec3::from_array(v));
        span = s.span();
    }
    if let Some(r) = &def.rotate {
        m = DMat4::from_mat3(rotate_def(ctx, r)?) * m;
    }
    if let Some(t) = &def.translate {
        let v = DVec3::from_array(*t.get_ref());
        if !v.is_finite() {
            return Err(ctx.at(t.span(), "`translate` has a NaN or infinite entry"));
        }
        m = DMat4::from_translation(v) * m;
    }
    Ok((m, span))
}

/// The rotation a `rotate` table describes (checked as for shapes).
pub fn rotate_def(
    ctx: &Ctx,
    r: &S<crate::toml_scene::schema::RotateDef>,
) -> Result<DMat3, SceneError> {
    let axis = DVec3::from_array(r.get_ref().axis);
    let angle = r.get_ref().angle;
    if !axis.is_finite() || !angle.is_finite() {
        return Err(ctx.at(r.span(), "`rotate` has a NaN or infinite value"));
    }
    if axis.length_squared() == 0.0 {
        return Err(ctx.at(r.span(), "`rotate` axis is the zero vector"));
    }
    Ok(rotation(axis.normalize(), angle))
}

/// The `up` a spot light or projector takes when the file gives none: +y, or +z when the axis
/// is within about 0.5° of vertical.
pub fn default_up(dir: DVec3) -> DVec3 {
    if dir.normalize().y.abs() < 0.99996 {
        DVec3::Y
    } else {
        DVec3::Z
    }
}

/// Mitsuba's lookat rotation: columns (up × d, d × (up × d), d), normalised, with d the unit
/// direction from `position` to `target` (+z of the local frame).
pub fn look_at_rotation(position: DVec3, target: DVec3, up: DVec3) -> Result<DMat3, String> {
    let dir = target - position;
    if !(dir.length() > 0.0) || !dir.is_finite() {
        return Err("`position` and `target` coincide".into());
    }
    let left = up.cross(dir);
    if !(left.length() > 1e-9 * up.length() * dir.length()) {
        return Err(
            "`up` is parallel to the direction from `position` to `target` (or zero)".into(),
        );
    }
    let (dir, left) = (dir.normalize(), left.normalize());
    Ok(positive_zeros(DMat3::from_cols(left, dir.cross(left), dir)))
}

/// The matrix with every −0 made +0: the XML loader's products give +0 where a cross product
/// gives −0, and a converted scene must read back bit for bit.
pub fn positive_zeros(m: DMat3) -> DMat3 {
    DMat3::from_cols_array(&m.to_cols_array().map(|x| x + 0.0))
}

/// Rodrigues' rotation about a unit axis, counter-clockwise by `deg` degrees.
fn rotation(a: DVec3, deg: f64) -> DMat3 {
    let (s, c) = sin_cos_deg(deg);
    let k = DMat3::from_cols(
        DVec3::new(0.0, a.z, -a.y),
        DVec3::new(-a.z, 0.0, a.x),
        DVec3::new(a.y, -a.x, 0.0),
    );
    DMat3::IDENTITY * c + k * s + outer(a, a) * (1.0 - c)
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Exact for multiples of 90° (so axis-aligned walls stay axis-aligned to the last bit).
fn sin_cos_deg(deg: f64) -> (f64, f64) {
    let r = deg.rem_euclid(360.0);
    if r % 90.0 == 0.0 {
        return [(0.0, 1.0), (1.0, 0.0), (0.0, -1.0), (-1.0, 0.0)][(r / 90.0) as usize];
    }
    deg.to_radians().sin_cos()
}

/// Rejects transforms that squash a quad to zero area (only the quad's own plane matters).
pub fn check_quad(ctx: &Ctx, m: &DMat4, span: std::ops::Range<usize>) -> Result<(), SceneError> {
    let (u, v) = (m.x_axis.truncate(), m.y_axis.truncate());
    let area = u.cross(v).length();
    if !(area > 1e-9 * u.length() * v.length()) || !(area > 0.0) {
        return Err(ctx.at(span, "degenerate transform: the quad has zero area"));
    }
    Ok(())
}

/// Rejects transforms that flatten a solid (a cube or a mesh) onto a plane, line or point.
pub fn check_solid(
    ctx: &Ctx,
    m: &DMat4,
    span: std::ops::Range<usize>,
    what: &str,
) -> Result<(), SceneError> {
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate());
    let det = DMat3::from_cols(cols[0], cols[1], cols[2]).determinant();
    let scale = cols[0].length() * cols[1].length() * cols[2].length();
    if !(det.abs() > 1e-9 * scale) || !(scale > 0.0) {
        return Err(ctx.at(
            span,
            format!("degenerate transform: it flattens the {what} (determinant {det:.3e})"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_turns_are_exact() {
        let r = rotation(DVec3::Y, -90.0);
        assert_eq!(r * DVec3::Z, DVec3::new(-1.0, 0.0, 0.0));
        let r = rotation(DVec3::X, -90.0);
        assert_eq!(r * DVec3::Z, DVec3::Y);
    }

    #[test]
    fn rotation_is_counter_clockwise() {
        let r = rotation(DVec3::Z, 30.0);
        let v = r * DVec3::X;
        assert!((v - DVec3::new(0.75f64.sqrt(), 0.5, 0.0)).length() < 1e-12);
    }
}
