//! `upbp`'s policy in the one bidirectional camera loop (`subpath::camera_loop`): bdpt's
//! connections (s = 0, next-event estimation, joins to the paired light subpath), PP3D at every
//! medium vertex of the camera walk (`at_vertex`), PB2D and BB1D along every segment of it
//! (`along_segment`, and `after_walk` for the segment that left the scene: `camera_beams`), all
//! weighed by `weights::weight` from the full path's densities.
//!
//! **PP3D** at the medium vertex z (β_z holding σs(z)), per photon y_i within r_P:
//! β_z f_p(ω_z, ω_y) (β_y / σs(y_i)) / (N (4/3)π r_P³). PB2D's and BB1D's estimates are
//! `camera_beams`'s.
//!
//! **BP2D** at the medium vertex z, per photon beam b within r_B of it (`beam_points`), x' the
//! projection of z on the beam: β_z f_p(ω_z, −ω_b) Φ_b(x') / (M_B π r_B²), Φ_b(x') the beam's
//! value there (`beam_end::BeamEnd`) — Jarosz et al. 2011's beam × point 2-D estimate, as
//! `volume_density::point_beam`.

use super::beam_end::BeamEnd;
use super::light_store::{LightPath, LightStore};
use super::rates::{camera_vertex, junction, Needs};
use super::weights::{weight, VertexRate};
use crate::density::surface_merge::SurfaceGather;
use crate::record::{Recorder, VolumeFamily, VolumeMerged, Work};
use crate::subpath::camera_loop::{CameraPolicy, Joins, SampleCtx, Weight};
use crate::subpath::connect::JoinFlights;
use crate::subpath::strategy_weight::{with_chain_in, Split};
use crate::subpath::walk::{Departure, Exit, Subpath};
use lt_core::bsdf::BsdfEval;
use lt_core::math::{Color, Vec2, Vec3};
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::{
    Chain, Heuristic, PathVertex, UpbpMode, VertexKind, VolumeSet, VolumeTechnique,
};
use lt_core::sampling::Sampler;
use lt_core::scene::ConnectionEnd;
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
    pub r_beam_beams: f32,
    /// 1 / (M (4/3)π r_P³), 1 / (M π r_B²), 1 / (M 2 r_BB) and 1 / (M π r_S²) (r_S = r_B).
    pub point_norm: f32,
    pub beam_norm: f32,
    pub beam_beam_norm: f32,
    pub surface_norm: f32,
    /// 1 / (M_B π r_B²): BP2D's kernel and beam count.
    pub beam_point_norm: f32,
    /// The rates the weights read (`rates::Needs`).
    pub needs: Needs,
}

/// The policy of one camera sample.
pub struct Policy<'a, const MEDIA: bool> {
    pub pass: &'a PassData<'a>,
    /// The paired light subpath, as a `Subpath` for the loop's joins and as stored.
    pub y: &'a Subpath,
    pub ly: LightPath<'a>,
    /// Per camera vertex: `rates::camera_vertex`.
    pub cam: Vec<VertexRate>,
    pub back_flight: Vec<f32>,
    pub departure: Vec<Departure>,
    pub exit: Option<Exit>,
    /// A camera side with a beam's query point last.
    pub buf: Vec<PathVertex>,
    /// A light side with a photon beam's point last.
    pub light_buf: Vec<PathVertex>,
    /// The camera walk's first vertex past the camera that is no delta surface, and whether it
    /// lies in a medium (`UpbpMode`'s class vertex x_m when it does).
    pub first: Option<(usize, bool)>,
}

/// `v / σs` per channel, zero where σs is (β is zero there too): a photon's power as
/// `volume_density::photons` keeps it.
pub fn without_sigma_s(v: Color, sigma_s: Color) -> Color {
    Color::select(sigma_s.cmpgt(Color::ZERO), v / sigma_s, Color::ZERO)
}

pub fn medium_of(v: &PathVertex) -> Option<u32> {
    match v.kind {
        VertexKind::Medium { medium } => Some(medium as u32),
        _ => None,
    }
}

