//! The path-space ground truth (`lt_core::path`) against the walks that sample paths, against
//! each other across techniques, and against analytic pixel values.

#[path = "path_space/checks.rs"]
mod checks;
#[path = "path_space/media.rs"]
mod media;
#[path = "path_space/scenes.rs"]
mod scenes;
#[path = "path_space/techniques.rs"]
mod techniques;
#[path = "path_space/walks.rs"]
mod walks;

use checks::*;
use lt_core::math::Vec3;
use lt_core::path::densities::{power_weight_by_ratios, relative_pdfs};
use lt_core::path::{balance_weight, power_weight, Path, PathVertex};
use scenes::*;
use techniques::techniques_agree;
use walks::Made;

#[test]
fn camera_walks_hitting_the_light_match_p0_and_f() {
    let scene = cornell(BoxConfig::default());
    let made: Vec<Made> = collect(&scene, 1, 40_000, true, 10)
        .into_iter()
        .filter(|m| m.s == 0)
        .collect();
    let through_mirror = made
        .iter()
        .filter(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v)))
        .count();
    assert!(
        made.len() > 1000 && through_mirror > 50,
        "{} paths, {through_mirror} via the mirror",
        made.len()
    );
    assert!(made.iter().any(|m| m.path.k() >= 5));
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=0: {} paths ({through_mirror} via the mirror), worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} ill-conditioned paths tested above 2e-4", made.len());
}

#[test]
fn nee_completed_camera_walks_match_p1_and_f() {
    let scene = cornell(BoxConfig::default());
    let made: Vec<Made> = collect(&scene, 2, 5_000, true, 8)
        .into_iter()
        .filter(|m| m.s == 1)
        .collect();
    assert!(
        made.len() > 10_000
            && made
                .iter()
                .any(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v)))
    );
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=1: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} ill-conditioned paths tested above 2e-4", made.len());
}

#[test]
fn light_walks_splatted_to_the_camera_match_pk_and_f() {
    let scene = cornell(BoxConfig::default());
    let made = collect(&scene, 3, 20_000, false, 8);
    assert!(made.len() > 10_000 && made.iter().all(|m| m.s == m.path.k()));
    // The emitter seen directly (k = 1) is technique 1 by the emitted point's density.
    assert!(made.iter().filter(|m| m.path.k() == 1).count() > 1000);
    assert!(made
        .iter()
        .any(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v))));
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=k: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} ill-conditioned paths tested above 2e-4", made.len());
}

#[test]
fn mis_weights_sum_to_one_and_vanish_at_delta_connections() {
    let scene = cornell(BoxConfig::default());
    let mut made = collect(&scene, 4, 3_000, true, 8);
    made.extend(collect(&scene, 5, 3_000, false, 8));
    let mut delta_connections = 0;
    for m in &made {
        let (k, v) = (m.path.k(), &m.path.vertices);
        let d = m.path.densities(&scene);
        let pdfs = d.all();
        assert_eq!(pdfs[k + 1], 0.0, "t = 0 cannot hit a pinhole");
        assert!(
            pdfs[m.s] > 0.0,
            "the technique that made the path has p > 0"
        );
        for (beta, sum) in [
            (
                1.0,
                (0..=k + 1).map(|s| balance_weight(&pdfs, s)).sum::<f64>(),
            ),
            (2.0, (0..=k + 1).map(|s| power_weight(&pdfs, s, 2.0)).sum()),
        ] {
            assert!(
                (sum - 1.0).abs() < 1e-9,
                "β={beta}: weights sum to {sum} for {pdfs:?}"
            );
        }
        for s in 0..=k + 1 {
            if (1..=k).contains(&s) && (is_mirror(&scene, &v[s - 1]) || is_mirror(&scene, &v[s])) {
                delta_connections += 1;
                assert_eq!(pdfs[s], 0.0, "s={s} connects at a mirror");
                assert_eq!(power_weight(&pdfs, s, 2.0), 0.0);
            }
            let direct = power_weight(&pdfs, s, 2.0);
            let by_ratios = power_weight_by_ratios(&d, s, 2.0);
            assert!(
                rel_close(direct, by_ratios, 1e-9),
                "s={s}: ratio form {by_ratios} vs {direct}; made by {} {d:?} {pdfs:?}",
                m.s
            );
        }
        let r = relative_pdfs(&d, m.s);
        for s in 0..=k + 1 {
            assert!(
                rel_close(r[s], pdfs[s] / pdfs[m.s], 1e-9),
                "ratio {s}/{}: {} vs {}",
                m.s,
                r[s],
                pdfs[s] / pdfs[m.s]
            );
        }
    }
    assert!(delta_connections > 100, "{delta_connections}");
}

