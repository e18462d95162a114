//! `upbp`'s policy in the one bidirectional camera loop (`subpath::camera_loop`): bdpt's
//! connections (s = 0, next-event estimation, joins to the paired light subpath), PP3D at every
//! medium vertex of the camera walk (`at_vertex`), PB2D along every segment of it (`along_segment`,
//! and `after_walk` for the segment that left the scene), all weighed by `weights::weight` from
//! the full path's densities.
//!
//! **PB2D's estimate** (a short camera beam: the segment the walk sampled, z_{t−2} → z_{t−1}, or
//! to infinity when it left the scene). Per medium piece of the segment (`Scene::
//! for_each_medium_piece`), each photon y_i of the piece's medium within r_B of it, at x its
//! projection on the beam, contributes
//!
//!   β_leave · T(z_{t−2}, x) / P_pass(z_{t−2}, x) · σs(x) f_p(−ω, ω_y) · (β_y / σs(y_i)) / (N π r_B²),
//!
//! β_leave the walk's throughput leaving z_{t−2} (`Subpath::departure`): the beam covers x when
//! the sampled flight passes it, with probability P_pass, and T is evaluated (deterministic, as
//! `volume_density::beams`). **PP3D** at the medium vertex z (β_z holding σs(z)):
//! β_z f_p(ω_z, ω_y) (β_y / σs(y_i)) / (N (4/3)π r_P³).

use super::light_store::{LightPath, LightStore};
use super::weights::{weight, VertexRate};
use crate::record::{Recorder, VolumeMerged};
use crate::subpath::camera_loop::{CameraPolicy, Joins, SampleCtx, Weight};
use crate::subpath::connect::JoinFlights;
use crate::subpath::strategy_weight::{with_chain_in, Split};
use crate::subpath::walk::{Departure, Exit, Subpath};
use lt_core::bsdf::BsdfEval;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::path::scatter::connectable_inside;
use lt_core::path::volume_merging::scatter_rate;
use lt_core::path::{Chain, Heuristic, PathVertex, VertexKind, VolumeSet, VolumeTechnique};
use lt_core::sampling::Sampler;
use lt_core::scene::{ConnectionEnd, Crossing, MediumPiece};
use lt_core::Scene;

/// What every camera sample of a pass shares.
pub struct PassData<'a> {
    pub store: &'a LightStore,
    pub set: VolumeSet,
    pub h: Heuristic,
    /// M/N (light tracing's sample count).
    pub ratio: f64,
    pub max_k: usize,
    pub r_points: f32,
    pub r_beams: f32,
    /// 1 / (M (4/3)π r_P³) and 1 / (M π r_B²).
    pub point_norm: f32,
    pub beam_norm: f32,
}

/// σ̂ at light vertex `y` of the flight from `from`, when PB2D runs and `y` is a medium vertex.
pub fn junction_rate(pass: &PassData, scene: &Scene, from: &PathVertex, y: &PathVertex) -> f64 {
    if pass.set.beams_eta > 0.0 && y.in_medium() {
        scatter_rate(scene, from, y)
    } else {
        0.0
    }
}

/// The policy of one camera sample.
pub struct Policy<'a, const MEDIA: bool> {
    pub pass: &'a PassData<'a>,
    /// The paired light subpath, as a `Subpath` for the loop's joins and as stored.
    pub y: &'a Subpath,
    pub ly: LightPath<'a>,
    /// Per camera vertex: medium and σ̂ of the walk's flight into it.
    pub cam: Vec<VertexRate>,
    pub back_flight: Vec<f32>,
    pub departure: Vec<Departure>,
    pub exit: Option<Exit>,
    /// A camera side with a beam's query point last.
    pub buf: Vec<PathVertex>,
}

/// `v / σs` per channel, zero where σs is (β is zero there too): a photon's power as
/// `volume_density::photons` keeps it.
fn without_sigma_s(v: Color, sigma_s: Color) -> Color {
    Color::select(sigma_s.cmpgt(Color::ZERO), v / sigma_s, Color::ZERO)
}

fn medium_of(v: &PathVertex) -> Option<u32> {
    match v.kind {
        VertexKind::Medium { medium } => Some(medium as u32),
        _ => None,
    }
}