/// The weight of connection technique s on `chain`, whose x_j is light vertex j below s (`light`)
/// and camera vertex k − j from s up (`cam`, the camera walk's; for s = 0, x_0 is the light the
/// walk reached); `ends` replace the rates of the path's vertices they name (the junction's two
/// ends, whose rates depend on the other end: `rates::junction`).
pub fn connection_weight(
    pass: &PassData,
    chain: &Chain,
    s: usize,
    (light, cam): (&[VertexRate], &[VertexRate]),
    ends: &[(usize, VertexRate)],
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
        *v = if j < s {
            light.get(j).copied().unwrap_or_default()
        } else if (s > 0 || j > 0) && k - j < cam.len() {
            cam[k - j]
        } else {
            VertexRate::default()
        };
    }
    for &(j, v) in ends {
        if j <= k {
            vol[j] = v;
        }
    }
    weight(chain, vol, &pass.set, VolumeTechnique::Connect(s), pass.h)
}

/// One side of a volumetric merge at x_i: its vertices (the side's x_i last), the free flight
/// of x_i → the side's vertex before walked back, the side's stored rates (per vertex of its
/// walk), σ̂ at the vertex before x_i of the flight from x_i (the other direction's), and σ̂ at
/// x_i of the side's own flight into it, sin θ at the vertex before x_i (its neighbours there:
/// its own vertex before and x_i; a walk's last vertex has none stored); for the light side,
/// next-event estimation's density of y_0 from y_1.
pub struct MergeSide<'a> {
    pub vertices: &'a [PathVertex],
    pub back: f64,
    pub rates: &'a [VertexRate],
    pub near_rate: f64,
    pub end_rate: f64,
    pub near_sin: f64,
    pub nee: f64,
}

impl<'a> MergeSide<'a> {
    /// A stored photon's side: light path `y` up to its vertex `i`, rates and flights as the
    /// light walk recorded them (PP3D and PB2D merge photons as stored).
    pub fn stored_photon(y: LightPath<'a>, i: usize) -> MergeSide<'a> {
        MergeSide {
            vertices: y.vertices,
            back: y.back_flight[i] as f64,
            rates: y.rates,
            near_rate: y.rates[i - 1].rate,
            end_rate: y.rates[i].light_rate,
            near_sin: y.rates[i - 1].sin,
            nee: y.nee,
        }
    }

    /// A photon beam's side at the merge point (`BeamEnd::at` filled `light_buf`).
    pub(super) fn at_beam_end<'s: 'a>(
        end: &BeamEnd<'s>,
        light_buf: &'a [PathVertex],
        p: &PassData,
    ) -> MergeSide<'a> {
        MergeSide {
            vertices: light_buf,
            back: end.back,
            rates: end.rates,
            near_rate: end.near_rate,
            end_rate: end.end_rate,
            near_sin: near_sin(light_buf, p.needs),
            nee: end.nee,
        }
    }
}