#[test]
fn techniques_agree_on_a_plane_under_a_quad_light() {
    techniques_agree(
        PlaneLight::Quad {
            half: 0.15,
            le: 20.0,
        },
        [400_000, 100_000, 1_500_000],
    );
}

#[test]
fn techniques_agree_on_a_plane_under_a_point_light() {
    // s = 0 cannot hit a point light (p_0 = 0): only NEE and light tracing.
    techniques_agree(PlaneLight::Point { intensity: 3.0 }, [0, 50_000, 1_000_000]);
}

#[test]
fn techniques_agree_on_a_plane_under_a_large_sun() {
    let sun = PlaneLight::Sun {
        dir: Vec3::new(0.3, 1.0, 0.2),
        omega: 0.05,
        radiance: 40.0,
    };
    techniques_agree(sun, [1_000_000, 50_000, 1_000_000]);
}

#[test]
fn walks_match_with_shading_normals_in_both_transport_modes() {
    // Light walks accumulate importance-mode BSDF factors, camera walks radiance-mode ones, while
    // `contribution` uses radiance mode throughout: with tilted shading normals this only agrees
    // if both modes give the same measurement factor f·|ns·ω_L|/|ng·ω_L| (bsdf/mod.rs).
    let scene = cornell(BoxConfig {
        bumpy_floor: true,
        ..BoxConfig::default()
    });
    let on_floor = |m: &Made| {
        m.path
            .vertices
            .iter()
            .any(|v| v.ng.y > 0.99 && (v.ns - v.ng).length() > 0.05)
    };
    for camera in [false, true] {
        let made = collect(&scene, 6, 10_000, camera, 6);
        assert!(made.iter().filter(|m| on_floor(m)).count() > 1000);
        let (wp, wf, _) = check_made(&scene, &made);
        println!(
            "bumpy floor, camera walks {camera}: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}",
            made.len()
        );
    }
}

