//! A pass's photon beams for `upbp`'s BB1D: each light subpath's segments through media as
//! **short** beams, y_{i−1} → y_i (the flight the light walk sampled, ending where it scattered
//! or met a surface), and the segment that left the scene (cut at the scene's bounding sphere).
//! A short beam covers a point at distance t with the probability P_pass(t) that the walk's flight
//! passes it, so its value there is β_leave T(t) / P_pass(t) (T evaluated, deterministic; the
//! expectation over the sampled flight is β_leave T(t)). One beam per medium piece of the segment
//! (`Scene::for_each_medium_piece`), carrying T and P_pass of the pieces before it.
//! (As PB2D's camera beams, a thin dielectric pane passed inside a segment is left out of
//! P_pass: no shipped media scene has one.)
//!
//! **Long** beams (`beams=long`, SmallUPBP's long photon beams): the segment's beam runs on past
//! a medium vertex y_i to the next surface that is not a null boundary (or out of the scene),
//! whatever the free flight sampled, so it covers every point of the flight with probability 1
//! and its value there is β_leave T(t) (no 1/P_pass). The light walk still goes on from the
//! y_i it sampled; the merges' weights read the flight's whole scattering density as σ̂ᴸ
//! (`lt_core::path::volume_merging::flight_rate`).

use crate::subpath::walk::Subpath;
use crate::volume_density::photon_beams::{sphere_exit, BeamIndex, PhotonBeam};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::path::PathVertex;
use lt_core::scene::{ConnectionEnd, Crossing, MediumPiece};
use lt_core::Scene;

/// Where a photon beam came from: light subpath `path`'s segment into vertex `vertex` (= its
/// length when the segment left the scene), the pass probability of the segment's pieces
/// before this one, and the direction density with which y_{vertex−1} chose the segment; and
/// for the flight from a point of the beam back to y_{vertex−1} (a merge's weight reads it), the
/// reverse densities of those pieces (`back`) and where it ends (`Back`).
#[derive(Clone, Copy, Debug)]
pub struct BeamRef {
    pub path: u32,
    pub vertex: u32,
    pub p_before: f32,
    pub pdf_w: f32,
    pub back: Back,
}

/// The flight from a point of a beam piece back to the segment's start, walked over the pieces
/// found when the segment was (as the walks' `Flight` does): the product of the reverse
/// densities of the pieces before this one, whether this piece is the first (the reverse walk
/// scatters at its start when that is a medium vertex), and σ̂ of the reverse walk at the start
/// when it ends in another piece (`first_rate`, 0 when the start lies on no medium).
#[derive(Clone, Copy, Debug, Default)]
pub struct Back {
    pub before: f32,
    pub first: bool,
    pub start_in_medium: bool,
    pub first_rate: f32,
}

impl Back {
    /// The reverse flight from `x` (in this piece of medium `mm`, starting at `a`) to the
    /// segment's start, and its rate there (0 at a surface or the camera): σ̂, or with `long` (a
    /// long photon beam's σ̂ᴸ, `flight_rate`) the reverse flight's whole scattering density —
    /// the first value itself.
    pub fn at(&self, mm: &lt_core::medium::Medium, x: Vec3, a: Vec3, long: bool) -> (f64, f64) {
        let scatter = self.first && self.start_in_medium;
        let d = mm.free_flight_density(x, a, scatter);
        let rate = if !self.start_in_medium {
            0.0
        } else if long {
            (self.before * d) as f64
        } else if self.first {
            let pass = mm.free_flight_density(x, a, false);
            if pass > 0.0 {
                (d / pass) as f64
            } else {
                0.0
            }
        } else {
            self.first_rate as f64
        };
        ((self.before * d) as f64, rate)
    }

    /// The state for the next piece after the piece a → b of medium `mm` (`None`: vacuum).
    pub fn after(self, mm: Option<&lt_core::medium::Medium>, a: Vec3, b: Vec3) -> Back {
        let mut next = Back {
            first: false,
            ..self
        };
        if let Some(mm) = mm {
            let scatter = self.first && self.start_in_medium;
            next.before *= mm.free_flight_density(b, a, scatter);
            if scatter {
                let pass = mm.free_flight_density(b, a, false);
                next.first_rate = if pass > 0.0 {
                    mm.free_flight_density(b, a, true) / pass
                } else {
                    0.0
                };
            }
        }
        next
    }

    pub fn start(start_in_medium: bool) -> Back {
        Back {
            before: 1.0,
            first: true,
            start_in_medium,
            first_rate: 0.0,
        }
    }
}