/// sin θ at the vertex before the last of `side` (0 when BB1D does not run, or it has no
/// vertex before it).
pub fn near_sin(side: &[PathVertex], needs: super::rates::Needs) -> f64 {
    let n = side.len();
    if needs.light && n >= 3 && side[n - 2].in_medium() {
        lt_core::path::volume_merging::sin_between(&side[n - 3], &side[n - 2], &side[n - 1])
    } else {
        0.0
    }
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
            light_buf: Vec::new(),
            first: None,
        }
    }

    /// Whether the techniques at camera vertex z_{t−1} run under the pass's mode: always
    /// (`Full`); once the walk passed its class vertex (`Compatible`); at it only (`Previous`).
    /// The weights give the others 0 anyway (`UpbpMode::counts`): this only spares their work.
    fn runs_at(&self, t: usize) -> bool {
        match (self.pass.set.mode, self.first) {
            (UpbpMode::Full, _) => true,
            (_, None | Some((_, false))) => false,
            (UpbpMode::Compatible, Some((m, true))) => m < t,
            (UpbpMode::Previous, Some((m, true))) => m == t - 1,
        }
    }

    /// Whether the camera beams along the segment leaving `prefix`'s last vertex run: their
    /// query points lie in a medium, so they are the class vertex when `prefix` is all delta.
    fn runs_along(&self, prefix: usize) -> bool {
        let all_delta = self.first.is_none_or(|(m, _)| m >= prefix);
        match self.pass.set.mode {
            UpbpMode::Full => true,
            UpbpMode::Compatible => all_delta || self.runs_at(prefix),
            UpbpMode::Previous => all_delta,
        }
    }

    /// The weight of a volumetric merge of light side `light` (y_0 … y_i) with camera side `cam`
    /// (z_0 …, its last the camera's x_i). The densities are `Densities::volume_merged`'s, the
    /// rates `VolumeRates::merged`'s.
    pub fn merge_weight(
        &self,
        scene: &Scene,
        light: MergeSide,
        cam: MergeSide,
        technique: VolumeTechnique,
    ) -> f64 {
        let (y_i, zx) = (
            &light.vertices[light.vertices.len() - 1],
            &cam.vertices[cam.vertices.len() - 1],
        );
        let medium = medium_of(zx).expect("a volumetric merge's camera side is a medium vertex");
        let phase = scene.media[medium as usize].phase();
        let pdfs = (phase.pdf(zx.wo, y_i.wo), phase.pdf(y_i.wo, zx.wo));
        self.merge_weight_with(scene, light, cam, technique, pdfs)
    }

    /// `merge_weight` with the camera side's x_i scattering densities given (solid angle): of
    /// ω_y given ω_z (the camera walk continuing towards y_{i−1}) and of ω_z given ω_y (the
    /// light walk continuing towards z_{t−2}) — the phase function's in a medium, the BSDF's
    /// (`BsdfEval::pdf_w`, `pdf_rev_w`) at a surface merge.
    pub fn merge_weight_with(
        &self,
        scene: &Scene,
        light: MergeSide,
        cam: MergeSide,
        technique: VolumeTechnique,
        (to_light, to_camera): (f32, f32),
    ) -> f64 {
        let (yv, zv) = (light.vertices, cam.vertices);
        let i = yv.len() - 1;
        let t = zv.len();
        let k = i + t - 1;
        // On the stack up to STACK vertices (every shipped depth), else on the heap.
        const STACK: usize = 33;
        let n = k + 1;
        let (mut l_st, mut c_st) = ([0.0f64; STACK], [0.0f64; STACK]);
        let (mut conn_st, mut vol_st) = ([false; STACK], [VertexRate::default(); STACK]);
        let (mut l_h, mut c_h, mut conn_h, mut vol_h);
        let (l, c, conn, vol): (&mut [f64], &mut [f64], &mut [bool], &mut [VertexRate]) =
            if n <= STACK {
                (
                    &mut l_st[..n],
                    &mut c_st[..n],
                    &mut conn_st[..n],
                    &mut vol_st[..n],
                )
            } else {
                l_h = vec![0.0f64; n];
                c_h = vec![0.0f64; n];
                conn_h = vec![false; n];
                vol_h = vec![VertexRate::default(); n];
                (&mut l_h, &mut c_h, &mut conn_h, &mut vol_h)
            };
        for j in 0..=k {
            if j <= i {
                l[j] = yv[j].pdf_fwd as f64;
            }
            if j + 2 <= i {
                c[j] = yv[j].pdf_rev as f64;
            }
            if j >= i {
                c[j] = zv[k - j].pdf_fwd as f64;
            }
            if j >= i + 2 {
                l[j] = zv[k - j].pdf_rev as f64;
            }
            conn[j] = match j.cmp(&i) {
                std::cmp::Ordering::Less => connectable_inside(scene, &yv[j]),
                std::cmp::Ordering::Equal => true,
                std::cmp::Ordering::Greater => connectable_inside(scene, &zv[k - j]),
            };
            vol[j] = match j.cmp(&i) {
                std::cmp::Ordering::Less => {
                    let mut v = light.rates[j];
                    if j + 1 == i {
                        v.rate = light.near_rate;
                        v.sin = light.near_sin;
                    }
                    v
                }
                std::cmp::Ordering::Equal if !zv[t - 1].in_medium() => VertexRate::default(),
                std::cmp::Ordering::Equal => {
                    let (u, w) = (yv[i].dir_to(&yv[i - 1]), zv[t - 1].dir_to(&zv[t - 2]));
                    let x = u.cross(w);
                    VertexRate {
                        medium: true,
                        rate: cam.end_rate,
                        light_rate: light.end_rate,
                        sin: (x.dot(x) as f64).sqrt(),
                    }
                }
                std::cmp::Ordering::Greater => {
                    let mut v = cam.rates.get(k - j).copied().unwrap_or_default();
                    if j == i + 1 {
                        v.light_rate = cam.near_rate;
                        v.sin = cam.near_sin;
                    }
                    v
                }
            };
        }
        let (y_i, zx) = (&yv[i], &zv[t - 1]);
        // c_{i−1}: the camera side's x_i sampling ω_y, in y_{i−1}'s measure from y_i.
        c[i - 1] = if i == 1 && yv[0].is_delta_light() {
            0.0
        } else {
            y_i.convert_density(to_light, &yv[i - 1]) as f64 * light.back
        };
        if i + 1 < k {
            l[i + 1] = zx.convert_density(to_camera, &zv[t - 2]) as f64 * cam.back;
        }
        c[k] = 1.0;
        l[k] = 0.0;
        let chain = Chain {
            light: l,
            camera: c,
            nee: light.nee,
            connectable: conn,
            light_tracing_ratio: self.pass.ratio,
        };
        let p = self.pass;
        weight(&chain, vol, &p.set, technique, p.h)
    }
}

