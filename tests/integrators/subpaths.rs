//! The subpath tracer's stored densities against the from-scratch oracle: for paths the walks
//! complete (a camera walk hitting an emitter, a light walk seen by the camera), every `pdf_fwd`
//! and `pdf_rev` the walk filled equals the oracle's per-vertex density of that path
//! (`Path::densities`: `light[i]`, `camera[i]`).

use lt_core::math::Vec2;
use lt_core::path::{Path, VertexKind};
use lt_core::sampling::{Domain, Sampler};
use lt_core::Scene;
use lt_integrators::subpath::connect::connect_to_camera;
use lt_integrators::subpath::walk::{camera_subpath, light_subpath, Subpath, WalkLimits};
use lt_scene_io::load_scene;
use std::path::PathBuf;

fn scene(name: &str) -> Scene {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(format!("../scenes/{name}.toml"));
    let mut s = load_scene(&p).unwrap();
    s.camera = s.camera.with_resolution(32, 32);
    s
}

/// Relative difference, zero for equal values (both zero included).
fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

/// (checked densities, worst relative error, how many exceed `loose`) over `n` walks of each kind.
fn check(scene: &Scene, n: u64, loose: f64) -> (usize, f64, usize) {
    let limits = WalkLimits {
        max_vertices: 9,
        rr_depth: 5,
    };
    let (mut count, mut worst, mut over) = (0usize, 0.0f64, 0usize);
    let mut note = |a: f32, b: f64| {
        let e = rel(a as f64, b);
        count += 1;
        worst = worst.max(e);
        over += (e > loose) as usize;
    };
    let mut sub = Subpath::default();
    for i in 0..n {
        // Camera walks that hit an emitter: x0 = z_{t−1}, x_i = z_{k−i}.
        let mut s = Sampler::for_item(Domain::Camera, 3, i, 0);
        let r = Vec2::new(s.next_f32(), s.next_f32()) * 32.0;
        camera_subpath(scene, r, &mut s, limits, &mut sub);
        let z = &sub.vertices;
        for t in 2..=z.len() {
            let Some(x0) = z[t - 1].as_light_endpoint() else {
                continue;
            };
            let path = Path::from_subpaths(&[x0], &z[..t - 1]);
            let k = t - 1;
            let d = path.densities(scene);
            for (j, v) in z.iter().enumerate().take(t).skip(1) {
                note(v.pdf_fwd, d.camera[k - j]);
                if j + 2 < t {
                    note(v.pdf_rev, d.light[k - j]);
                }
            }
        }
        // Light walks seen by the camera: x_i = y_i for i < s, then the pinhole.
        let mut s = Sampler::for_item(Domain::Light, 3, i, 0);
        light_subpath(scene, &mut s, limits, &mut sub);
        let y = &sub.vertices;
        for len in 1..=y.len() {
            if matches!(y[len - 1].kind, VertexKind::Surface { material } if scene.material(material).is_delta())
            {
                continue;
            }
            let Some(c) = connect_to_camera(scene, &y[len - 1], &mut s) else {
                continue;
            };
            let path = Path::from_subpaths(&y[..len], &[c.camera]);
            let d = path.densities(scene);
            for (i, v) in y.iter().enumerate().take(len) {
                note(v.pdf_fwd, d.light[i]);
                if i + 3 <= len {
                    note(v.pdf_rev, d.camera[i]);
                }
            }
        }
    }
    (count, worst, over)
}

#[test]
fn walk_densities_match_the_oracle_on_shipped_scenes() {
    // The walk converts the density of the direction it sampled; the oracle rebuilds that
    // direction from the two f32 positions, good to about |p_err| / distance, and near-grazing
    // cosines, sharp GGX lobes and refraction near the critical angle magnify it. So all but
    // one in a thousand agree to 1e-3 (most to f32 rounding), and ill-conditioned ones (short
    // segments, grazing hits, glass) may reach 1e-2. A wrong conversion or a density
    // filled on the wrong vertex is off by O(1) on most vertices.
    for name in [
        "cornell-box",
        "cornell-point-caustic",
        "cornell-glass-light",
        "sun-room",
        "cornell-env",
        "veach-mis",
        "cornell-directional",
        "cornell-plastic",
    ] {
        let sc = scene(name);
        let (count, worst, over) = check(&sc, 4000, 1e-3);
        println!("{name}: {count} densities, worst rel. error {worst:.2e}, {over} above 1e-3");
        assert!(count > 1000, "{name}: only {count} densities checked");
        assert!(worst < 1e-2, "{name}: worst {worst:.3e}");
        assert!(
            (over as f64) < 1e-3 * count as f64,
            "{name}: {over} of {count} above 1e-3"
        );
    }
}
