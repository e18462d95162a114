//! The path-space ground truth (`lt_core::path`) against the walks that sample paths, against
//! each other across techniques, and against analytic pixel values.

#[path = "path_space/scenes.rs"]
mod scenes;
#[path = "path_space/walks.rs"]
mod walks;

use lt_core::bsdf::Material;
use lt_core::math::{Vec2, Vec3};
use lt_core::path::mis::{power_weight_by_ratios, relative_pdfs};
use lt_core::path::{balance_weight, power_weight, Path, PathVertex, VertexKind};
use lt_core::sampling::Sampler;
use lt_core::Scene;
use scenes::*;
use walks::{camera_walk, light_walk, Made};

/// Relative tolerances (p, f) for p_s and f recomputed from the stored vertices. The walk used
/// sampled directions; the path rebuilds them from f32 hit points, each known only to within its
/// `p_err` box. So the recomputed values are defined only up to their first-order sensitivity to
/// those boxes: Σ over vertices and axes of |∂p/∂x_a|·err_a, measured by moving each coordinate
/// by its error bound (this covers cosines, 1/d², GGX lobes and Fresnel alike). We allow twice
/// that (the walk's ray started from the offset origin, up to one more error box away), plus
/// 1e-4 for f32 arithmetic (≲ 10 vertices × a few dozen operations of 6e-8 each). Most paths are
/// held to about 1e-4; corner paths with segments of 1e-4 of the box get what they need.
const SENS: f64 = 2.0;

fn tolerance(scene: &Scene, path: &Path, s: usize) -> (f64, f64) {
    let (p, f) = (path.pdf(scene, s), path.contribution_for(scene, s));
    let (mut dp, mut df) = (0.0, 0.0);
    for i in 0..path.vertices.len() {
        for a in 0..3 {
            if path.vertices[i].is_infinite() || path.vertices[i].p_err[a] == 0.0 {
                continue;
            }
            let (mut ddp, mut ddf) = (0.0f64, 0.0f64);
            for sign in [-1.0, 1.0] {
                let mut v = path.vertices.clone();
                v[i].p[a] += sign * v[i].p_err[a];
                let moved = Path::new(v);
                ddp = ddp.max((moved.pdf(scene, s) - p).abs());
                ddf = ddf.max((moved.contribution_for(scene, s) - f).abs().max_element());
            }
            (dp, df) = (dp + ddp, df + ddf);
        }
    }
    let rel = |d: f64, x: f64| if x > 0.0 { d / x } else { 0.0 };
    // Rounding of the cosines themselves: a dot product of unit f32 vectors is good to ~8 ulp
    // absolute, so each cosine of each interior vertex adds 8·6e-8 / |cos| relative.
    let v = &path.vertices;
    let mut arith = 1e-4;
    for i in 1..v.len() - 1 {
        for w in [v[i].dir_to(&v[i - 1]), v[i].dir_to(&v[i + 1])] {
            arith += 5e-7 * (1.0 / v[i].ns.dot(w).abs() as f64 + 1.0 / v[i].ng.dot(w).abs() as f64);
        }
    }
    (arith + SENS * rel(dp, p), arith + SENS * rel(df, f.max_element()))
}

fn collect(scene: &Scene, seed: u64, n: u64, camera: bool, max_k: usize) -> Vec<Made> {
    let mut made = Vec::new();
    for i in 0..n {
        let mut rng = Sampler::new(seed, i, 0);
        let mut push = |m: Made| made.push(m);
        if camera {
            camera_walk(scene, &mut rng, None, max_k, &mut push);
        } else {
            light_walk(scene, &mut rng, max_k, &mut push);
        }
    }
    made
}

/// A delta surface: mirror or glass.
fn is_mirror(scene: &Scene, v: &PathVertex) -> bool {
    matches!(v.kind, VertexKind::Surface { material } if scene.material(material).is_delta())
}