impl<const MEDIA: bool> Policy<'_, MEDIA> {
    /// The camera side of a merge at the walk's last vertex z_{t−1} (`z`), its rates as walked.
    fn camera_side<'b>(&'b self, z: &'b [PathVertex]) -> MergeSide<'b> {
        let t = z.len();
        MergeSide {
            vertices: z,
            back: self.back_flight[t - 1] as f64,
            rates: &self.cam,
            near_rate: self.cam[t - 2].light_rate,
            end_rate: self.cam[t - 1].rate,
            near_sin: self.cam[t - 2].sin,
            nee: 0.0,
        }
    }

    /// vcm's surface merges at the camera walk's non-delta surface vertex z_{t−1} with the light
    /// subpaths' non-delta surface vertices y_i within r_S: β_z f(ω_z, ω_y)|cos| β_y / |n_y·ω_y|
    /// / (M π r_S²) each (the kernel and side tests of `density::surface_merge`, vcm's own).
    fn surface_merges<R: Recorder>(
        &self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let t = z.len();
        let zv = &z[t - 1];
        let Some(grid) = p.store.surface_grid.as_ref() else {
            return;
        };
        if t > p.max_k || t < 2 || !connectable(scene, zv) || zv.beta == Color::ZERO {
            return;
        }
        let Some(gather) = SurfaceGather::at(scene, zv) else {
            return;
        };
        let positions = &p.store.surface_positions;
        grid.for_each_within(positions, zv.p, p.r_beams, |idx, _| {
            let sr = p.store.surface[idx as usize];
            let i = sr.vertex as usize;
            if i + t - 1 > p.max_k {
                return;
            }
            let Some(ev) = gather.eval(sr.wi, sr.ng, sr.cos_g) else {
                return;
            };
            let y = p.store.up_to(sr.path, sr.vertex);
            let value = zv.beta * ev.f_cos * y.vertices[i].beta / sr.cos_g * p.surface_norm;
            let light = MergeSide::stored_photon(y, i);
            let technique = VolumeTechnique::Surface(i);
            let pdfs = (ev.pdf_w, ev.pdf_rev_w);
            let w = self.merge_weight_with(scene, light, self.camera_side(z), technique, pdfs);
            if R::ACTIVE {
                ctx.rec.volume_merged(VolumeMerged {
                    technique,
                    light: y.vertices,
                    camera: z,
                    weight: w,
                    value,
                    raster: ctx.raster,
                    radius: p.r_beams,
                });
            }
            *l += value * w as f32;
        });
    }
}

