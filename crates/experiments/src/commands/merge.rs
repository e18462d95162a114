//! `lt merge PARTS… -o OUT.exr`: partial renders (`lt render … --partial`) merged exactly into
//! what `lt render` writes, or into one larger part (`--partial`) for merging in stages.

use crate::cluster::partial::{merge as merge_parts, Partial, Span};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Partial renders (`.ltp`), in any order: they are merged in order of their first pass or
    /// seed.
    #[arg(required = true)]
    pub parts: Vec<PathBuf>,
    /// The merged render: OUT.exr with .png, .stderr.exr and .json beside it.
    #[arg(long, short, required_unless_present = "partial")]
    pub output: Option<PathBuf>,
    /// Also write the merged accumulation as one part.
    #[arg(long, value_name = "OUT.ltp")]
    pub partial: Option<PathBuf>,
    /// Merge even if passes (or seeds) are missing between the parts; the record lists them.
    #[arg(long)]
    pub allow_incomplete: bool,
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(args: &MergeArgs) -> Result<(), String> {
    let mut parts = Vec::new();
    for p in &args.parts {
        parts.push((p.clone(), Partial::read(p)?));
    }
    let merged = merge_parts(&parts, args.allow_incomplete)?;
    if !merged.missing.is_empty() {
        eprintln!(
            "warning: merged with {} missing: {}",
            if merged.missing.len() == 1 {
                "a gap"
            } else {
                "gaps"
            },
            merged.missing.join(", ")
        );
    }
    let sources: Vec<String> = args.parts.iter().map(|p| p.display().to_string()).collect();
    if let Some(out) = &args.output {
        merged.write_outputs(out, &sources, serde_json::Value::Null)?;
    }
    if let Some(p) = &args.partial {
        merged.to_partial().write(p)?;
    }
    if !args.quiet {
        eprintln!(
            "merged {} parts ({}, {} {}) -> {}",
            merged.parts,
            merged.span.describe(),
            merged.acc.count(),
            if matches!(merged.span, Span::Passes { .. }) {
                "passes"
            } else {
                "runs"
            },
            args.output
                .iter()
                .chain(&args.partial)
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join(" and ")
        );
    }
    Ok(())
}
