//! `<shape>`: geometry, its BSDF and its area emitter; shapegroups and instances.

use super::Loader;
use crate::error::Ctx;
use crate::mesh::{ply, serialized};
use crate::transform::{check_quad, check_solid};
use crate::world::{out_of_range_message, WorldBuilder, WorldGeometry, WorldMesh};
use crate::xml::doc::Elem;
use crate::xml::props::{ColorUse, Plugin};
use crate::xml::resolve::Resolver;
use crate::xml::values::Xform;
use crate::SceneError;
use glam::{DMat4, DVec3};
use lt_core::bsdf::{Diffuse, Material};
use lt_core::math::Color;
use lt_core::scene::TriangleMesh;
use lt_core::texture::Texture;
use std::path::PathBuf;

/// The shapes lt reads: every geometry of `GEOMETRIES`, groups and instances.
pub(super) fn shape_types() -> Vec<&'static str> {
    let geometries = GEOMETRIES.iter().map(|(name, _)| *name);
    geometries.chain(["shapegroup", "instance"]).collect()
}

impl<'a> Loader<'a> {
    /// Adds the shape; returns whether it emits.
    /// A top-level `<shape>`: a shape, a `shapegroup` (nothing until instanced) or an `instance`
    /// of one, which adds a copy of each of the group's shapes under the instance's `to_world`
    /// (flattened: lt's ray core has no instancing, the geometry is repeated). Returns how many
    /// emitting shapes it added.
    pub(super) fn shape_or_instance(
        &mut self,
        e: &'a Elem,
        b: &mut WorldBuilder,
    ) -> Result<usize, SceneError> {
        match e.attr("type").unwrap_or("") {
            "shapegroup" => {
                let p = self.plugin(e)?;
                for s in p.nested(&["shape"]) {
                    if matches!(s.attr("type"), Some("shapegroup" | "instance")) {
                        return Err(p.err(s, "a shapegroup holds shapes, not groups or instances"));
                    }
                }
                p.finish(&[], &mut self.report)?;
                Ok(0)
            }
            "instance" => {
                let p = self.plugin(e)?;
                let parent = p
                    .transform("to_world")?
                    .map_or(DMat4::IDENTITY, |(x, _)| x.m);
                let groups = p.nested(&["shape"]);
                let group = match groups[..] {
                    [g] if g.attr("type") == Some("shapegroup") => g,
                    _ => {
                        return Err(p.err(e, "an instance needs exactly one <ref> to a shapegroup"))
                    }
                };
                p.finish(&[], &mut self.report)?;
                let gp = self.plugin(group)?;
                let members = gp.nested(&["shape"]);
                let mut emitters = 0;
                for s in members {
                    emitters += self.shape(s, b, parent)? as usize;
                }
                Ok(emitters)
            }
            _ => Ok(self.shape(e, b, DMat4::IDENTITY)? as usize),
        }
    }

