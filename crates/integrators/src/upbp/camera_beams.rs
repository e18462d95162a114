//! `upbp`'s techniques along a camera segment, a **short camera beam**: the segment the walk
//! sampled, z_{t−2} → z_{t−1} (or to infinity when it left the scene), left with throughput
//! β_leave (`Subpath::departure`). The beam covers a point x at distance s with the probability
//! P_pass(s) that the walk's flight passes it, and T is evaluated there (deterministic), so its
//! value at x is β_leave T(s) / P_pass(s). Per medium piece of the segment
//! (`Scene::for_each_medium_piece`):
//!
//! - **PB2D**: each photon y_i of the piece's medium within r_B of it, x its projection on the
//!   beam, contributes β_leave T/P_pass · σs(x) f_p(−ω, ω_y) · (β_y / σs(y_i)) / (N π r_B²);
//! - **BB1D**: each photon beam b (`light_beams`: the light walk's segment y_{i−1} → y_i, value
//!   Φ_b T_b(t) / P_pass,b(t) at t along it) whose line passes within r_BB of the camera beam's,
//!   at the closest points x (camera, at s) and x' (photon beam, at t), both inside their
//!   beams, contributes
//!   β_leave T/P_pass · σs(x) f_p(−ω, −ω_b) · Φ_b T_b/P_pass,b · 1 / (N 2 r_BB sin θ)
//!   (Jarosz et al. 2011's beam × beam estimate, as `volume_density::beam_beam`; the path's
//!   density in `lt_core::path::volume_merging`).
//!
//! Each merged path is weighed with its two x_i: the camera side ends at x (a medium vertex
//! with the walk's density of reaching it, scattering there), the light side at the photon or
//! at x' (likewise, from y_{i−1}).

use super::beam_end::BeamEnd;
use super::light_beams::Back;
use super::policy::{medium_of, near_sin, without_sigma_s, MergeSide, Policy};
use super::rates::Needs;
use super::weights::VertexRate;
use crate::record::{Recorder, VolumeFamily, VolumeMerged, Work};
use crate::subpath::camera_loop::SampleCtx;
use crate::subpath::walk::Departure;
use crate::volume_density::beam_beam::closest_points;
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::Medium;
use lt_core::path::{PathVertex, VolumeTechnique};
use lt_core::scene::{ConnectionEnd, Crossing, MediumPiece};
use lt_core::Scene;

/// One medium piece of a camera beam: from `a` (at distance 0 of the piece) along the beam's
/// direction for `len`, with T and P_pass of the segment's pieces before it and the flight back
/// to the segment's start.
struct Piece<'m> {
    m: u32,
    mm: &'m Medium,
    a: Vec3,
    len: f32,
    t_before: Color,
    p_before: f32,
    back: Back,
}

/// The camera side's end at distance `s` of `piece`: the beam's value there (β_leave T/P_pass),
/// its vertex x (walk densities of reaching it), σ̂ of the beam's flight at x, and the flight
/// back from x to the beam's start with σ̂ there (`Back::at`).
struct CameraPoint {
    value: Color,
    vertex: PathVertex,
    rate: f64,
    back: (f64, f64),
}

impl CameraPoint {
    /// The camera's side of a merge at this point: `vertices` the camera subpath ending in it.
    fn side<'a>(
        &self,
        vertices: &'a [PathVertex],
        rates: &'a [VertexRate],
        needs: Needs,
    ) -> MergeSide<'a> {
        let (back, near_rate) = self.back;
        MergeSide {
            vertices,
            back,
            rates,
            near_rate,
            end_rate: self.rate,
            near_sin: near_sin(vertices, needs),
            nee: 0.0,
        }
    }
}