fn is_glass(scene: &Scene, v: &PathVertex) -> bool {
    matches!(v.kind, VertexKind::Surface { material } if matches!(scene.material(material), Material::Dielectric(_)))
}

/// Checks p_s, f and f/(N p_s) of every path a walk made against what the walk accumulated.
/// Returns the worst relative errors of p and f and how many paths needed more than 2e-4.
fn check_made(scene: &Scene, made: &[Made]) -> (f64, f64, usize) {
    let mut loose = 0;
    let n_pix = scene.camera.pixel_count() as f64;
    let (mut worst_p, mut worst_f) = (0.0f64, 0.0f64);
    for m in made {
        let p = m.path.pdf(scene, m.s);
        let f = m.path.contribution_for(scene, m.s);
        let (tol_p, tol) = tolerance(scene, &m.path, m.s);
        loose += (tol_p.max(tol) > 2e-4) as usize;
        // Only a refraction sampled by the light subpath strips its Dirac differently.
        let refracts_on_light_side = m.path.vertices[1..m.s.max(1)].iter().any(|v| is_glass(scene, v));
        if !refracts_on_light_side {
            // Both modes give the same factor up to f32 rounding of differently computed cosines
            // (frame-local z against a dot product: 1e-7 absolute, so 1e-7/cos relative).
            let g = m.path.contribution(scene);
            assert!((0..3).all(|c| rel_close(f[c], g[c], tol)), "modes differ: {f} vs {g}");
        }
        let rel = |a: f64, b: f64| if a == b { 0.0 } else { (a - b).abs() / a.abs().max(b.abs()) };
        worst_p = worst_p.max(rel(p, m.pdf));
        assert!(rel_close(p, m.pdf, tol_p), "k={} s={}: p_s {p} vs walk {}", m.path.k(), m.s, m.pdf);
        for c in 0..3 {
            worst_f = worst_f.max(rel(f[c], m.f[c]));
            assert!(rel_close(f[c], m.f[c], tol), "k={} s={}: f {f} vs walk {}", m.path.k(), m.s, m.f);
            let est = if p > 0.0 { f[c] / (n_pix * p) } else { 0.0 };
            assert!(rel_close(est, m.estimate[c], tol + tol_p), "k={} s={}: f/(N p) {est} vs estimator {}", m.path.k(), m.s, m.estimate);
        }
    }
    (worst_p, worst_f, loose)
}

#[test]
fn camera_walks_hitting_the_light_match_p0_and_f() {
    let scene = cornell(Box::default());
    let made: Vec<Made> = collect(&scene, 1, 40_000, true, 10).into_iter().filter(|m| m.s == 0).collect();
    let through_mirror = made.iter().filter(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v))).count();
    assert!(made.len() > 1000 && through_mirror > 50, "{} paths, {through_mirror} via the mirror", made.len());
    assert!(made.iter().any(|m| m.path.k() >= 5));
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=0: {} paths ({through_mirror} via the mirror), worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} short-segment paths tested above 2e-4", made.len());
}

#[test]
fn nee_completed_camera_walks_match_p1_and_f() {
    let scene = cornell(Box::default());
    let made: Vec<Made> = collect(&scene, 2, 5_000, true, 8).into_iter().filter(|m| m.s == 1).collect();
    assert!(made.len() > 10_000 && made.iter().any(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v))));
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=1: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} short-segment paths tested above 2e-4", made.len());
}

#[test]
fn light_walks_splatted_to_the_camera_match_pk_and_f() {
    let scene = cornell(Box::default());
    let made = collect(&scene, 3, 20_000, false, 8);
    assert!(made.len() > 10_000 && made.iter().all(|m| m.s == m.path.k()));
    assert!(made.iter().any(|m| m.path.vertices.iter().any(|v| is_mirror(&scene, v))));
    let (wp, wf, loose) = check_made(&scene, &made);
    println!("s=k: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}; {loose} short-segment paths tested above 2e-4", made.len());
}

