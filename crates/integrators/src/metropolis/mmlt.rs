//! `mmlt` — multiplexed Metropolis light transport (Hachisuka, Kaplanyan & Dachsbacher 2014):
//! one chain set per path length k (1 … `max_depth` segments), each state choosing one bdpt
//! strategy (s, t = k + 1 − s) from its own primary number and contributing that strategy's
//! MIS-weighted value times k + 1 (`target`). A mutation evaluates that strategy alone
//! (`strategy`): a camera walk of t vertices and a light walk of s vertices from the state's
//! camera and light streams, one connection, bdpt's MIS weight. The lengths share one bootstrap:
//! each of its points walks both subpaths in full once and reads every length's strategies from
//! them (the same number picks each length's strategy), so every b̂_k averages all `bootstrap`
//! points; a pass's N mutations are shared ∝ b̂_k. Consistent: error bars from `--runs K`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance | power | heuristic over bdpt's strategies |
//! | `p_large` | f32 | 0.3 | probability of a large step (an independent proposal) |
//! | `sigma` | f32 | 0.01 | standard deviation of a small step per primary coordinate |
//! | `bootstrap` | u64 | the pixel count | independent points (full walks, every strategy joined), each giving every length's I_k, estimating the b_k |
//! | `chains` | u64 | 256 | at most this many chains per path length, fewer when its share of a pass's mutations is smaller |

use super::chain::ChainSet;
use super::target::Base;
use super::{bootstrap_size, ChainParams, MetropolisRun};
use crate::bidirectional::bdpt::{Bdpt, BdptParams, BdptWeights};
use crate::params::ParamReader;
use crate::{Progressive, ProgressiveRun};
use lt_core::path::Heuristic;
use lt_core::Scene;

pub struct Mmlt {
    pub base: Base,
    pub max_depth: u32,
    pub chains: ChainParams,
}

impl Mmlt {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Mmlt, String> {
        let max_depth = r.max_depth(scene)?;
        let rr_depth = r.rr_depth(scene)?;
        let mis = r
            .get_with("mis", |v| match Heuristic::parse(v)? {
                Heuristic::Uniform => Err("mmlt takes power or balance".to_string()),
                h => Ok(h),
            })?
            .unwrap_or(Heuristic::Power);
        let chains = ChainParams::read(r)?;
        let base = Base::Bdpt(Bdpt {
            params: BdptParams {
                max_depth,
                rr_depth,
                mis,
                light_paths: None,
                weights: BdptWeights::Recursive,
            },
        });
        Ok(Mmlt {
            base,
            max_depth,
            chains,
        })
    }
}

impl Progressive for Mmlt {
    fn name(&self) -> &'static str {
        "mmlt"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        let p = self.chains;
        let (sets, bad) = ChainSet::bootstrap_lengths(
            &self.base,
            scene,
            bootstrap_size(scene, &p),
            p.mutations.sigma,
            seed,
        );
        Box::new(MetropolisRun::new(scene, &self.base, p, sets, bad))
    }
}
