//! The MIS weight of one bidirectional strategy (s, t) from the two subpaths' stored densities:
//! `with_chain` builds the `lt_core::path::Chain` of the joined path (the ≤ 4 densities the join
//! changes patched) and `mis_weight` weighs it with bdpt's sample counts. Its own module because
//! two integrators read it — `bdpt` and `lvc_bdpt`, whose connection counts differ — and
//! integrator files import no other integrator file.

use crate::subpath::camera_loop::Connection;
use crate::subpath::connect::{emission_densities, nee_density, JoinFlights};
use crate::subpath::walk::reverse_density;
use lt_core::bsdf::BsdfEval;
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::{Chain, Heuristic, PathVertex, VertexKind};
use lt_core::Scene;

/// The two subpath prefixes one strategy joins, as the MIS weight needs them.
#[derive(Clone, Copy)]
pub struct Split<'a> {
    /// x0 … x_{s−1}. For s = 1 the light sample next-event estimation drew (pdf_fwd = its NEE
    /// density); empty for s = 0.
    pub light: &'a [PathVertex],
    /// x_k … x_s, camera first. For s = 0 the last entry is the light endpoint x0 (an emitter
    /// the walk hit, or a light at infinity it escaped to), with the walk's pdf_fwd.
    pub camera: &'a [PathVertex],
    /// For s ≥ 2: the density of x0 under next-event estimation from x1 (`nee_density`).
    pub light_nee: f64,
}

/// The BSDFs at the two ends of a connection towards each other, as the contribution used them:
/// `light_end` at x_{s−1} (importance mode, s ≥ 2), `camera_end` at x_s (radiance mode, t ≥ 2).
#[derive(Clone, Copy, Default)]
pub struct EndEvals {
    pub light_end: Option<BsdfEval>,
    pub camera_end: Option<BsdfEval>,
    /// Through media: the free flights the join and the walks found (`JoinFlights`); `None`
    /// walks each patched segment again (`Scene::free_flight_density`), as a checker holding
    /// only the path must.
    pub flights: Option<JoinFlights>,
}

impl<'a> Split<'a> {
    /// s = 0: `path` = a camera walk and the light endpoint it reached.
    pub fn reached(path: &'a [PathVertex]) -> (Split<'a>, EndEvals) {
        let split = Split {
            light: &[],
            camera: path,
            light_nee: 0.0,
        };
        (split, EndEvals::default())
    }

    /// s = 1: next-event estimation's `x0` joined to z_{t−1} (`z` = z_0 … z_{t−1}), whose BSDF
    /// towards it is `camera_end`.
    pub fn next_event(
        z: &'a [PathVertex],
        x0: &'a PathVertex,
        camera_end: BsdfEval,
    ) -> (Split<'a>, EndEvals) {
        let split = Split {
            light: std::slice::from_ref(x0),
            camera: z,
            light_nee: 0.0,
        };
        let evals = EndEvals {
            light_end: None,
            camera_end: Some(camera_end),
            flights: None,
        };
        (split, evals)
    }

    /// s, t ≥ 2: the connection `c`, whose light subpath's x0 next-event estimation from x1
    /// would choose with density `light_nee`.
    pub fn connection(c: Connection<'a>, light_nee: f64) -> (Split<'a>, EndEvals) {
        let split = Split {
            light: c.light,
            camera: c.camera,
            light_nee,
        };
        let evals = EndEvals {
            light_end: Some(c.joined.light_end),
            camera_end: Some(c.joined.camera_end),
            flights: Some(c.flights),
        };
        (split, evals)
    }
}

/// Longest path weighed without allocating (segments); longer ones use the heap.
const STACK_K: usize = 23;

/// The MIS weight of strategy (s, t) for the path `split` forms (Veach 1997, eq. 10.9 with the
/// ratios of §10.2), under `h`, with `ratio` = M/N light subpaths per camera sample.
pub fn mis_weight(scene: &Scene, split: Split, evals: EndEvals, h: Heuristic, ratio: f64) -> f64 {
    mis_weight_in::<false>(scene, split, evals, h, ratio)
}

