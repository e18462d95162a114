//! Turns the parsed file into a `Scene` through `SceneBuilder`, checking each value on the way.

use crate::error::Ctx;
use crate::format::{CameraDef, LightDef, MaterialDef, SceneFile, ShapeDef, S};
use crate::transform::{check_quad, check_solid, shape_matrix};
use crate::SceneError;
use lt_core::bsdf::{Dielectric, Diffuse, Glossy, Material, Mirror};
use lt_core::camera::{Camera, FovAxis};
use lt_core::light::SunLight;
use lt_core::math::{Color, Vec3, PI};
use lt_core::scene::{LightDesc, RenderSettings, Scene, SceneBuilder, ShapeGeometry, TriangleMesh};
use std::collections::HashMap;

/// GGX α below this is numerically a mirror; use `mirror` instead.
const MIN_ROUGHNESS: f32 = 1e-4;

pub fn assemble(ctx: &Ctx, file: &SceneFile) -> Result<Scene, SceneError> {
    let camera = camera(ctx, &file.camera)?;
    let settings = render(ctx, file)?;
    let mut b = SceneBuilder::new(camera, settings);
    let mut ids = HashMap::new();
    // In file order, so ids and the first error reported follow the file.
    let mut materials: Vec<_> = file.materials.iter().collect();
    materials.sort_by_key(|(_, def)| def.span().start);
    for (name, def) in materials {
        ids.insert(name.as_str(), b.add_material(material(ctx, name, def)?));
    }
    let mut emitters = 0;
    for def in &file.shapes {
        emitters += shape(ctx, def, &ids, &mut b)? as usize;
    }
    for def in &file.lights {
        if let Some(l) = light(ctx, def)? {
            b.add_light(l);
            emitters += 1;
        }
    }
    if emitters == 0 {
        return Err(ctx.whole(
            "the scene has no light: give a shape a non-zero `emission` or add a [[lights]] entry",
        ));
    }
    Ok(b.build())
}

fn camera(ctx: &Ctx, c: &S<CameraDef>) -> Result<Camera, SceneError> {
    let d = c.get_ref();
    let eye = ctx.vec3(&d.eye, "eye")?;
    let target = ctx.vec3(&d.target, "target")?;
    let up =
        d.up.as_ref()
            .map(|u| ctx.vec3(u, "up"))
            .transpose()?
            .unwrap_or(Vec3::Y);
    let fov = ctx.num(&d.fov, "fov")?;
    let [w, h] = *d.resolution.get_ref();
    Camera::look_at(
        eye,
        target,
        up,
        fov,
        d.fov_axis.map_or(FovAxis::X, FovAxis::from),
        w,
        h,
    )
    .map_err(|e| ctx.at(c.span(), format!("degenerate camera: {e}")))
}

fn render(ctx: &Ctx, file: &SceneFile) -> Result<RenderSettings, SceneError> {
    let mut s = RenderSettings::default();
    let Some(r) = &file.render else { return Ok(s) };
    if let Some(m) = &r.max_depth {
        s.max_depth = *m.get_ref();
        if s.max_depth == 0 {
            return Err(ctx.at(
                m.span(),
                "`max_depth` must be at least 1 (1 = emitters seen directly)",
            ));
        }
    }
    if let Some(spp) = &r.spp {
        s.spp = *spp.get_ref();
        if s.spp == 0 {
            return Err(ctx.at(spp.span(), "`spp` must be at least 1"));
        }
    }
    s.rr_depth = r.rr_depth.unwrap_or(s.rr_depth);
    Ok(s)
}