/// The weight of connection technique s on `chain`, whose x_j is light vertex j below s (`light`;
/// `junction` the σ̂ of x_{s−1} seen from x_s) and camera vertex k − j from s up (`cam`, the
/// camera walk's; for s = 0, x_0 is the light the walk reached).
pub fn connection_weight(
    pass: &PassData,
    chain: &Chain,
    s: usize,
    (light, junction): (&[VertexRate], f64),
    cam: &[VertexRate],
) -> f64 {
    let k = chain.k();
    let mut stack = [VertexRate::default(); 32];
    let mut heap = Vec::new();
    let vol: &mut [VertexRate] = if k < 32 {
        &mut stack[..=k]
    } else {
        heap.resize(k + 1, VertexRate::default());
        &mut heap
    };
    for (j, v) in vol.iter_mut().enumerate() {
        *v = if j + 1 < s {
            light[j]
        } else if j + 1 == s {
            VertexRate {
                medium: light[j].medium,
                rate: junction,
            }
        } else if (s > 0 || j > 0) && k - j < cam.len() {
            cam[k - j]
        } else {
            VertexRate::default()
        };
    }
    weight(chain, vol, &pass.set, VolumeTechnique::Connect(s), pass.h)
}

impl<'a, const MEDIA: bool> Policy<'a, MEDIA> {
    pub fn new(pass: &'a PassData<'a>, y: &'a Subpath, ly: LightPath<'a>) -> Self {
        Policy {
            pass,
            y,
            ly,
            cam: Vec::new(),
            back_flight: Vec::new(),
            departure: Vec::new(),
            exit: None,
            buf: Vec::new(),
        }
    }

    /// The weight of a volumetric merge of photon path `y` (y_0 … y_i) with the camera side
    /// `cam` (z_0 … , its last the camera's x_i), `zx_back` the free flight of x_i → its camera
    /// predecessor walked back, `zx_rate` σ̂ at x_i. The densities are `Densities::volume_merged`'s.
    fn merge_weight(
        &self,
        scene: &Scene,
        y: LightPath,
        cam: &[PathVertex],
        (zx_back, zx_rate): (f64, f64),
        technique: VolumeTechnique,
    ) -> f64 {
        let yv = y.vertices;
        let i = yv.len() - 1;
        let t = cam.len();
        let k = i + t - 1;
        let (mut light, mut camera) = (vec![0.0f64; k + 1], vec![0.0f64; k + 1]);
        let mut conn = vec![false; k + 1];
        let mut vol = vec![VertexRate::default(); k + 1];
        for j in 0..=k {
            if j <= i {
                light[j] = yv[j].pdf_fwd as f64;
            }
            if j + 2 <= i {
                camera[j] = yv[j].pdf_rev as f64;
            }
            if j >= i {
                camera[j] = cam[k - j].pdf_fwd as f64;
            }
            if j >= i + 2 {
                light[j] = cam[k - j].pdf_rev as f64;
            }
            conn[j] = match j.cmp(&i) {
                std::cmp::Ordering::Less => connectable_inside(scene, &yv[j]),
                std::cmp::Ordering::Equal => true,
                std::cmp::Ordering::Greater => connectable_inside(scene, &cam[k - j]),
            };
            vol[j] = match j.cmp(&i) {
                std::cmp::Ordering::Less => y.rates[j],
                std::cmp::Ordering::Equal => VertexRate {
                    medium: true,
                    rate: zx_rate,
                },
                std::cmp::Ordering::Greater => {
                    if k - j < self.cam.len() {
                        self.cam[k - j]
                    } else {
                        VertexRate::default()
                    }
                }
            };
        }
        let (y_i, zx) = (&yv[i], &cam[t - 1]);
        let medium = medium_of(zx).expect("a volumetric merge's camera side is a medium vertex");
        let phase = scene.media[medium as usize].phase();
        // c_{i−1}: the camera side's phase function sampling ω_y, in y_{i−1}'s measure from y_i.
        camera[i - 1] = if i == 1 && yv[0].is_delta_light() {
            0.0
        } else {
            let pdf = phase.pdf(zx.wo, y_i.wo);
            y_i.convert_density(pdf, &yv[i - 1]) as f64 * y.back_flight[i] as f64
        };
        if i + 1 < k {
            let pdf = phase.pdf(y_i.wo, zx.wo);
            light[i + 1] = zx.convert_density(pdf, &cam[t - 2]) as f64 * zx_back;
        }
        camera[k] = 1.0;
        light[k] = 0.0;
        let chain = Chain {
            light: &light,
            camera: &camera,
            nee: y.nee,
            connectable: &conn,
            light_tracing_ratio: self.pass.ratio,
        };
        let p = self.pass;
        weight(&chain, &vol, &p.set, technique, p.h)
    }

