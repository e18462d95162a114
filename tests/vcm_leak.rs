//! Merging must not carry light through a wall. On the SmallVCM sun twin the sun lights the
//! outside of the ceiling and of the right wall; light vertices stored there lie within the merge
//! radius of inner surfaces meeting those walls at an edge (the light box's front face, the top
//! of the back wall). With direct light only (max_depth 2) every pixel that `pt` (exact next-event
//! estimation of a directional light) leaves black, and whose neighbourhood is black too (so no
//! legitimate blur of a lit region reaches it), must stay exactly black for `vcm` and `bpm`.
//! Without the normal test in `connect_merge`'s merge, 388 of those 11769 pixels light up (vcm).

use lt_integrators::{make_integrator, render, Estimator, IntegratorParams, RenderOptions};
use lt_tests::shipped_scene;
use std::ops::ControlFlow;

fn image(name: &str, params: &IntegratorParams, passes: u32) -> lt_estimators::Image {
    let scene = shipped_scene("smallvcm-spheres-sun", Some((128, 128)));
    let est: Estimator = make_integrator(name, &scene, params).unwrap();
    let opts = RenderOptions {
        passes,
        time_limit: None,
        seed: 3,
        threads: 0,
    };
    render(&scene, &est, &opts, |_| ControlFlow::Continue(()))
        .unwrap()
        .estimate
}

#[test]
fn merging_does_not_leak_sunlight_through_walls() {
    let direct = IntegratorParams::new().with("max_depth", 2);
    let pt = image("pt", &direct, 8);
    let (w, h) = (pt.width as i64, pt.height as i64);
    let black = |x: i64, y: i64| pt.data[(y * w + x) as usize].iter().all(|&c| c == 0.0);
    let reach = 3;
    let mask: Vec<usize> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            (-reach..=reach).all(|dy| {
                (-reach..=reach).all(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    u < 0 || v < 0 || u >= w || v >= h || black(u, v)
                })
            })
        })
        .map(|(x, y)| (y * w + x) as usize)
        .collect();
    assert!(
        mask.len() > 500,
        "too few dark pixels to test: {}",
        mask.len()
    );
    for name in ["vcm", "bpm"] {
        let img = image(name, &direct, 4);
        let lit: Vec<usize> = mask
            .iter()
            .copied()
            .filter(|&i| img.data[i].iter().any(|&c| c != 0.0))
            .collect();
        eprintln!("{name}: {} of {} dark pixels lit", lit.len(), mask.len());
        assert!(
            lit.is_empty(),
            "{name} lights {} of {} pixels that no light reaches, e.g. pixel {} = {:?}",
            lit.len(),
            mask.len(),
            lit[0],
            img.data[lit[0]]
        );
    }
}
