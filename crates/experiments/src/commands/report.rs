//! `lt report`: RESULTS/index.html from the studies' outputs (`crate::report`).

use crate::report::write_report;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The results folder holding one sub-folder per study.
    #[arg(long, default_value = "results")]
    pub results: PathBuf,
    /// First re-encode the folder's rendered PNGs as the JPEG previews galleries now write,
    /// moving each PNG into its study's git-ignored `full/` folder (`crate::report::slim`).
    #[arg(long)]
    pub slim: bool,
}

pub fn run(args: &ReportArgs) -> Result<(), String> {
    if args.slim {
        let s = crate::report::slim::slim(&args.results)?;
        println!(
            "{} PNGs ({:.1} MB) now JPEG previews ({:.1} MB); {} crops moved to full/; \
             {} charts re-encoded, {:.1} MB saved; {} thumbnails made",
            s.previews,
            s.png_bytes as f64 / 1e6,
            s.jpeg_bytes as f64 / 1e6,
            s.crops,
            s.charts,
            s.chart_bytes_saved as f64 / 1e6,
            s.thumbs
        );
    }
    let path = write_report(&args.results)?;
    println!("{}", path.display());
    Ok(())
}
