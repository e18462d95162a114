//! Scale-out: exact partial renders, their merge, and plans of shards for Slurm or GNU parallel
//! (issue 14; not yet).

use clap::Args;

macro_rules! not_yet {
    ($args:ident, $fn:ident, $what:literal) => {
        #[derive(Args, Debug)]
        pub struct $args {}
        pub fn $fn(_: &$args) -> Result<(), String> {
            Err(concat!("lt ", $what, " is not written yet").into())
        }
    };
}
not_yet!(MergeArgs, merge, "merge");
not_yet!(PlanArgs, plan, "plan");
not_yet!(RunShardArgs, run_shard, "run-shard");
not_yet!(SubmitArgs, submit, "submit");
not_yet!(CollectArgs, collect, "collect");
