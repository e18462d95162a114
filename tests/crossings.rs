//! The one-query crossings of a segment (`Scene::boundary_crossings`, every hit of the first ray
//! sorted along it) against the restart walk it replaced (a closest-hit query restarted past each
//! crossing and re-aimed at the end), on random segments through the shipped media scenes: the
//! same surfaces crossed on the same side in the same order, the first at the same bits (both
//! walks' first ray is the same), each later one within the error bounds of the two points plus
//! how far the restart ray has drifted from the first: it starts at the last crossing's offset
//! point and aims at the same end, so it lies within δ (that point's distance from the first
//! ray's line) of it up to the end, and two lines δ apart meet a surface at incidence cos θ at
//! points δ / |cos θ| apart (a line towards infinity stays parallel: δ throughout).

use lt_core::bsdf::{Diffuse, Material, Null, ThinDielectric};
use lt_core::camera::{Camera, FovAxis};
use lt_core::geometry::{offset_ray_origin, Ray};
use lt_core::math::{gamma, Vec3};
use lt_core::medium::{Medium, PhaseFunction};
use lt_core::sampling::Sampler;
use lt_core::scene::{ConnectionEnd, SegmentCrossing};
use lt_core::scene::{MediumInterface, RenderSettings, SceneBuilder, ShapeGeometry, TriangleMesh};
use lt_core::Color;
use lt_core::Scene;
use lt_tests::{shipped_media_scene_names, shipped_scene};

/// A bare point's error bound as a walk would carry it: the rounding of a few operations on its
/// coordinates (given, so the test knows the end the query moves it out of).
fn bare(p: Vec3) -> ConnectionEnd {
    ConnectionEnd {
        p,
        p_err: p.abs().max(Vec3::splat(1e-6)) * gamma(7),
        ng: Vec3::ZERO,
        infinite: false,
    }
}

/// A point uniformly in the scene's bounding sphere's box.
fn point_in(s: &Scene, u: &mut Sampler) -> Vec3 {
    let (c, r) = s.bounding_sphere;
    let mut coordinate = || (2.0 * u.next_f32() - 1.0) * r;
    c + Vec3::new(coordinate(), coordinate(), coordinate())
}

fn direction(u: &mut Sampler) -> Vec3 {
    let z = 2.0 * u.next_f32() - 1.0;
    let phi = 2.0 * std::f32::consts::PI * u.next_f32();
    let s = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), z)
}

/// One random end: a bare point (a medium vertex, a point light), a surface point (where a
/// random ray first hits), or (`may_be_infinite`) a direction to a light at infinity.
fn end(s: &Scene, u: &mut Sampler, may_be_infinite: bool) -> ConnectionEnd {
    let kind = u.next_f32();
    if may_be_infinite && kind < 0.2 {
        return ConnectionEnd {
            p: direction(u),
            p_err: Vec3::ZERO,
            ng: Vec3::ZERO,
            infinite: true,
        };
    }
    let p = point_in(s, u);
    if kind < 0.6 {
        return bare(p);
    }
    match s.intersect(&Ray::new(p, direction(u))) {
        Some(h) => ConnectionEnd {
            p: h.p,
            p_err: h.p_err,
            ng: h.ng,
            infinite: false,
        },
        None => bare(p),
    }
}

/// The first ray's origin and direction, as `boundary_crossings` derives them from the ends (both
/// ends here carry their own error bounds, so none is filled in by the scene).
fn first_ray(from: &ConnectionEnd, to: &ConnectionEnd) -> (Vec3, Vec3) {
    let dir0 = if to.infinite { to.p } else { to.p - from.p };
    let start = if from.ng == Vec3::ZERO {
        from.p
    } else {
        offset_ray_origin(from.p, from.p_err, from.ng, dir0)
    };
    let d = if to.infinite {
        dir0.normalize()
    } else if to.ng == Vec3::ZERO {
        (to.p - start).normalize()
    } else {
        (offset_ray_origin(to.p, to.p_err, to.ng, -dir0) - start).normalize()
    };
    (start, d)
}

