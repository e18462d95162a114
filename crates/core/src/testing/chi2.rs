//! Pearson's χ² goodness-of-fit test of a direction sampler against the pdf it claims (modelled
//! on Mitsuba 3's `chi2.py`).
//!
//! Directions are binned on a `Chart`: a map from a rectangle of coordinates (a, b) to directions,
//! with its Jacobian dω/(da db). `SphereGrid` charts the sphere or a cap by (1 − cos θ, φ);
//! `ParallelogramChart` charts the directions towards a planar parallelogram by its own (u, v),
//! so that a polygonal light's edges are bin edges. The expected count of a bin is N times the pdf
//! integrated over it with adaptive Gauss–Legendre cubature whose error target is a small
//! fraction of the bin's Poisson noise, so integration error cannot decide the test. Charts are
//! chosen so that the pdf's discontinuities lie on bin edges. Bins expecting < 5 are pooled.
//!
//! A chart covering the whole sphere tests the unconditional distribution (samples the sampler
//! rejects form one more cell, expecting N·(1 − ∫pdf)); a partial chart tests the distribution
//! conditioned on landing in it, and `check_mass` tests the chart's share of the samples.

use crate::math::{Frame, Vec3};
use crate::sampling::Sampler;
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;

/// Directions parameterised by a rectangle of coordinates, cut into bins by `a_edges × b_edges`.
pub trait Chart {
    /// Bin edges of each coordinate, increasing; they span the chart.
    fn a_edges(&self) -> &[f64];
    fn b_edges(&self) -> &[f64];
    /// The direction at (a, b) and the Jacobian dω / (da db) there.
    fn direction(&self, a: f64, b: f64) -> (Vec3, f64);
    /// Coordinates of a unit direction, or None when the chart does not hold it. Directions just
    /// beyond the edge (relative 1e-4: the sampler's own f32 rounding) are clamped inside.
    fn coords(&self, w: Vec3) -> Option<(f64, f64)>;
    /// True when the chart holds every direction.
    fn covers_sphere(&self) -> bool;
}

fn bin_of(chart: &dyn Chart, (a, b): (f64, f64)) -> usize {
    let find = |edges: &[f64], x: f64| {
        edges
            .partition_point(|&e| e <= x)
            .saturating_sub(1)
            .min(edges.len() - 2)
    };
    find(chart.a_edges(), a) * (chart.b_edges().len() - 1) + find(chart.b_edges(), b)
}

/// `edges` from 0 to `max` with spacing growing as (i/n)^power.
fn power_edges(max: f64, n: usize, power: f64) -> Vec<f64> {
    (0..=n)
        .map(|i| max * (i as f64 / n as f64).powf(power))
        .collect()
}

/// The sphere or a cap around `frame.z`, charted by (h, φ) with h = 1 − cos θ, so dω = dh dφ.
#[derive(Clone, Debug)]
pub struct SphereGrid {
    pub frame: Frame,
    /// Ring edges in h, increasing from 0; the last is the chart's extent (2 = whole sphere).
    h_edges: Vec<f64>,
    phi_edges: Vec<f64>,
}

impl SphereGrid {
    /// The whole sphere, rings uniform in cos θ (equal areas). An even `n_h` puts the equator on a
    /// ring edge, where hemispherical pdfs are discontinuous.
    pub fn sphere(frame: Frame, n_h: usize, n_phi: usize) -> SphereGrid {
        SphereGrid::cap(frame, 2.0, n_h, n_phi, 1.0)
    }

    /// A cap of extent `h_max` with ring edges h_max·(i/n_h)^power: power 1 gives equal areas,
    /// power 2 rings of nearly equal angular width (fine near a peak at the axis).
    pub fn cap(frame: Frame, h_max: f64, n_h: usize, n_phi: usize, power: f64) -> SphereGrid {
        SphereGrid::with_edges(frame, power_edges(h_max.min(2.0), n_h, power), n_phi)
    }

    /// Explicit ring edges (from 0), e.g. to put a cone's rim on an edge.
    pub fn with_edges(frame: Frame, h_edges: Vec<f64>, n_phi: usize) -> SphereGrid {
        assert!(
            h_edges.len() >= 2
                && h_edges[0] == 0.0
                && h_edges.windows(2).all(|w| w[0] < w[1])
                && *h_edges.last().unwrap() <= 2.0
        );
        SphereGrid {
            frame,
            h_edges,
            phi_edges: power_edges(2.0 * PI, n_phi, 1.0),
        }
    }

