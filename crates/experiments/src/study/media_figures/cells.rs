//! A cell of a figure — one estimator with its parameters on one scene — and its equal-time
//! pass count from two cached probes (the module doc of `media_figures` says why two).

use super::super::figures::equal_time_passes;
use super::super::output::film;
use super::super::{Scale, StudyContext};
use super::Budget;
use crate::runs::{RunEntry, RunSpec};
use std::path::PathBuf;

/// Passes of the first probe.
pub const PROBE_PASSES: u32 = 4;

/// Seeds of the probes (first, second): far from the runs' 1 … K and the references' 10⁶, so a
/// probe shares no random sequence with a run.
const PROBE_SEEDS: [u64; 2] = [500_000, 500_001];

#[derive(Clone, Debug)]
pub struct Cell {
    pub scene: PathBuf,
    pub integrator: &'static str,
    /// `--set` parameters, as (key, value).
    pub params: Vec<(&'static str, String)>,
}

impl Cell {
    pub fn new(scene: PathBuf, integrator: &'static str) -> Cell {
        Cell {
            scene,
            integrator,
            params: Vec::new(),
        }
    }

    pub fn with(mut self, key: &'static str, value: impl ToString) -> Cell {
        self.params.push((key, value.to_string()));
        self
    }

    fn spec(&self, fs: &Scale, seed: u64, passes: u32) -> Result<RunSpec, String> {
        let mut s = RunSpec::new(&self.scene, self.integrator, seed, passes)
            .resolution(Some(film(fs, &self.scene)?));
        for (k, v) in &self.params {
            s = s.param(k, v);
        }
        Ok(s)
    }

    fn probe(&self, fs: &Scale, stage: usize, passes: u32) -> Result<RunSpec, String> {
        self.spec(fs, PROBE_SEEDS[stage], passes)
    }

    /// The K runs at `passes` (seeds 1 … K).
    pub fn runs(&self, b: &Budget, fs: &Scale, passes: u32) -> Result<Vec<RunSpec>, String> {
        (1..=b.runs as u64)
            .map(|seed| self.spec(fs, seed, passes))
            .collect()
    }
}

fn cpu(e: &RunEntry) -> f64 {
    e.cpu_seconds_at(e.record.spec.passes).unwrap_or(f64::NAN)
}

/// Mean CPU seconds per run of `entries`.
pub fn mean_cpu(entries: &[RunEntry]) -> f64 {
    entries.iter().map(cpu).sum::<f64>() / entries.len().max(1) as f64
}

/// The pass count that fits the budget at a probe's measured cost per pass.
fn passes_after(b: &Budget, probe: &RunEntry) -> Result<u32, String> {
    equal_time_passes(b.cpu_seconds, cpu(probe) / probe.record.spec.passes as f64)
        .map_err(|e| format!("{}: {e}", probe.record.spec.label()))
}

/// The cell's renders the cache makes known (for `lt plan study`): probe 1; probe 2 once probe 1
/// is found; the runs once probe 2 is. Without a context, probe 1 alone.
pub fn planned(
    c: &Cell,
    b: &Budget,
    fs: &Scale,
    ctx: Option<&StudyContext>,
) -> Result<Vec<RunSpec>, String> {
    let p1 = c.probe(fs, 0, PROBE_PASSES)?;
    let mut v = vec![p1.clone()];
    let Some(ctx) = ctx else { return Ok(v) };
    let Some(e1) = ctx.runs.lookup(&p1)? else {
        return Ok(v);
    };
    let p2 = c.probe(fs, 1, passes_after(b, &e1)?)?;
    v.push(p2.clone());
    if let Some(e2) = ctx.runs.lookup(&p2)? {
        v.extend(c.runs(b, fs, passes_after(b, &e2)?)?);
    }
    Ok(v)
}

/// The cell's runs at its equal-time pass count (probes and runs rendered if the cache lacks
/// them) and that count.
pub fn measure(
    ctx: &StudyContext,
    c: &Cell,
    b: &Budget,
    fs: &Scale,
) -> Result<(u32, Vec<RunEntry>), String> {
    let e1 = ctx.run(&c.probe(fs, 0, PROBE_PASSES)?)?;
    let e2 = ctx.run(&c.probe(fs, 1, passes_after(b, &e1)?)?)?;
    let n = passes_after(b, &e2)?;
    Ok((n, ctx.run_all(&c.runs(b, fs, n)?)?))
}