#[test]
fn mis_weights_sum_to_one_and_vanish_at_delta_connections() {
    let scene = cornell(Box::default());
    let mut made = collect(&scene, 4, 3_000, true, 8);
    made.extend(collect(&scene, 5, 3_000, false, 8));
    let mut delta_connections = 0;
    for m in &made {
        let (k, v) = (m.path.k(), &m.path.vertices);
        let d = m.path.densities(&scene);
        let pdfs = d.all();
        assert_eq!(pdfs[k + 1], 0.0, "t = 0 cannot hit a pinhole");
        assert!(pdfs[m.s] > 0.0, "the technique that made the path has p > 0");
        for (beta, sum) in [(1.0, (0..=k + 1).map(|s| balance_weight(&pdfs, s)).sum::<f64>()), (2.0, (0..=k + 1).map(|s| power_weight(&pdfs, s, 2.0)).sum())] {
            assert!((sum - 1.0).abs() < 1e-9, "β={beta}: weights sum to {sum} for {pdfs:?}");
        }
        for s in 0..=k + 1 {
            if (1..=k).contains(&s) && (is_mirror(&scene, &v[s - 1]) || is_mirror(&scene, &v[s])) {
                delta_connections += 1;
                assert_eq!(pdfs[s], 0.0, "s={s} connects at a mirror");
                assert_eq!(power_weight(&pdfs, s, 2.0), 0.0);
            }
            let direct = power_weight(&pdfs, s, 2.0);
            let by_ratios = power_weight_by_ratios(&d, s, 2.0);
            assert!(rel_close(direct, by_ratios, 1e-9), "s={s}: ratio form {by_ratios} vs {direct}; made by {} {d:?} {pdfs:?}", m.s);
        }
        let r = relative_pdfs(&d, m.s);
        for s in 0..=k + 1 {
            assert!(rel_close(r[s], pdfs[s] / pdfs[m.s], 1e-9), "ratio {s}/{}: {} vs {}", m.s, r[s], pdfs[s] / pdfs[m.s]);
        }
    }
    assert!(delta_connections > 100, "{delta_connections}");
}

/// Mean over a block of pixels of one technique's estimate f/(N p_s) on the plane scene, for
/// paths of exactly two segments (camera → plane → light). Returns (mean, standard error).
/// Nothing can occlude a plane-to-light segment there; the camera-to-plane connection of light
/// tracing is tested (from the eye, so no surface offset is involved).
fn block_estimate(scene: &Scene, s: usize, n: u64, block: (Vec2, Vec2)) -> (f64, f64) {
    let cam = &scene.camera;
    let in_block = |r: Vec2| r.cmpge(block.0).all() && r.cmplt(block.1).all();
    let block_px = ((block.1 - block.0).x * (block.1 - block.0).y) as f64;
    let mut stats = Stats::default();
    for i in 0..n {
        let mut rng = Sampler::new(77 + s as u64, i, 0);
        let mut x = 0.0;
        let mut visit = |m: Made| {
            if m.path.k() != 2 || m.s != s {
                return;
            }
            let x1 = m.path.vertices[1].p;
            if s == 2 && !(in_block(cam.project(x1).unwrap().raster) && scene.visible_between(cam.eye, x1)) {
                return;
            }
            // Light tracing covers the whole film: N·spp light paths for spp samples per pixel,
            // so one light path stands for N/|B| camera samples of the block.
            let e = m.path.estimate(scene, s).x as f64;
            x += if s == 2 { e * cam.pixel_count() as f64 / block_px } else { e };
        };
        if s == 2 {
            light_walk(scene, &mut rng, 2, &mut visit);
        } else {
            let r = block.0 + rng.next_2d() * (block.1 - block.0);
            camera_walk(scene, &mut rng, Some(r), 2, &mut visit);
        }
        stats.add(x);
    }
    (stats.mean(), stats.se())
}