    pub fn h_max(&self) -> f64 {
        *self.h_edges.last().unwrap()
    }

    /// World direction at (h, φ).
    pub fn at(&self, h: f64, phi: f64) -> Vec3 {
        let sin_t = (h * (2.0 - h)).max(0.0).sqrt();
        let local = Vec3::new(
            (sin_t * phi.cos()) as f32,
            (sin_t * phi.sin()) as f32,
            (1.0 - h) as f32,
        );
        self.frame.to_world(local).normalize()
    }
}

impl Chart for SphereGrid {
    fn a_edges(&self) -> &[f64] {
        &self.h_edges
    }
    fn b_edges(&self) -> &[f64] {
        &self.phi_edges
    }
    fn direction(&self, h: f64, phi: f64) -> (Vec3, f64) {
        (self.at(h, phi), 1.0)
    }
    fn coords(&self, w: Vec3) -> Option<(f64, f64)> {
        let l = self.frame.to_local(w);
        let (x, y, z) = (l.x as f64, l.y as f64, l.z as f64);
        // 1 − cos θ from the chord length, accurate for tiny angles.
        let h = 0.5 * (x * x + y * y + (z - 1.0) * (z - 1.0));
        if !self.covers_sphere() && h > self.h_max() * (1.0 + 1e-4) {
            return None;
        }
        Some((h, y.atan2(x).rem_euclid(2.0 * PI)))
    }
    fn covers_sphere(&self) -> bool {
        self.h_max() >= 2.0
    }
}

/// Directions from `origin` towards the parallelogram corner + u·e1 + v·e2, (u, v) ∈ [0, 1]²,
/// charted by (u, v): dω = |n·(x − origin)| |e1 × e2| / |x − origin|³ du dv.
#[derive(Clone, Debug)]
pub struct ParallelogramChart {
    origin: [f64; 3],
    corner: [f64; 3],
    e1: [f64; 3],
    e2: [f64; 3],
    u_edges: Vec<f64>,
    v_edges: Vec<f64>,
}

fn d3(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn axpy(p: [f64; 3], s: f64, d: [f64; 3]) -> [f64; 3] {
    [p[0] + s * d[0], p[1] + s * d[1], p[2] + s * d[2]]
}

impl ParallelogramChart {
    pub fn new(
        origin: Vec3,
        corner: Vec3,
        e1: Vec3,
        e2: Vec3,
        n_u: usize,
        n_v: usize,
    ) -> ParallelogramChart {
        ParallelogramChart {
            origin: d3(origin),
            corner: d3(corner),
            e1: d3(e1),
            e2: d3(e2),
            u_edges: power_edges(1.0, n_u, 1.0),
            v_edges: power_edges(1.0, n_v, 1.0),
        }
    }
}

impl Chart for ParallelogramChart {
    fn a_edges(&self) -> &[f64] {
        &self.u_edges
    }
    fn b_edges(&self) -> &[f64] {
        &self.v_edges
    }
    fn direction(&self, u: f64, v: f64) -> (Vec3, f64) {
        let x = axpy(axpy(self.corner, u, self.e1), v, self.e2);
        let d = axpy(x, -1.0, self.origin);
        let len = dot(d, d).sqrt();
        let n = cross(self.e1, self.e2);
        let jac = dot(n, d).abs() / (len * len * len);
        (
            Vec3::new(
                (d[0] / len) as f32,
                (d[1] / len) as f32,
                (d[2] / len) as f32,
            ),
            jac,
        )
    }
    fn coords(&self, w: Vec3) -> Option<(f64, f64)> {
        let (w, n) = (d3(w), cross(self.e1, self.e2));
        let t = dot(n, axpy(self.corner, -1.0, self.origin)) / dot(n, w);
        if !(t > 0.0 && t.is_finite()) {
            return None;
        }
        let q = axpy(axpy(self.origin, t, w), -1.0, self.corner);
        // Solve q = u·e1 + v·e2 through the Gram matrix.
        let (g11, g12, g22) = (
            dot(self.e1, self.e1),
            dot(self.e1, self.e2),
            dot(self.e2, self.e2),
        );
        let (r1, r2) = (dot(q, self.e1), dot(q, self.e2));
        let det = g11 * g22 - g12 * g12;
        let (u, v) = ((r1 * g22 - r2 * g12) / det, (r2 * g11 - r1 * g12) / det);
        let inside = |x: f64| (-1e-4..=1.0 + 1e-4).contains(&x);
        (inside(u) && inside(v)).then_some((u.clamp(0.0, 1.0), v.clamp(0.0, 1.0)))
    }
    fn covers_sphere(&self) -> bool {
        false
    }
}

/// Result of one χ² test. `check` turns it into a verdict.
#[derive(Clone, Debug)]
pub struct Chi2Outcome {
    pub name: String,
    pub samples: usize,
    /// Samples the sampler returned (not rejected).
    pub accepted: usize,
    /// Accepted samples that landed in the chart.
    pub in_domain: usize,
    /// ∫ pdf over the chart, and an estimate of its absolute cubature error.
    pub pdf_integral: f64,
    pub integral_error: f64,
    pub chi2: f64,
    pub dof: usize,
    pub p_value: f64,
    /// Samples in bins over which the claimed pdf integrates to zero.
    pub zero_pdf_hits: usize,
    /// Bins whose cubature did not reach its error target.
    pub unconverged_bins: usize,
    /// Samples with a non-unit or non-finite direction.
    pub invalid: usize,
    /// Samples moved by rounding distance out of a bin where the pdf is zero.
    pub snapped: usize,
}

/// Settings of a χ² run.
#[derive(Clone, Copy, Debug)]
pub struct Chi2Test {
    pub samples: usize,
    pub seed: u64,
}

impl Default for Chi2Test {
    fn default() -> Self {
        Chi2Test {
            samples: 1_000_000,
            seed: 0x5eed,
        }
    }
}

const MIN_EXPECTED: f64 = 5.0;
/// Target cubature error of a bin, as a fraction of the Poisson noise √E of its count: it adds at
/// most 0.05² = 0.0025 to the expectation of that bin's χ² term (whose mean is ≈ 1).
const ERROR_FRACTION: f64 = 0.05;
const MAX_DEPTH: u32 = 12;

/// Three-point Gauss–Legendre nodes and weights on [−1, 1] (exact for degree-5 polynomials).
const GL_X: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
const GL_W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];