    /// Adds the shape, placed by `parent` (an instance's transform) after its own `to_world`;
    /// returns whether it emits.
    pub(super) fn shape(
        &mut self,
        e: &'a Elem,
        b: &mut WorldBuilder,
        parent: DMat4,
    ) -> Result<bool, SceneError> {
        let p = self.plugin(e)?;
        let doc = self.doc;
        let xform = p.transform("to_world")?.map(|(x, te)| {
            (
                Xform {
                    m: parent * x.m,
                    ..x
                },
                te,
            )
        });
        let xform = match xform {
            None if parent != DMat4::IDENTITY => Some((
                Xform {
                    m: parent,
                    lookat: None,
                },
                e,
            )),
            x => x,
        };
        let flip = p.boolean("flip_normals")?.unwrap_or(false);
        let ctx = doc.ctx(e.src);
        let (m, span) = match &xform {
            Some((x, te)) => (x.m, te.range.clone()),
            None => (DMat4::IDENTITY, e.range.clone()),
        };
        let Some(&(_, build)) = GEOMETRIES.iter().find(|(name, _)| *name == p.kind) else {
            return Err(super::kinds::unknown_type(self.doc, e));
        };
        let at = Placement {
            ctx,
            m,
            span,
            xform,
        };
        let geometry = build(self, &p, &at)?;
        let bsdf = p.one_nested(&["bsdf"], "BSDF")?;
        // Mitsuba gives a shape without a BSDF a diffuse one of reflectance 0.5, except an
        // emitting shape, whose default is black: a light does not reflect unless it is told to
        // (the material grid's floor was 0.35 % too bright by light bounced off the lamp).
        let emits = p.one_nested(&["emitter"], "emitter")?.is_some();
        let material = match bsdf {
            Some(be) => self.material(be, b)?,
            None if emits => match self.default_emitter_material {
                Some(id) => id,
                None => {
                    let id = b.add_material(Material::Diffuse(Diffuse {
                        albedo: Color::ZERO,
                    }));
                    self.default_emitter_material = Some(id);
                    id
                }
            },
            None => match self.default_material {
                Some(id) => id,
                None => {
                    let id = b.add_material(Material::Diffuse(Diffuse {
                        albedo: Color::splat(0.5),
                    }));
                    self.default_material = Some(id);
                    id
                }
            },
        };
        let media = self.shape_media(&p, &geometry)?;
        let emission = match p.one_nested(&["emitter"], "emitter")? {
            None => None,
            Some(em) => {
                let ep = self.plugin(em)?;
                if ep.kind != "area" {
                    return Err(ep.err(
                        em,
                        format!(
                            "emitter `{}` inside a shape: only `area` emitters attach to shapes",
                            ep.kind
                        ),
                    ));
                }
                // A textured radiance is read at the shape's uv, as materials' textures are.
                if let Some(t) = ep.texture("radiance") {
                    let texture = self.texture(t)?;
                    if texture.mesh_attribute().is_some() {
                        return Err(ep.err(
                            t,
                            "a mesh attribute as an area emitter's `radiance` is not supported \
                             (light samples know a point's uv, not its attributes)",
                        ));
                    }
                    ep.finish(&["sampling_weight"], &mut self.report)?;
                    // A black texture emits nothing, as a black radiance does.
                    let radiance = (texture.max_value() > 0.0).then_some(texture);
                    let emits = self.finish_shape(&p, b, geometry, material, radiance, flip)?;
                    b.set_last_shape_media(media)
                        .map_err(|m| p.err(p.elem, m))?;
                    return Ok(emits);
                }
                let r = ep
                    .color("radiance", ColorUse::Emission, self.opts, &mut self.report)?
                    .unwrap_or(Color::ONE);
                ep.finish(&["sampling_weight"], &mut self.report)?;
                (r.max_element() > 0.0).then_some(Texture::Constant(r))
            }
        };
        let emits = self.finish_shape(&p, b, geometry, material, emission, flip)?;
        b.set_last_shape_media(media)
            .map_err(|m| p.err(p.elem, m))?;
        Ok(emits)
    }

    /// The shape's last step: its remaining parameters checked, then added (emitting when
    /// `radiance` is given); whether it emits.
    pub(super) fn finish_shape(
        &mut self,
        p: &Plugin<'a>,
        b: &mut WorldBuilder,
        geometry: WorldGeometry,
        material: u32,
        radiance: Option<Texture>,
        flip: bool,
    ) -> Result<bool, SceneError> {
        if let Some(name) = b.material(material).mesh_attribute() {
            let has = match &geometry {
                WorldGeometry::Mesh(m) => m.attributes.iter().any(|a| a.name == name),
                _ => false,
            };
            if !has {
                let known: Vec<&str> = match &geometry {
                    WorldGeometry::Mesh(m) => {
                        m.attributes.iter().map(|a| a.name.as_str()).collect()
                    }
                    _ => Vec::new(),
                };
                return Err(p.err(
                    p.elem,
                    format!(
                        "the shape's material reads mesh attribute `{name}`, which the shape does not have (it has: {})",
                        if known.is_empty() { "none".to_string() } else { known.join(", ") }
                    ),
                ));
            }
        }
        if radiance.is_some() && matches!(geometry, WorldGeometry::SdfGrid { .. }) {
            return Err(p.err(
                p.elem,
                "an sdfgrid cannot be an area emitter (Mitsuba's cannot either)",
            ));
        }
        let ignored: &[&str] = match p.kind {
            "obj" | "ply" => &["flip_tex_coords"],
            _ => &[],
        };
        p.finish(ignored, &mut self.report)?;
        let emits = radiance.is_some();
        b.add_shape(geometry, material, radiance, flip);
        Ok(emits)
    }
}

