//! Multiple importance sampling weights over the techniques s = 0 … k+1 of one path (Veach &
//! Guibas 1995; Veach 1997, ch. 9 and 10). Pure functions of the densities: they read, never
//! mutate vertices (Tungsten's `misWeight`, not pbrt's scoped assignments).
//!
//! Every weight is computed from a [`Chain`]: the per-vertex densities of the path in both walk
//! directions. `Path::densities` fills one from scratch (the oracle); BDPT and VCM fill one from
//! their subpaths' stored `pdf_fwd`/`pdf_rev`, patching the entries at the connection. Both then
//! run the same arithmetic here, so a disagreement between them is a disagreement about densities.
//!
//! **Sample counts.** The heuristics weigh n_s·p_s, n_s being how many samples technique s takes
//! per pass (Veach 1997, eq. 9.13). Every technique with a camera subpath (t ≥ 2) is taken once
//! per camera sample; light tracing (t = 1) once per light subpath, and a pass may trace M light
//! subpaths for its N camera samples. Only the ratio matters: `Chain::light_tracing_ratio` = M/N.
//!
//! The densities are delta-stripped (`path::scatter`). For mirrors and every non-delta vertex the
//! stripped p_s are the true densities in one common measure, so these are exactly the balance and
//! power heuristics. A refraction sampled from the light side by one technique and from the camera
//! side by another carries its Dirac in different solid angles (`Path::contribution_for`): the
//! stripped p_s then differ from common-measure densities by the Jacobian η_L² cos θ_L /
//! (η_C² cos θ_C) per such refraction. The weights still sum to one and vanish where p_s = 0, so
//! every estimator stays unbiased; they are just not the exact heuristic there (nor are pbrt's,
//! which make the same choice).

/// How techniques that can produce the same path share it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Heuristic {
    /// w_s = n_s p_s / Σ n_i p_i.
    Balance,
    /// w_s = (n_s p_s)² / Σ (n_i p_i)² — the project default (Veach's β = 2).
    Power,
    /// w_s = 1 / (number of techniques with p_i > 0): unbiased, no variance reduction.
    Uniform,
}

impl Heuristic {
    /// The command-line names: `balance`, `power`, `none`.
    pub fn parse(name: &str) -> Result<Heuristic, String> {
        match name {
            "balance" => Ok(Heuristic::Balance),
            "power" => Ok(Heuristic::Power),
            "none" => Ok(Heuristic::Uniform),
            _ => Err(format!(
                "unknown MIS heuristic '{name}' (known: balance, power, none)"
            )),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Heuristic::Balance => "balance",
            Heuristic::Power => "power",
            Heuristic::Uniform => "none",
        }
    }

    /// The weight of a technique given r_i = n_i p_i / (n_s p_s) for every technique (r_s = 1).
    #[inline]
    pub fn weight_from_ratios(self, r: &[f64]) -> f64 {
        let sum: f64 = match self {
            Heuristic::Balance => r.iter().sum(),
            Heuristic::Power => r.iter().map(|&x| x * x).sum(),
            Heuristic::Uniform => r.iter().filter(|&&x| x > 0.0).count() as f64,
        };
        let w = 1.0 / sum;
        // An infinite ratio (a neighbour infinitely more likely) or a NaN from a zero density
        // where the contribution is zero as well: the technique gets nothing.
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }
}

/// The densities of one path of k segments, x0 (light) … xk (camera), that every weight reads.
/// `light[i]`: density of x_i when the light subpath generates it; `camera[i]`: when the camera
/// subpath does; `nee`: of x0 chosen by next-event estimation from x1. See `Densities`.
#[derive(Clone, Copy, Debug)]
pub struct Chain<'a> {
    pub light: &'a [f64],
    pub camera: &'a [f64],
    pub nee: f64,
    pub connectable: &'a [bool],
    /// Light subpaths per camera sample in a pass (M/N): n_k / n_s for s < k.
    pub light_tracing_ratio: f64,
}