fn gauss3(f: &dyn Fn(f64, f64) -> f64, a0: f64, a1: f64, b0: f64, b1: f64) -> f64 {
    let (ac, ar) = (0.5 * (a0 + a1), 0.5 * (a1 - a0));
    let (bc, br) = (0.5 * (b0 + b1), 0.5 * (b1 - b0));
    let mut s = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            s += GL_W[i] * GL_W[j] * f(ac + ar * GL_X[i], bc + br * GL_X[j]);
        }
    }
    s * ar * br
}

/// Adaptive cubature of a cell whose one-rule estimate is `whole`: compare with the sum over its
/// four quarters and recurse (tolerance halved per level, so cells cut by a discontinuity still
/// converge). Returns (integral, error estimate, converged).
fn adapt(
    f: &dyn Fn(f64, f64) -> f64,
    c: [f64; 4],
    whole: f64,
    tol: f64,
    depth: u32,
) -> (f64, f64, bool) {
    let [h0, h1, p0, p1] = c;
    let (hm, pm) = (0.5 * (h0 + h1), 0.5 * (p0 + p1));
    let quads = [
        [h0, hm, p0, pm],
        [hm, h1, p0, pm],
        [h0, hm, pm, p1],
        [hm, h1, pm, p1],
    ];
    let parts = quads.map(|q| gauss3(f, q[0], q[1], q[2], q[3]));
    let sum: f64 = parts.iter().sum();
    let err = (sum - whole).abs();
    if err <= tol {
        return (sum, err, true);
    }
    if depth >= MAX_DEPTH {
        return (sum, err, false);
    }
    let mut out = (0.0, 0.0, true);
    for (q, part) in quads.iter().zip(parts) {
        let (v, e, ok) = adapt(f, *q, part, 0.5 * tol, depth + 1);
        out = (out.0 + v, out.1 + e, out.2 && ok);
    }
    out
}

/// Sub-cells per side of `fine_cubature`.
const FINE_CELLS: usize = 32;

