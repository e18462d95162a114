//! What an integrator can report about the paths it completes, for `lt mis-check`: the path's
//! vertices and the MIS weight it gave the technique that made it. Rendering passes `NoRecord`,
//! which compiles to nothing. The recorders that tally each technique's contributions and time
//! live beside it: `tally` (per pass), `tally_run` (a run), `cpu_clock` (the time-stamp counter).

pub mod cpu_clock;
pub mod tally;
pub mod tally_run;

use lt_core::math::{Color, Vec2};
use lt_core::path::camis::Mixture;
use lt_core::path::PathVertex;

/// One completed path: x0 (light end) first, xk (camera) last, as `lt_core::path::Path` wants.
pub struct Completed<'a> {
    /// Technique s (vertices taken from the light side) that produced it.
    pub s: usize,
    /// The light-side prefix x0 … x_{s−1} (for s = 0, the emitter vertex the camera walk hit).
    pub light: &'a [PathVertex],
    /// The camera-side prefix, camera first: x_k … x_s.
    pub camera: &'a [PathVertex],
    /// The weight the integrator applied.
    pub weight: f64,
    /// The unweighted contribution to the image (the weight is applied on top of it), already
    /// normalised as the integrator adds it: per-pixel units, light tracing divided by M.
    pub value: Color,
    /// Where on the film it lands.
    pub raster: Vec2,
    /// The weights the integrator's own code gives the same path under each of the other
    /// techniques it runs, as (s, weight); empty when it computes none.
    pub alternatives: &'a [(usize, f64)],
}

/// One path completed by vertex merging (`vcm`, `bpm`): a light vertex y_i found within the
/// radius of camera vertex z_{t−1}, which stands for x_i.
pub struct Merged<'a> {
    /// The merging vertex x_i (1 ≤ i ≤ k − 1).
    pub i: usize,
    /// The light subpath y_0 … y_i, the merged light vertex last.
    pub light: &'a [PathVertex],
    /// The camera subpath, camera first: x_k … x_i (its last vertex is the merge point).
    pub camera: &'a [PathVertex],
    /// The weight the integrator applied.
    pub weight: f64,
    /// The unweighted contribution, normalised as added (kernel, 1/(N_VM π r²) included).
    pub value: Color,
    pub raster: Vec2,
    /// The merging radius of the pass.
    pub radius: f32,
}

/// One path completed by a volumetric merge (`upbp`): a light medium vertex y_i found within the
/// radius of the camera walk's medium vertex (PP3D) or of its segment (PB2D, the query point on
/// the segment standing for the camera side's x_i).
pub struct VolumeMerged<'a> {
    /// PP3D, PB2D or BB1D at the merging vertex x_i (1 ≤ i ≤ k − 1).
    pub technique: lt_core::path::VolumeTechnique,
    /// The light subpath y_0 … y_i, the merged photon (or the photon beam's point) last.
    pub light: &'a [PathVertex],
    /// The camera side, camera first: x_k … x_i (the medium vertex, or the beam's query point).
    pub camera: &'a [PathVertex],
    pub weight: f64,
    /// The unweighted contribution, normalised as added (kernel and 1/N included).
    pub value: Color,
    pub raster: Vec2,
    /// The kernel's radius in this pass.
    pub radius: f32,
}

/// What one stretch of a work item's time went to, for `crate::record::tally` (per-technique cost): the
/// code since the previous lap. Connections are keyed as `Completed` paths are — s light
/// vertices, t camera vertices, k = s + t − 1 segments (s = 0 at a camera walk of k + 1 vertices
/// whose end is the emitter) — merges by the camera vertex count t (every light length at once,
/// as one range query serves them all).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Work {
    /// Tracing the light subpath (and forming its MIS records, for `vcm`).
    LightWalk,
    /// The camera sample: film position, camera subpath, its MIS records.
    CameraWalk,
    Connection {
        s: u16,
        t: u16,
    },
    Merge {
        t: u16,
    },
    /// A volumetric merge (`upbp`) whose camera side has t vertices, the query point or medium
    /// vertex x_i last: PP3D and BP2D at the camera walk's medium vertex z_{t−1}, PB2D and BB1D
    /// along the camera segment ending at z_{t−1}. Surface merges inside upbp are `Merge`.
    VolumeMerge {
        family: VolumeFamily,
        t: u16,
    },
}

/// upbp's volumetric technique families, by their SmallUPBP names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum VolumeFamily {
    /// Photon points × camera points (3-D kernel).
    Pp3d,
    /// Photon points × camera beams (2-D kernel).
    Pb2d,
    /// Photon beams × camera points (2-D kernel).
    Bp2d,
    /// Photon beams × camera beams (1-D kernel).
    Bb1d,
}

impl VolumeFamily {
    pub const ALL: [VolumeFamily; 4] = [
        VolumeFamily::Pp3d,
        VolumeFamily::Pb2d,
        VolumeFamily::Bp2d,
        VolumeFamily::Bb1d,
    ];

    /// The lower-case name the tables and `--set techniques=` use.
    pub fn name(self) -> &'static str {
        match self {
            VolumeFamily::Pp3d => "pp3d",
            VolumeFamily::Pb2d => "pb2d",
            VolumeFamily::Bp2d => "bp2d",
            VolumeFamily::Bb1d => "bb1d",
        }
    }

    /// The work a volumetric merge of `technique` with a camera side of `t` vertices is:
    /// `None` for a connection (not a merge).
    pub fn work_of(technique: lt_core::path::VolumeTechnique, t: u16) -> Option<Work> {
        use lt_core::path::VolumeTechnique as V;
        let family = match technique {
            V::Point(_) => VolumeFamily::Pp3d,
            V::Beam(_) => VolumeFamily::Pb2d,
            V::BeamPoint(_) => VolumeFamily::Bp2d,
            V::BeamBeam(_) => VolumeFamily::Bb1d,
            V::Surface(_) => return Some(Work::Merge { t }),
            V::Connect(_) => return None,
        };
        Some(Work::VolumeMerge { family, t })
    }
}

pub trait Recorder {
    /// False for `NoRecord`: integrators skip building what only a recorder would read.
    const ACTIVE: bool;
    fn completed(&mut self, path: Completed);
    /// A path made by merging; recorders of connection-only integrators ignore it.
    fn merged(&mut self, _path: Merged) {}
    /// A path made by a volumetric merge (`upbp`); other recorders ignore it.
    #[inline]
    fn volume_merged(&mut self, _path: VolumeMerged) {}
    /// The effective densities of every technique of the path reported next (`completed` or
    /// `merged`), where its weight was computed from the full path (`lt_core::path::camis`).
    #[inline]
    fn mixture(&mut self, _m: Mixture) {}
    /// Work item `item` starts (`crate::record::tally` decides here whether it times this item).
    #[inline]
    fn begin_item(&mut self, _item: u64) {}
    /// The camera sample of `pixel` starts; its t ≥ 2 estimate is multiplied by `film_weight`.
    #[inline]
    fn begin_sample(&mut self, _pixel: u64, _film_weight: f32) {}
    /// The code since the previous lap (or `begin_item`) did `work`.
    #[inline]
    fn lap(&mut self, _work: Work) {}
}

/// Records nothing.
pub struct NoRecord;

impl Recorder for NoRecord {
    const ACTIVE: bool = false;
    #[inline]
    fn completed(&mut self, _: Completed) {}
}
