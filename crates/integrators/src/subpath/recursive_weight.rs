//! The MIS weight of one bidirectional strategy (s, t) in O(1): the per-vertex recursion of
//! `lt_core::path::SubpathMis` (Georgiev et al. 2012's dVC over this project's stored densities),
//! fed exactly the ≤ 4 densities a join patches that `strategy_weight::with_chain_in` writes
//! into its chain, each from the same f32 evaluation. The two differ only in the order of their
//! f64 operations; the chain, O(k) per strategy, is the oracle this is held to
//! (tests/bdpt_weights.rs). Each subpath's records are formed once per walk (`light_records`,
//! `camera_records`): O(k) per subpath instead of per strategy.
//!
//! Through media the stored densities already carry their free flights (volume measure at a
//! medium vertex), and each patched density takes its free flight from `JoinFlights`, as the
//! chain's do; no transmittance estimate enters.
//!
//! Notation (Veach 1997, §10.2): a path x0 … xk, l_i / c_i the light / camera walk's density of
//! x_i; for (s, t) the light end is y_{s−1} = x_{s−1}, the camera end z_{t−1} = x_s.

use crate::subpath::camera_loop::Connection;
use crate::subpath::connect::{emission_densities, nee_density, CameraConnection, JoinFlights};
use crate::subpath::walk::reverse_density;
use lt_core::bsdf::BsdfEval;
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::subpath_mis::{ConnectionDensities, NextEventDensities, VertexTechniques};
use lt_core::path::{CameraMis, LightMis, PathVertex, SubpathMis};
use lt_core::Scene;

/// A patched density times its free flight `f` through media (as `with_chain_in` multiplies).
#[inline]
fn with_flight<const MEDIA: bool>(density: f64, f: f32) -> f64 {
    if MEDIA {
        density * f as f64
    } else {
        density
    }
}

/// The records of light subpath y_0 … (`SubpathMis::light_vertex`) into `out`; `nee` is next-event
/// estimation's density of y_0 from y_1 (`nee_density`; read only when y_1 exists).
pub fn light_records(
    scene: &Scene,
    mis: &SubpathMis,
    y: &[PathVertex],
    nee: f64,
    out: &mut Vec<LightMis>,
) {
    out.clear();
    let Some(y0) = y.first() else {
        return;
    };
    let l0 = y0.pdf_fwd as f64;
    out.push(mis.light_origin(l0));
    let nee_over_l0 = nee / l0;
    for j in 1..y.len() {
        let c_pp = if j >= 2 { y[j - 2].pdf_rev as f64 } else { 0.0 };
        let vertex = VertexTechniques {
            // VC(1) is next-event estimation: the light samples x0 itself (`Chain::valid`);
            // VC(j) joins y_j, the connection's end, to y_{j−1}, inside the path.
            vc_valid: if j == 1 {
                connectable(scene, &y[1])
            } else {
                connectable_inside(scene, &y[j - 1]) && connectable(scene, &y[j])
            },
            mergeable: false,
            through_delta: y[j].delta,
        };
        let r = mis.light_vertex(
            j,
            y[j].pdf_fwd as f64,
            (&out[j - 1], c_pp),
            nee_over_l0,
            vertex,
        );
        out.push(r);
    }
}

/// The records of camera subpath z_0 (the lens point) … (`SubpathMis::camera_vertex`) into `out`.
pub fn camera_records(scene: &Scene, mis: &SubpathMis, z: &[PathVertex], out: &mut Vec<CameraMis>) {
    out.clear();
    out.push(mis.camera_origin());
    for m in 1..z.len() {
        let vertex = VertexTechniques {
            // VC(i+1) joins z_m, the connection's end, to z_{m−1}, inside the path.
            vc_valid: connectable(scene, &z[m]) && connectable_inside(scene, &z[m - 1]),
            mergeable: false,
            through_delta: z[m].delta,
        };
        let prev = (&out[m - 1], z[m - 1].pdf_rev as f64);
        let r = mis.camera_vertex(m, z[m].pdf_fwd as f64, prev, vertex);
        out.push(r);
    }
}

