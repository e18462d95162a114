//! A pass's light subpaths for `upbp`: walked through media (`media_walk::light_subpath_in`),
//! kept whole (a merge's weight reads every density of the light side), with what the weights
//! need per vertex besides the walk's densities (σ̂ of the camera direction's flight into it,
//! next-event estimation's density of y_0), their medium vertices indexed as photons for
//! points (`PointGrid`) and for camera beams (`volume_density::beams::BeamGrid`), and their
//! segments through media as photon beams for BB1D (`light_beams`).

use super::light_beams::LightBeams;
use super::rates::{light_vertex, Needs};
use super::weights::VertexRate;
use crate::subpath::connect::nee_density;
use crate::subpath::media_walk::light_subpath_in;
use crate::subpath::walk::{Subpath, WalkLimits};
use crate::volume_density::beams::BeamGrid;
use lt_core::math::Vec3;
use lt_core::path::scatter::connectable;
use lt_core::path::{PathVertex, VertexKind};
use lt_core::sampling::{Domain, Sampler};
use lt_core::spatial::PointGrid;
use lt_core::Scene;
use rayon::prelude::*;

/// The radii a pass indexes its light subpaths for: r_P (PP3D), r_B (PB2D), the photon beams
/// (BB1D, BP2D), r_S (surface merges); None where no technique reads them.
pub type Radii = (Option<f32>, Option<f32>, Option<BeamSetup>, Option<f32>);

/// A pass's photon beams: the radius their index serves (the largest of BB1D's and BP2D's), the
/// light subpaths whose segments are beams (the pass's first M_B), and whether they are long.
#[derive(Clone, Copy, Debug)]
pub struct BeamSetup {
    pub r_index: f32,
    pub paths: u64,
    pub long: bool,
}

/// Light subpaths traced per parallel chunk (fixed: the stored order, hence every sum, does not
/// depend on the thread count).
const CHUNK: u64 = 256;

/// One light subpath as a merge or a connection reads it.
#[derive(Clone, Copy)]
pub struct LightPath<'a> {
    pub vertices: &'a [PathVertex],
    /// `Subpath::back_flight` per vertex.
    pub back_flight: &'a [f32],
    /// Per vertex y_j (`rates::light_vertex`): medium, σ̂ of the flight y_{j+1} → y_j, σ̂ᴸ of
    /// y_{j−1} → y_j, sin θ_j (σ̂ and sin θ are 0 at the last vertex: the flight into it from a
    /// camera side is the join's or the merge's).
    pub rates: &'a [VertexRate],
    /// Next-event estimation's density of y_0 from y_1 (0 for a one-vertex subpath).
    pub nee: f64,
}

#[derive(Default)]
struct Chunk {
    vertices: Vec<PathVertex>,
    back_flight: Vec<f32>,
    rates: Vec<VertexRate>,
    starts: Vec<u32>,
    nee: Vec<f64>,
    beams: LightBeams,
}

/// A photon: light subpath `path`'s medium vertex `vertex` (≥ 1).
#[derive(Clone, Copy, Debug)]
pub struct PhotonRef {
    pub path: u32,
    pub vertex: u32,
}

/// A surface light vertex for surface merges: light subpath `path`'s vertex `vertex` (≥ 1, on a
/// non-delta surface), with what the merge kernel reads (`density::surface_merge`).
#[derive(Clone, Copy, Debug)]
pub struct SurfaceRef {
    pub path: u32,
    pub vertex: u32,
    /// Unit direction towards y_{i−1}, geometric normal, |n_g · ω_y|.
    pub wi: Vec3,
    pub ng: Vec3,
    pub cos_g: f32,
}

/// The pass's light subpaths and their photon indices.
pub struct LightStore {
    chunks: Vec<Chunk>,
    pub photon_positions: Vec<Vec3>,
    pub photons: Vec<PhotonRef>,
    /// For PP3D (cells of 2 r_P).
    pub points: Option<PointGrid>,
    /// For PB2D (photon spheres of r_B).
    pub beams: Option<BeamGrid>,
    /// For BB1D and BP2D: the light subpaths' segments through media as photon beams.
    pub light_beams: Option<LightBeams>,
    /// For surface merges: the non-delta surface vertices (cells of 2 r_S).
    pub surface_positions: Vec<Vec3>,
    pub surface: Vec<SurfaceRef>,
    pub surface_grid: Option<PointGrid>,
}

