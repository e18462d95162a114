//! A pass's light subpaths: traced in fixed chunks, their MIS records formed once
//! (`SubpathMis`), the mergeable vertices stored compactly in a `PointGrid`.

use super::{Engine, PassSetup};
use crate::subpath::connect::nee_density;
use crate::subpath::walk::{light_subpath, reverse_density, Subpath, WalkLimits};
use lt_core::math::{Color, Vec3};
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::subpath_mis::VertexTechniques;
use lt_core::path::{LightMis, PathVertex, SubpathMis, VertexKind};
use lt_core::sampling::{Domain, Sampler};
use lt_core::spatial::PointGrid;
use lt_core::Scene;
use rayon::prelude::*;

/// The light subpaths of one pass with their MIS records and the merge index. Paths are kept in
/// the fixed chunks they were traced in (no copy into one array), and a run reuses the buffers
/// from pass to pass (`Engine::trace_light_paths_into`).
#[derive(Default)]
pub struct LightPaths {
    pub(super) chunks: Vec<LightChunk>,
    /// Mergeable vertices, compact (what a merge reads, contiguous).
    pub(super) merge_vertex: Vec<MergeVertex>,
    pub(super) merge_positions: Vec<Vec3>,
    pub(super) grid: Option<PointGrid>,
}

/// Light subpaths c·LIGHT_CHUNK … of one pass.
#[derive(Default)]
pub(super) struct LightChunk {
    pub(super) vertices: Vec<PathVertex>,
    mis: Vec<LightMis>,
    /// Path j of the chunk is `vertices[starts[j]..starts[j + 1]]`.
    starts: Vec<u32>,
}

impl LightPaths {
    pub fn path(&self, j: usize) -> (&[PathVertex], &[LightMis]) {
        let c = &self.chunks[j / LIGHT_CHUNK as usize];
        let l = j % LIGHT_CHUNK as usize;
        let (a, b) = (c.starts[l] as usize, c.starts[l + 1] as usize);
        (&c.vertices[a..b], &c.mis[a..b])
    }

    /// Stored light vertices (for the record and memory figures).
    pub fn merge_candidates(&self) -> usize {
        self.merge_vertex.len()
    }
}

/// What a merge reads of a stored light vertex y_j, in one place.
#[derive(Clone, Copy, Debug)]
pub(super) struct MergeVertex {
    /// Unit direction towards y_{j−1}: the light's incoming direction ω_y.
    pub(super) wi: Vec3,
    /// |n_g · ω_y| of y_j's own surface.
    pub(super) cos_g: f32,
    /// y_j's geometric normal.
    pub(super) ng: Vec3,
    pub(super) beta: Color,
    /// Segments from the light (j).
    pub(super) segments: u32,
    /// Where the vertex is kept: chunk and index in it (for the record).
    pub(super) chunk: u32,
    pub(super) index: u32,
    /// Turns a solid-angle density at y_j towards y_{j−1} into y_{j−1}'s measure
    /// (`walk::reverse_density` of y_{j−1} from y_j, factored: |cos at y_{j−1}| / d², 1 at
    /// infinity, 0 on a point light).
    pub(super) to_prev: f32,
    pub(super) mis: LightMis,
}

/// Light subpaths traced per parallel chunk (fixed: the order of the flat arrays, hence every
/// sum, does not depend on the thread count).
const LIGHT_CHUNK: u64 = 1024;