/// The exact block mean: ρ/π · E(x) averaged over the block's raster area by a 16×16 midpoint
/// rule per pixel (smooth integrand: error far below the standard errors).
fn block_exact(scene: &Scene, light: PlaneLight, block: (Vec2, Vec2)) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    let q = 16;
    let size = (block.1 - block.0) * q as f32;
    for j in 0..size.y as usize {
        for i in 0..size.x as usize {
            let r = block.0 + (Vec2::new(i as f32, j as f32) + 0.5) / q as f32;
            let hit = scene.intersect(&scene.camera.generate_ray(r)).expect("the block sees the plane");
            assert!(hit.ng.y > 0.99);
            sum += PLANE_ALBEDO as f64 / std::f64::consts::PI * plane_irradiance(light, hit.p);
            n += 1;
        }
    }
    sum / n as f64
}

/// s = 0, 1, 2 estimate the same pixels, pairwise and against the exact value.
fn techniques_agree(light: PlaneLight, n: [u64; 3]) {
    let scene = plane(light);
    let block = (Vec2::new(12.0, 8.0), Vec2::new(20.0, 16.0));
    let exact = block_exact(&scene, light, block);
    let est: Vec<(usize, (f64, f64))> = (0..3).filter(|&s| n[s] > 0).map(|s| (s, block_estimate(&scene, s, n[s], block))).collect();
    let mut report = format!("{light:?}: exact {exact:.6}");
    for &(s, e) in &est {
        let za = z(e, (exact, 0.0));
        report += &format!(", s={s} {:.6}±{:.6} (z {za:+.2})", e.0, e.1);
        assert!(e.1 < 0.05 * exact, "s={s}: standard error too large to test anything");
        assert!(za.abs() < 4.0, "{report}");
    }
    for a in 0..est.len() {
        for b in a + 1..est.len() {
            let zab = z(est[a].1, est[b].1);
            report += &format!(", z(s{}−s{}) {zab:+.2}", est[a].0, est[b].0);
            assert!(zab.abs() < 4.0, "{report}");
        }
    }
    println!("{report}");
}

#[test]
fn techniques_agree_on_a_plane_under_a_quad_light() {
    techniques_agree(PlaneLight::Quad { half: 0.15, le: 20.0 }, [400_000, 100_000, 1_500_000]);
}

#[test]
fn techniques_agree_on_a_plane_under_a_point_light() {
    // s = 0 cannot hit a point light (p_0 = 0): only NEE and light tracing.
    techniques_agree(PlaneLight::Point { intensity: 3.0 }, [0, 50_000, 1_000_000]);
}

#[test]
fn techniques_agree_on_a_plane_under_a_large_sun() {
    let sun = PlaneLight::Sun { dir: Vec3::new(0.3, 1.0, 0.2), omega: 0.05, radiance: 40.0 };
    techniques_agree(sun, [1_000_000, 50_000, 1_000_000]);
}


#[test]
fn walks_match_with_shading_normals_in_both_transport_modes() {
    // Light walks accumulate importance-mode BSDF factors, camera walks radiance-mode ones, while
    // `contribution` uses radiance mode throughout: with tilted shading normals this only agrees
    // if both modes give the same measurement factor f·|ns·ω_L|/|ng·ω_L| (bsdf/mod.rs).
    let scene = cornell(Box { bumpy_floor: true, ..Box::default() });
    let on_floor = |m: &Made| m.path.vertices.iter().any(|v| v.ng.y > 0.99 && (v.ns - v.ng).length() > 0.05);
    for camera in [false, true] {
        let made = collect(&scene, 6, 10_000, camera, 6);
        assert!(made.iter().filter(|m| on_floor(m)).count() > 1000);
        let (wp, wf, _) = check_made(&scene, &made);
        println!("bumpy floor, camera walks {camera}: {} paths, worst rel. error p {wp:.2e}, f {wf:.2e}", made.len());
    }
}

