//! Holding recomputed p_s and f to what the walks accumulated, with tolerances from the
//! vertices' own error bounds.

use super::scenes::rel_close;
use super::walks::{camera_walk, light_walk, Made};
use lt_core::bsdf::Material;
use lt_core::path::{Path, PathVertex, VertexKind};
use lt_core::sampling::Sampler;
use lt_core::Scene;

/// How many times its first-order sensitivity a recomputed value may differ from the walk's.
/// Observed: at most 0.8 over 330 000 paths of every test scene (glass and GGX included).
pub const SENS: f64 = 2.0;

/// Relative tolerances (for p, for f) when p_s and f are recomputed from a walk's vertices.
/// The walk used sampled directions; the path rebuilds them from f32 hit points, each known only
/// to within its `p_err` box (and the walk's rays left from offset origins, about one more box
/// away). The recomputed values are therefore defined only up to their first-order sensitivity
/// to those boxes, Σ over vertices and axes of |∂p/∂x_a|·err_a, which we measure by moving each
/// coordinate by ± its bound; it covers cosines, 1/d², GGX lobes and Fresnel alike. On top come
/// 1e-4 for f32 arithmetic (≲ 10 vertices × a few dozen operations of 6e-8 each) and the rounding
/// of each cosine itself (a dot product of unit f32 vectors is good to ~8 ulp absolute, i.e.
/// 5e-7/|cos| relative). Typical paths are held to 1e-4 … 2e-4; corner paths with segments of
/// 1e-4 of the box, grazing cosines and long specular chains get the slack they need.
pub fn tolerance(scene: &Scene, path: &Path, s: usize) -> (f64, f64) {
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
    let v = &path.vertices;
    let mut arith = 1e-4;
    // A medium vertex has no surface: no cosine to round.
    for i in (1..v.len() - 1).filter(|&i| v[i].on_surface()) {
        for w in [v[i].dir_to(&v[i - 1]), v[i].dir_to(&v[i + 1])] {
            arith += 5e-7 * (1.0 / v[i].ns.dot(w).abs() as f64 + 1.0 / v[i].ng.dot(w).abs() as f64);
        }
    }
    (
        arith + SENS * rel(dp, p),
        arith + SENS * rel(df, f.max_element()),
    )
}

pub fn collect(scene: &Scene, seed: u64, n: u64, camera: bool, max_k: usize) -> Vec<Made> {
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
pub fn is_mirror(scene: &Scene, v: &PathVertex) -> bool {
    matches!(v.kind, VertexKind::Surface { material } if scene.material(material).is_delta())
}

pub fn is_glass(scene: &Scene, v: &PathVertex) -> bool {
    matches!(v.kind, VertexKind::Surface { material } if matches!(scene.material(material), Material::Dielectric(_)))
}

/// Checks p_s, f and f/(N p_s) of every path a walk made against what the walk accumulated.
/// Returns the worst relative errors of p and f and how many paths had a tolerance above 2e-4.
pub fn check_made(scene: &Scene, made: &[Made]) -> (f64, f64, usize) {
    let mut loose = 0;
    let n_pix = scene.camera.pixel_count() as f64;
    let (mut worst_p, mut worst_f) = (0.0f64, 0.0f64);
    for m in made {
        let p = m.path.pdf(scene, m.s);
        let f = m.path.contribution_for(scene, m.s);
        let (tol_p, tol) = tolerance(scene, &m.path, m.s);
        loose += (tol_p.max(tol) > 2e-4) as usize;
        // Only a refraction sampled by the light subpath strips its Dirac differently.
        let refracts_on_light_side = m.path.vertices[1..m.s.max(1)]
            .iter()
            .any(|v| is_glass(scene, v));
        if !refracts_on_light_side {
            // Elsewhere both modes give the same factor (mirrors, diffuse, GGX, shading normals).
            let g = m.path.contribution(scene);
            assert!(
                (0..3).all(|c| rel_close(f[c], g[c], tol)),
                "modes differ: {f} vs {g}"
            );
        }
        let rel = |a: f64, b: f64| {
            if a == b {
                0.0
            } else {
                (a - b).abs() / a.abs().max(b.abs())
            }
        };
        worst_p = worst_p.max(rel(p, m.pdf));
        assert!(
            rel_close(p, m.pdf, tol_p),
            "k={} s={}: p_s {p} vs walk {}",
            m.path.k(),
            m.s,
            m.pdf
        );
        for c in 0..3 {
            worst_f = worst_f.max(rel(f[c], m.f[c]));
            assert!(
                rel_close(f[c], m.f[c], tol),
                "k={} s={}: f {f} vs walk {}",
                m.path.k(),
                m.s,
                m.f
            );
            let est = if p > 0.0 { f[c] / (n_pix * p) } else { 0.0 };
            assert!(
                rel_close(est, m.estimate[c], tol + tol_p),
                "k={} s={}: f/(N p) {est} vs estimator {}",
                m.path.k(),
                m.s,
                m.estimate
            );
        }
    }
    (worst_p, worst_f, loose)
}