fn material(ctx: &Ctx, name: &str, def: &S<MaterialDef>) -> Result<Material, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("material `{name}` of type {kind}");
    let given = [
        ("albedo", d.albedo.as_ref().map(S::span)),
        ("reflectance", d.reflectance.as_ref().map(S::span)),
        ("ior", d.ior.as_ref().map(S::span)),
        ("roughness", d.roughness.as_ref().map(S::span)),
    ];
    let reflectance = |default: f32| {
        d.reflectance
            .as_ref()
            .map(|r| ctx.color(r, "reflectance", true))
            .transpose()
            .map(|c| c.unwrap_or(Color::splat(default)))
    };
    Ok(match kind {
        "diffuse" => {
            ctx.only(&given, &["albedo"], &what)?;
            Material::Diffuse(Diffuse {
                albedo: ctx.color(
                    ctx.need(&d.albedo, "albedo", &def.span(), &what)?,
                    "albedo",
                    true,
                )?,
            })
        }
        "mirror" => {
            ctx.only(&given, &["reflectance"], &what)?;
            Material::Mirror(Mirror {
                reflectance: reflectance(1.0)?,
            })
        }
        "dielectric" => {
            ctx.only(&given, &["ior"], &what)?;
            Material::Dielectric(Dielectric {
                ior: ctx.positive(ctx.need(&d.ior, "ior", &def.span(), &what)?, "ior")?,
            })
        }
        "glossy" => {
            ctx.only(&given, &["reflectance", "roughness"], &what)?;
            let r = ctx.need(&d.roughness, "roughness", &def.span(), &what)?;
            let roughness = ctx.num(r, "roughness")?;
            if !(roughness >= MIN_ROUGHNESS) {
                return Err(ctx.at(r.span(), format!("`roughness` (GGX α) must be at least {MIN_ROUGHNESS}, got {roughness} (use a mirror for a perfectly smooth surface)")));
            }
            Material::Glossy(Glossy {
                reflectance: reflectance(1.0)?,
                roughness,
            })
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                "unknown material type `{other}` (expected diffuse, mirror, dielectric or glossy)"
            ),
            ))
        }
    })
}

