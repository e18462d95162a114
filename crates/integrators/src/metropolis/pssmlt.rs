//! `pssmlt` — primary-sample-space Metropolis light transport (Kelemen et al. 2002): Markov
//! chains over the random numbers of the base integrator's work item (`pt`'s pixel sample, or
//! `bdpt`'s pixel sample with its light subpath and light-tracing splats), following the
//! luminance of everything the item adds (`target`), normalised by a bootstrap estimate of b
//! (`chain`). Consistent: error bars only from `--runs K`.
//!
//! | key | type | default | meaning |
//! |---|---|---|---|
//! | `base` | bdpt/pt | bdpt | the per-path estimator the chains run |
//! | `max_depth` | u32 | scene `[render] max_depth` (8) | longest path in segments, camera ray included |
//! | `rr_depth` | u32 | scene `[render] rr_depth` (5) | Russian roulette from this many segments on |
//! | `mis` | power/balance | power | the base's heuristic |
//! | `p_large` | f32 | 0.3 | probability of a large step (an independent proposal) |
//! | `sigma` | f32 | 0.01 | standard deviation of a small step per primary coordinate |
//! | `bootstrap` | u64 | the pixel count | independent points estimating the normalisation b |
//! | `chains` | u64 | 256 | at most this many Markov chains, fewer when a pass has fewer mutations (fixed by the scene, never by threads) |

use super::chain::{ChainSet, Keys};
use super::target::{Base, Restrict};
use super::{bootstrap_size, ChainParams, MetropolisRun};
use crate::bidirectional::bdpt::{Bdpt, BdptParams, BdptWeights};
use crate::params::ParamReader;
use crate::unidirectional::pt::{Pt, PtParams, Techniques};
use crate::{Progressive, ProgressiveRun};
use lt_core::path::Heuristic;
use lt_core::Scene;

pub struct Pssmlt {
    pub base: Base,
    pub chains: ChainParams,
}

impl Pssmlt {
    pub fn read(scene: &Scene, r: &ParamReader) -> Result<Pssmlt, String> {
        let base = r.get::<String>("base")?.unwrap_or_else(|| "bdpt".into());
        let max_depth = r.max_depth(scene)?;
        let rr_depth = r.rr_depth(scene)?;
        let mis = r
            .get_with("mis", |v| match Heuristic::parse(v)? {
                Heuristic::Uniform => Err("pssmlt takes power or balance".to_string()),
                h => Ok(h),
            })?
            .unwrap_or(Heuristic::Power);
        let chains = ChainParams::read(r)?;
        let base = match base.as_str() {
            "bdpt" => Base::Bdpt(Bdpt {
                params: BdptParams {
                    max_depth,
                    rr_depth,
                    mis,
                    light_paths: None,
                    weights: BdptWeights::Recursive,
                },
            }),
            "pt" => Base::Pt(Pt {
                params: PtParams {
                    max_depth,
                    rr_depth,
                    mis,
                    techniques: Techniques::Both,
                },
            }),
            other => return Err(format!("base = {other}: expected bdpt or pt")),
        };
        Ok(Pssmlt { base, chains })
    }
}

impl Progressive for Pssmlt {
    fn name(&self) -> &'static str {
        "pssmlt"
    }

    fn start<'a>(&'a self, scene: &'a Scene, seed: u64) -> Box<dyn ProgressiveRun + 'a> {
        let p = self.chains;
        let (set, bad) = ChainSet::bootstrap(
            &self.base,
            scene,
            Restrict::Full,
            bootstrap_size(scene, &p),
            p.mutations.sigma,
            Keys {
                seed,
                set: 0,
                bootstrap_set: 0,
            },
        );
        Box::new(MetropolisRun::new(scene, &self.base, p, vec![set], bad))
    }
}