    /// PB2D along the segment from `prefix`'s last vertex in direction `dir` up to `end`, left
    /// with `leave`.
    #[allow(clippy::too_many_arguments)]
    fn beam<R: Recorder>(
        &mut self,
        scene: &Scene,
        prefix: &[PathVertex],
        (dir, end): (Vec3, ConnectionEnd),
        leave: Departure,
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let Some(grid) = p.store.beams.as_ref() else {
            return;
        };
        if p.set.beams_eta == 0.0 || prefix.len() >= p.max_k || leave.beta == Color::ZERO {
            return;
        }
        let o = &prefix[prefix.len() - 1];
        let mut pieces: Vec<MediumPiece> = Vec::new();
        let m0 = o.medium_towards(scene, dir);
        scene.for_each_medium_piece(o.into(), end, m0, Crossing::Everything, |piece| {
            pieces.push(piece)
        });
        let r2 = p.r_beams * p.r_beams;
        let (mut t_before, mut p_before) = (Color::ONE, 1.0f32);
        let mut buf = std::mem::take(&mut self.buf);
        for piece in pieces {
            let Some(m) = piece.medium else {
                continue;
            };
            let mm = &scene.media[m as usize];
            let len = (piece.b - piece.a).length();
            if !(len > 0.0) {
                continue;
            }
            let phase = mm.phase();
            let ray = Ray::new(piece.a, dir);
            grid.for_each_along(&ray, len, |idx, t_lo, t_hi| {
                let ph = p.store.photons[idx as usize];
                let i = ph.vertex as usize;
                if i + prefix.len() > p.max_k {
                    return;
                }
                let y = p.store.photon(ph);
                let yv = &y.vertices[i];
                if medium_of(yv) != Some(m as u32) {
                    return;
                }
                let to = p.store.photon_positions[idx as usize] - piece.a;
                let tp = to.dot(dir);
                if !(tp >= t_lo && tp < t_hi && tp < len) {
                    return;
                }
                if (to - dir * tp).length_squared() > r2 {
                    return;
                }
                let x = piece.a + dir * tp;
                let pass = p_before * mm.free_flight_density(piece.a, x, false);
                let scatter = p_before * mm.free_flight_density(piece.a, x, true);
                if !(pass > 0.0 && scatter > 0.0) {
                    return;
                }
                let tr = t_before * mm.transmittance(piece.a, x);
                let power = without_sigma_s(yv.beta, mm.sigma_s(yv.p));
                let value = leave.beta * tr / pass
                    * mm.sigma_s(x)
                    * phase.eval(-dir, yv.wo)
                    * power
                    * p.beam_norm;
                if value == Color::ZERO {
                    return;
                }
                let xv = PathVertex::medium(m, x, -dir, value, leave.pdf_w, scatter, o);
                buf.clear();
                buf.extend_from_slice(prefix);
                buf.push(xv);
                let back =
                    scene.free_flight_density((&xv).into(), o.into(), Some(m), o.in_medium());
                let rate = (scatter / pass) as f64;
                let w = self.merge_weight(
                    scene,
                    y,
                    &buf,
                    (back as f64, rate),
                    VolumeTechnique::Beam(i),
                );
                if R::ACTIVE {
                    ctx.rec.volume_merged(VolumeMerged {
                        beam: true,
                        i,
                        light: y.vertices,
                        camera: &buf,
                        weight: w,
                        value,
                        raster: ctx.raster,
                        radius: p.r_beams,
                    });
                }
                *l += value * w as f32;
            });
            t_before *= mm.transmittance(piece.a, piece.b);
            p_before *= mm.free_flight_density(piece.a, piece.b, false);
        }
        self.buf = buf;
    }
}