#[test]
fn point_light_paths_have_no_s0_and_sun_paths_take_part_in_mis() {
    // Point light: p_0 = 0 exactly (no walk hits a point), the other techniques are finite.
    let point = plane(PlaneLight::Point { intensity: 3.0 });
    let mut made = collect(&point, 8, 2_000, true, 4);
    made.extend(collect(&point, 9, 2_000, false, 4));
    assert!(made.len() > 1000);
    for m in &made {
        let pdfs = m.path.pdfs(&point);
        assert_eq!(pdfs[0], 0.0);
        assert!(pdfs[1..=m.path.k()].iter().all(|p| p.is_finite() && *p > 0.0), "{pdfs:?}");
        let sum: f64 = (0..pdfs.len()).map(|s| power_weight(&pdfs, s, 2.0)).sum();
        assert!((sum - 1.0).abs() < 1e-9 && power_weight(&pdfs, 0, 2.0) == 0.0);
    }
    // The real sun (6.87e-5 sr): a finite cone, so s = 0 (a BSDF sample landing in the cone), s = 1
    // and s = k all have finite, positive densities and share the path through MIS.
    let sun_light = PlaneLight::Sun { dir: Vec3::new(0.3, 1.0, 0.2), omega: 6.87e-5, radiance: 1.0e4 };
    let sun = plane(sun_light);
    let made: Vec<Made> = collect(&sun, 10, 2_000, true, 4).into_iter().filter(|m| m.s == 1).collect();
    assert!(made.len() > 1000);
    let (mut w0_max, mut w1_min) = (0.0f64, 1.0f64);
    for m in &made {
        let x0 = &m.path.vertices[0];
        assert!(x0.is_infinite() && (x0.p.length() - 1.0).abs() < 1e-5, "x0 holds the unit direction to the sun");
        let pdfs = m.path.pdfs(&sun);
        assert!(pdfs[..=m.path.k()].iter().all(|p| p.is_finite() && *p > 0.0), "{pdfs:?}");
        let w: Vec<f64> = (0..pdfs.len()).map(|s| power_weight(&pdfs, s, 2.0)).collect();
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
    let scene = cornell(Box { glass_and_glossy: true, ..Box::default() });
    let mut differs = 0;
    for camera in [true, false] {
        let made = collect(&scene, 11, 20_000, camera, 8);
        let glass = made.iter().filter(|m| m.path.vertices.iter().any(|v| is_glass(&scene, v))).count();
        assert!(glass > 300, "{glass} paths through glass");
        let (wp, wf, _) = check_made(&scene, &made);
        for m in made.iter().filter(|m| m.path.vertices[1..m.s.max(1)].iter().any(|v| is_glass(&scene, v))) {
            let (a, b) = (m.path.contribution(&scene), m.path.contribution_for(&scene, m.s));
            differs += ((a - b).length() > 1e-3 * b.length()) as usize;
        }
        println!("glass + glossy, camera walks {camera}: {} paths ({glass} through glass), worst rel. error p {wp:.2e}, f {wf:.2e}", made.len());
    }
    assert!(differs > 30, "refraction on the light side changes the stripping: {differs}");
}

#[test]
fn zz_debug() {
    let scene = plane(PlaneLight::Point { intensity: 3.0 });
    let mut rng = Sampler::new(1, 2, 3);
    let (mut n, mut bad) = (0, 0);
    for _ in 0..1_000_000 {
        let r = rng.next_2d() * Vec2::new(32.0, 24.0);
        let Some(hit) = scene.intersect(&scene.camera.generate_ray(r)) else { continue };
        let u = rng.next_2d();
        let phi = 6.2831853 * u.x;
        let z = 0.3 * u.y; // upwards
        let d = Vec3::new(phi.cos(), 0.0, phi.sin()) * (1.0 - z * z).sqrt() + Vec3::Y * z;
        n += 1;
        let ray = hit.spawn_ray(d);
        if let Some(h2) = scene.intersect(&ray) {
            bad += 1;
            if bad < 4 { println!("self-hit: p {} o {} d {} t {} ", hit.p, ray.o, d, h2.t); }
        }
    }
    println!("{bad} of {n} grazing rays re-hit the plane");
}