#[test]
fn point_light_paths_have_no_s0_and_sun_paths_take_part_in_mis() {
    // Point light: p_0 = 0 exactly (no walk hits a point), the other techniques are finite.
    // Walks stop at k = 2: a lone plane has no longer paths. (Longer walks here also met a
    // geometry bug: rays spawned from the plane y = 0, whose p_err.y is exactly 0, re-hit it at
    // t ≈ 1e-7 when their dominant axis is not y — see the report on issue 2.)
    let point = plane(PlaneLight::Point { intensity: 3.0 });
    let mut made = collect(&point, 8, 2_000, true, 2);
    made.extend(collect(&point, 9, 2_000, false, 2));
    assert!(made.len() > 1000);
    for m in &made {
        let pdfs = m.path.pdfs(&point);
        assert_eq!(pdfs[0], 0.0);
        assert!(
            pdfs[1..=m.path.k()]
                .iter()
                .all(|p| p.is_finite() && *p > 0.0),
            "{pdfs:?}"
        );
        let sum: f64 = (0..pdfs.len()).map(|s| power_weight(&pdfs, s, 2.0)).sum();
        assert!((sum - 1.0).abs() < 1e-9 && power_weight(&pdfs, 0, 2.0) == 0.0);
    }
    // The real sun (6.87e-5 sr): a finite cone, so s = 0 (a BSDF sample landing in the cone), s = 1
    // and s = k all have finite, positive densities and share the path through MIS.
    let sun_light = PlaneLight::Sun {
        dir: Vec3::new(0.3, 1.0, 0.2),
        omega: 6.87e-5,
        radiance: 1.0e4,
    };
    let sun = plane(sun_light);
    let made: Vec<Made> = collect(&sun, 10, 2_000, true, 2)
        .into_iter()
        .filter(|m| m.s == 1)
        .collect();
    assert!(made.len() > 1000);
    let (mut w0_max, mut w1_min) = (0.0f64, 1.0f64);
    for m in &made {
        let x0 = &m.path.vertices[0];
        assert!(
            x0.is_infinite() && (x0.p.length() - 1.0).abs() < 1e-5,
            "x0 holds the unit direction to the sun"
        );
        let pdfs = m.path.pdfs(&sun);
        assert!(
            pdfs[..=m.path.k()]
                .iter()
                .all(|p| p.is_finite() && *p > 0.0),
            "{pdfs:?}"
        );
        let w: Vec<f64> = (0..pdfs.len())
            .map(|s| power_weight(&pdfs, s, 2.0))
            .collect();
        assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-9 && w[0] > 0.0 && w[1] > 0.0);
        // Escaping towards the same direction is the s = 0 path: same vertex, same density.
        let escaped = PathVertex::light_escaped(sun.infinite_lights[0], x0.p, x0.beta, 0.0);
        let mut v = m.path.vertices.clone();
        v[0] = escaped;
        assert!(rel_close(Path::new(v).pdf(&sun, 0), pdfs[0], 1e-12));
        (w0_max, w1_min) = (w0_max.max(w[0]), w1_min.min(w[1]));
    }
    println!("real sun: max w0 {w0_max:.3e}, min w1 {w1_min:.6}");
}

#[test]
fn walks_match_through_glass_and_glossy_surfaces() {
    // Refraction is the one place where the Dirac's measure depends on the side that samples it:
    // light walks must match `contribution_for(s)`, which differs from `contribution` there by
    // Π η_L² cos θ_L / (η_C² cos θ_C) over the refractions on the light subpath. Through a sphere
    // the entry and exit cosines are equal and the product is 1; through adjacent faces of a
    // glass cube it is not.
    let scene = cornell(BoxConfig {
        glass_and_glossy: true,
        ..BoxConfig::default()
    });
    let mut differs = 0;
    for camera in [true, false] {
        let made = collect(&scene, 11, 20_000, camera, 8);
        let glass = made
            .iter()
            .filter(|m| m.path.vertices.iter().any(|v| is_glass(&scene, v)))
            .count();
        assert!(glass > 300, "{glass} paths through glass");
        let (wp, wf, _) = check_made(&scene, &made);
        for m in made.iter().filter(|m| {
            m.path.vertices[1..m.s.max(1)]
                .iter()
                .any(|v| is_glass(&scene, v))
        }) {
            let (a, b) = (
                m.path.contribution(&scene),
                m.path.contribution_for(&scene, m.s),
            );
            differs += ((a - b).length() > 1e-3 * b.length()) as usize;
        }
        println!("glass + glossy, camera walks {camera}: {} paths ({glass} through glass), worst rel. error p {wp:.2e}, f {wf:.2e}", made.len());
    }
    assert!(
        differs > 10,
        "refraction on the light side changes the stripping: {differs}"
    );
}

#[test]
fn walks_under_a_sun_and_a_point_light_match_p_and_f() {
    // Lights at infinity (x0 in solid angle, x1 from the bounding disk) and at a point (x0 a
    // discrete position, no cosine at x0), for s = 0 (escaping into the sun), 1 and k.
    let sun = PlaneLight::Sun {
        dir: Vec3::new(0.3, 1.0, 0.2),
        omega: 0.05,
        radiance: 40.0,
    };
    for light in [sun, PlaneLight::Point { intensity: 3.0 }] {
        let scene = plane(light);
        for camera in [true, false] {
            let made = collect(&scene, 12, 20_000, camera, 2);
            let by_s = |s: usize| made.iter().filter(|m| m.s == s).count();
            let expected_s0 = camera && matches!(light, PlaneLight::Sun { .. });
            assert!(by_s(if camera { 1 } else { 2 }) > 1_000 && (by_s(0) > 100) == expected_s0);
            let (wp, wf, _) = check_made(&scene, &made);
            println!("{light:?}, camera walks {camera}: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}", made.len());
        }
    }
}

