//! The one report of `lt mis-check`, whichever checker (`pt_bdpt`, `vcm_bpm`) judged the paths:
//! one row per path length k, each path's verdict added to its row.
//!
//! Columns per length k: paths made by a connection technique (and, for estimators that merge,
//! by merging); connection techniques s recorded, and the techniques the oracle found valid
//! (non-zero density) on them — connections s, merges i; max |Σw − 1| and paths failing (b);
//! max relative mismatch of connected (and merged) paths, max absolute mismatch; the median and
//! largest derived tolerance; the largest mismatch over its path's tolerance; paths over their
//! tolerance; paths over 1e-4, 1e-5, 1e-6 relative; max |replayed − oracle| weight.

use super::tolerance::{STRICT_LEVELS, SUM_TOLERANCE};
use lt_core::path::{Heuristic, Technique};
use std::collections::BTreeSet;
use std::fmt;

/// The verdict on one path, as either checker gives it.
#[derive(Clone, Debug)]
pub struct Verdict {
    pub k: usize,
    /// The technique that made the path: a connection s or a merge at x_i.
    pub technique: Technique,
    /// The weight the integrator applied.
    pub weight: f64,
    /// The oracle's weight of the same technique.
    pub oracle: f64,
    /// Relative mismatch of the integrator's weight (check a).
    pub mismatch: f64,
    /// The tolerance of (a) derived for this path: `tolerance::derived_tolerance`.
    pub allowed: f64,
    /// Σ of the integrator's own weights over the techniques, minus 1 (check b).
    pub sum_error: f64,
    /// Largest |replayed weight − oracle weight| over the techniques (0 where nothing replays).
    pub replay_error: f64,
    /// Techniques the oracle considers valid with non-zero density.
    pub valid: Vec<Technique>,
}

impl Verdict {
    /// Over its tolerance (a).
    pub fn over(&self) -> bool {
        !(self.mismatch <= self.allowed)
    }

    /// Fails the partition of unity (b).
    pub fn sum_fails(&self) -> bool {
        !(self.sum_error.abs() <= SUM_TOLERANCE)
    }
}

/// One line of the table: paths of k segments.
#[derive(Clone, Debug, Default)]
pub struct Row {
    pub k: usize,
    /// Paths made by a connection technique.
    pub paths: usize,
    /// Paths made by merging.
    pub merges: usize,
    /// Connection techniques the recorded paths came from.
    pub recorded: BTreeSet<usize>,
    /// Connection techniques the oracle found valid (non-zero density) on any of them.
    pub valid: BTreeSet<usize>,
    /// Merging vertices x_i the oracle found valid on any of them.
    pub valid_merge: BTreeSet<usize>,
    pub max_sum_error: f64,
    /// Largest relative mismatch of a connected path, and of a merged one.
    pub max_mismatch: f64,
    pub max_mismatch_merge: f64,
    pub max_abs_mismatch: f64,
    pub max_replay_error: f64,
    /// Paths over their tolerance of (a).
    pub over: usize,
    /// Paths over each of `STRICT_LEVELS`.
    pub over_strict: [usize; 3],
    /// Paths failing (b).
    pub sum_fail: usize,
    /// Largest mismatch / its path's tolerance.
    pub max_ratio: f64,
    /// Every path's tolerance, for the median and the largest.
    pub allowed: Vec<f64>,
}

impl Row {
    fn add(&mut self, v: &Verdict) {
        match v.technique {
            Technique::Connect(s) => {
                self.paths += 1;
                self.recorded.insert(s);
                self.max_mismatch = self.max_mismatch.max(v.mismatch);
            }
            Technique::Merge(_) => {
                self.merges += 1;
                self.max_mismatch_merge = self.max_mismatch_merge.max(v.mismatch);
            }
        }
        for t in &v.valid {
            match *t {
                Technique::Connect(s) => self.valid.insert(s),
                Technique::Merge(i) => self.valid_merge.insert(i),
            };
        }
        self.max_sum_error = self.max_sum_error.max(v.sum_error.abs());
        self.max_abs_mismatch = self.max_abs_mismatch.max((v.weight - v.oracle).abs());
        self.max_ratio = self.max_ratio.max(v.mismatch / v.allowed);
        self.allowed.push(v.allowed);
        self.max_replay_error = self.max_replay_error.max(v.replay_error);
        for (n, &lvl) in self.over_strict.iter_mut().zip(&STRICT_LEVELS) {
            if v.mismatch > lvl {
                *n += 1;
            }
        }
        self.over += v.over() as usize;
        self.sum_fail += v.sum_fails() as usize;
    }
}

/// The outcome of a check.
#[derive(Clone, Debug)]
pub struct Report {
    pub scene: String,
    /// The integrator, with the options that change its weights (`vcm correlation_aware`).
    pub integrator: String,
    pub heuristic: Heuristic,
    pub slack: f64,
    /// Whether the integrator merges: the table then has the merge columns.
    pub merging: bool,
    pub passes: u32,
    pub rows: Vec<Row>,
    /// Paths the integrator reported beyond max_depth.
    pub too_long: usize,
    /// A few failing paths, described.
    pub examples: Vec<String>,
}

impl Report {
    /// An empty report with rows for k = 0 … `max_depth` (`finish` drops k = 0).
    pub fn new(scene: &str, integrator: String, heuristic: Heuristic, max_depth: u32) -> Report {
        Report {
            scene: scene.to_string(),
            integrator,
            heuristic,
            slack: 1.0,
            merging: false,
            passes: 0,
            rows: (0..=max_depth as usize)
                .map(|k| Row {
                    k,
                    ..Row::default()
                })
                .collect(),
            too_long: 0,
            examples: Vec::new(),
        }
    }

