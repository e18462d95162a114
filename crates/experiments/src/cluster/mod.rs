//! Scale-out (issue 14): exact partial renders and their merge, and plans of independent shards
//! handed to Slurm, GNU parallel or the local pool. The testbed plans the work and merges it; the
//! cluster's own scheduler runs it. Every shard's output lives in the experiments' one cache
//! (`crate::cache`), keyed by the hash of its inputs, so a rerun redoes only what is missing.
//!
//! - `partial`: the `.ltp` format (count, per-pixel mean and M2 in f64, identity), the pass-range
//!   and run-set renders, and the exact merge with its refusals.
//! - `plan`: plans of a render or a study (`lt plan render|study`), the plan folder.
//! - `shard`: one shard run into the cache, with its state file (`lt run-shard`).
//! - `submit`: a plan handed to Slurm, GNU parallel or the local pool (`lt submit`).
//! - `collect`: finished shards merged into the render or the study (`lt collect`).
//! - `assemble`: a study render split into pass ranges made back into its cache entry.
//! - `study_link`: which renders a study needs and how its outputs are made.
//!
//! The five subcommands' arguments live in `crate::commands` (`merge`, `plan`, `run_shard`,
//! `submit`, `collect`), which hands them here. See docs/cluster.md.

pub mod assemble;
pub mod collect;
pub mod partial;
pub mod plan;
pub mod shard;
pub mod study_link;
pub mod submit;
