//! The statistics every test and study in the workspace stands on: running means and variances,
//! per-region estimates, the agreement test, image metrics, bias/variance decomposition,
//! log-log fits, efficiency. No rendering code lives here.

pub mod agreement;
pub mod batch_means;
pub mod bias_variance;
pub mod binomial;
pub mod blocks;
pub mod fit;
pub mod image;
pub mod jackknife;
pub mod metrics;
pub mod mse_time;
pub mod running;

#[cfg(test)]
mod test_rng;

pub use agreement::{
    agreement, agreement_t, agreement_with_reference, agreement_with_reference_t, sidak_threshold,
    Agreement,
};
pub use batch_means::{naive_interval_coverage, BatchMeans, Ess, EssSummary};
pub use bias_variance::{BiasVariance, ImageBiasVariance, Interval};
pub use binomial::{binomial_test, BinomialTest};
pub use blocks::{block_means, BlockEstimate, RunningBlocks};
pub use fit::{fit_line, fit_log_log, LineFit};
pub use image::Image;
pub use jackknife::{jackknife, Jackknifed};
pub use metrics::{image_metrics, psnr, ChannelMetrics, ImageMetrics};
pub use mse_time::{efficiency, time_to_mse, time_to_mse_extrapolated};
pub use running::{RunningImage, RunningStat};
