//! Random walks that record, independently of `Path`, the densities and factors they actually
//! used, and hand every complete path they form to a callback.

use glam::DVec3;
use lt_core::bsdf::TransportMode;
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::measure::solid_angle_to_area;
use lt_core::path::{Path, PathVertex};
use lt_core::sampling::Sampler;
use lt_core::Scene;

/// A complete path with what the walk that made it knows about it.
pub struct Made {
    pub path: Path,
    /// The technique that made it.
    pub s: usize,
    /// Product of the area-measure densities the walk used (Russian roulette aside).
    pub pdf: f64,
    /// Product of the measurement-contribution factors the walk met, grouped as a walk sees them:
    /// Le or We times the cosine it leaves with, then per vertex cos/d² on arrival and f_cos
    /// (the sample's weight · pdf) on leaving. Same product as Le·G·∏fs·G·We, but each vertex's
    /// outgoing cosine is the sampled direction's, as in the walk's throughput.
    pub f: DVec3,
    /// The estimator's own value, f/(N p) computed from sample weights: Le · β for the camera
    /// techniques, the splat for light tracing.
    pub estimate: DVec3,
}

fn uv(s: &mut Sampler) -> Vec2 {
    s.next_2d()
}

/// One camera walk through `raster` (uniform over the film when `None`) that reports paths of at
/// most `max_k` segments: s = 0 when it hits a light and s = 1 (next-event estimation) at every
/// non-delta surface vertex.
pub fn camera_walk(
    scene: &Scene,
    rng: &mut Sampler,
    raster: Option<Vec2>,
    max_k: usize,
    out: &mut dyn FnMut(Made),
) {
    let cam = &scene.camera;
    let raster =
        raster.unwrap_or_else(|| rng.next_2d() * Vec2::new(cam.width as f32, cam.height as f32));
    let mut ray = cam.generate_ray(raster);
    let mut verts = vec![PathVertex::camera(cam, Color::ONE)];
    let mut pdf_w = cam.pdf_dir(ray.o, ray.d);
    // The pinhole's discrete 1; We times the camera's cosine (G's camera end).
    let mut pdf = 1.0f64;
    let mut f = DVec3::splat((cam.importance(ray.o, ray.d) * cam.forward().dot(ray.d)) as f64);
    let mut beta = DVec3::ONE;
    for k in 1..=max_k {
        let prev = *verts.last().unwrap();
        let Some(hit) = scene.intersect(&ray) else {
            // Escaped: every light at infinity is an x0 in solid angle, G = |cos| at prev — but
            // a directional light's single direction, which no ray hits (measure zero).
            for &li in &scene.infinite_lights {
                if scene.lights[li as usize].delta_direction() {
                    continue;
                }
                let x0 = PathVertex::light_escaped(li, ray.d, beta.as_vec3(), pdf_w);
                let le = scene.lights[li as usize].escaped(ray.d).as_dvec3();
                out(Made {
                    path: Path::from_subpaths(&[x0], &verts),
                    s: 0,
                    pdf: pdf * pdf_w as f64,
                    f: f * le,
                    estimate: beta * le,
                });
            }
            return;
        };
        let v = PathVertex::surface(&hit, -ray.d, beta.as_vec3(), pdf_w, &prev);
        let pa = solid_angle_to_area(pdf_w, prev.p, hit.p, hit.ng);
        assert_eq!(v.pdf_fwd, pa, "the vertex stores the density the walk used");
        pdf *= pa as f64;
        f *= solid_angle_to_area(1.0, prev.p, hit.p, hit.ng) as f64;
        if let Some(x0) = v.as_light_endpoint() {
            let le = scene.lights[hit.light.unwrap() as usize]
                .emitted(hit.ng, -ray.d, hit.uv)
                .as_dvec3();
            out(Made {
                path: Path::from_subpaths(&[x0], &verts),
                s: 0,
                pdf,
                f: f * le,
                estimate: beta * le,
            });
            return; // lights are black: the walk ends
        }
        let m = scene.material(hit.material);
        let sf = hit.shading_frame();
        let wo = -ray.d;
        let mut camera_sub = verts.clone();
        camera_sub.push(v);
        if !m.is_delta() && k < max_k {
            let so_far = WalkSoFar {
                sub: &camera_sub,
                pdf,
                f,
                beta,
            };
            nee(scene, rng, (&hit, wo), so_far, out);
        }
        let Some(bs) = m.sample(&sf, wo, rng.next_f32(), uv(rng), TransportMode::Radiance) else {
            return;
        };
        f *= (bs.weight * bs.pdf_w).as_dvec3();
        beta *= bs.weight.as_dvec3();
        pdf_w = bs.pdf_w;
        let mut v = v;
        v.delta = bs.delta;
        verts.push(v);
        ray = hit.spawn_ray(bs.wi);
    }
}