impl<const MEDIA: bool> Policy<'_, MEDIA> {
    /// BP2D at the camera walk's medium vertex z_{t−1}: the photon beams within r_B of it.
    fn beam_points<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let t = z.len();
        let zv = &z[t - 1];
        let Some(lb) = p.store.light_beams.as_ref() else {
            return;
        };
        let (Some(index), Some(m)) = (lb.index.as_ref(), medium_of(zv)) else {
            return;
        };
        if t > p.max_k || zv.beta == Color::ZERO {
            return;
        }
        let phase = scene.media[m as usize].phase();
        let frame = &index.lists.frame;
        // Every beam within the index's radius (≥ r_B) of z is listed in z's cell.
        let cell = frame.index(frame.cell_of(zv.p));
        let r2 = p.r_beams * p.r_beams;
        let mut light_buf = std::mem::take(&mut self.light_buf);
        for &bi in index.lists.items(cell) {
            let b = &lb.beams[bi as usize];
            let i = lb.refs[bi as usize].vertex as usize;
            if b.medium != m || i + t - 1 > p.max_k {
                continue;
            }
            let tb = (zv.p - b.origin).dot(b.dir);
            if !(tb >= 0.0 && tb < b.length) {
                continue;
            }
            if (zv.p - (b.origin + b.dir * tb)).length_squared() > r2 {
                continue;
            }
            let Some(end) = BeamEnd::at(scene, lb, p.store, (bi, tb), &mut light_buf) else {
                continue;
            };
            let value = zv.beta * phase.eval(zv.wo, -b.dir) * end.value * p.beam_point_norm;
            if value == Color::ZERO {
                continue;
            }
            let light = MergeSide::at_beam_end(&end, &light_buf, p);
            let technique = VolumeTechnique::BeamPoint(i);
            let w = self.merge_weight(scene, light, self.camera_side(z), technique);
            if R::ACTIVE {
                ctx.rec.volume_merged(VolumeMerged {
                    technique,
                    light: &light_buf,
                    camera: z,
                    weight: w,
                    value,
                    raster: ctx.raster,
                    radius: p.r_beams,
                });
            }
            *l += value * w as f32;
        }
        self.light_buf = light_buf;
    }
}

