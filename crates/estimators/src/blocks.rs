//! Per-region (block) estimates. A block's mean is taken within each pass first, and the passes'
//! block means are then treated as the independent samples: pixels inside one pass may be
//! correlated (light-tracing splats, shared light paths), passes are not.

use crate::image::Image;
use crate::running::RunningImage;

/// Mean of each `block`×`block` region of `img`, as a `blocks_x`×`blocks_y` image. Edge blocks are
/// smaller when the size is not a multiple of `block`; each is the mean of the pixels it covers.
pub fn block_means(img: &Image, block: usize) -> Image {
    assert!(block > 0, "block size must be positive");
    let (bx, by) = (img.width.div_ceil(block), img.height.div_ceil(block));
    let mut out = Image::new(bx, by);
    let mut n = vec![0u32; bx * by];
    for y in 0..img.height {
        for x in 0..img.width {
            let i = (y / block) * bx + x / block;
            let p = img.get(x, y);
            for (o, v) in out.data[i].iter_mut().zip(p) {
                *o += v;
            }
            n[i] += 1;
        }
    }
    for (o, &k) in out.data.iter_mut().zip(&n) {
        o.iter_mut().for_each(|v| *v /= k as f64);
    }
    out
}

/// Welford over passes of each pass's per-block mean.
#[derive(Clone, Debug, PartialEq)]
pub struct RunningBlocks {
    width: usize,
    height: usize,
    block: usize,
    acc: RunningImage,
}

impl RunningBlocks {
    /// `block` is the side in pixels; edge blocks may be smaller.
    pub fn new(width: usize, height: usize, block: usize) -> Self {
        assert!(block > 0, "block size must be positive");
        let acc = RunningImage::new(width.div_ceil(block), height.div_ceil(block));
        RunningBlocks {
            width,
            height,
            block,
            acc,
        }
    }

    pub fn add(&mut self, pass: &Image) {
        assert!(
            pass.width == self.width && pass.height == self.height,
            "RunningBlocks::add: pass is {}x{}, expected {}x{}",
            pass.width,
            pass.height,
            self.width,
            self.height
        );
        self.acc.add(&block_means(pass, self.block));
    }

    pub fn merge(&mut self, other: &RunningBlocks) {
        assert!(
            (self.width, self.height, self.block) == (other.width, other.height, other.block),
            "RunningBlocks::merge: different image or block size"
        );
        self.acc.merge(&other.acc);
    }

    pub fn count(&self) -> u64 {
        self.acc.count()
    }

    pub fn block(&self) -> usize {
        self.block
    }

    /// Per block and channel: the mean over passes and its standard error (NaN below two passes,
    /// which makes any agreement test on it fail rather than pass vacuously).
    pub fn estimate(&self) -> BlockEstimate {
        BlockEstimate {
            blocks_x: self.acc.width(),
            blocks_y: self.acc.height(),
            mean: self.acc.mean().data,
            std_error: self.acc.std_error().data,
        }
    }
}

/// Per-region means with their standard errors, row-major over blocks.
#[derive(Clone, Debug, PartialEq)]
pub struct BlockEstimate {
    pub blocks_x: usize,
    pub blocks_y: usize,
    pub mean: Vec<[f64; 3]>,
    pub std_error: Vec<[f64; 3]>,
}

impl BlockEstimate {
    pub fn regions(&self) -> usize {
        self.blocks_x * self.blocks_y
    }

