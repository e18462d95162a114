//! Photon beams (Jarosz, Nowrouzezahrai, Sadeghi & Jensen 2011): the flights of the light
//! subpaths through media, each kept whole — a *long* beam from where the flight starts to the
//! next surface, with the throughput β at its start; the transmittance along it is evaluated
//! inside the estimate (`beam_beam.rs`), not sampled. Only flights in media are kept, so a scene
//! without media stores none.
//!
//! **Why a beam carries what the photon points of the same flight carry.** `photons.rs`'s walk
//! samples a scattering on the flight at density p(t) and stores power β T(t)/p(t) there (σs
//! left out); for any g, E[power · g(x_t)] = β ∫ T(t) g(x_t) dt, which is what the beam gives
//! deterministically. The walk goes on from the sampled scattering as before, so a flight is a
//! beam for the paths whose light vertex lies on it and a prefix for the later flights' beams:
//! each path counted once, as with points.
//!
//! **The index.** A uniform grid (`cell_frame.rs`) of cells ≥ 2r, each beam listed in every cell
//! within r of its segment (per cell its segment crosses, the cells of the bounding box of the
//! segment's piece in that cell grown by r: at most 2 per axis). A camera beam walks the
//! grid and counts a photon beam only in the cell whose t interval holds its closest point
//! (`beam_beam.rs`), which lies within r of the photon beam, so the photon beam is listed there.

use super::cell_frame::{CellFrame, CellLists};
use super::photons::{LightRecord, PhotonData};
use lt_core::geometry::Ray;
use lt_core::math::{Color, Vec3};
use lt_core::medium::MediumId;
use lt_core::Scene;

/// One photon beam: 12 + 12 + 4 + 12 + 4 + 4 = 48 bytes.
#[derive(Clone, Copy, Debug)]
pub struct PhotonBeam {
    pub origin: Vec3,
    /// Unit direction of the light's travel.
    pub dir: Vec3,
    /// The flight's length to the next surface (an unbounded flight is cut where it leaves the
    /// scene's bounding sphere: no camera beam meets it beyond).
    pub length: f32,
    /// Throughput at the start of the flight, scaled by 1 / photon paths.
    pub power: Color,
    pub medium: MediumId,
    /// The index of the light vertex on this flight (segments from the light to it).
    pub segments: u32,
}

/// One pass's photon beams, in the order of their paths (then along each path).
#[derive(Default)]
pub struct PhotonBeams {
    pub beams: Vec<PhotonBeam>,
}

impl PhotonBeams {
    pub const BYTES_PER_BEAM: usize = std::mem::size_of::<PhotonBeam>();

    /// Traces `paths` light subpaths of pass `pass` as `photons::trace` does (same streams, same
    /// walks) and keeps their flights through media.
    pub fn trace(
        scene: &Scene,
        max_depth: u32,
        rr_depth: u32,
        paths: u64,
        seed: u64,
        pass: u32,
    ) -> PhotonBeams {
        let mut beams: PhotonBeams =
            super::photons::trace_records(scene, max_depth, rr_depth, paths, seed, pass);
        let (c, r) = scene.bounding_sphere;
        for b in &mut beams.beams {
            if !b.length.is_finite() {
                b.length = sphere_exit(b.origin, b.dir, c, r.max(1e-3));
            }
        }
        beams.beams.retain(|b| b.length > 0.0);
        beams
    }
}

/// Where a ray from `o` along unit `d` leaves the sphere (c, r); 0 if it never is inside.
pub fn sphere_exit(o: Vec3, d: Vec3, c: Vec3, r: f32) -> f32 {
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    if disc < 0.0 {
        return 0.0;
    }
    (-b + disc.sqrt()).max(0.0)
}

impl LightRecord for PhotonBeams {
    fn flight(&mut self, ray: &Ray, t_max: f32, m: MediumId, beta: Color, n: u32) {
        if beta == Color::ZERO {
            return;
        }
        // Unit direction, the length in the same units (t is in units of |d|).
        let speed = ray.d.length();
        self.beams.push(PhotonBeam {
            origin: ray.o,
            dir: ray.d / speed,
            length: t_max * speed,
            power: beta,
            medium: m,
            segments: n,
        });
    }