/// s = 0: `path` = z_0 … z_m, x0, the camera walk and the light endpoint it reached (its pdf_fwd
/// the walk's c_0); `zr` the walk's records; `camera_back` the walk's free flight x0 → z_m.
pub fn emitter_weight<const MEDIA: bool>(
    scene: &Scene,
    mis: &SubpathMis,
    path: &[PathVertex],
    zr: &[CameraMis],
    camera_back: f32,
) -> f64 {
    let (camera, x0) = path.split_at(path.len() - 1);
    let x0 = &x0[0];
    let x1 = camera.last().expect("the lens point");
    if !connectable(scene, x0) {
        // Technique 0 cannot end at a light delta in direction (`Chain::valid`).
        return 0.0;
    }
    let c0 = x0.pdf_fwd as f64;
    if camera.len() == 1 {
        let (l0, _) = emission_densities(scene, x0, None);
        let vc1 = connectable(scene, x1);
        return mis.emitter_seen(c0, l0, vc1);
    }
    // VC(1) is next-event estimation from x1, which is inside this path.
    let vc1 = connectable_inside(scene, x1);
    let (l0, l1) = emission_densities(scene, x0, Some(x1));
    let l1 = with_flight::<MEDIA>(l1, camera_back);
    let nee = nee_density(scene, x0, x1);
    mis.emitter_hit(&zr[camera.len() - 1], c0, l0, l1, nee, vc1)
}

/// s = 1: next-event estimation's `x0` (pdf_fwd = its density) joined to z_{t−1}, whose BSDF
/// towards it is `ev_z`; `zr` the camera walk's records.
pub fn next_event_weight<const MEDIA: bool>(
    scene: &Scene,
    mis: &SubpathMis,
    (z, zr): (&[PathVertex], &[CameraMis]),
    (x0, ev_z): (&PathVertex, BsdfEval),
    flights: JoinFlights,
) -> f64 {
    let t = z.len();
    let zv = &z[t - 1];
    let (l0, l1) = emission_densities(scene, x0, Some(zv));
    let c0 = reverse_density(x0, zv, ev_z.pdf_w) as f64;
    let l_z_prev = if t >= 3 {
        let l2 = reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64;
        with_flight::<MEDIA>(l2, flights.camera_back)
    } else {
        0.0
    };
    let d = NextEventDensities {
        nee: x0.pdf_fwd as f64,
        c0: with_flight::<MEDIA>(c0, flights.edge.from_camera),
        l0,
        l1: with_flight::<MEDIA>(l1, flights.edge.from_light),
        l_z_prev,
    };
    mis.next_event((&zr[t - 1], &zr[t - 2]), d)
}

/// s, t ≥ 2: the connection `c`, with `ly` the light subpath's records and `zr` the camera's.
pub fn connection_weight<const MEDIA: bool>(
    mis: &SubpathMis,
    c: Connection,
    ly: &[LightMis],
    zr: &[CameraMis],
) -> f64 {
    let (y, z) = (c.light, c.camera);
    let (s, t) = (y.len(), z.len());
    let (yv, zv) = (&y[s - 1], &z[t - 1]);
    let (ev_y, ev_z, f) = (c.joined.light_end, c.joined.camera_end, c.flights);
    let c_y = reverse_density(yv, zv, ev_z.pdf_w) as f64;
    let c_y_prev = reverse_density(&y[s - 2], yv, ev_y.pdf_rev_w) as f64;
    let l_z = yv.convert_density(ev_y.pdf_w, zv) as f64;
    let l_z_prev = if t >= 3 {
        let l = reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64;
        with_flight::<MEDIA>(l, f.camera_back)
    } else {
        0.0
    };
    let d = ConnectionDensities {
        c_y: with_flight::<MEDIA>(c_y, f.edge.from_camera),
        c_y_prev: with_flight::<MEDIA>(c_y_prev, f.light_back),
        l_z: with_flight::<MEDIA>(l_z, f.edge.from_light),
        l_z_prev,
    };
    mis.connection(&ly[s - 1], (&zr[t - 1], &zr[t - 2]), d)
}

/// t = 1: light vertex y_{s−1} of `y` = y_0 … y_{s−1} joined to the lens point of `c`, with `ly`
/// the light subpath's records and `light_back` its walk's free flight y_{s−1} → y_{s−2}.
pub fn light_tracing_weight<const MEDIA: bool>(
    scene: &Scene,
    mis: &SubpathMis,
    (y, ly): (&[PathVertex], &[LightMis]),
    c: &CameraConnection,
    light_back: f32,
) -> f64 {
    let s = y.len();
    let (yv, cam) = (&y[s - 1], &c.camera);
    let pdf_dir = scene.camera.pdf_dir(cam.p, cam.dir_to(yv));
    let c_y = reverse_density(yv, cam, pdf_dir) as f64;
    let c_y = with_flight::<MEDIA>(c_y, c.flights.from_camera);
    if s == 1 {
        return mis.light_tracing_origin(&ly[0], c_y);
    }
    let ev = c.eval.expect("a surface connected to the camera");
    let c_prev = reverse_density(&y[s - 2], yv, ev.pdf_rev_w) as f64;
    let c_prev = with_flight::<MEDIA>(c_prev, light_back);
    mis.light_tracing(&ly[s - 1], c_y, c_prev)
}
