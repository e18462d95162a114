//! Little-endian numbers in the bytes of a binary file (Mitsuba's `.serialized` meshes and `.vol`
//! grids are both little endian). A read past the end is `None`, so a truncated file becomes an
//! error naming what was cut short, never a panic.

/// The `N` bytes from `at` on, None past the end.
fn word<const N: usize>(b: &[u8], at: usize) -> Option<[u8; N]> {
    b.get(at..at.checked_add(N)?)?.try_into().ok()
}

pub(crate) fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    word(b, at).map(u16::from_le_bytes)
}

pub(crate) fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    word(b, at).map(u32::from_le_bytes)
}

pub(crate) fn i32_at(b: &[u8], at: usize) -> Option<i32> {
    word(b, at).map(i32::from_le_bytes)
}

pub(crate) fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    word(b, at).map(u64::from_le_bytes)
}

/// Every whole u32 in `b`, in order.
pub(crate) fn u32s(b: &[u8]) -> Vec<u32> {
    b.chunks_exact(4)
        .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect()
}

/// Every whole f32 in `b`, in order.
pub(crate) fn f32s(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(4)
        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
        .collect()
}

/// Every whole f64 in `b`, in order, rounded to f32 (as Mitsuba rounds a double-precision mesh).
pub(crate) fn f64s_as_f32(b: &[u8]) -> Vec<f32> {
    b.chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")) as f32)
        .collect()
}