    fn scatter(&mut self, _x: Vec3, _photon: PhotonData) {}

    fn append(&mut self, other: Self) {
        self.beams.extend(other.beams);
    }
}

/// The grid's longest side in cells at most. A beam is listed in ~4 cells per cell it crosses,
/// so memory grows with this; 64 keeps a pass of 10⁴ beams near 10 MB.
const MAX_CELLS_PER_AXIS: f32 = 64.0;

/// Photon beams' radius-r capsules in a uniform grid, for camera-beam queries.
pub struct BeamIndex {
    pub lists: CellLists,
}

impl BeamIndex {
    pub fn build(beams: &[PhotonBeam], r: f32) -> Option<BeamIndex> {
        if beams.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for b in beams {
            let end = b.origin + b.dir * b.length;
            lo = lo.min(b.origin).min(end);
            hi = hi.max(b.origin).max(end);
        }
        // A margin past r: DDA boundaries carry rounding, and closest points must stay inside.
        let margin = Vec3::splat(r * 1.01 + 1e-4 * (hi - lo).max_element());
        let frame = CellFrame::new(lo - margin, hi + margin, 2.0 * r, MAX_CELLS_PER_AXIS);
        // Every point within r of the beam lies within r of the piece of the beam in some cell
        // the beam crosses: the cells of that piece's bounding box grown by r (with slack for
        // rounding) hold them all, at most 2 per axis as cells are ≥ 2r.
        let reach = Vec3::splat(r * 1.01 + 1e-5 * frame.cell);
        let mut stamp = vec![u32::MAX; frame.cell_count()];
        let mut call = 0u32;
        let lists = CellLists::build(frame, beams.len(), |i, emit| {
            // Each call marks its cells with its own number: a cell is emitted once per call.
            call += 1;
            let b = &beams[i];
            let ray = Ray::new(b.origin, b.dir);
            frame.for_cells_along(&ray, b.length, |_, _, t_lo, t_hi| {
                let p0 = b.origin + b.dir * t_lo;
                let p1 = b.origin + b.dir * t_hi.min(b.length);
                frame.for_cells_of_box(p0.min(p1) - reach, p0.max(p1) + reach, |cell| {
                    if stamp[cell] != call {
                        stamp[cell] = call;
                        emit(cell);
                    }
                });
            });
        });
        Some(BeamIndex { lists })
    }

    /// Bytes held by the index (not the beams): 4 per entry and per cell.
    pub fn bytes(&self) -> usize {
        self.lists.bytes()
    }
}

/// Which kernel a photon-beam query gathers with: at the camera walk's first medium vertex, 2-D
/// across each beam (`bp2d`: `point_beam.rs`), or along the camera's flight, 1-D across the two
/// lines (`bb1d`: `beam_beam.rs`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BeamKernel {
    /// 1/(π r²) over the disk across a beam.
    Point2d,
    /// 1/(2r) over the lines' separation.
    Line1d,
}

/// One pass's photon beams indexed for queries at radius `r` with `kernel` (`bp2d`, `bb1d`).
pub struct BeamQuery<'a> {
    pub scene: &'a Scene,
    pub beams: &'a PhotonBeams,
    pub index: Option<BeamIndex>,
    pub r: f32,
    pub kernel: BeamKernel,
    /// The kernel's normalisation: 1/(π r²) or 1/(2r).
    pub norm: f32,
    pub max_depth: u32,
}

impl<'a> BeamQuery<'a> {
    pub fn new(
        scene: &'a Scene,
        beams: &'a PhotonBeams,
        (r, kernel): (f32, BeamKernel),
        max_depth: u32,
    ) -> BeamQuery<'a> {
        let norm = match kernel {
            BeamKernel::Point2d => 1.0 / (std::f32::consts::PI * r * r),
            BeamKernel::Line1d => 1.0 / (2.0 * r),
        };
        BeamQuery {
            scene,
            beams,
            index: BeamIndex::build(&beams.beams, r),
            r,
            kernel,
            norm,
            max_depth,
        }
    }
}