    /// Adds one path's verdict to the row of its length (a longer path gets a row of its own).
    pub fn add(&mut self, v: &Verdict) {
        if v.k >= self.rows.len() {
            let n = self.rows.len();
            self.rows.extend((n..=v.k).map(|k| Row {
                k,
                ..Row::default()
            }));
        }
        self.rows[v.k].add(v);
    }

    /// Drops the rows of no length (k = 0) and the empty rows past the last path.
    pub fn finish(mut self) -> Report {
        self.rows.retain(|r| r.k >= 1);
        self
    }

    pub fn failures(&self) -> usize {
        self.too_long
            + self
                .rows
                .iter()
                .map(|r| r.over.max(r.sum_fail))
                .sum::<usize>()
    }

    pub fn passed(&self) -> bool {
        self.failures() == 0
    }

    /// Paths checked, connected and merged.
    pub fn checked(&self) -> usize {
        self.rows.iter().map(|r| r.paths + r.merges).sum()
    }

    /// Merged paths checked.
    pub fn merges(&self) -> usize {
        self.rows.iter().map(|r| r.merges).sum()
    }
}

/// " × slack" when it is not 1.
pub fn slack_note(slack: f64) -> String {
    if slack == 1.0 {
        String::new()
    } else {
        format!(" × {slack}")
    }
}

/// Median and largest of the tolerances (0, 0 when none).
pub fn median_and_max(v: &[f64]) -> (f64, f64) {
    if v.is_empty() {
        return (0.0, 0.0);
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    (s[s.len() / 2], s[s.len() - 1])
}

fn set_string(s: &BTreeSet<usize>) -> String {
    if s.is_empty() {
        return "-".into();
    }
    s.iter()
        .map(|x| x.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// A column of the table: its header, width and each row's cell; `merging_only` columns are
/// shown for estimators that merge.
struct Column {
    head: &'static str,
    width: usize,
    merging_only: bool,
    cell: fn(&Row) -> String,
}

const fn col(head: &'static str, width: usize, cell: fn(&Row) -> String) -> Column {
    Column {
        head,
        width,
        merging_only: false,
        cell,
    }
}

const fn merge_col(head: &'static str, width: usize, cell: fn(&Row) -> String) -> Column {
    Column {
        head,
        width,
        merging_only: true,
        cell,
    }
}

const COLUMNS: [Column; 19] = [
    col("k", 2, |r| r.k.to_string()),
    col("paths", 6, |r| r.paths.to_string()),
    merge_col("merges", 6, |r| r.merges.to_string()),
    col("recorded s", 15, |r| set_string(&r.recorded)),
    col("valid s", 17, |r| set_string(&r.valid)),
    merge_col("valid merge i", 13, |r| set_string(&r.valid_merge)),
    col("max|Σw−1|", 9, |r| format!("{:.2e}", r.max_sum_error)),
    col("Σfail", 5, |r| r.sum_fail.to_string()),
    col("max rel", 8, |r| format!("{:.2e}", r.max_mismatch)),
    merge_col("rel merge", 9, |r| format!("{:.2e}", r.max_mismatch_merge)),
    col("max abs", 8, |r| format!("{:.2e}", r.max_abs_mismatch)),
    col("tol med", 8, |r| {
        format!("{:.2e}", median_and_max(&r.allowed).0)
    }),
    col("tol max", 8, |r| {
        format!("{:.2e}", median_and_max(&r.allowed).1)
    }),
    col("rel/tol", 7, |r| format!("{:.3}", r.max_ratio)),
    col("over", 5, |r| r.over.to_string()),
    col(">1e-4", 5, |r| r.over_strict[0].to_string()),
    col(">1e-5", 5, |r| r.over_strict[1].to_string()),
    col(">1e-6", 5, |r| r.over_strict[2].to_string()),
    col("replay", 8, |r| format!("{:.1e}", r.max_replay_error)),
];

impl fmt::Display for Report {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        writeln!(
            f,
            "mis-check {} {} mis={} passes={}: (a) |w−w°|/max(w,w°) ≤ the path's derived tolerance{}; (b) |Σw−1| ≤ {:e}{}",
            self.scene,
            self.integrator,
            self.heuristic.name(),
            self.passes,
            slack_note(self.slack),
            SUM_TOLERANCE,
            if self.merging { " over connections and merges" } else { "" }
        )?;
        let columns: Vec<&Column> = COLUMNS
            .iter()
            .filter(|c| self.merging || !c.merging_only)
            .collect();
        let line = |cells: Vec<String>| {
            cells
                .iter()
                .zip(&columns)
                .map(|(s, c)| format!("{s:>w$}", w = c.width))
                .collect::<Vec<_>>()
                .join(" ")
        };
        writeln!(
            f,
            "{}",
            line(columns.iter().map(|c| c.head.to_string()).collect())
        )?;
        for r in &self.rows {
            writeln!(f, "{}", line(columns.iter().map(|c| (c.cell)(r)).collect()))?;
        }
        if self.too_long > 0 {
            writeln!(f, "{} paths reported beyond max_depth", self.too_long)?;
        }
        for e in &self.examples {
            writeln!(f, "  FAIL {e}")?;
        }
        let verdict = if self.passed() { "ok" } else { "FAILED" };
        let merged = if self.merging {
            format!(" ({} merged)", self.merges())
        } else {
            String::new()
        };
        writeln!(
            f,
            "{verdict}: {} paths checked{merged}, {} failing",
            self.checked(),
            self.failures()
        )
    }
}