/// The object-to-world map `m` of a disk, cylinder or sdfgrid (of its unit shape), refused when
/// singular or reaching beyond the coordinates the scene can hold.
pub(super) fn checked_map(
    p: &Plugin,
    e: &Elem,
    m: &DMat4,
    what: &str,
) -> Result<DMat4, SceneError> {
    let corner = m.transform_point3(DVec3::ONE);
    let det = glam::DMat3::from_mat4(*m).determinant();
    if !crate::world::in_range(corner) || !crate::world::in_range(m.w_axis.truncate()) {
        return Err(p.err(e, out_of_range_message(&format!("the {what}"), corner)));
    }
    if !(det.abs() > 0.0) || !det.is_finite() {
        return Err(p.err(
            e,
            format!("the {what}'s to_world is singular (determinant {det})"),
        ));
    }
    Ok(*m)
}

/// Angle-weighted vertex normals (each face's unit normal weighted by its angle at the vertex),
/// what Mitsuba computes for a mesh file without normals (checked against it on a tetrahedron).
pub(super) fn vertex_normals(m: &TriangleMesh) -> Vec<glam::Vec3> {
    let mut acc = vec![DVec3::ZERO; m.positions.len()];
    for t in &m.indices {
        let p = t.map(|i| m.positions[i as usize].as_dvec3());
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        if !(n.length() > 0.0) {
            continue;
        }
        let n = n.normalize();
        for k in 0..3 {
            let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            let angle = a.angle_between(b);
            if angle.is_finite() {
                acc[t[k] as usize] += angle * n;
            }
        }
    }
    acc.into_iter()
        .map(|n| n.normalize_or_zero().as_vec3())
        .collect()
}

/// The uniform scale of a similarity transform (rotation × uniform scale + translation).
pub(super) fn similarity_scale(m: &DMat4) -> Option<f64> {
    let cols = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate());
    let s = cols[0].length();
    let tol = 1e-5 * s;
    let ok = s > 0.0
        && cols.iter().all(|c| (c.length() - s).abs() <= tol)
        && cols[0].dot(cols[1]).abs() <= tol * s
        && cols[0].dot(cols[2]).abs() <= tol * s
        && cols[1].dot(cols[2]).abs() <= tol * s;
    ok.then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Mitsuba 3.9.1's vertex normals of the OBJ tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1)
    /// with faces 1 3 2, 1 2 4, 1 4 3, 2 3 4, at the vertex (0,1,0).
    #[test]
    fn xml_vertex_normals_are_mitsubas() {
        let m = TriangleMesh {
            positions: vec![
                glam::Vec3::ZERO,
                glam::Vec3::X,
                glam::Vec3::Y,
                glam::Vec3::Z,
            ],
            normals: None,
            uvs: None,
            indices: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            attributes: Vec::new(),
        };
        let n = vertex_normals(&m);
        let theirs = glam::Vec3::new(-0.275_421_47, 0.921_024_4, -0.275_421_47);
        assert!((n[2] - theirs).abs().max_element() < 1e-6, "{:?}", n[2]);
        let k = -(1.0f32 / 3.0).sqrt();
        assert!((n[0] - glam::Vec3::splat(k)).abs().max_element() < 1e-6);
    }
}

/// Where a shape goes: its file (for errors), its object-to-world map `m` with the span of its
/// `to_world` (else of the shape), and the transform as written.
pub(super) struct Placement<'a> {
    ctx: Ctx<'a>,
    m: DMat4,
    span: std::ops::Range<usize>,
    xform: Option<(Xform, &'a Elem)>,
}

/// A geometry builder: the shape's geometry from its parameters and placement.
type ShapeBuilder = for<'a, 'p> fn(
    &mut Loader<'a>,
    &'p Plugin<'a>,
    &'p Placement<'a>,
) -> Result<WorldGeometry, SceneError>;

/// Every shape type a `<shape>` can have (groups and instances are read in
/// `shape_or_instance`), with its geometry builder.
const GEOMETRIES: &[(&str, ShapeBuilder)] = &[
    ("rectangle", rectangle),
    ("cube", cube),
    ("sphere", sphere),
    ("disk", disk),
    ("cylinder", cylinder),
    ("sdfgrid", sdfgrid),
    ("obj", obj_ply_serialized),
    ("ply", obj_ply_serialized),
    ("serialized", obj_ply_serialized),
];

/// A mesh placed in the world whose every vertex is in range, else an error at `span`.
fn placed(
    ctx: &Ctx,
    mesh: WorldMesh,
    span: std::ops::Range<usize>,
) -> Result<WorldGeometry, SceneError> {
    match mesh.out_of_range() {
        Some(p) => Err(ctx.at(span, out_of_range_message("the transformed shape", p))),
        None => Ok(WorldGeometry::Mesh(mesh)),
    }
}