/// Why the one-query crossings `new` are not the restart walk's `old`, if they are not.
fn mismatch(
    from: &ConnectionEnd,
    to: &ConnectionEnd,
    old: &[SegmentCrossing],
    new: &[SegmentCrossing],
) -> Option<String> {
    if old.len() != new.len() {
        return Some(format!(
            "{} crossings, restarting {}: {new:?} vs {old:?}",
            new.len(),
            old.len()
        ));
    }
    let (o, d) = first_ray(from, to);
    for (k, (a, b)) in old.iter().zip(new).enumerate() {
        if a.shape != b.shape || (a.ng.dot(d) > 0.0) != (b.ng.dot(d) > 0.0) {
            return Some(format!(
                "crossing {k}: shape {} vs {}, or another side",
                b.shape, a.shape
            ));
        }
        let drift = if k == 0 {
            if a.p != b.p {
                return Some(format!(
                    "first crossing at {} vs {}: not the same ray's",
                    b.p, a.p
                ));
            }
            0.0
        } else {
            let prev = &old[k - 1];
            let origin = offset_ray_origin(prev.p, prev.p_err, prev.ng, d);
            let v = origin - o;
            (v - d * v.dot(d)).length()
        };
        let cos = a.ng.dot(d).abs().min(b.ng.dot(d).abs());
        // The bound, plus the rounding of computing these lengths from coordinates this large.
        let bound = a.p_err.length() + b.p_err.length() + drift / cos;
        let rounding = gamma(16) * a.p.abs().max(b.p.abs()).max_element();
        let gap = (a.p - b.p).length();
        if !(gap <= bound + rounding) {
            return Some(format!(
                "crossing {k}: {} vs {} apart by {gap:e}, bound {bound:e} (drift {drift:e}, cos {cos})",
                b.p, a.p
            ));
        }
    }
    None
}

/// A triangle-mesh sphere (`n` bands of latitude, 2n of longitude): every crossing of it is at a
/// triangle, and many at an edge or vertex two or more triangles share.
fn mesh_sphere(c: Vec3, r: f32, n: u32) -> ShapeGeometry {
    let mut positions = Vec::new();
    for i in 0..=n {
        let theta = std::f32::consts::PI * i as f32 / n as f32;
        for j in 0..2 * n {
            let phi = std::f32::consts::PI * j as f32 / n as f32;
            let d = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            positions.push(c + d * r);
        }
    }
    let at = |i: u32, j: u32| i * 2 * n + j % (2 * n);
    let mut indices = Vec::new();
    for i in 0..n {
        for j in 0..2 * n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            // Outward (counter-clockwise seen from outside); the pole rows' degenerate ones
            // are kept (zero area: never hit).
            indices.push([a, c, b]);
            indices.push([b, c, d]);
        }
    }
    ShapeGeometry::Mesh(TriangleMesh {
        positions,
        normals: None,
        uvs: None,
        indices,
        attributes: Vec::new(),
    })
}

/// Two nested null mesh spheres of fog (the inner one naming the outer fog as its exterior), a
/// thin dielectric pane through both and a floor, all triangles: what the wide BVH answers.
fn mesh_media_scene() -> Scene {
    let camera =
        Camera::look_at(Vec3::Z * 5.0, Vec3::ZERO, Vec3::Y, 40.0, FovAxis::X, 8, 8).unwrap();
    let mut b = SceneBuilder::new(camera, RenderSettings::default());
    let fog = |s: f32| {
        let h = lt_core::medium::Homogeneous::new(
            Color::splat(s),
            Color::splat(0.5),
            1.0,
            PhaseFunction::Isotropic,
        );
        Medium::Homogeneous(h.unwrap())
    };
    let (outer, inner) = (b.add_medium(fog(1.0)), b.add_medium(fog(3.0)));
    let null = b.add_material(Material::Null(Null));
    let pane = b.add_material(Material::ThinDielectric(ThinDielectric::mitsuba_default()));
    let floor = b.add_material(Material::Diffuse(Diffuse {
        albedo: Color::splat(0.5),
    }));
    b.add_shape(mesh_sphere(Vec3::ZERO, 1.0, 24), null, None, false);
    b.set_last_shape_media(MediumInterface {
        interior: Some(outer),
        exterior: None,
    });
    b.add_shape(
        mesh_sphere(Vec3::new(0.2, 0.1, 0.0), 0.4, 12),
        null,
        None,
        false,
    );
    b.set_last_shape_media(MediumInterface {
        interior: Some(inner),
        exterior: Some(outer),
    });
    let quad = |p: [Vec3; 4]| {
        ShapeGeometry::Mesh(TriangleMesh {
            positions: p.to_vec(),
            normals: None,
            uvs: None,
            indices: vec![[0, 1, 2], [0, 2, 3]],
            attributes: Vec::new(),
        })
    };
    let (x, y) = (1.5, -1.2);
    b.add_shape(
        quad([[-x, -x, 0.1], [x, -x, 0.1], [x, x, 0.1], [-x, x, 0.1]].map(Vec3::from)),
        pane,
        None,
        false,
    );
    b.add_shape(
        quad(
            [
                [-2.0, y, -2.0],
                [-2.0, y, 2.0],
                [2.0, y, 2.0],
                [2.0, y, -2.0],
            ]
            .map(Vec3::from),
        ),
        floor,
        None,
        false,
    );
    b.try_build().unwrap()
}

