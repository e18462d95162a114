//! The VCM engine's policy in the bidirectional camera loop (`crate::subpath::camera_loop`):
//! its weights of s = 0, s = 1 and the connections, and the merges at every camera vertex.

use super::full_path::{merge_weight, MergeDensities};
use super::{light_nee, Engine, LightPaths, PassInputs, PassSetup, Scratch};
use crate::density::surface_merge::SurfaceGather;
use crate::film::splat::Worker;
use crate::record::{Merged, Recorder, Work};
use crate::subpath::camera_loop::{
    camera_sample, CameraPolicy, Connection, Depths, Joins, SampleCtx, Weight,
};
use crate::subpath::connect::{emission_densities, nee_density, JoinFlights, Joined};
use crate::subpath::strategy_weight::Split;
use crate::subpath::walk::reverse_density;
use lt_core::bsdf::BsdfEval;
use lt_core::math::{Color, Vec2};
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::subpath_mis::{ConnectionDensities, NextEventDensities, VertexTechniques};
use lt_core::path::{CameraMis, LightMis, PathVertex, SubpathMis, VertexKind};
use lt_core::sampling::Sampler;
use lt_core::Scene;

impl Engine<'_> {
    /// The camera sample of `pixel`: every technique with t ≥ 2 (merges included), through the
    /// camera loop under the VCM policy.
    pub(super) fn camera_sample<R: Recorder>(
        &self,
        inputs: &PassInputs,
        light: (&[PathVertex], &[LightMis]),
        pixel: u64,
        worker: &mut Worker<'_, Scratch, R>,
    ) -> Color {
        let PassInputs {
            setup,
            lights,
            pass,
        } = *inputs;
        let Scratch { walk, records } = &mut *worker.scratch;
        let mut policy = VcmCamera {
            engine: self,
            setup,
            lights,
            light,
            records,
            primary: 0.0,
            light_nee: 0.0,
            merges_here: true,
        };
        let depths = Depths {
            max_depth: self.params.max_depth,
            rr_depth: self.params.rr_depth,
        };
        camera_sample(
            self.scene,
            (pass, pixel),
            depths,
            &mut policy,
            walk,
            &mut *worker.rec,
        )
    }
}

/// The VCM engine's policy in the camera loop, for one camera sample: its connections are
/// bdpt's (light subpath j mod M), every weight comes from the per-vertex recursion
/// (`SubpathMis`) or, when on, from the full path (`FullPathSetup`), and every non-delta camera
/// vertex merges with the stored light vertices within the pass's radius.
struct VcmCamera<'a, 'e> {
    engine: &'a Engine<'e>,
    setup: &'a PassSetup,
    lights: &'a LightPaths,
    /// The light subpath this sample connects to, and its MIS records.
    light: (&'a [PathVertex], &'a [LightMis]),
    /// The camera walk's MIS records, one per vertex (`walked`).
    records: &'a mut Vec<CameraMis>,
    /// |z_1 − z_0|: the primary hit's distance (the footprint of correlation-aware MIS).
    primary: f32,
    /// With full-path weights: next-event estimation's density of y_0 of `light`, read by each
    /// of its connections.
    light_nee: f64,
    /// Whether the sample's pixel merges (efficiency-aware MIS's mask).
    merges_here: bool,
}

impl CameraPolicy for VcmCamera<'_, '_> {
    fn walked(&mut self, scene: &Scene, z: &[PathVertex], raster: Vec2) {
        let setup = self.setup;
        camera_records(scene, &setup.mis, z, self.records);
        self.merges_here = setup.camis.as_ref().is_none_or(|c| c.merges_at(raster));
        self.primary = if z.len() >= 2 {
            (z[1].p - z[0].p).length()
        } else {
            0.0
        };
        self.light_nee = if setup.camis.is_some() {
            light_nee(scene, self.light.0)
        } else {
            0.0
        };
    }