impl Chain<'_> {
    /// Number of segments k.
    #[inline]
    pub fn k(&self) -> usize {
        self.light.len() - 1
    }

    /// Whether technique s can produce the path at all, judged by structure only: s = k+1 needs
    /// a camera a walk can hit (never, with a pinhole); 1 ≤ s ≤ k connects x_{s−1} with x_s,
    /// which must both be connectable — except technique 1 when it is next-event estimation
    /// (`one_is_nee`): x0 is then sampled by the light itself (`Light::sample_li`), which can
    /// draw any light's Dirac, so only x1 must be connectable.
    ///
    /// This is where a light delta in direction (a directional light, `connectable[0]` false) is
    /// decided, once for the oracle and every integrator: next-event estimation (s = 1, k ≥ 2)
    /// and the light walks from it (s ≥ 2) are valid; joining it to the pinhole (s = 1 = k,
    /// light tracing's x0) is not; nor is s = 0, since no walk hits a single direction
    /// (`camera[0]` = 0 says the same as a density, as it does for a point light, which
    /// `connectable[0]` leaves connectable).
    #[inline]
    pub fn valid(&self, s: usize) -> bool {
        let k = self.k();
        match s {
            _ if s > k => false,
            0 => self.connectable[0],
            1 if self.one_is_nee() => self.connectable[1],
            _ => self.connectable[s - 1] && self.connectable[s],
        }
    }

    /// Whether technique 1 takes x0 from next-event estimation. It does whenever a camera subpath
    /// vertex x1 exists to sample from (k ≥ 2). On a one-segment path (an emitter seen directly)
    /// technique 1 is light tracing's x0: the emitted point, from `light[0]`, connected to the
    /// pinhole — what a light tracer does; next-event estimation from the pinhole is not sampled
    /// by any integrator here.
    #[inline]
    pub fn one_is_nee(&self) -> bool {
        self.k() >= 2
    }

    /// The density of the light subpath x0 … x_{s−1} alone.
    pub fn light_prefix(&self, s: usize) -> f64 {
        match s {
            0 => 1.0,
            1 if self.one_is_nee() => self.nee,
            _ => self.light[..s].iter().product(),
        }
    }

    /// p_s(x̄) (Russian roulette excluded), zero when technique s cannot produce the path.
    #[inline]
    pub fn technique(&self, s: usize) -> f64 {
        if !self.valid(s) {
            return 0.0;
        }
        self.light_prefix(s) * self.camera[s..].iter().product::<f64>()
    }

    /// n_s relative to the camera-sample count: the light-tracing ratio for s = k, else 1.
    #[inline]
    pub fn sample_count(&self, s: usize) -> f64 {
        if s == self.k() {
            self.light_tracing_ratio
        } else {
            1.0
        }
    }

    /// n_s·p_s for every s = 0 … k+1: what the heuristics compare.
    pub fn effective_all(&self) -> Vec<f64> {
        (0..=self.k() + 1)
            .map(|s| self.sample_count(s) * self.technique(s))
            .collect()
    }

    /// r_i = n_i p_i / (n_s p_s) for every i (p_s > 0), by Veach's recursion (1997, §10.2)
    /// instead of products: moving x_i from the camera subpath to the light subpath gives
    /// p_{i+1} / p_i = l_i / c_i. When technique 1 is next-event estimation it draws x0 by `nee`
    /// instead of l_0, so the chain steps from 0 straight to 2 (ratio l_0·l_1 / (c_0·c_1)) and
    /// p_1 hangs off a neighbour (p_1 / p_0 = nee / c_0). Every divisor is a density of p_s itself,
    /// hence non-zero: no remap0 (pbrt) is needed, and a delta light's c_0 = 0 (point or
    /// directional) zeroes p_0 by itself. Delta-stripped densities keep the chain finite through
    /// delta vertices; techniques that connect there are zeroed at the end. `out` must hold k+2
    /// entries.
    pub fn relative(&self, s: usize, out: &mut [f64]) {
        let k = self.k();
        let (l, c) = (self.light, self.camera);
        let r = &mut out[..k + 2];
        // No fill: every entry 0 … k+1 is written below before it is read (r[s]; the chain up
        // and down from it; r[0] and r[1] by the next-event cases) — a `memset` call per weight.
        r[s] = 1.0;
        let skip = self.one_is_nee();
        if skip && s == 1 {
            r[0] = c[0] / self.nee;
            r[2] = l[0] * l[1] / (self.nee * c[1]);
        }
        let lo = if skip && s == 1 { 2 } else { s };
        // Up the chain: techniques lo+1 … k+1 (with next-event estimation, 0 steps to 2).
        let mut i = lo;
        while i <= k {
            let (next, ratio) = if skip && i == 0 {
                (2, l[0] * l[1] / (c[0] * c[1]))
            } else {
                (i + 1, l[i] / c[i])
            };
            r[next] = r[i] * ratio;
            i = next;
        }
        // Down the chain: techniques lo−1 … 2 (… 0 without next-event estimation).
        let bottom = if skip { 2 } else { 0 };
        for i in (bottom..lo).rev() {
            r[i] = r[i + 1] * c[i] / l[i];
        }
        if skip && s != 1 {
            if lo >= 2 {
                r[0] = r[2] * c[0] * c[1] / (l[0] * l[1]);
            }
            r[1] = if c[0] > 0.0 {
                r[0] * self.nee / c[0]
            } else {
                r[2] * self.nee * c[1] / (l[0] * l[1])
            };
        }
        // `valid(i)` and `sample_count(i)` by position, without their per-entry dispatch: only
        // technique k has a count other than 1, and x · 1 / 1 is x exactly, so the other entries
        // are scaled only when n_s differs from 1 (the same operations, so the same bits).
        let ns = self.sample_count(s);
        let conn = &self.connectable[..=k];
        for i in 0..=k {
            let valid = match i {
                0 => conn[0],
                1 if skip => conn[1],
                _ => conn[i - 1] && conn[i],
            };
            r[i] = if !valid {
                0.0
            } else if i == k || ns != 1.0 {
                r[i] * self.sample_count(i) / ns
            } else {
                r[i]
            };
        }
        // Technique k+1 (a camera a walk hits) is never valid.
        r[k + 1] = 0.0;
    }

    /// The weight of technique s under `h`; zero when s cannot produce the path.
    pub fn weight(&self, s: usize, h: Heuristic) -> f64 {
        if !self.valid(s) || self.technique(s) == 0.0 {
            return 0.0;
        }
        let mut r = [0.0f64; MAX_TECHNIQUES];
        let k = self.k();
        if k + 2 > MAX_TECHNIQUES {
            let mut v = vec![0.0; k + 2];
            self.relative(s, &mut v);
            return h.weight_from_ratios(&v);
        }
        self.relative(s, &mut r);
        h.weight_from_ratios(&r[..k + 2])
    }
}