/// `mis_weight` of a path through media when `MEDIA` (see `with_chain_in`).
pub fn mis_weight_in<const MEDIA: bool>(
    scene: &Scene,
    split: Split,
    evals: EndEvals,
    h: Heuristic,
    ratio: f64,
) -> f64 {
    with_chain_in::<MEDIA, _>(scene, split, evals, ratio, |chain, s| chain.weight(s, h))
}

/// Builds the `Chain` of the path `split` forms (stored densities, the ≤ 4 entries the join
/// changes patched) and hands it, with the technique s, to `f` — `mis_weight`, or an integrator
/// whose sample counts differ from bdpt's (`lvc_bdpt`).
pub fn with_chain<T>(
    scene: &Scene,
    split: Split,
    evals: EndEvals,
    ratio: f64,
    f: impl FnOnce(&Chain, usize) -> T,
) -> T {
    with_chain_in::<false, T>(scene, split, evals, ratio, f)
}

/// `with_chain`, for a path that may pass through media when `MEDIA`: every density the join
/// patches is a walk's that was never walked (the connecting edge in either direction, and the
/// two end vertices' arriving edges walked backwards), so each takes its free-flight density
/// beside the converted direction density, as the walks' stored ones do: from `evals.flights`
/// (what the join's walk of the edge and the subpaths' walks found), or walked anew (`free_flight`)
/// when absent. No transmittance estimate enters: the weights read densities only.
pub fn with_chain_in<const MEDIA: bool, T>(
    scene: &Scene,
    split: Split,
    evals: EndEvals,
    ratio: f64,
    f: impl FnOnce(&Chain, usize) -> T,
) -> T {
    let (y, z) = (split.light, split.camera);
    let s = if z
        .last()
        .is_some_and(|v| matches!(v.kind, VertexKind::Light { .. }))
    {
        0
    } else {
        y.len()
    };
    let t = z.len();
    let k = s + t - 1;
    debug_assert!(k >= 1);
    let (mut light_a, mut camera_a, mut conn_a) = (
        [0.0f64; STACK_K + 1],
        [0.0f64; STACK_K + 1],
        [false; STACK_K + 1],
    );
    let (mut light_v, mut camera_v, mut conn_v) = (Vec::new(), Vec::new(), Vec::new());
    let (light, camera, conn): (&mut [f64], &mut [f64], &mut [bool]) = if k <= STACK_K {
        (&mut light_a, &mut camera_a, &mut conn_a)
    } else {
        light_v.resize(k + 1, 0.0);
        camera_v.resize(k + 1, 0.0);
        conn_v.resize(k + 1, false);
        (&mut light_v, &mut camera_v, &mut conn_v)
    };
    // x_i: light vertices below s, camera vertices from s up (for s = 0, z's last is x0).
    let at = |i: usize| -> &PathVertex {
        if i < s {
            &y[i]
        } else {
            &z[k - i]
        }
    };
    for i in 0..=k {
        let v = at(i);
        // The connection's two ends (x_{s−1}, x_s; x0 alone for s = 0) scatter by evaluation;
        // inner vertices as their walk sampled (`connectable_inside`).
        let end = i == s || i + 1 == s;
        conn[i] = if end {
            connectable(scene, v)
        } else {
            connectable_inside(scene, v)
        };
        if i < s {
            light[i] = v.pdf_fwd as f64;
            camera[i] = v.pdf_rev as f64;
        } else {
            camera[i] = v.pdf_fwd as f64;
            light[i] = v.pdf_rev as f64;
        }
    }
    // The pinhole: chosen with the discrete 1, never hit by a walk.
    camera[k] = 1.0;
    light[k] = 0.0;
    let mut nee = split.light_nee;
    // The stored free flight `pick(f)`, or the segment `from` → `to` walked anew.
    let flight = |pick: fn(&JoinFlights) -> f32, from: &PathVertex, to: &PathVertex| -> f64 {
        match &evals.flights {
            Some(f) => pick(f) as f64,
            None => free_flight(scene, from, to),
        }
    };
    match (s, t) {
        (0, _) => {
            // The camera walk made x0; the light walk's densities of x0 and x1 are emission's.
            let x0 = &z[t - 1];
            let x1 = (k >= 2).then(|| &z[t - 2]);
            let (l0, l1) = emission_densities(scene, x0, x1);
            light[0] = l0;
            if k >= 2 {
                let x1 = x1.unwrap();
                light[1] = l1;
                if MEDIA {
                    light[1] *= flight(|f| f.camera_back, x0, x1);
                }
                nee = nee_density(scene, x0, x1);
            }
        }
        (_, 1) => {
            // x_{k−1} = y_{s−1} joined to the lens point z[0].
            let yv = &y[s - 1];
            let cam = &z[0];
            let dir = cam.dir_to(yv);
            camera[k - 1] = reverse_density(yv, cam, scene.camera.pdf_dir(cam.p, dir)) as f64;
            if MEDIA {
                camera[k - 1] *= flight(|f| f.edge.from_camera, cam, yv);
            }
            if s >= 2 {
                let ev = evals.light_end.expect("a surface connected to the camera");
                camera[k - 2] = reverse_density(&y[s - 2], yv, ev.pdf_rev_w) as f64;
                if MEDIA {
                    camera[k - 2] *= flight(|f| f.light_back, yv, &y[s - 2]);
                }
            }
        }
        _ => {
            let (yv, zv) = (&y[s - 1], &z[t - 1]);
            let ev_z = evals.camera_end.expect("the camera end is a surface");
            camera[s - 1] = reverse_density(yv, zv, ev_z.pdf_w) as f64;
            if MEDIA {
                camera[s - 1] *= flight(|f| f.edge.from_camera, zv, yv);
            }
            if s + 1 < k {
                light[s + 1] = reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64;
                if MEDIA {
                    light[s + 1] *= flight(|f| f.camera_back, zv, &z[t - 2]);
                }
            }
            if s == 1 {
                // x0 came from next-event estimation: its light-walk densities are emission's.
                let (l0, l1) = emission_densities(scene, yv, Some(zv));
                light[0] = l0;
                light[1] = l1;
                if MEDIA {
                    light[1] *= flight(|f| f.edge.from_light, yv, zv);
                }
                nee = yv.pdf_fwd as f64;
            } else {
                let ev_y = evals.light_end.expect("the light end is a surface");
                light[s] = yv.convert_density(ev_y.pdf_w, zv) as f64;
                camera[s - 2] = reverse_density(&y[s - 2], yv, ev_y.pdf_rev_w) as f64;
                if MEDIA {
                    light[s] *= flight(|f| f.edge.from_light, yv, zv);
                    camera[s - 2] *= flight(|f| f.light_back, yv, &y[s - 2]);
                }
            }
        }
    }
    let chain = Chain {
        light: &light[..=k],
        camera: &camera[..=k],
        nee,
        connectable: &conn[..=k],
        light_tracing_ratio: ratio,
    };
    f(&chain, s)
}

/// The free-flight density of a walk from `from` reaching `to` (`Scene::free_flight_density`:
/// per unit length when `to` lies in a medium, the probability of passing every medium when it
/// is a surface or a light), starting in the medium `from` leaves into towards `to`: the factor
/// of a walk's density that the direction's conversion (`PathVertex::convert_density`) leaves
/// out. The oracle computes it the same way (`Path::densities`).
fn free_flight(scene: &Scene, from: &PathVertex, to: &PathVertex) -> f64 {
    from.free_flight_to(scene, to) as f64
}