/// Three-point Gauss–Legendre on an n × n grid of sub-cells of `c` (no adaptivity: for a cell
/// whose adaptive estimate saw nothing).
fn fine_cubature(f: &dyn Fn(f64, f64) -> f64, c: [f64; 4], n: usize) -> f64 {
    let [a0, a1, b0, b1] = c;
    let (da, db) = ((a1 - a0) / n as f64, (b1 - b0) / n as f64);
    let mut s = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (a, b) = (a0 + i as f64 * da, b0 + j as f64 * db);
            s += gauss3(f, a, a + da, b, b + db);
        }
    }
    s
}

/// Runs the test. `sample` draws one direction (it may consume any number of variates) or
/// rejects; `pdf` is the solid-angle density the sampler claims, for any unit direction.
pub fn run(
    name: &str,
    cfg: Chi2Test,
    chart: &dyn Chart,
    mut sample: impl FnMut(&mut Sampler) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f32,
) -> Chi2Outcome {
    // Probability of each bin by cubature of pdf · Jacobian over the chart.
    let (ae, be) = (chart.a_edges(), chart.b_edges());
    let n_b = be.len() - 1;
    let n_bins = (ae.len() - 1) * n_b;
    let f = |a: f64, b: f64| {
        let (w, jac) = chart.direction(a, b);
        pdf(w) as f64 * jac
    };
    let n = cfg.samples as f64;
    let mut prob = vec![0.0f64; n_bins];
    let (mut integral_error, mut unconverged_bins) = (0.0, 0usize);
    for i in 0..ae.len() - 1 {
        for j in 0..n_b {
            let c = [ae[i], ae[i + 1], be[j], be[j + 1]];
            let first = gauss3(&f, c[0], c[1], c[2], c[3]);
            let tol = ERROR_FRACTION * (n * first.abs()).max(1.0).sqrt() / n;
            let (v, e, ok) = adapt(&f, c, first, tol, 0);
            prob[i * n_b + j] = v;
            integral_error += e;
            unconverged_bins += usize::from(!ok);
        }
    }

    let mut observed = vec![0u64; n_bins];
    let mut sampler = Sampler::new(cfg.seed, 0, 0);
    let (mut accepted, mut in_domain, mut invalid, mut snapped) = (0usize, 0usize, 0usize, 0usize);
    for _ in 0..cfg.samples {
        let Some(w) = sample(&mut sampler) else {
            continue;
        };
        accepted += 1;
        if !w.is_finite() || (w.length() - 1.0).abs() > 1e-4 {
            invalid += 1;
            continue;
        }
        let Some(c) = chart.coords(w) else { continue };
        let mut b = bin_of(chart, c);
        // A sample on the edge of the pdf's support may be rounded across a bin edge into a bin
        // where the pdf is zero; move it back if a bin within rounding distance is live.
        if prob[b] <= 0.0 {
            let t = Frame::from_z(w);
            let delta = super::DIRECTION_ROUNDING;
            let live = [t.x, -t.x, t.y, -t.y]
                .into_iter()
                .filter_map(|d| chart.coords((w + delta * d).normalize()))
                .map(|c| bin_of(chart, c))
                .find(|&nb| prob[nb] > 0.0);
            if let Some(nb) = live {
                b = nb;
                snapped += 1;
            }
        }
        observed[b] += 1;
        in_domain += 1;
    }

    // A bin that caught samples although its cubature nodes all saw a zero pdf may hold a
    // sliver of the support (an edge where the pdf falls continuously to zero, crossing the bin
    // off its nodes): integrate it again on a fine regular grid before declaring the hits
    // impossible. A pdf that is zero there (a sampler bug) stays zero.
    for (b, p) in prob.iter_mut().enumerate() {
        if *p == 0.0 && observed[b] > 0 {
            let (i, j) = (b / n_b, b % n_b);
            *p = fine_cubature(&f, [ae[i], ae[i + 1], be[j], be[j + 1]], FINE_CELLS);
        }
    }
    let pdf_integral: f64 = prob.iter().sum();

    // Cells: (observed, expected).
    let mut cells: Vec<(f64, f64)> = Vec::with_capacity(n_bins + 1);
    if chart.covers_sphere() {
        for (o, p) in observed.iter().zip(&prob) {
            cells.push((*o as f64, n * p));
        }
        cells.push((
            (cfg.samples - accepted + invalid) as f64,
            n * (1.0 - pdf_integral),
        ));
    } else {
        let m = in_domain as f64;
        for (o, p) in observed.iter().zip(&prob) {
            cells.push((
                *o as f64,
                if pdf_integral > 0.0 {
                    m * p / pdf_integral
                } else {
                    0.0
                },
            ));
        }
    }
    let (chi2, dof, zero_pdf_hits) = pooled_chi2(&mut cells);
    let p_value = if dof >= 1 {
        ChiSquared::new(dof as f64)
            .map(|d| d.sf(chi2))
            .unwrap_or(f64::NAN)
    } else {
        f64::NAN
    };
    Chi2Outcome {
        name: name.to_string(),
        samples: cfg.samples,
        accepted,
        in_domain,
        pdf_integral,
        integral_error,
        chi2,
        dof,
        p_value,
        zero_pdf_hits,
        unconverged_bins,
        invalid,
        snapped,
    }
}