impl Engine<'_> {
    /// Traces the pass's light subpaths and forms their MIS records (and the merge index).
    pub fn trace_light_paths(&self, setup: &PassSetup, seed: u64, pass: u32) -> LightPaths {
        let mut out = LightPaths::default();
        self.trace_light_paths_into(setup, seed, pass, &mut out);
        out
    }

    /// `trace_light_paths` into `out`, reusing its buffers.
    pub fn trace_light_paths_into(
        &self,
        setup: &PassSetup,
        seed: u64,
        pass: u32,
        out: &mut LightPaths,
    ) {
        let scene = self.scene;
        let m = setup.light_paths;
        let n_chunks = m.div_ceil(LIGHT_CHUNK) as usize;
        out.chunks.resize_with(n_chunks, LightChunk::default);
        out.chunks
            .par_iter_mut()
            .enumerate()
            .for_each(|(c, chunk)| {
                let c = c as u64;
                let mut sub = Subpath::with_capacity(self.params.max_depth as usize);
                chunk.vertices.clear();
                chunk.mis.clear();
                chunk.starts.clear();
                chunk.starts.push(0);
                for j in c * LIGHT_CHUNK..((c + 1) * LIGHT_CHUNK).min(m) {
                    let mut ls = Sampler::for_item(Domain::Light, seed, j, pass as u64);
                    light_subpath(
                        scene,
                        &mut ls,
                        WalkLimits::light(self.params.max_depth, self.params.rr_depth),
                        &mut sub,
                    );
                    light_records(scene, &setup.mis, &sub.vertices, &mut chunk.mis);
                    chunk.vertices.extend_from_slice(&sub.vertices);
                    chunk.starts.push(chunk.vertices.len() as u32);
                }
            });
        out.merge_vertex.clear();
        out.merge_positions.clear();
        out.grid = None;
        if !self.params.merging {
            return;
        }
        for (c, chunk) in out.chunks.iter().enumerate() {
            for w in chunk.starts.windows(2) {
                for (d, idx) in (w[0] + 1..w[1]).enumerate() {
                    let mis = chunk.mis[idx as usize];
                    if !mis.mergeable {
                        continue;
                    }
                    let (y, before) = (
                        &chunk.vertices[idx as usize],
                        &chunk.vertices[idx as usize - 1],
                    );
                    out.merge_vertex.push(MergeVertex {
                        wi: y.wo,
                        cos_g: y.ng.dot(y.wo).abs(),
                        ng: y.ng,
                        beta: y.beta,
                        segments: d as u32 + 1,
                        chunk: c as u32,
                        index: idx,
                        to_prev: reverse_density(before, y, 1.0),
                        mis,
                    });
                    out.merge_positions.push(y.p);
                }
            }
        }
        out.grid = Some(PointGrid::build(&out.merge_positions, 2.0 * setup.radius));
    }
}

/// The MIS records of a light subpath y_0 … (see `SubpathMis`), appended to `out`.
pub(super) fn light_records(
    scene: &Scene,
    mis: &SubpathMis,
    y: &[PathVertex],
    out: &mut Vec<LightMis>,
) {
    let Some(y0) = y.first() else {
        return;
    };
    let base = out.len();
    out.push(mis.light_origin(y0.pdf_fwd as f64));
    let nee_over_l0 = if y.len() >= 2 {
        nee_density(scene, &y[0], &y[1]) / y0.pdf_fwd as f64
    } else {
        0.0
    };
    for j in 1..y.len() {
        let c_pp = if j >= 2 { y[j - 2].pdf_rev as f64 } else { 0.0 };
        let prev = out[base + j - 1];
        let surface = matches!(y[j].kind, VertexKind::Surface { .. });
        let vertex = VertexTechniques {
            // VC(1) is next-event estimation: the light samples x0 itself (`Chain::valid`).
            // VC(j) joins y_j, the end, to y_{j−1}, inside the path.
            vc_valid: if j == 1 {
                connectable(scene, &y[1])
            } else {
                connectable_inside(scene, &y[j - 1]) && connectable(scene, &y[j])
            },
            mergeable: surface && connectable(scene, &y[j]) && mis.merging(),
            through_delta: y[j].delta,
        };
        let r = mis.light_vertex(j, y[j].pdf_fwd as f64, (&prev, c_pp), nee_over_l0, vertex);
        out.push(r);
    }
}