    /// From a per-pixel mean image and its per-pixel standard-error image (e.g. written by a
    /// renderer). Assumes pixel errors are independent — true when each pixel is sampled on its
    /// own (path tracing), false for splatting estimators; for those use [`RunningBlocks`].
    pub fn from_pixel_estimates(mean: &Image, std_error: &Image, block: usize) -> BlockEstimate {
        assert!(
            mean.same_size(std_error),
            "mean and standard-error images differ in size"
        );
        let var = Image {
            width: mean.width,
            height: mean.height,
            data: std_error.data.iter().map(|s| s.map(|v| v * v)).collect(),
        };
        let (m, v) = (block_means(mean, block), block_means(&var, block));
        let std_error = (0..m.data.len())
            .map(|i| {
                let (bx, by) = (i % m.width, i / m.width);
                let w = mean.width.min((bx + 1) * block) - bx * block;
                let h = mean.height.min((by + 1) * block) - by * block;
                // Mean of n independent errors: variance (mean of σ²)/n.
                v.data[i].map(|v| (v / (w * h) as f64).sqrt())
            })
            .collect();
        BlockEstimate {
            blocks_x: m.width,
            blocks_y: m.height,
            mean: m.data,
            std_error,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_rng::Rng;

    #[test]
    fn edge_blocks_average_only_their_pixels() {
        let img = Image::from_fn(5, 3, |x, y| [x as f64, y as f64, 1.0]);
        let b = block_means(&img, 2);
        assert_eq!((b.width, b.height), (3, 2));
        assert_eq!(b.get(2, 0), [4.0, 0.5, 1.0]); // column 4, rows 0-1
        assert_eq!(b.get(2, 1), [4.0, 2.0, 1.0]); // a single pixel
        assert_eq!(b.get(0, 1), [0.5, 2.0, 1.0]);
    }

    // Passes where every pixel of a block shares one random offset: the pixel-level spread says
    // nothing about the block mean's error, the pass-level spread does. The standard error must
    // match the known σ/√n within its own sampling error.
    #[test]
    fn correlated_pixels_use_pass_level_spread() {
        let (w, h, block, n) = (8, 8, 4, 400);
        let mut rng = Rng::new(11);
        let mut rb = RunningBlocks::new(w, h, block);
        for _ in 0..n {
            let offs: Vec<f64> = (0..4).map(|_| rng.normal()).collect();
            rb.add(&Image::from_fn(w, h, |x, y| {
                [offs[(y / block) * 2 + x / block] + 10.0; 3]
            }));
        }
        let e = rb.estimate();
        let expect = 1.0 / (n as f64).sqrt();
        // s/σ has relative standard deviation ≈ 1/sqrt(2(n-1)); allow 4 of them.
        let rel = 4.0 / (2.0 * (n as f64 - 1.0)).sqrt();
        for se in &e.std_error {
            assert!((se[0] / expect - 1.0).abs() < rel, "{} vs {expect}", se[0]);
        }
    }

    #[test]
    fn blocks_merge_equals_sequential() {
        let mut rng = Rng::new(5);
        let passes: Vec<Image> = (0..20)
            .map(|_| Image::from_fn(7, 5, |_, _| [rng.normal(), rng.uniform(), rng.exp()]))
            .collect();
        let (mut all, mut a, mut b) = (
            RunningBlocks::new(7, 5, 3),
            RunningBlocks::new(7, 5, 3),
            RunningBlocks::new(7, 5, 3),
        );
        for (i, p) in passes.iter().enumerate() {
            all.add(p);
            if i % 3 == 0 {
                a.add(p)
            } else {
                b.add(p)
            }
        }
        a.merge(&b);
        let (x, y) = (a.estimate(), all.estimate());
        // Rounding bound as in running.rs: n·eps·|x|max for means, ·|d|max/(n-1) for variances.
        let n = passes.len() as f64;
        let xmax = passes
            .iter()
            .flat_map(|p| p.data.iter().flatten())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let (tol_m, tol_v) = (
            8.0 * n * f64::EPSILON * xmax,
            8.0 * n * f64::EPSILON * xmax * 2.0 * xmax / (n - 1.0),
        );
        for i in 0..x.mean.len() {
            for c in 0..3 {
                assert!((x.mean[i][c] - y.mean[i][c]).abs() <= tol_m);
                let (va, vb) = (x.std_error[i][c].powi(2) * n, y.std_error[i][c].powi(2) * n);
                assert!((va - vb).abs() <= tol_v, "{va} vs {vb}");
            }
        }
    }

    #[test]
    fn pixel_estimates_combine_as_independent() {
        let mean = Image::from_fn(3, 2, |x, _| [x as f64; 3]);
        let se = Image::from_fn(3, 2, |_, _| [2.0; 3]);
        let e = BlockEstimate::from_pixel_estimates(&mean, &se, 2);
        assert!((e.std_error[0][0] - 1.0).abs() < 1e-15); // 4 pixels: 2/√4
        assert!((e.std_error[1][0] - 2.0f64 / 2f64.sqrt()).abs() < 1e-15); // 2 pixels
        assert_eq!(e.mean[1], [2.0; 3]);
    }
}