/// χ² statistic over cells sorted by expected count, pooling those below `MIN_EXPECTED` (as
/// Mitsuba's `chi2` does). Cells whose expectation is zero or negative are left out, and the
/// samples they hold are returned as a count to be rejected outright.
fn pooled_chi2(cells: &mut [(f64, f64)]) -> (f64, usize, usize) {
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));
    let (mut chi2, mut n_cells, mut zero_hits) = (0.0, 0usize, 0usize);
    let (mut po, mut pe) = (0.0, 0.0);
    for &(o, e) in cells.iter() {
        if e <= 0.0 {
            zero_hits += o as usize;
            continue;
        }
        if e < MIN_EXPECTED {
            po += o;
            pe += e;
            if pe >= MIN_EXPECTED {
                chi2 += (po - pe) * (po - pe) / pe;
                n_cells += 1;
                (po, pe) = (0.0, 0.0);
            }
            continue;
        }
        // First large cell absorbs what is left in the pool.
        let (o, e) = (o + po, e + pe);
        (po, pe) = (0.0, 0.0);
        chi2 += (o - e) * (o - e) / e;
        n_cells += 1;
    }
    if pe > 0.0 {
        chi2 += (po - pe) * (po - pe) / pe;
        n_cells += 1;
    }
    (chi2, n_cells.saturating_sub(1), zero_hits)
}

impl Chi2Outcome {
    /// Ok when the sampler is consistent with the pdf at per-test significance `alpha`.
    pub fn check(&self, alpha: f64) -> Result<(), String> {
        let mut why = Vec::new();
        if self.invalid > 0 {
            why.push(format!("{} non-unit directions", self.invalid));
        }
        if self.zero_pdf_hits > 0 {
            why.push(format!("{} samples where the pdf is 0", self.zero_pdf_hits));
        }
        if self.unconverged_bins > 0 {
            why.push(format!(
                "cubature did not converge in {} bins",
                self.unconverged_bins
            ));
        }
        if self.dof < 1 {
            why.push("fewer than 2 cells".into());
        }
        if !(self.p_value >= alpha) {
            why.push(format!("rejected: p = {:.3e} < {alpha:.3e}", self.p_value));
        }
        if why.is_empty() {
            Ok(())
        } else {
            Err(format!(
                "{}: {} [{}]",
                self.name,
                why.join("; "),
                self.summary()
            ))
        }
    }

    /// The domain's share of the samples agrees with ∫ pdf over the domain: |z| < 4 for the
    /// binomial count, widened by the cubature error and by the pdf's own f32 rounding (16 ulps).
    pub fn check_mass(&self) -> Result<(), String> {
        let n = self.samples as f64;
        let p = self.pdf_integral.clamp(0.0, 1.0);
        let k = self.in_domain as f64;
        let slack = self.integral_error + 16.0 * f32::EPSILON as f64 * self.pdf_integral.abs();
        let sd = (n * p * (1.0 - p)).sqrt();
        let excess = ((k / n - self.pdf_integral).abs() - slack).max(0.0) * n;
        if self.pdf_integral <= 1.0 + slack && excess <= 4.0 * sd {
            Ok(())
        } else {
            Err(format!(
                "{}: ∫pdf = {:.6} but {} of {} samples landed ({:.6}) [{}]",
                self.name,
                self.pdf_integral,
                k,
                n,
                k / n,
                self.summary()
            ))
        }
    }

    pub fn summary(&self) -> String {
        format!(
            "χ²={:.1} dof={} p={:.4} ∫pdf={:.6}±{:.1e} accepted={}/{} in-domain={} snapped={}",
            self.chi2,
            self.dof,
            self.p_value,
            self.pdf_integral,
            self.integral_error,
            self.accepted,
            self.samples,
            self.in_domain,
            self.snapped
        )
    }
}
