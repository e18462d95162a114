//! A linear RGB image in f64, row-major, the currency of every statistic in this crate.

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    /// Row-major pixels, (x, y) at `y * width + x`.
    pub data: Vec<[f64; 3]>,
}

impl Image {
    pub fn new(width: usize, height: usize) -> Image {
        Image {
            width,
            height,
            data: vec![[0.0; 3]; width * height],
        }
    }

    pub fn from_fn(
        width: usize,
        height: usize,
        mut f: impl FnMut(usize, usize) -> [f64; 3],
    ) -> Image {
        let mut data = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                data.push(f(x, y));
            }
        }
        Image {
            width,
            height,
            data,
        }
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> [f64; 3] {
        self.data[y * self.width + x]
    }

    pub fn same_size(&self, other: &Image) -> bool {
        self.width == other.width && self.height == other.height
    }

    /// The mean of `passes` images whose sum this is (the sum itself when `passes` is 0):
    /// every value times 1/`passes`, as the progressive estimators report their passes' mean.
    pub fn mean_of_passes(&self, passes: u32) -> Image {
        let mut img = self.clone();
        if passes > 0 {
            let k = 1.0 / passes as f64;
            for c in img.data.iter_mut().flatten() {
                *c *= k;
            }
        }
        img
    }
}