impl LightStore {
    /// Traces light subpaths 0 … m−1 of `pass` (streams `Domain::Light`, item = index, as bdpt's)
    /// and indexes their medium vertices for radii `r_points` (`None`: no PP3D) and `r_beams`
    /// (no PB2D), the segments through media of the first M_B as photon beams (`BeamSetup`; no
    /// BB1D or BP2D), their non-delta surface vertices for `r_surface` (no surface merges); `needs`:
    /// the rates the weights read.
    pub fn trace(
        scene: &Scene,
        (seed, pass): (u64, u32),
        (m, limits, needs): (u64, WalkLimits, Needs),
        (r_points, r_beams, r_beam_beams, r_surface): Radii,
    ) -> LightStore {
        let n_chunks = m.div_ceil(CHUNK) as usize;
        let chunks: Vec<Chunk> = (0..n_chunks)
            .into_par_iter()
            .map(|c| {
                let mut chunk = Chunk::default();
                chunk.starts.push(0);
                chunk.beams.long = r_beam_beams.is_some_and(|b| b.long);
                let mut sub = Subpath::with_capacity(limits.max_vertices);
                for j in c as u64 * CHUNK..((c as u64 + 1) * CHUNK).min(m) {
                    let mut ls = Sampler::for_item(Domain::Light, seed, j, pass as u64);
                    if scene.has_media {
                        light_subpath_in::<true>(scene, &mut ls, limits, &mut sub);
                    } else {
                        light_subpath_in::<false>(scene, &mut ls, limits, &mut sub);
                    }
                    let y = &sub.vertices;
                    chunk.vertices.extend_from_slice(y);
                    chunk
                        .back_flight
                        .extend((0..y.len()).map(|i| sub.back_flight(i)));
                    chunk
                        .rates
                        .extend((0..y.len()).map(|i| light_vertex(scene, y, i, needs)));
                    if r_beam_beams.is_some_and(|b| j < b.paths) && scene.has_media {
                        chunk.beams.add_path(scene, j as u32, &sub);
                    }
                    chunk.nee.push(if y.len() >= 2 {
                        nee_density(scene, &y[0], &y[1])
                    } else {
                        0.0
                    });
                    chunk.starts.push(chunk.vertices.len() as u32);
                }
                chunk
            })
            .collect();
        let mut chunks = chunks;
        let light_beams = r_beam_beams.map(|b| {
            let mut all = LightBeams {
                long: b.long,
                ..LightBeams::default()
            };
            for c in &mut chunks {
                all.append(std::mem::take(&mut c.beams));
            }
            all.build_index(b.r_index);
            all
        });
        let mut store = LightStore {
            chunks,
            photon_positions: Vec::new(),
            photons: Vec::new(),
            points: None,
            beams: None,
            light_beams,
            surface_positions: Vec::new(),
            surface: Vec::new(),
            surface_grid: None,
        };
        let (mut positions, mut photons) = (Vec::new(), Vec::new());
        let (mut s_positions, mut surface) = (Vec::new(), Vec::new());
        for path in 0..m as usize {
            let y = store.path(path).vertices;
            for (vertex, v) in y.iter().enumerate().skip(1) {
                if v.in_medium() {
                    positions.push(v.p);
                    photons.push(PhotonRef {
                        path: path as u32,
                        vertex: vertex as u32,
                    });
                } else if r_surface.is_some()
                    && matches!(v.kind, VertexKind::Surface { .. })
                    && connectable(scene, v)
                {
                    s_positions.push(v.p);
                    surface.push(SurfaceRef {
                        path: path as u32,
                        vertex: vertex as u32,
                        wi: v.wo,
                        ng: v.ng,
                        cos_g: v.ng.dot(v.wo).abs(),
                    });
                }
            }
        }
        if let Some(r) = r_surface.filter(|_| !surface.is_empty()) {
            store.surface_grid = Some(PointGrid::build(&s_positions, 2.0 * r));
        }
        store.surface_positions = s_positions;
        store.surface = surface;
        store.photon_positions = positions;
        store.photons = photons;
        if !store.photons.is_empty() {
            store.points = r_points.map(|r| PointGrid::build(&store.photon_positions, 2.0 * r));
            store.beams = r_beams.and_then(|r| BeamGrid::build(&store.photon_positions, r));
        }
        store
    }

    /// M, the light subpaths stored.
    pub fn len(&self) -> usize {
        self.chunks.iter().map(|c| c.nee.len()).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Light subpath `j`.
    pub fn path(&self, j: usize) -> LightPath<'_> {
        let c = &self.chunks[j / CHUNK as usize];
        let l = j % CHUNK as usize;
        let (a, b) = (c.starts[l] as usize, c.starts[l + 1] as usize);
        LightPath {
            vertices: &c.vertices[a..b],
            back_flight: &c.back_flight[a..b],
            rates: &c.rates[a..b],
            nee: c.nee[l],
        }
    }

    /// The photon's light subpath up to it (y_0 … y_i).
    pub fn photon(&self, p: PhotonRef) -> LightPath<'_> {
        self.up_to(p.path, p.vertex)
    }

    /// Light subpath `path` up to its vertex `vertex`.
    pub fn up_to(&self, path: u32, vertex: u32) -> LightPath<'_> {
        let full = self.path(path as usize);
        let n = vertex as usize + 1;
        LightPath {
            vertices: &full.vertices[..n],
            back_flight: &full.back_flight[..n],
            rates: &full.rates[..n],
            nee: full.nee,
        }
    }
}
