//! A TOML `[[shapes]]` entry: its geometry, material and emission.

use crate::error::Ctx;
use crate::toml_scene::schema::{ShapeDef, S};
use crate::transform::{check_quad, check_solid, shape_matrix};
use crate::world::{out_of_range_message, WorldBuilder, WorldGeometry, WorldMesh};
use crate::SceneError;
use lt_core::scene::TriangleMesh;
use lt_core::texture::Texture;
use std::collections::HashMap;

/// Adds the shape; returns whether it emits.
pub(super) fn shape(
    ctx: &Ctx,
    def: &S<ShapeDef>,
    ids: &HashMap<&str, u32>,
    media: &HashMap<String, lt_core::medium::MediumId>,
    b: &mut WorldBuilder,
) -> Result<bool, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("a {kind} shape");
    let given = [
        ("file", d.file.as_ref().map(S::span)),
        ("center", d.center.as_ref().map(S::span)),
        ("radius", d.radius.as_ref().map(S::span)),
        ("to_world", d.to_world.as_ref().map(S::span)),
        ("translate", d.translate.as_ref().map(S::span)),
        ("rotate", d.rotate.as_ref().map(S::span)),
        ("scale", d.scale.as_ref().map(S::span)),
    ];
    const PLACED: [&str; 4] = ["to_world", "translate", "rotate", "scale"];
    let geometry = match kind {
        "sphere" => {
            ctx.only(&given, &["center", "radius"], &what)?;
            let center = ctx.dvec3(ctx.need(&d.center, "center", &def.span(), &what)?, "center")?;
            let radius =
                ctx.positive(ctx.need(&d.radius, "radius", &def.span(), &what)?, "radius")?;
            WorldGeometry::Sphere {
                center,
                radius: radius.into(),
                rotation: None,
            }
        }
        "quad" | "cube" => {
            ctx.only(&given, &PLACED, &what)?;
            let (m, span) = shape_matrix(ctx, d)?;
            if kind == "quad" {
                check_quad(ctx, &m, span.clone())?;
                placed(
                    ctx,
                    span,
                    WorldMesh::place(&TriangleMesh::unit_rectangle(), &m),
                )?
            } else {
                check_solid(ctx, &m, span.clone(), "cube")?;
                placed(ctx, span, WorldMesh::place(&TriangleMesh::unit_cube(), &m))?
            }
        }
        "mesh" => {
            ctx.only(
                &given,
                &["file", "to_world", "translate", "rotate", "scale"],
                &what,
            )?;
            let file = ctx.need(&d.file, "file", &def.span(), &what)?;
            let (m, span) = shape_matrix(ctx, d)?;
            check_solid(ctx, &m, span.clone(), "mesh")?;
            let local = crate::mesh::obj::load_obj(ctx, file)?;
            let mesh = placed(ctx, span, WorldMesh::place(&local, &m))?;
            if !matches!(&mesh, WorldGeometry::Mesh(m) if m.area() > 0.0) {
                return Err(ctx.at(
                    file.span(),
                    "the mesh has zero area (every triangle is degenerate)",
                ));
            }
            mesh
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!("unknown shape type `{other}` (expected mesh, quad, cube or sphere)"),
            ))
        }
    };
    let name = d.material.get_ref();
    let Some(&material) = ids.get(name.as_str()) else {
        let mut defined: Vec<&str> = ids.keys().copied().collect();
        defined.sort_unstable();
        let list = if defined.is_empty() {
            "no materials are defined".to_string()
        } else {
            format!("defined: {}", defined.join(", "))
        };
        return Err(ctx.at(
            d.material.span(),
            format!("material `{name}` is not defined ({list})"),
        ));
    };
    let radiance = match (&d.emission, &d.emission_texture) {
        (Some(_), Some(t)) => {
            return Err(ctx.at(t.span(), "give `emission` or `emission_texture`, not both"))
        }
        (Some(e), None) => Some(ctx.color(e, "emission", false)?)
            .filter(|e| e.max_element() > 0.0)
            .map(Texture::Constant),
        (None, Some(t)) => {
            Some(crate::toml_scene::texture::texture(ctx, t)?).filter(|t| t.max_value() > 0.0)
        }
        (None, None) => None,
    };
    let interface = lt_core::scene::MediumInterface {
        interior: super::medium_named(ctx, &d.interior, media)?,
        exterior: super::medium_named(ctx, &d.exterior, media)?,
    };
    if let (Some(_), Some(why)) = (
        interface.interior,
        crate::xml::build::open_surface(&geometry),
    ) {
        return Err(ctx.at(
            def.span(),
            format!(
                "{what} has an interior medium but is not closed ({why}): a medium needs a \
                 surface that bounds it"
            ),
        ));
    }
    let emits = radiance.is_some();
    b.add_shape(geometry, material, radiance, d.flip_normals);
    b.set_last_shape_media(interface)
        .map_err(|why| ctx.at(def.span(), format!("{what}: {why}")))?;
    Ok(emits)
}

/// A mesh placed in the world whose every vertex is in range, else an error at `span`.
pub(super) fn placed(
    ctx: &Ctx,
    span: std::ops::Range<usize>,
    mesh: WorldMesh,
) -> Result<WorldGeometry, SceneError> {
    match mesh.out_of_range() {
        Some(p) => Err(ctx.at(span, out_of_range_message("the transformed shape", p))),
        None => Ok(WorldGeometry::Mesh(mesh)),
    }
}