/// Two directional lights (deltas in direction) above the plane, with unequal powers 2:1, so that
/// light selection pmfs are ½·⅔ + ½·½ = 7/12 and 5/12 (half by power, half uniform).
fn directional_pair() -> PlaneLight {
    PlaneLight::Directional {
        dir: Vec3::new(0.3, 1.0, 0.2),
        irradiance: 2.0,
        second: Some((Vec3::new(-0.8, 0.6, -0.3), 1.0)),
    }
}

#[test]
fn techniques_agree_on_a_plane_under_two_directional_lights() {
    // s = 0 cannot hit a single direction (p_0 = 0): only NEE and light tracing.
    techniques_agree(directional_pair(), [0, 50_000, 1_000_000]);
}

#[test]
fn directional_light_paths_match_p_and_f_and_only_nee_and_light_walks_reach_them() {
    // x0 is a delta in direction: next-event estimation (s = 1, density pmf) and light walks
    // (s = 2: pmf · 1, then the bounding disk's density at x1) reach it; a camera walk cannot hit
    // it (p_0 = 0) and the pinhole cannot be joined to it (no k = 1 path, p = 0 if built).
    let scene = plane(directional_pair());
    let pmfs = [0, 1].map(|i| scene.light_sampler.pmf(i));
    assert!((pmfs[0] - 7.0 / 12.0).abs() < 1e-6, "pmfs {pmfs:?}");
    for camera in [true, false] {
        let made = collect(&scene, 13, 20_000, camera, 2);
        let by_s = |s: usize| made.iter().filter(|m| m.s == s).count();
        assert!(
            by_s(0) == 0 && by_s(if camera { 1 } else { 2 }) > 1_000,
            "s=0: {}, s=1: {}, s=2: {}",
            by_s(0),
            by_s(1),
            by_s(2)
        );
        assert!(
            made.iter().all(|m| m.path.k() == 2),
            "a k = 1 path was made"
        );
        let (wp, wf, _) = check_made(&scene, &made);
        for m in &made {
            assert!(m.path.vertices[0].delta, "x0 carries its delta direction");
            let d = m.path.densities(&scene);
            assert_eq!(d.camera[0], 0.0, "no walk hits a direction");
            assert!(!d.valid(0) && d.valid(1) && d.valid(2) && !d.valid(3));
            let pdfs = d.all();
            assert!(
                pdfs[0] == 0.0 && pdfs[1] > 0.0 && pdfs[2] > 0.0 && pdfs[3] == 0.0,
                "{pdfs:?}"
            );
            for beta in [1.0, 2.0] {
                let sum: f64 = (0..4).map(|s| power_weight(&pdfs, s, beta)).sum();
                assert!((sum - 1.0).abs() < 1e-9, "β={beta}: Σw = {sum}");
                for s in 0..4 {
                    let by_ratios = power_weight_by_ratios(&d, s, beta);
                    assert!(rel_close(power_weight(&pdfs, s, beta), by_ratios, 1e-9));
                }
            }
        }
        println!(
            "two directional lights, camera walks {camera}: {} paths, worst rel. error p {wp:.2e}, \
             f {wf:.2e}",
            made.len()
        );
    }
    // x0 joined to the pinhole would be technique 1 of a one-segment path: not a technique.
    let le = scene.lights[0]
        .sample_le(
            lt_core::math::Vec2::splat(0.5),
            lt_core::math::Vec2::splat(0.5),
            scene.bounding_sphere,
        )
        .unwrap();
    let x0 = PathVertex::light_emitted(&scene, 0, &le, pmfs[0]);
    assert!(x0.is_infinite() && x0.delta && x0.is_delta_light());
    let cam = PathVertex::camera(&scene.camera, lt_core::math::Color::ONE);
    assert_eq!(Path::new(vec![x0, cam]).pdfs(&scene), vec![0.0; 3]);
}