/// Segments along the axes through `mesh_media_scene`'s two north poles, where every triangle of
/// a fan reports the hit, and through the pane's diagonal, where both of its triangles do: one
/// crossing each, which the one query must not count twice.
fn edges_and_vertices() -> Vec<(ConnectionEnd, ConnectionEnd)> {
    let down = ConnectionEnd {
        p: -Vec3::Y,
        p_err: Vec3::ZERO,
        ng: Vec3::ZERO,
        infinite: true,
    };
    let mut v = Vec::new();
    for x in [0.0, 0.2] {
        let (a, b) = (Vec3::new(x, 3.0, 0.0), Vec3::new(x, -3.0, 0.0));
        v.extend([(bare(a), bare(b)), (bare(a), down), (bare(b), bare(a))]);
    }
    let (a, b) = (Vec3::new(0.5, 0.5, 3.0), Vec3::new(0.5, 0.5, -3.0));
    v.extend([(bare(a), bare(b)), (bare(b), bare(a))]);
    v
}

/// Random segments through every shipped media scene and `mesh_media_scene`, after
/// `edges_and_vertices`; returns the crossings compared and the ray
/// cores seen.
fn compare_on_media_scenes(segments: usize) -> (usize, Vec<String>) {
    let mut compared = 0;
    let mut cores = Vec::new();
    let mut scenes: Vec<(String, Scene)> = shipped_media_scene_names()
        .into_iter()
        .map(|name| {
            let s = shipped_scene(&name, Some((8, 8)));
            (name, s)
        })
        .collect();
    scenes.push(("nested mesh spheres".into(), mesh_media_scene()));
    for (n, (name, s)) in scenes.into_iter().enumerate() {
        cores.push(s.ray_core());
        let mut u = Sampler::new(47, n as u64, 0);
        let random = (0..segments).map(|_| (end(&s, &mut u, false), end(&s, &mut u, true)));
        for (i, (from, to)) in edges_and_vertices().into_iter().chain(random).enumerate() {
            for panes in [false, true] {
                let old = s.boundary_crossings(from, to, panes, true);
                let new = s.boundary_crossings(from, to, panes, false);
                let (Some(old), Some(new)) = (&old, &new) else {
                    assert_eq!(old.is_some(), new.is_some(), "{name}, segment {i}");
                    continue;
                };
                if let Some(why) = mismatch(&from, &to, old, new) {
                    panic!("{name}, segment {i} ({from:?} to {to:?}): {why}");
                }
                compared += old.len();
            }
        }
    }
    (compared, cores)
}

#[test]
fn one_query_crosses_what_the_restart_walk_crosses() {
    let (compared, cores) = compare_on_media_scenes(1500);
    // Enough crossings, through both cores that have the query.
    assert!(compared > 5000, "only {compared} crossings compared");
    assert!(cores.iter().any(|c| c.starts_with("flat")), "{cores:?}");
    if lt_core::geometry::flat::Isa::available().contains(&lt_core::geometry::flat::Isa::Avx2) {
        assert!(cores.iter().any(|c| c.starts_with("wide")), "{cores:?}");
    }
}
