//! Weights from the full path's densities (`lt_core::path::camis`) rather than the per-vertex
//! recursion: correlation-aware MIS, vertex connections off, and efficiency-aware MIS's
//! per-pixel merging (`MergeMask`), where the recursion's one η for every pixel does not hold.

use super::{light_nee, MergeMask};
use crate::film::splat::pixel_of;
use crate::subpath::strategy_weight::{with_chain, EndEvals, Split};
use lt_core::math::Vec2;
use lt_core::path::camis::{self, Weighed};
use lt_core::path::scatter::{connectable, connectable_inside};
use lt_core::path::{Chain, Correlation, Heuristic, PathVertex, Technique, TechniqueSet};
use lt_core::Scene;

/// What full-path weights (`camis::weigh`) read besides a path's densities.
#[derive(Clone, Debug)]
pub(super) struct FullPathSetup {
    pub(super) set: TechniqueSet,
    pub(super) heuristic: Heuristic,
    /// M, light subpaths per pass (N_VM).
    pub(super) light_paths: f64,
    /// M/N.
    pub(super) ratio: f64,
    /// Merging at x_i counted η ρ_i (correlation-aware) instead of η.
    pub(super) correlation: bool,
    pub(super) merge_mask: Option<MergeMask>,
    pub(super) width: u32,
    pub(super) height: u32,
}

impl FullPathSetup {
    /// Whether merging runs for paths landing at `raster`.
    pub(super) fn merges_at(&self, raster: Vec2) -> bool {
        match &self.merge_mask {
            None => true,
            Some(mask) => mask[pixel_of(raster, self.width, self.height)],
        }
    }

    /// The weight of `technique` on `chain`, whose primary hit lies `distance` from the camera
    /// and which lands at `raster`.
    fn weigh(&self, chain: &Chain, technique: Technique, distance: f32, raster: Vec2) -> Weighed {
        // ρ always, for `Mixture::merges_correlated`; in the weights only when correlation-aware.
        let corr = Correlation::new(self.light_paths, distance as f64);
        let mut set = self.set;
        if !self.merges_at(raster) {
            set.merging_eta = 0.0;
        }
        camis::weigh_full(
            chain,
            set,
            Some(&corr),
            self.correlation,
            technique,
            self.heuristic,
        )
    }

    /// The weight of connection technique (s, t) formed by `split` (`strategy_weight`).
    pub(super) fn connection(
        &self,
        scene: &Scene,
        split: Split,
        evals: EndEvals,
        distance: f32,
        raster: Vec2,
    ) -> Weighed {
        with_chain(scene, split, evals, self.ratio, |chain, s| {
            self.weigh(chain, Technique::Connect(s), distance, raster)
        })
    }
}

/// The two densities a merge adds, as `SubpathMis::merge` takes them.
#[derive(Clone, Copy)]
pub(super) struct MergeDensities {
    /// c_{i−1}: z's BSDF towards y_{i−1}, given the light's incoming direction, in area at y_{i−1}.
    pub(super) c_y_prev: f64,
    /// l_{i+1}: z's BSDF (importance) towards z_{t−2} given ω_y, in area at z_{t−2} (0 if t = 2).
    pub(super) l_z_prev: f64,
}

/// Longest merged path (segments, + 1) whose densities `merge_weight` keeps on the stack.
const MERGE_STACK: usize = 24;

/// The full-path weight of merging light vertex y_i (`y` = y_0 … y_i) at z_{t−1} (`z` =
/// z_0 … z_{t−1}): the full path's densities from the walks' stored ones, as
/// `Densities::merged` defines them from scratch — the light side l_0 … l_i, c_0 … c_{i−2} from
/// the light walk, c_i … c_k and l_{i+2} … from the camera walk, c_{i−1} and l_{i+1} the merge's.
pub(super) fn merge_weight(
    scene: &Scene,
    camis: &FullPathSetup,
    (y, z): (&[PathVertex], &[PathVertex]),
    m: MergeDensities,
    (primary, raster): (f32, Vec2),
) -> Weighed {
    let i = y.len() - 1;
    let t = z.len();
    let k = i + t - 1;
    // On the stack up to k = MERGE_STACK − 1 (every merge of a pass builds one).
    let (mut la, mut ca, mut na) = (
        [0.0f64; MERGE_STACK],
        [0.0f64; MERGE_STACK],
        [false; MERGE_STACK],
    );
    let (mut lv, mut cv, mut nv) = (Vec::new(), Vec::new(), Vec::new());
    let (light, camera, conn): (&mut [f64], &mut [f64], &mut [bool]) = if k < MERGE_STACK {
        (&mut la[..=k], &mut ca[..=k], &mut na[..=k])
    } else {
        lv.resize(k + 1, 0.0);
        cv.resize(k + 1, 0.0);
        nv.resize(k + 1, false);
        (&mut lv, &mut cv, &mut nv)
    };
    for j in 0..=k {
        if j <= i {
            light[j] = y[j].pdf_fwd as f64;
        }
        if j + 2 <= i {
            camera[j] = y[j].pdf_rev as f64;
        }
        if j >= i {
            camera[j] = z[k - j].pdf_fwd as f64;
        }
        if j >= i + 2 {
            light[j] = z[k - j].pdf_rev as f64;
        }
        // Inner vertices as their walk left them; x_i, the merge, by evaluation on both sides.
        conn[j] = if j == i {
            connectable(scene, &z[t - 1]) && connectable(scene, &y[i])
        } else if j < i {
            connectable_inside(scene, &y[j])
        } else {
            connectable_inside(scene, &z[k - j])
        };
    }
    camera[i - 1] = m.c_y_prev;
    if i + 1 < k {
        light[i + 1] = m.l_z_prev;
    }
    camera[k] = 1.0;
    light[k] = 0.0;
    let chain = Chain {
        light,
        camera,
        nee: light_nee(scene, y),
        connectable: conn,
        light_tracing_ratio: camis.ratio,
    };
    camis.weigh(&chain, Technique::Merge(i), primary, raster)
}
