//! The film side of a pass: one camera sample per pixel through the pixel filter (`pixel`) and
//! deterministic splatting of contributions that land anywhere (`splat`).

pub mod pixel;
pub mod splat;