/// Paths with medium vertices from walks that sample free flights through a homogeneous fog
/// (camera inside a fog-filled box; a `null`-bounded fog cube in air): p_s, f and f/(N p_s) for
/// s = 0 (reaching the light), 1 (next-event estimation from medium and surface vertices) and k
/// (light tracing from medium and surface vertices) against what the walks used.
#[test]
fn fog_walks_match_p_and_f_through_media_and_null_boundaries() {
    for (name, fs) in [
        ("fog box", media::fog_box()),
        ("null box", media::null_box_in_air()),
    ] {
        for camera in [true, false] {
            let made = media::collect(&fs, 21, if camera { 3_000 } else { 8_000 }, camera, 5);
            let in_medium = |m: &Made| m.path.vertices.iter().filter(|v| v.in_medium()).count();
            let with_medium = made.iter().filter(|m| in_medium(m) > 0).count();
            let twice = made.iter().filter(|m| in_medium(m) > 1).count();
            let mixed = made
                .iter()
                .filter(|m| {
                    in_medium(m) > 0
                        && m.path.vertices.iter().any(|v| {
                            v.on_surface()
                                && !matches!(v.kind, lt_core::path::VertexKind::Light { .. })
                        })
                })
                .count();
            assert!(
                with_medium > 1000 && twice > 100 && mixed > 100,
                "{name}: {} paths, {with_medium} with a medium vertex, {twice} with two, {mixed} mixed",
                made.len()
            );
            let by_s: Vec<usize> = (0..3)
                .map(|s| made.iter().filter(|m| m.s == s).count())
                .collect();
            let (wp, wf, loose) = check_made(&fs.scene, &made);
            println!(
                "{name}, camera walks {camera}: {} paths ({with_medium} with medium vertices, s=0/1/2: {by_s:?}), worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} loose",
                made.len()
            );
        }
    }
}

/// Every technique reaches a fog path (no vertex of these scenes is a delta): p_s > 0 for s = 0
/// … k, p_{k+1} = 0, and the weights of the power and balance heuristics, direct and by `Chain`'s
/// ratios, sum to one.
#[test]
fn fog_paths_have_every_technique_and_weights_sum_to_one() {
    for fs in [media::fog_box(), media::null_box_in_air()] {
        let mut made = media::collect(&fs, 22, 500, true, 5);
        made.extend(media::collect(&fs, 23, 500, false, 5));
        let mut checked = 0;
        for m in made
            .iter()
            .filter(|m| m.path.vertices.iter().any(|v| v.in_medium()))
        {
            let k = m.path.k();
            let d = m.path.densities(&fs.scene);
            let pdfs = d.all();
            assert!(
                pdfs[..=k].iter().all(|p| p.is_finite() && *p > 0.0) && pdfs[k + 1] == 0.0,
                "{pdfs:?}"
            );
            for beta in [1.0, 2.0] {
                let sum: f64 = (0..=k + 1).map(|s| power_weight(&pdfs, s, beta)).sum();
                assert!((sum - 1.0).abs() < 1e-9, "β={beta}: Σw = {sum}");
                for s in 0..=k + 1 {
                    let by_ratios = power_weight_by_ratios(&d, s, beta);
                    assert!(rel_close(power_weight(&pdfs, s, beta), by_ratios, 1e-9));
                }
            }
            checked += 1;
        }
        assert!(checked > 300, "{checked}");
    }
}