    /// The camera walk (camera first, ending at x1) reached light endpoint x0 with density c0
    /// (its `pdf_fwd`).
    fn emitter_weight(
        &self,
        scene: &Scene,
        path: &[PathVertex],
        _: JoinFlights,
        raster: Vec2,
    ) -> Weight {
        let (camera, x0) = path.split_at(path.len() - 1);
        let (x0, c0) = (&x0[0], x0[0].pdf_fwd);
        let x1 = camera.last().expect("the pinhole");
        if let Some(camis) = &self.setup.camis {
            let primary = if camera.len() == 1 {
                (x0.p - x1.p).length()
            } else {
                self.primary
            };
            let (split, evals) = Split::reached(path);
            let wd = camis.connection(scene, split, evals, primary, raster);
            return (wd.weight, Some(wd.mixture));
        }
        let mis = &self.setup.mis;
        if camera.len() == 1 {
            let (l0, _) = emission_densities(scene, x0, None);
            return (
                mis.emitter_seen(c0 as f64, l0, joinable(scene, x0, x1)),
                None,
            );
        }
        // VC(1) is next-event estimation from x1 (`Chain::valid`); x1 is inside this path.
        let vc1 = connectable_inside(scene, x1);
        let (l0, l1) = emission_densities(scene, x0, Some(x1));
        let nee = nee_density(scene, x0, x1);
        let records = &self.records[camera.len() - 1];
        (mis.emitter_hit(records, c0 as f64, l0, l1, nee, vc1), None)
    }

    fn connects(&self) -> bool {
        self.engine.params.connections
    }

    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        (x0, ev_z): (&PathVertex, BsdfEval),
        _: JoinFlights,
        raster: Vec2,
    ) -> Weight {
        let t = z.len();
        let zv = &z[t - 1];
        if let Some(camis) = &self.setup.camis {
            let (split, evals) = Split::next_event(z, x0, ev_z);
            let wd = camis.connection(scene, split, evals, self.primary, raster);
            return (wd.weight, Some(wd.mixture));
        }
        let (l0, l1) = emission_densities(scene, x0, Some(zv));
        let d = NextEventDensities {
            nee: x0.pdf_fwd as f64,
            c0: reverse_density(x0, zv, ev_z.pdf_w) as f64,
            l0,
            l1,
            l_z_prev: if t >= 3 {
                reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64
            } else {
                0.0
            },
        };
        let zr = &self.records;
        (self.setup.mis.next_event((&zr[t - 1], &zr[t - 2]), d), None)
    }

    /// bdpt's connections to light subpath j mod M; with vertex connections off, none.
    fn connect<R: Recorder>(&mut self, scene: &Scene, joins: &mut Joins<'_, R>, _: &mut Sampler) {
        if self.engine.params.vertex_connections {
            joins.join_subpath(scene, self.light.0, |c| self.connection_weight(scene, c));
        }
    }

    fn at_vertex<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        sample: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let params = &self.engine.params;
        let t = z.len();
        if params.merging && t <= params.max_depth as usize && self.merges_here {
            *l += self.merge(scene, z, sample);
            sample.rec.lap(Work::Merge { t: t as u16 });
        }
    }
}

impl VcmCamera<'_, '_> {
    /// The weight of strategy (s, t), s ≥ 2, t ≥ 2: a shadow ray from z_{t−1} to y_{s−1}.
    fn connection_weight(&self, scene: &Scene, c: Connection) -> Weight {
        let (y, z) = (c.light, c.camera);
        let (s, t) = (y.len(), z.len());
        let (yv, zv) = (&y[s - 1], &z[t - 1]);
        if let Some(camis) = &self.setup.camis {
            let (split, evals) = Split::connection(c, self.light_nee);
            let wd = camis.connection(scene, split, evals, self.primary, c.raster);
            return (wd.weight, Some(wd.mixture));
        }
        let Joined {
            light_end: ev_y,
            camera_end: ev_z,
            ..
        } = *c.joined;
        let d = ConnectionDensities {
            c_y: reverse_density(yv, zv, ev_z.pdf_w) as f64,
            c_y_prev: reverse_density(&y[s - 2], yv, ev_y.pdf_rev_w) as f64,
            l_z: yv.convert_density(ev_y.pdf_w, zv) as f64,
            l_z_prev: if t >= 3 {
                reverse_density(&z[t - 2], zv, ev_z.pdf_rev_w) as f64
            } else {
                0.0
            },
        };
        let (ly, zr) = (self.light.1, &self.records);
        let w = self
            .setup
            .mis
            .connection(&ly[s - 1], (&zr[t - 1], &zr[t - 2]), d);
        (w, None)
    }

