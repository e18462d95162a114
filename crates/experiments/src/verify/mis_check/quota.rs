//! How many recorded paths a checker keeps: up to a quota per (path length k, technique), paths
//! beyond the longest length counted as errors (an integrator reporting a path it should not
//! have made). One generic counter for the checkers whose techniques are an ordered type
//! (`vcm_bpm`'s `Technique`, `upbp`'s `VolumeTechnique`).

use std::collections::BTreeMap;

pub struct QuotaCounts<T> {
    quota: usize,
    max_depth: usize,
    counts: BTreeMap<(usize, T), usize>,
    /// Paths reported with k = 0 or beyond `max_depth`.
    pub too_long: usize,
}

impl<T: Ord + Copy> QuotaCounts<T> {
    pub fn new(quota: usize, max_depth: usize) -> QuotaCounts<T> {
        QuotaCounts {
            quota,
            max_depth,
            counts: BTreeMap::new(),
            too_long: 0,
        }
    }

    pub fn quota(&self) -> usize {
        self.quota
    }

    pub fn max_depth(&self) -> usize {
        self.max_depth
    }

    /// Whether a path of length `k` made by `t` is kept (its count then goes up).
    pub fn keep(&mut self, k: usize, t: T) -> bool {
        if k > self.max_depth || k == 0 {
            self.too_long += 1;
            return false;
        }
        let n = self.counts.entry((k, t)).or_insert(0);
        if *n >= self.quota {
            return false;
        }
        *n += 1;
        true
    }

    /// Paths kept of length `k` whose technique satisfies `which`.
    pub fn of_length(&self, k: usize, which: impl Fn(&T) -> bool) -> usize {
        self.counts
            .iter()
            .filter(|((kk, t), _)| *kk == k && which(t))
            .map(|(_, n)| n)
            .sum()
    }
}