/// A camera walk up to its last vertex: the vertices (camera first), the path's density, its
/// contribution f, and the estimator's weight β.
struct WalkSoFar<'a> {
    sub: &'a [PathVertex],
    pdf: f64,
    f: DVec3,
    beta: DVec3,
}

/// Next-event estimation from `hit` (reached along -`wo`), the walk's last vertex.
fn nee(
    scene: &Scene,
    rng: &mut Sampler,
    (hit, wo): (&lt_core::scene::SurfaceHit, Vec3),
    so_far: WalkSoFar,
    out: &mut dyn FnMut(Made),
) {
    let WalkSoFar { sub, pdf, f, beta } = so_far;
    let Some((li, pmf, _)) = scene.light_sampler.sample(rng.next_f32()) else {
        return;
    };
    let light = &scene.lights[li];
    let Some(ls) = light.sample_li(hit.p, uv(rng)) else {
        return;
    };
    let x0 = PathVertex::light_sampled(scene, li as u32, &ls, pmf, sub.last().unwrap());
    let e =
        scene
            .material(hit.material)
            .eval(&hit.shading_frame(), wo, ls.wi, TransportMode::Radiance);
    // Density of x0 and the arrival factor at it (cos/d², 1/d² at a point, 1 at infinity; a
    // directional light is at infinity with the discrete density 1).
    let point = ls.delta && !light.is_infinite();
    let (pa, g) = if point {
        (1.0, 1.0 / (ls.p - hit.p).length_squared())
    } else if light.is_infinite() {
        (ls.pdf_w, 1.0)
    } else {
        (
            solid_angle_to_area(ls.pdf_w, hit.p, ls.p, ls.n),
            solid_angle_to_area(1.0, hit.p, ls.p, ls.n),
        )
    };
    // A point light's LightLiSample radiance is I/d²: Le·G needs the intensity I and G with 1/d².
    // A directional light's is its irradiance, the delta-stripped Le at infinity.
    let le = if point {
        ls.radiance * (ls.p - hit.p).length_squared()
    } else {
        ls.radiance
    };
    let est = beta * (e.f_cos * ls.radiance).as_dvec3() / (pmf * ls.pdf_w) as f64;
    let f = f * (e.f_cos * le).as_dvec3() * g as f64;
    out(Made {
        path: Path::from_subpaths(&[x0], sub),
        s: 1,
        pdf: pdf * (pmf * pa) as f64,
        f,
        estimate: est,
    });
}