/// Adds the shape; returns whether it emits.
fn shape(
    ctx: &Ctx,
    def: &S<ShapeDef>,
    ids: &HashMap<&str, u32>,
    b: &mut SceneBuilder,
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
            let center = ctx.vec3(ctx.need(&d.center, "center", &def.span(), &what)?, "center")?;
            let radius =
                ctx.positive(ctx.need(&d.radius, "radius", &def.span(), &what)?, "radius")?;
            ShapeGeometry::Sphere { center, radius }
        }
        "quad" | "cube" => {
            ctx.only(&given, &PLACED, &what)?;
            let (m, span) = shape_matrix(ctx, d)?;
            if kind == "quad" {
                check_quad(ctx, &m, span)?;
                ShapeGeometry::Mesh(TriangleMesh::unit_rectangle().transformed(&m))
            } else {
                check_solid(ctx, &m, span, "cube")?;
                ShapeGeometry::Mesh(TriangleMesh::unit_cube().transformed(&m))
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
            check_solid(ctx, &m, span, "mesh")?;
            let mesh = crate::mesh::obj::load_obj(ctx, file)?.transformed(&m);
            if !((0..mesh.indices.len())
                .map(|i| mesh.triangle_area(i))
                .sum::<f32>()
                > 0.0)
            {
                return Err(ctx.at(
                    file.span(),
                    "the mesh has zero area (every triangle is degenerate)",
                ));
            }
            ShapeGeometry::Mesh(mesh)
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
    let emission = d
        .emission
        .as_ref()
        .map(|e| ctx.color(e, "emission", false))
        .transpose()?
        .filter(|e| e.max_element() > 0.0);
    let emits = emission.is_some();
    b.add_shape(geometry, material, emission, d.flip_normals);
    Ok(emits)
}

/// The light, or None when it emits nothing.
fn light(ctx: &Ctx, def: &S<LightDef>) -> Result<Option<LightDesc>, SceneError> {
    let d = def.get_ref();
    let kind = d.kind.get_ref().as_str();
    let what = format!("a {kind} light");
    let given = [
        ("position", d.position.as_ref().map(S::span)),
        ("intensity", d.intensity.as_ref().map(S::span)),
        ("direction", d.direction.as_ref().map(S::span)),
        ("solid_angle", d.solid_angle.as_ref().map(S::span)),
        ("radiance", d.radiance.as_ref().map(S::span)),
        ("irradiance", d.irradiance.as_ref().map(S::span)),
    ];
    let span = def.span();
    let desc = match kind {
        "point" => {
            ctx.only(&given, &["position", "intensity"], &what)?;
            let position =
                ctx.vec3(ctx.need(&d.position, "position", &span, &what)?, "position")?;
            let intensity = ctx.color(
                ctx.need(&d.intensity, "intensity", &span, &what)?,
                "intensity",
                false,
            )?;
            LightDesc::Point {
                position,
                intensity,
            }
        }
        "sun" => {
            ctx.only(
                &given,
                &["direction", "solid_angle", "radiance", "irradiance"],
                &what,
            )?;
            let dir = ctx.need(&d.direction, "direction", &span, &what)?;
            let direction = ctx.vec3(dir, "direction")?;
            if !(direction.length() > 0.0) {
                return Err(ctx.at(
                    dir.span(),
                    "`direction` (towards the sun) is the zero vector",
                ));
            }
            let sa = ctx.need(&d.solid_angle, "solid_angle", &span, &what)?;
            let solid_angle = ctx.positive(sa, "solid_angle")?;
            if !(solid_angle < 2.0 * PI) {
                return Err(ctx.at(
                    sa.span(),
                    format!("`solid_angle` must be below 2π sr (a hemisphere), got {solid_angle}"),
                ));
            }
            let radiance = match (&d.radiance, &d.irradiance) {
                (Some(r), None) => ctx.color(r, "radiance", false)?,
                (None, Some(e)) => {
                    let l = SunLight::radiance_from_irradiance(
                        ctx.color(e, "irradiance", false)?,
                        solid_angle,
                    );
                    if !l.is_finite() {
                        return Err(ctx.at(sa.span(), format!("`solid_angle` {solid_angle} is too small to turn the irradiance into a finite radiance")));
                    }
                    l
                }
                (Some(_), Some(e)) => {
                    return Err(ctx.at(
                        e.span(),
                        "give the sun `radiance` or `irradiance`, not both",
                    ))
                }
                (None, None) => {
                    return Err(ctx.at(
                        span,
                        "missing required key `radiance` or `irradiance` for a sun light",
                    ))
                }
            };
            LightDesc::Sun {
                direction: direction.normalize(),
                solid_angle,
                radiance,
            }
        }
        "directional" => {
            // A delta in direction has no solid angle, so no radiance: say so before the generic
            // "does not apply" check would.
            if let Some(r) = &d.radiance {
                return Err(ctx.at(
                    r.span(),
                    "a directional light takes `irradiance` (W/m² on a surface facing it), not \
                     `radiance`: it is a delta in direction, with no solid angle to spread a \
                     radiance over (for a light of finite angular size use type = \"sun\")",
                ));
            }
            ctx.only(&given, &["direction", "irradiance"], &what)?;
            let dir = ctx.need(&d.direction, "direction", &span, &what)?;
            let direction = ctx.vec3(dir, "direction")?;
            if !(direction.length() > 0.0) {
                return Err(ctx.at(
                    dir.span(),
                    "`direction` (towards the light) is the zero vector",
                ));
            }
            let irradiance = ctx.color(
                ctx.need(&d.irradiance, "irradiance", &span, &what)?,
                "irradiance",
                false,
            )?;
            LightDesc::Directional {
                direction: direction.normalize(),
                irradiance,
            }
        }
        "environment" => {
            ctx.only(&given, &["radiance"], &what)?;
            LightDesc::Environment {
                radiance: ctx.color(
                    ctx.need(&d.radiance, "radiance", &span, &what)?,
                    "radiance",
                    false,
                )?,
            }
        }
        other => {
            return Err(ctx.at(
                d.kind.span(),
                format!(
                    "unknown light type `{other}` (expected point, sun, directional or environment)"
                ),
            ))
        }
    };
    let power = match &desc {
        LightDesc::Point { intensity: c, .. }
        | LightDesc::Sun { radiance: c, .. }
        | LightDesc::Directional { irradiance: c, .. }
        | LightDesc::Environment { radiance: c } => c.max_element(),
    };
    Ok((power > 0.0).then_some(desc))
}