fn rectangle<'a>(
    _: &mut Loader<'a>,
    _: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (ctx, m, span) = (&at.ctx, at.m, at.span.clone());
    check_quad(&ctx, &m, span.clone())?;
    placed(
        ctx,
        WorldMesh::place(&TriangleMesh::unit_rectangle(), &m),
        span,
    )
}

fn cube<'a>(
    _: &mut Loader<'a>,
    _: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (ctx, m, span) = (&at.ctx, at.m, at.span.clone());
    check_solid(&ctx, &m, span.clone(), "cube")?;
    placed(ctx, WorldMesh::place(&TriangleMesh::unit_cube(), &m), span)
}

fn sphere<'a>(
    _: &mut Loader<'a>,
    p: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (e, xform) = (p.elem, &at.xform);
    let c = DVec3::from_array(p.vec3("center")?.unwrap_or([0.0; 3]));
    let r = p.float("radius")?.unwrap_or(1.0);
    if !(r > 0.0) {
        return Err(p.err(e, format!("sphere `radius` must be positive, got {r}")));
    }
    let (center, radius, rotation) = match &xform {
        None => (c, r, None),
        Some((x, te)) => {
            let s = similarity_scale(&x.m).ok_or_else(|| {
                p.err(te, "a sphere's to_world must be a rotation, uniform scale and translation (an ellipsoid is not supported)")
            })?;
            // The rotation is kept for uv and tangents (Mitsuba's are in the
            // sphere's object frame); none when there is none.
            let rot = glam::DMat3::from_mat4(x.m) * (1.0 / s);
            let rotation = (rot != glam::DMat3::IDENTITY).then_some(rot);
            (x.m.transform_point3(c), r * s, rotation)
        }
    };
    if !crate::world::in_range(center) || !(radius as f32).is_finite() {
        return Err(p.err(e, out_of_range_message("the sphere", center + radius)));
    }
    Ok(WorldGeometry::Sphere {
        center,
        radius,
        rotation,
    })
}

/// Exact disk: the unit disk under `to_world` (an ellipse under a non-uniform scale).
fn disk<'a>(
    _: &mut Loader<'a>,
    p: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (e, ctx, m, span) = (p.elem, &at.ctx, at.m, at.span.clone());
    check_quad(&ctx, &m, span.clone())?;
    Ok(WorldGeometry::Disk {
        to_world: checked_map(&p, e, &m, "disk")?,
    })
}

/// Mitsuba's cylinder: to_world · translate(p0) · to_frame(p1 − p0) · scale(r, r, |p1 −
/// p0|) maps the unit cylinder; Mitsuba then keeps only that map's rotation and its
/// diagonal stretch (r, l), so a shear or unequal x/y scale is refused here rather
/// than rendered differently.
fn cylinder<'a>(
    _: &mut Loader<'a>,
    p: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (e, m, xform) = (p.elem, at.m, &at.xform);
    let r = p.float("radius")?.unwrap_or(1.0);
    let p0 = DVec3::from_array(p.vec3("p0")?.unwrap_or([0.0; 3]));
    let p1 = DVec3::from_array(p.vec3("p1")?.unwrap_or([0.0, 0.0, 1.0]));
    let axis = p1 - p0;
    let len = axis.length();
    if !(len > 0.0) || !(r != 0.0) || !r.is_finite() {
        return Err(p.err(e, format!("a cylinder needs p0 ≠ p1 and a non-zero radius (got radius {r}, |p1 − p0| = {len})")));
    }
    // Duff et al.'s orthonormal basis around the axis (Mitsuba's Frame, lt's Frame::from_z).
    let f = lt_core::math::Frame::from_z(axis.normalize().as_vec3());
    let frame = DMat4::from_cols(
        f.x.as_dvec3().extend(0.0),
        f.y.as_dvec3().extend(0.0),
        (axis / len).extend(0.0),
        glam::DVec4::W,
    );
    let full = m * DMat4::from_translation(p0) * frame * DMat4::from_scale(DVec3::new(r, r, len));
    if !lt_core::geometry::quadric::is_round_cylinder_map(&glam::DMat3::from_mat4(full), 1e-5) {
        return Err(p.err(
            xform.as_ref().map_or(e, |(_, te)| te),
            "a cylinder's to_world must be a rotation, a scale equal along x and y, and a translation (Mitsuba drops shear and unequal x/y scales, with a warning)",
        ));
    }
    Ok(WorldGeometry::Cylinder {
        to_world: checked_map(&p, e, &full, "cylinder")?,
    })
}