/// One light walk of at most `max_k` segments, connected to the camera (t = 1, s = k) at every
/// non-delta surface vertex that projects onto the film. Visibility is not tested (f excludes it).
pub fn light_walk(scene: &Scene, rng: &mut Sampler, max_k: usize, out: &mut dyn FnMut(Made)) {
    let Some((li, pmf, _)) = scene.light_sampler.sample(rng.next_f32()) else {
        return;
    };
    let light = &scene.lights[li];
    let Some(le) = light.sample_le(uv(rng), uv(rng), scene.bounding_sphere) else {
        return;
    };
    let x0 = PathVertex::light_emitted(scene, li as u32, &le, pmf);
    let infinite = light.is_infinite();
    let mut verts = vec![x0];
    let mut pdf = (pmf * if infinite { le.pdf_dir } else { le.pdf_pos }) as f64;
    let mut f = le.radiance.as_dvec3()
        * if infinite || light.delta_position() {
            1.0
        } else {
            le.n.dot(le.ray.d).abs() as f64
        };
    let mut beta = le.radiance.as_dvec3()
        * if infinite {
            1.0
        } else {
            le.n.dot(le.ray.d).abs() as f64
        }
        / (pmf * le.pdf_pos * le.pdf_dir) as f64;
    let mut pdf_w = if infinite { le.pdf_pos } else { le.pdf_dir };
    let mut ray = le.ray;
    let cam = &scene.camera;
    // x0 itself connected to the pinhole: technique 1 of a one-segment path (an emitter seen
    // directly), by the emitted point's density alone. A point light has no surface to be seen,
    // and no camera ray hits a directional light's single direction.
    if !light.is_delta() && max_k >= 1 {
        let towards_cam = if infinite {
            Some((-x0.p, 1.0f32))
        } else {
            cam.project(le.p).map(|pr| (-pr.dir, pr.distance))
        };
        if let Some((d, dist)) = towards_cam {
            let dir_from_cam = -d;
            let imp = cam.importance(cam.eye, dir_from_cam);
            let le_cam = if infinite {
                light.escaped(dir_from_cam)
            } else {
                light.emitted(le.n, d, le.uv)
            };
            if imp > 0.0 && le_cam != Color::ZERO {
                let cos_l = if infinite { 1.0 } else { le.n.dot(d).abs() };
                let cos_c = cam.forward().dot(dir_from_cam);
                let g = (cos_l * cos_c / (dist * dist)) as f64;
                let p0 = (pmf * if infinite { le.pdf_dir } else { le.pdf_pos }) as f64;
                let fc = le_cam.as_dvec3() * g * imp as f64;
                let path = Path::from_subpaths(&[x0], &[PathVertex::camera(cam, Color::ONE)]);
                out(Made {
                    path,
                    s: 1,
                    pdf: p0,
                    f: fc,
                    estimate: fc / (p0 * cam.pixel_count() as f64),
                });
            }
        }
    }
    for k in 1..max_k {
        let Some(hit) = scene.intersect(&ray) else {
            return;
        };
        let prev = *verts.last().unwrap();
        let v = PathVertex::surface(&hit, -ray.d, beta.as_vec3(), pdf_w, &prev);
        let (pa, g) = if k == 1 && infinite {
            (pdf_w * hit.ng.dot(ray.d).abs(), hit.ng.dot(ray.d).abs())
        } else {
            (
                solid_angle_to_area(pdf_w, prev.p, hit.p, hit.ng),
                solid_angle_to_area(1.0, prev.p, hit.p, hit.ng),
            )
        };
        pdf *= pa as f64;
        f *= g as f64;
        let m = scene.material(hit.material);
        let sf = hit.shading_frame();
        let wo = -ray.d;
        if let (false, Some(proj)) = (m.is_delta(), cam.project(hit.p)) {
            let e = m.eval(&sf, wo, -proj.dir, TransportMode::Importance);
            let cos_c = cam.forward().dot(proj.dir);
            let arrive = (proj.importance * cos_c / (proj.distance * proj.distance)) as f64;
            let fc = f * e.f_cos.as_dvec3() * arrive;
            let splat = beta * e.f_cos.as_dvec3() * arrive / cam.pixel_count() as f64;
            let mut sub = verts.clone();
            sub.push(v);
            let path = Path::from_subpaths(&sub, &[PathVertex::camera(cam, Color::ONE)]);
            out(Made {
                path,
                s: k + 1,
                pdf,
                f: fc,
                estimate: splat,
            });
        }
        let Some(bs) = m.sample(&sf, wo, rng.next_f32(), uv(rng), TransportMode::Importance) else {
            return;
        };
        f *= (bs.weight * bs.pdf_w).as_dvec3();
        beta *= bs.weight.as_dvec3();
        pdf_w = bs.pdf_w;
        let mut v = v;
        v.delta = bs.delta;
        verts.push(v);
        ray = hit.spawn_ray(bs.wi);
    }
}