impl<const MEDIA: bool> CameraPolicy for Policy<'_, MEDIA> {
    const MEDIA: bool = MEDIA;

    fn camera_walk(&mut self, scene: &Scene, camera: &Subpath) {
        let z = &camera.vertices;
        self.cam.clear();
        self.cam.extend((0..z.len()).map(|j| VertexRate {
            medium: z[j].in_medium(),
            rate: if j >= 1 && z[j].in_medium() {
                scatter_rate(scene, &z[j - 1], &z[j])
            } else {
                0.0
            },
        }));
        self.back_flight.clear();
        self.back_flight
            .extend((0..z.len()).map(|j| camera.back_flight(j)));
        self.departure.clear();
        self.departure
            .extend((0..z.len()).map(|j| camera.departure(j)));
        self.exit = camera.exit;
    }

    fn emitter_weight(
        &self,
        scene: &Scene,
        path: &[PathVertex],
        f: JoinFlights,
        _: Vec2,
    ) -> Weight {
        let (split, mut evals) = Split::reached(path);
        evals.flights = Some(f);
        let w = with_chain_in::<MEDIA, _>(scene, split, evals, self.pass.ratio, |chain, s| {
            connection_weight(self.pass, chain, s, (&[], 0.0), &self.cam)
        });
        (w, None)
    }

    fn next_event_weight(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        (x0, camera_end): (&PathVertex, BsdfEval),
        f: JoinFlights,
        _: Vec2,
    ) -> Weight {
        let (split, mut evals) = Split::next_event(z, x0, camera_end);
        evals.flights = Some(f);
        let light = [VertexRate::default()];
        let w = with_chain_in::<MEDIA, _>(scene, split, evals, self.pass.ratio, |chain, s| {
            connection_weight(self.pass, chain, s, (&light, 0.0), &self.cam)
        });
        (w, None)
    }

    fn connects(&self) -> bool {
        self.pass.set.connections
    }

    fn connect<R: Recorder>(&mut self, scene: &Scene, joins: &mut Joins<'_, R>, _: &mut Sampler) {
        let this = &*self;
        joins.join_subpath_in::<MEDIA>(scene, this.y, |c| {
            let s = c.light.len();
            let junction = junction_rate(
                this.pass,
                scene,
                &c.camera[c.camera.len() - 1],
                &c.light[s - 1],
            );
            let (split, evals) = Split::connection(c, this.ly.nee);
            let w = with_chain_in::<MEDIA, _>(scene, split, evals, this.pass.ratio, |chain, s| {
                connection_weight(this.pass, chain, s, (this.ly.rates, junction), &this.cam)
            });
            (w, None)
        });
    }

    fn at_vertex<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let t = z.len();
        let zv = &z[t - 1];
        let (Some(grid), Some(m)) = (p.store.points.as_ref(), medium_of(zv)) else {
            return;
        };
        if p.set.points_eta == 0.0 || t > p.max_k || zv.beta == Color::ZERO {
            return;
        }
        let mm = &scene.media[m as usize];
        let phase = mm.phase();
        let zx_back = self.back_flight[t - 1] as f64;
        let zx_rate = self.cam[t - 1].rate;
        let positions = &p.store.photon_positions;
        grid.for_each_within(positions, zv.p, p.r_points, |idx, _| {
            let ph = p.store.photons[idx as usize];
            let i = ph.vertex as usize;
            if i + t - 1 > p.max_k {
                return;
            }
            let y = p.store.photon(ph);
            let yv = &y.vertices[i];
            if medium_of(yv) != Some(m) {
                return;
            }
            let power = without_sigma_s(yv.beta, mm.sigma_s(yv.p));
            let value = zv.beta * phase.eval(zv.wo, yv.wo) * power * p.point_norm;
            if value == Color::ZERO {
                return;
            }
            let w = self.merge_weight(scene, y, z, (zx_back, zx_rate), VolumeTechnique::Point(i));
            if R::ACTIVE {
                ctx.rec.volume_merged(VolumeMerged {
                    beam: false,
                    i,
                    light: y.vertices,
                    camera: z,
                    weight: w,
                    value,
                    raster: ctx.raster,
                    radius: p.r_points,
                });
            }
            *l += value * w as f32;
        });
    }

    fn along_segment<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        if !MEDIA {
            return;
        }
        let t = z.len();
        let (a, b) = (&z[t - 2], &z[t - 1]);
        let leave = self.departure[t - 1];
        self.beam(scene, &z[..t - 1], (a.dir_to(b), b.into()), leave, ctx, l);
    }

    fn after_walk<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let Some(exit) = self.exit.filter(|_| MEDIA) else {
            return;
        };
        let far = ConnectionEnd {
            p: exit.dir,
            p_err: Vec3::ZERO,
            ng: Vec3::ZERO,
            infinite: true,
        };
        self.beam(scene, z, (exit.dir, far), exit.leave, ctx, l);
    }
}
