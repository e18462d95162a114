//! The per-vertex densities of one complete path, from which every technique's density p_s and
//! weight follow: owned storage for a [`Chain`], which does the arithmetic. `Path::densities`
//! computes them from scratch (the oracle), `Densities::merged` for vertex merging.

use super::mis::Chain;

/// Per-vertex densities of a path, from which every p_s follows (Veach 1997, ch. 10: p_s is the
/// product of the light subpath's densities of x0 … x_{s−1} and the camera subpath's of x_s … xk).
/// Owned storage for a [`Chain`], which does the arithmetic.
#[derive(Clone, Debug)]
pub struct Densities {
    /// `light[i]`: density of x_i when the light subpath generates it, given x0 … x_{i−1}.
    /// `light[0]` = pmf · pdf_le position (solid angle pdf_le direction at infinity: the
    /// discrete 1 for a directional light); `light[1]` after a light at infinity is the bounding
    /// disk's density times |cos θ1|; `light[k]` = 0, since no walk hits a pinhole.
    pub light: Vec<f64>,
    /// `camera[i]`: density of x_i when the camera subpath generates it, given x_{i+1} … xk.
    /// `camera[k]` = 1 (pinhole); `camera[0]` = 0 for a delta light (point or directional).
    pub camera: Vec<f64>,
    /// Density of x0 when next-event estimation from x1 chooses it (technique s = 1 when k ≥ 2):
    /// pmf · pdf_li converted to area at x0 (solid angle at infinity, the pmf alone for a delta
    /// light: point or directional).
    pub nee: f64,
    /// `connectable[i]`: a connection edge may end at x_i (not a delta surface, not a light
    /// delta in direction; see `scatter::connectable` and `Chain::valid`).
    pub connectable: Vec<bool>,
    /// Light subpaths per camera sample in a pass (M/N, see `mis`); 1 by default.
    pub light_tracing_ratio: f64,
}

impl Densities {
    /// The borrowed view every weight is computed from.
    pub fn chain(&self) -> Chain<'_> {
        Chain {
            light: &self.light,
            camera: &self.camera,
            nee: self.nee,
            connectable: &self.connectable,
            light_tracing_ratio: self.light_tracing_ratio,
        }
    }

    /// Number of segments k.
    pub fn k(&self) -> usize {
        self.light.len() - 1
    }

    /// See `Chain::valid`.
    pub fn valid(&self, s: usize) -> bool {
        self.chain().valid(s)
    }

    /// The density of the light subpath x0 … x_{s−1} alone (see `Chain::one_is_nee` for s = 1).
    pub fn light_prefix(&self, s: usize) -> f64 {
        self.chain().light_prefix(s)
    }

    /// p_s(x̄) (Russian roulette excluded).
    pub fn technique(&self, s: usize) -> f64 {
        self.chain().technique(s)
    }

    /// p_s for s = 0 … k+1.
    pub fn all(&self) -> Vec<f64> {
        (0..=self.k() + 1).map(|s| self.technique(s)).collect()
    }

    /// n_s·p_s for s = 0 … k+1: the densities the heuristics compare.
    pub fn effective_all(&self) -> Vec<f64> {
        self.chain().effective_all()
    }
}

/// `Chain::relative` of a from-scratch `Densities`, as a vector.
pub fn relative_pdfs(d: &Densities, s: usize) -> Vec<f64> {
    let mut r = vec![0.0; d.k() + 2];
    d.chain().relative(s, &mut r);
    r
}

/// The power-heuristic weight of technique s computed from `relative_pdfs` (β = 1: balance).
pub fn power_weight_by_ratios(d: &Densities, s: usize, beta: f64) -> f64 {
    let c = d.chain();
    if !c.valid(s) || c.technique(s) == 0.0 {
        return 0.0;
    }
    let sum: f64 = relative_pdfs(d, s).iter().map(|&r| r.powf(beta)).sum();
    1.0 / sum
}