impl<const MEDIA: bool> CameraPolicy for Policy<'_, MEDIA> {
    const MEDIA: bool = MEDIA;

    fn camera_walk(&mut self, scene: &Scene, camera: &Subpath) {
        let z = &camera.vertices;
        let needs = self.pass.needs;
        self.cam.clear();
        self.cam
            .extend((0..z.len()).map(|j| camera_vertex(scene, z, j, needs)));
        self.back_flight.clear();
        self.back_flight
            .extend((0..z.len()).map(|j| camera.back_flight(j)));
        self.departure.clear();
        self.departure
            .extend((0..z.len()).map(|j| camera.departure(j)));
        self.exit = camera.exit;
        self.first = (1..z.len())
            .find(|&j| z[j].in_medium() || connectable_inside(scene, &z[j]))
            .map(|j| (j, z[j].in_medium()));
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
        let n = path.len();
        // x_1's rates towards x_0: the walk's own when it hit x_0 (a vertex of its walk); from a
        // light at infinity, found here.
        let mut ends = [(usize::MAX, VertexRate::default())];
        if n >= 2 && path[n - 1].is_infinite() && n - 2 < self.cam.len() {
            let (_, z) = junction(
                scene,
                (&path[n - 1..], &path[..n - 1]),
                (VertexRate::default(), self.cam[n - 2]),
                self.pass.needs,
            );
            ends[0] = (1, z);
        }
        let w = with_chain_in::<MEDIA, _>(scene, split, evals, self.pass.ratio, |chain, s| {
            connection_weight(self.pass, chain, s, (&[], &self.cam), &ends)
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
        let t = z.len();
        let (y, c) = junction(
            scene,
            (std::slice::from_ref(x0), z),
            (VertexRate::default(), self.cam[t - 1]),
            self.pass.needs,
        );
        let ends = [(0, y), (1, c)];
        let w = with_chain_in::<MEDIA, _>(scene, split, evals, self.pass.ratio, |chain, s| {
            connection_weight(self.pass, chain, s, (&[], &self.cam), &ends)
        });
        (w, None)
    }

    fn connects(&self) -> bool {
        self.pass.set.connections
    }

    fn connect<R: Recorder>(&mut self, scene: &Scene, joins: &mut Joins<'_, R>, _: &mut Sampler) {
        if !self.runs_at(joins.t()) {
            return;
        }
        let this = &*self;
        joins.join_subpath_in::<MEDIA>(scene, this.y, |c| {
            let (s, t) = (c.light.len(), c.camera.len());
            let (y, z) = junction(
                scene,
                (c.light, c.camera),
                (this.ly.rates[s - 1], this.cam[t - 1]),
                this.pass.needs,
            );
            let ends = [(s - 1, y), (s, z)];
            let (split, evals) = Split::connection(c, this.ly.nee);
            let w = with_chain_in::<MEDIA, _>(scene, split, evals, this.pass.ratio, |chain, s| {
                connection_weight(this.pass, chain, s, (this.ly.rates, &this.cam), &ends)
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
        if !self.runs_at(t) {
            return;
        }
        if !zv.in_medium() {
            if p.store.surface_grid.is_some() {
                self.surface_merges(scene, z, ctx, l);
                ctx.rec.lap(Work::Merge { t: t as u16 });
            }
            return;
        }
        if p.set.beam_points_eta > 0.0 {
            self.beam_points(scene, z, ctx, l);
            ctx.rec.lap(Work::VolumeMerge {
                family: VolumeFamily::Bp2d,
                t: t as u16,
            });
        }
        let (Some(grid), Some(m)) = (p.store.points.as_ref(), medium_of(zv)) else {
            return;
        };
        if p.set.points_eta == 0.0 || t > p.max_k || zv.beta == Color::ZERO {
            return;
        }
        let mm = &scene.media[m as usize];
        let phase = mm.phase();
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
            let light = MergeSide::stored_photon(y, i);
            let cam = MergeSide {
                vertices: z,
                back: self.back_flight[t - 1] as f64,
                rates: &self.cam,
                near_rate: self.cam[t - 2].light_rate,
                end_rate: self.cam[t - 1].rate,
                near_sin: self.cam[t - 2].sin,
                nee: 0.0,
            };
            let w = self.merge_weight(scene, light, cam, VolumeTechnique::Point(i));
            if R::ACTIVE {
                ctx.rec.volume_merged(VolumeMerged {
                    technique: VolumeTechnique::Point(i),
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
        ctx.rec.lap(Work::VolumeMerge {
            family: VolumeFamily::Pp3d,
            t: t as u16,
        });
    }

    fn along_segment<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        if !MEDIA || !self.runs_along(z.len() - 1) {
            return;
        }
        let t = z.len();
        let (a, b) = (&z[t - 2], &z[t - 1]);
        let leave = self.departure[t - 1];
        self.camera_beam(scene, &z[..t - 1], (a.dir_to(b), b.into()), leave, ctx, l);
    }

    fn after_walk<R: Recorder>(
        &mut self,
        scene: &Scene,
        z: &[PathVertex],
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let Some(exit) = self.exit.filter(|_| MEDIA && self.runs_along(z.len())) else {
            return;
        };
        let far = ConnectionEnd {
            p: exit.dir,
            p_err: Vec3::ZERO,
            ng: Vec3::ZERO,
            infinite: true,
        };
        self.camera_beam(scene, z, (exit.dir, far), exit.leave, ctx, l);
    }
}
