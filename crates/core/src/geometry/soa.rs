//! Structure-of-arrays chunks: the layout the flat core's vectorised primitive tests read
//! (`quad::QuadSoa`, `sphere::SphereSoa`).

/// Primitives per vectorised test: AVX-512's 16 f32 lanes, two AVX2 vectors, four SSE ones.
pub const CHUNK: usize = 16;

/// Items in structure-of-arrays chunks of `CHUNK`: `[k][i]` is field k of the chunk's item i (as
/// `fields` lists them). The last chunk is padded with NaN fields, which no primitive test hits.
pub fn soa_chunks<T, const K: usize>(
    items: &[T],
    fields: impl Fn(&T) -> [f32; K],
) -> Vec<[[f32; CHUNK]; K]> {
    items
        .chunks(CHUNK)
        .map(|chunk| {
            let mut f = [[f32::NAN; CHUNK]; K];
            for (i, item) in chunk.iter().enumerate() {
                for (k, x) in fields(item).into_iter().enumerate() {
                    f[k][i] = x;
                }
            }
            f
        })
        .collect()
}