/// Paths up to this many techniques (k ≤ 24) weigh without allocating.
const MAX_TECHNIQUES: usize = 26;

/// Balance heuristic w_s = p_s / Σ_i p_i over effective densities n_i p_i. Zero when p_s = 0.
pub fn balance_weight(pdfs: &[f64], s: usize) -> f64 {
    power_weight(pdfs, s, 1.0)
}

/// Power heuristic w_s = p_s^β / Σ_i p_i^β over effective densities, evaluated as
/// 1 / Σ_i (p_i / p_s)^β so that densities far outside f64's range of squares cannot overflow.
/// This is the brute-force oracle that `Chain::weight` must match.
pub fn power_weight(pdfs: &[f64], s: usize, beta: f64) -> f64 {
    let ps = pdfs[s];
    if ps.is_nan() || ps <= 0.0 {
        return 0.0;
    }
    let sum: f64 = pdfs.iter().map(|&p| (p / ps).powf(beta)).sum();
    1.0 / sum
}

/// The oracle's weight of technique s under `h` from effective densities (`Densities::effective_all`).
pub fn oracle_weight(pdfs: &[f64], s: usize, h: Heuristic) -> f64 {
    match h {
        Heuristic::Balance => power_weight(pdfs, s, 1.0),
        Heuristic::Power => power_weight(pdfs, s, 2.0),
        Heuristic::Uniform => {
            if pdfs[s] > 0.0 {
                1.0 / pdfs.iter().filter(|&&p| p > 0.0).count() as f64
            } else {
                0.0
            }
        }
    }
}