/// The beams (`PhotonBeam::power` = β_leave T_before / P_before at the piece's start, or
/// β_leave T_before when `long`) and their sources, in path order.
#[derive(Default)]
pub struct LightBeams {
    pub beams: Vec<PhotonBeam>,
    pub refs: Vec<BeamRef>,
    pub index: Option<BeamIndex>,
    /// Long beams (module doc): no 1/P_pass in their values.
    pub long: bool,
}

/// Shapes a long beam passes before it meets a surface at most (null boundaries: a medium's
/// shell and its nesting).
const MAX_NULL_CROSSINGS: usize = 64;

/// The end of a long beam leaving medium vertex `x` along `dir`: the first surface that is not a
/// null boundary, or the far end at infinity.
fn next_surface(scene: &Scene, x: Vec3, dir: Vec3) -> ConnectionEnd {
    let mut ray = Ray::new(x, dir);
    for _ in 0..MAX_NULL_CROSSINGS {
        let Some(hit) = scene.intersect(&ray) else {
            break;
        };
        if !scene.shapes[hit.shape as usize].null {
            return ConnectionEnd {
                p: hit.p,
                p_err: hit.p_err,
                ng: hit.ng,
                infinite: false,
            };
        }
        ray = hit.spawn_ray(dir);
    }
    ConnectionEnd {
        p: dir,
        p_err: Vec3::ZERO,
        ng: Vec3::ZERO,
        infinite: true,
    }
}

impl LightBeams {
    /// Appends light subpath `path`'s beams (`sub`, as walked).
    pub fn add_path(&mut self, scene: &Scene, path: u32, sub: &Subpath) {
        let y = &sub.vertices;
        for i in 1..=y.len() {
            let (end, dir, leave) = if i < y.len() {
                let dir = y[i - 1].dir_to(&y[i]);
                let e: ConnectionEnd = if self.long && y[i].in_medium() {
                    next_surface(scene, y[i].p, dir)
                } else {
                    (&y[i]).into()
                };
                (e, dir, sub.departure(i))
            } else if let Some(exit) = sub.exit {
                let far = ConnectionEnd {
                    p: exit.dir,
                    p_err: Vec3::ZERO,
                    ng: Vec3::ZERO,
                    infinite: true,
                };
                (far, exit.dir, exit.leave)
            } else {
                break;
            };
            if leave.beta == Color::ZERO {
                continue;
            }
            self.add_segment(scene, (path, i as u32), &y[i - 1], (end, dir), leave);
        }
    }

    fn add_segment(
        &mut self,
        scene: &Scene,
        (path, vertex): (u32, u32),
        from: &PathVertex,
        (end, dir): (ConnectionEnd, Vec3),
        leave: crate::subpath::walk::Departure,
    ) {
        let mut pieces: Vec<MediumPiece> = Vec::new();
        let m0 = from.medium_towards(scene, dir);
        scene.for_each_medium_piece(from.into(), end, m0, Crossing::Everything, |piece| {
            pieces.push(piece)
        });
        let (c, r) = scene.bounding_sphere;
        let (mut t_before, mut p_before) = (Color::ONE, 1.0f32);
        let mut back = Back::start(from.in_medium());
        for piece in pieces {
            let Some(m) = piece.medium else {
                back = back.after(None, piece.a, piece.b);
                continue;
            };
            let mm = &scene.media[m as usize];
            let mut length = (piece.b - piece.a).length();
            if end.infinite {
                length = length.min(sphere_exit(piece.a, dir, c, r.max(1e-3)));
            }
            if length > 0.0 && p_before > 0.0 {
                let cover = if self.long { 1.0 } else { p_before };
                self.beams.push(PhotonBeam {
                    origin: piece.a,
                    dir,
                    length,
                    power: leave.beta * t_before / cover,
                    medium: m,
                    segments: vertex,
                });
                self.refs.push(BeamRef {
                    path,
                    vertex,
                    p_before,
                    pdf_w: leave.pdf_w,
                    back,
                });
            }
            back = back.after(Some(mm), piece.a, piece.b);
            t_before *= mm.transmittance(piece.a, piece.b);
            p_before *= mm.free_flight_density(piece.a, piece.b, false);
        }
    }

    pub fn append(&mut self, other: LightBeams) {
        self.beams.extend(other.beams);
        self.refs.extend(other.refs);
    }

    /// Indexes the beams for camera-beam queries at radius `r`.
    pub fn build_index(&mut self, r: f32) {
        self.index = BeamIndex::build(&self.beams, r);
    }

    /// Bytes held: the beams, their sources and the index.
    pub fn bytes(&self) -> usize {
        self.beams.len() * (std::mem::size_of::<PhotonBeam>() + std::mem::size_of::<BeamRef>())
            + self.index.as_ref().map_or(0, |i| i.bytes())
    }
}