    /// Merges at z_{t−1} (`z` = z_0 … z_{t−1}) with every stored light vertex within the pass's
    /// radius (disk kernel).
    fn merge<R: Recorder>(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        sample: &mut SampleCtx<'_, R>,
    ) -> Color {
        let (setup, lights, zr) = (self.setup, self.lights, &self.records);
        let t = z.len();
        let zv = &z[t - 1];
        let Some(grid) = &lights.grid else {
            return Color::ZERO;
        };
        let Some(gather) = SurfaceGather::at(scene, zv) else {
            return Color::ZERO;
        };
        let max_k = self.engine.params.max_depth;
        let camera_segments = (t - 1) as u32;
        let mut sum = Color::ZERO;
        grid.for_each_within(&lights.merge_positions, zv.p, setup.radius, |e, _| {
            let y = &lights.merge_vertex[e as usize];
            if y.segments + camera_segments > max_k {
                return;
            }
            let Some(ev) = gather.eval(y.wi, y.ng, y.cos_g) else {
                return;
            };
            let value = zv.beta * ev.f_cos * y.beta / y.cos_g;
            let c_y_prev = (ev.pdf_w * y.to_prev) as f64;
            let l_z_prev = if t >= 3 {
                reverse_density(&z[t - 2], zv, ev.pdf_rev_w) as f64
            } else {
                0.0
            };
            let (vi, first) = (y.index as usize, (y.index - y.segments) as usize);
            let ys = &lights.chunks[y.chunk as usize].vertices[first..=vi];
            let (w, mixture) = match &setup.camis {
                Some(camis) => {
                    let merge = MergeDensities { c_y_prev, l_z_prev };
                    let wd =
                        merge_weight(scene, camis, (ys, z), merge, (self.primary, sample.raster));
                    (wd.weight, Some(wd.mixture))
                }
                None => (
                    setup
                        .mis
                        .merge(&y.mis, &zr[t - 1], &zr[t - 2], c_y_prev, l_z_prev),
                    None,
                ),
            };
            if R::ACTIVE {
                if let Some(m) = mixture {
                    sample.rec.mixture(m);
                }
                sample.rec.merged(Merged {
                    i: y.segments as usize,
                    light: ys,
                    camera: z,
                    weight: w,
                    value: value * setup.merge_norm,
                    raster: sample.raster,
                    radius: setup.radius,
                });
            }
            sum += value * w as f32;
        });
        sum * setup.merge_norm
    }
}

/// Whether a connection technique can join `a` and `b` (both non-delta).
#[inline]
fn joinable(scene: &Scene, a: &PathVertex, b: &PathVertex) -> bool {
    connectable(scene, a) && connectable(scene, b)
}

/// The MIS records of a camera subpath z_0 (pinhole) … into `out`.
pub(super) fn camera_records(
    scene: &Scene,
    mis: &SubpathMis,
    z: &[PathVertex],
    out: &mut Vec<CameraMis>,
) {
    out.clear();
    out.push(mis.camera_origin());
    for m in 1..z.len() {
        let surface = matches!(z[m].kind, VertexKind::Surface { .. });
        let vertex = VertexTechniques {
            // VC(i+1) joins z_m, the end, to z_{m−1}, inside the path.
            vc_valid: connectable(scene, &z[m]) && connectable_inside(scene, &z[m - 1]),
            mergeable: surface && connectable(scene, &z[m]) && mis.merging(),
            through_delta: z[m].delta,
        };
        let r = mis.camera_vertex(
            m,
            z[m].pdf_fwd as f64,
            (&out[m - 1], z[m - 1].pdf_rev as f64),
            vertex,
        );
        out.push(r);
    }
}