impl<const MEDIA: bool> Policy<'_, MEDIA> {
    /// PB2D and BB1D along the segment from `prefix`'s last vertex in direction `dir` up to
    /// `end`, left with `leave`.
    pub(super) fn camera_beam<R: Recorder>(
        &mut self,
        scene: &Scene,
        prefix: &[PathVertex],
        (dir, end): (Vec3, ConnectionEnd),
        leave: Departure,
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let points = p.store.beams.is_some() && p.set.beams_eta > 0.0;
        let beams = p
            .store
            .light_beams
            .as_ref()
            .is_some_and(|b| b.index.is_some())
            && p.set.beam_beams_eta > 0.0;
        if !(points || beams) || prefix.len() >= p.max_k || leave.beta == Color::ZERO {
            return;
        }
        let o = &prefix[prefix.len() - 1];
        let mut pieces: Vec<MediumPiece> = Vec::new();
        let m0 = o.medium_towards(scene, dir);
        scene.for_each_medium_piece(o.into(), end, m0, Crossing::Everything, |piece| {
            pieces.push(piece)
        });
        let (mut t_before, mut p_before) = (Color::ONE, 1.0f32);
        let mut back = Back::start(o.in_medium());
        for piece in pieces {
            let Some(m) = piece.medium else {
                back = back.after(None, piece.a, piece.b);
                continue;
            };
            let mm = &scene.media[m as usize];
            let len = (piece.b - piece.a).length();
            if len > 0.0 && p_before > 0.0 {
                let pc = Piece {
                    m,
                    mm,
                    a: piece.a,
                    len,
                    t_before,
                    p_before,
                    back,
                };
                // The camera side of a merge on this segment: the prefix and the query point.
                let t = prefix.len() as u16 + 1;
                if points {
                    self.photons_near(scene, prefix, (&pc, dir), leave, ctx, l);
                    let family = VolumeFamily::Pb2d;
                    ctx.rec.lap(Work::VolumeMerge { family, t });
                }
                if beams {
                    self.beams_near(scene, prefix, (&pc, dir), leave, ctx, l);
                    let family = VolumeFamily::Bb1d;
                    ctx.rec.lap(Work::VolumeMerge { family, t });
                }
            }
            back = back.after(Some(mm), piece.a, piece.b);
            t_before *= mm.transmittance(piece.a, piece.b);
            p_before *= mm.free_flight_density(piece.a, piece.b, false);
        }
    }

    /// The camera beam's end at distance `s` of `piece` (`None` where it cannot pass or
    /// scatter there).
    fn camera_point(
        piece: &Piece,
        (o, dir, s): (&PathVertex, Vec3, f32),
        leave: Departure,
        needs: Needs,
    ) -> Option<CameraPoint> {
        let x = piece.a + dir * s;
        let pass = piece.p_before * piece.mm.free_flight_density(piece.a, x, false);
        let scatter = piece.p_before * piece.mm.free_flight_density(piece.a, x, true);
        if !(pass > 0.0 && scatter > 0.0) {
            return None;
        }
        let tr = piece.t_before * piece.mm.transmittance(piece.a, x);
        let value = leave.beta * tr / pass;
        let vertex = PathVertex::medium(piece.m, x, -dir, value, leave.pdf_w, scatter, o);
        Some(CameraPoint {
            value,
            vertex,
            rate: (scatter / pass) as f64,
            back: piece.back.at(piece.mm, x, piece.a, needs.long),
        })
    }

    /// PB2D: the photons within r_B of `piece`.
    fn photons_near<R: Recorder>(
        &mut self,
        scene: &Scene,
        prefix: &[PathVertex],
        (piece, dir): (&Piece, Vec3),
        leave: Departure,
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let Some(grid) = p.store.beams.as_ref() else {
            return;
        };
        let o = &prefix[prefix.len() - 1];
        let t = prefix.len() + 1;
        let phase = piece.mm.phase();
        let r2 = p.r_beams * p.r_beams;
        let ray = Ray::new(piece.a, dir);
        let mut buf = std::mem::take(&mut self.buf);
        grid.for_each_along(&ray, piece.len, |idx, t_lo, t_hi| {
            let ph = p.store.photons[idx as usize];
            let i = ph.vertex as usize;
            if i + prefix.len() > p.max_k {
                return;
            }
            let y = p.store.photon(ph);
            let yv = &y.vertices[i];
            if medium_of(yv) != Some(piece.m) {
                return;
            }
            let to = p.store.photon_positions[idx as usize] - piece.a;
            let s = to.dot(dir);
            if !(s >= t_lo && s < t_hi && s < piece.len) {
                return;
            }
            if (to - dir * s).length_squared() > r2 {
                return;
            }
            let Some(cp) = Self::camera_point(piece, (o, dir, s), leave, p.needs) else {
                return;
            };
            let x = cp.vertex.p;
            let power = without_sigma_s(yv.beta, piece.mm.sigma_s(yv.p));
            let value =
                cp.value * piece.mm.sigma_s(x) * phase.eval(-dir, yv.wo) * power * p.beam_norm;
            if value == Color::ZERO {
                return;
            }
            buf.clear();
            buf.extend_from_slice(prefix);
            buf.push(cp.vertex);
            let light = MergeSide::stored_photon(y, i);
            let cam = cp.side(&buf, &self.cam, p.needs);
            let technique = VolumeTechnique::Beam(i);
            let w = self.merge_weight(scene, light, cam, technique);
            debug_assert_eq!(buf.len(), t);
            if R::ACTIVE {
                ctx.rec.volume_merged(VolumeMerged {
                    technique,
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
        self.buf = buf;
    }

    /// BB1D: the photon beams within r_BB of `piece`.
    fn beams_near<R: Recorder>(
        &mut self,
        scene: &Scene,
        prefix: &[PathVertex],
        (piece, dir): (&Piece, Vec3),
        leave: Departure,
        ctx: &mut SampleCtx<'_, R>,
        l: &mut Color,
    ) {
        let p = self.pass;
        let Some(lb) = p.store.light_beams.as_ref() else {
            return;
        };
        let Some(index) = lb.index.as_ref() else {
            return;
        };
        let o = &prefix[prefix.len() - 1];
        let phase = piece.mm.phase();
        let r = p.r_beam_beams;
        let ray = Ray::new(piece.a, dir);
        let mut buf = std::mem::take(&mut self.buf);
        let mut light_buf = std::mem::take(&mut self.light_buf);
        index
            .lists
            .frame
            .for_cells_along(&ray, piece.len, |cell, _, t_lo, t_hi| {
                for &bi in index.lists.items(cell) {
                    let b = &lb.beams[bi as usize];
                    let src = lb.refs[bi as usize];
                    let i = src.vertex as usize;
                    if b.medium != piece.m || i + prefix.len() > p.max_k {
                        continue;
                    }
                    let Some((s, tb, u, sin)) = closest_points(piece.a, dir, b.origin, b.dir)
                    else {
                        continue;
                    };
                    // Counted in the one cell whose interval holds s (each beam once).
                    if !(s >= t_lo && s < t_hi && s < piece.len && tb >= 0.0 && tb < b.length) {
                        continue;
                    }
                    if u > r {
                        continue;
                    }
                    let Some(cp) = Self::camera_point(piece, (o, dir, s), leave, p.needs) else {
                        continue;
                    };
                    let Some(end) = BeamEnd::at(scene, lb, p.store, (bi, tb), &mut light_buf)
                    else {
                        continue;
                    };
                    let x = cp.vertex.p;
                    let value = cp.value
                        * piece.mm.sigma_s(x)
                        * phase.eval(-dir, -b.dir)
                        * end.value
                        * (p.beam_beam_norm / sin);
                    if value == Color::ZERO {
                        continue;
                    }
                    buf.clear();
                    buf.extend_from_slice(prefix);
                    buf.push(cp.vertex);
                    let light = MergeSide::at_beam_end(&end, &light_buf, p);
                    let cam = cp.side(&buf, &self.cam, p.needs);
                    let technique = VolumeTechnique::BeamBeam(i);
                    let w = self.merge_weight(scene, light, cam, technique);
                    if R::ACTIVE {
                        ctx.rec.volume_merged(VolumeMerged {
                            technique,
                            light: &light_buf,
                            camera: &buf,
                            weight: w,
                            value,
                            raster: ctx.raster,
                            radius: r,
                        });
                    }
                    *l += value * w as f32;
                }
            });
        self.buf = buf;
        self.light_buf = light_buf;
    }
}