/// Mitsuba's SDF grid: its file's values over the unit cube, under to_world.
fn sdfgrid<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (e, doc, m) = (p.elem, l.doc, at.m);
    let Some((file, fe)) = p.string("filename")? else {
        return Err(p.err(e, "shape `sdfgrid` needs a `filename`"));
    };
    let smooth = match p.string("normals")? {
        None | Some(("smooth", _)) => true,
        Some(("analytic", _)) => false,
        Some((other, ne)) => {
            return Err(p.err(
                ne,
                format!("sdfgrid `normals` must be `smooth` or `analytic`, got `{other}`"),
            ))
        }
    };
    let path = doc
        .resolver
        .resolve(file)
        .map_err(|looked| p.err(fe, Resolver::not_found("volume grid file", file, &looked)))?;
    let resolved = Ctx {
        base_dir: PathBuf::new(),
        ..doc.ctx(e.src)
    };
    let spanned = toml::Spanned::new(fe.range.clone(), path.to_string_lossy().into_owned());
    let grid = crate::mesh::vol::load_sdf_grid(&resolved, &spanned, smooth)?;
    l.meshes.push(path);
    Ok(WorldGeometry::SdfGrid {
        grid: std::sync::Arc::new(grid),
        to_world: checked_map(&p, e, &m, "sdfgrid")?,
    })
}

fn obj_ply_serialized<'a>(
    l: &mut Loader<'a>,
    p: &Plugin<'a>,
    at: &Placement<'a>,
) -> Result<WorldGeometry, SceneError> {
    let (e, doc, ctx, m, span) = (p.elem, l.doc, &at.ctx, at.m, at.span.clone());
    let Some((file, fe)) = p.string("filename")? else {
        return Err(p.err(e, format!("shape `{}` needs a `filename`", p.kind)));
    };
    let mut face_normals = p.boolean("face_normals")?.unwrap_or(false);
    // lt's own: what a mesh without normals shades with, Mitsuba's smooth normals or flat faces
    // (a TOML mesh's rule); `lt convert` prints "flat" as `face_normals` when the file has none.
    let flat_if_missing = match p.string("missing_normals")? {
        None | Some(("smooth", _)) => false,
        Some(("flat", _)) => true,
        Some((other, ne)) => {
            return Err(p.err(
                ne,
                format!("`missing_normals` must be `smooth` or `flat`, got `{other}`"),
            ))
        }
    };
    let shape_index = match p.kind {
        "serialized" => p.integer("shape_index")?.map_or(Ok(0), |i| {
            u32::try_from(i).map_err(|_| {
                p.err(
                    e,
                    format!("`shape_index` must be a non-negative integer, got {i}"),
                )
            })
        })?,
        _ => 0,
    };
    check_solid(&ctx, &m, span.clone(), "mesh")?;
    let path = doc
        .resolver
        .resolve(file)
        .map_err(|looked| p.err(fe, Resolver::not_found("mesh file", file, &looked)))?;
    // The mesh readers join their context's folder with the name: give them the
    // resolved path and no folder.
    let resolved = Ctx {
        base_dir: PathBuf::new(),
        ..doc.ctx(e.src)
    };
    let spanned = toml::Spanned::new(fe.range.clone(), path.to_string_lossy().into_owned());
    let mut mesh = match p.kind {
        "obj" => crate::mesh::obj::load_obj(&resolved, &spanned)?,
        "ply" => ply::load_ply(&resolved, &spanned)?,
        _ => {
            // The file's own "face normals" flag is the same as `face_normals`.
            let s = serialized::load_serialized(&resolved, &spanned, shape_index)?;
            face_normals |= s.face_normals;
            s.mesh
        }
    };
    l.meshes.push(path);
    if face_normals {
        mesh.normals = None;
    } else if mesh.normals.is_none() && !flat_if_missing {
        // Mitsuba shades a mesh without normals smoothly, with normals it computes.
        mesh.normals = Some(vertex_normals(&mesh));
    }
    let mesh = WorldMesh::place(&mesh, &m);
    if !(mesh.area() > 0.0) {
        return Err(p.err(fe, "the mesh has zero area (every triangle is degenerate)"));
    }
    placed(ctx, mesh, span)
}