/// f/(N p_s) is unbiased through fog: camera walks reaching the light (s = 0), next-event
/// estimation (s = 1) and light tracing (s = k) agree on the film's mean for paths of 2 and 3
/// segments, most of them through medium vertices, in the fog box (nothing occludes there, so
/// f without visibility is what every technique samples). |z| < 4 over the 6 comparisons is a
/// family-wise false alarm rate of 4e-4 (Šidák: 1 − (1 − 6.3e-5)⁶).
#[test]
fn fog_techniques_agree_on_the_film() {
    let fs = media::fog_box();
    let mut report = String::new();
    for k in [2, 3] {
        let est: Vec<(usize, (f64, f64))> = [(0, 60_000), (1, 20_000), (k, 60_000)]
            .into_iter()
            .map(|(s, n)| (s, media::film_estimate(&fs, s, k, n)))
            .collect();
        for &(s, e) in &est {
            report += &format!("k={k} s={s} {:.5}±{:.5}; ", e.0, e.1);
            assert!(
                e.1 < 0.05 * e.0,
                "k={k} s={s}: standard error too large: {report}"
            );
        }
        for a in 0..3 {
            for b in a + 1..3 {
                let zab = z(est[a].1, est[b].1);
                report += &format!("z(s{}−s{}) {zab:+.2}; ", est[a].0, est[b].0);
                assert!(zab.abs() < 4.0, "{report}");
            }
        }
    }
    println!("{report}");
}

/// The scene's media queries on the null-bounded fog cube [-½,½]³ (σt 1.5) in air: T through
/// the null boundaries is exp(−σt · chord) (the chord known from the geometry), an opaque floor
/// blocks a shadow ray but not the oracle's edge, and the free-flight density of stopping inside
/// the cube is σt e^{−σt t}. The bound: σt × the hit points' rounding (coordinates ≤ 2, a few
/// f32 ulps: < 1e-6 per crossing) — 1e-5 relative leaves a factor 5 over it.
#[test]
fn fog_queries_pass_null_boundaries_and_stop_at_opaque_ones() {
    use lt_core::scene::ConnectionEnd;
    let fs = media::null_box_in_air();
    let s = &fs.scene;
    let end = |p: Vec3| ConnectionEnd {
        p,
        p_err: Vec3::ZERO,
        ng: Vec3::ZERO,
        infinite: false,
    };
    let sigma = fs.sigma_t as f64;
    let (a, b) = (Vec3::new(0.1, 0.2, 2.0), Vec3::new(-0.1, 0.1, -2.0));
    let chord = (b - a).length() as f64 * 0.25;
    let t = s
        .transmittance(end(a), end(b), None)
        .expect("only null boundaries between");
    assert!(
        rel_close(t.x as f64, (-sigma * chord).exp(), 1e-5),
        "{t} vs chord {chord}"
    );
    let mut rng = lt_core::sampling::Sampler::new(1, 0, 0);
    let est = s
        .transmittance_estimate(end(b), end(a), None, &mut rng)
        .unwrap();
    assert!(rel_close(est.x as f64, t.x as f64, 1e-5), "{est} vs {t}");
    // Into the cube: the medium after the boundary is its interior.
    let inside = Vec3::new(0.0, 0.1, 0.0);
    let to_inside = (inside - a).length() as f64 * (0.5 / 2.0);
    let p = s.free_flight_density(end(a), end(inside), None, true) as f64;
    let expect = sigma * (-sigma * to_inside).exp();
    assert!(rel_close(p, expect, 1e-5), "{p} vs {expect}");
    let pass = s.free_flight_density(end(inside), end(a), Some(0), false) as f64;
    assert!(rel_close(pass, (-sigma * to_inside).exp(), 1e-5), "{pass}");
    // Through the opaque floor: a shadow ray is blocked, the oracle's edge is not (0.6 of it in
    // the cube: y from 0.1 to −0.5).
    let below = Vec3::new(0.0, -1.5, 0.0);
    assert!(s.transmittance(end(inside), end(below), Some(0)).is_none());
    let edge = s.edge_transmittance(end(inside), end(below), Some(0)).x as f64;
    assert!(rel_close(edge, (-sigma * 0.6).exp(), 1e-5), "{edge}");
    // A scene without media pays nothing: the flag is off, every vertex's interface is 0.
    let plain = cornell(BoxConfig::default());
    assert!(!plain.has_media && plain.interfaces.len() == 1 && s.has_media);
    assert_eq!(std::mem::size_of::<PathVertex>(), 128);
}
