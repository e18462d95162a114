//! Mitsuba's binary volume grids (`.vol`, the format of its `gridvolume` and `sdfgrid`): "VOL",
//! version byte 3, then little-endian i32 encoding (1 = f32, the only one read here), i32
//! x, y, z resolution and channel count, six f32 of a bounding box (unused: an sdfgrid spans its
//! unit cube), then the values, x fastest, then y, then z, channels interleaved.

use super::le_bytes::{f32s, i32_at};
use crate::error::Ctx;
use crate::format::S;
use crate::SceneError;
use lt_core::shape::SdfGrid;

/// The one-channel grid of `file` for an `sdfgrid` (`smooth`: its shading normals).
pub(crate) fn load_sdf_grid(
    ctx: &Ctx,
    file: &S<String>,
    smooth: bool,
) -> Result<SdfGrid, SceneError> {
    let (path, bytes) = ctx.read_mesh(file)?;
    parse(&bytes, smooth).map_err(|msg| {
        ctx.at(
            file.span(),
            format!("malformed volume grid file {}: {msg}", path.display()),
        )
    })
}

const HEADER: usize = 48;

fn parse(b: &[u8], smooth: bool) -> Result<SdfGrid, String> {
    if b.get(..3) != Some(b"VOL") {
        return Err("it does not start with `VOL`".into());
    }
    let short = || "it is shorter than its 48-byte header".to_string();
    if b.get(3) != Some(&3) {
        return Err(format!(
            "version {:?} is not 3",
            b.get(3).ok_or_else(short)?
        ));
    }
    let encoding = i32_at(b, 4).ok_or_else(short)?;
    if encoding != 1 {
        return Err(format!(
            "encoding {encoding} is not 1 (32-bit floats), the one lt reads"
        ));
    }
    let dims: Vec<i32> = (0..4)
        .map(|k| i32_at(b, 8 + 4 * k))
        .collect::<Option<_>>()
        .ok_or_else(short)?;
    let channels = dims[3];
    if channels != 1 {
        return Err(format!("it has {channels} channels; an sdfgrid needs 1"));
    }
    if dims[..3].iter().any(|&n| n < 2) {
        return Err(format!(
            "resolution {}×{}×{}: an sdfgrid needs at least 2 values per axis",
            dims[0], dims[1], dims[2]
        ));
    }
    let res = [dims[0] as usize, dims[1] as usize, dims[2] as usize];
    let count = res
        .iter()
        .try_fold(1usize, |n, &r| n.checked_mul(r))
        .ok_or("its resolution overflows")?;
    let need = count
        .checked_mul(4)
        .and_then(|n| n.checked_add(HEADER))
        .ok_or("its resolution overflows")?;
    if b.len() < need {
        return Err(format!(
            "truncated: {}×{}×{} values need {need} bytes, the file has {}",
            res[0],
            res[1],
            res[2],
            b.len()
        ));
    }
    let values = f32s(&b[HEADER..need]);
    if let Some(k) = values.iter().position(|v| !v.is_finite()) {
        return Err(format!("value {k} is NaN or infinite"));
    }
    let grid = SdfGrid {
        res,
        values,
        smooth,
    };
    if grid.surface_voxels().is_empty() {
        return Err("no voxel holds a surface (every value has one sign)".into());
    }
    Ok(grid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn file(res: [i32; 3], values: &[f32]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, res[0], res[1], res[2], 1] {
            b.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
        for v in values {
            b.extend(v.to_le_bytes());
        }
        b
    }

    #[test]
    fn reads_a_grid_and_refuses_bad_ones() {
        let vals = [-1.0, 1.0, -1.0, 1.0, -1.0, 1.0, -1.0, 1.0];
        let g = parse(&file([2, 2, 2], &vals), true).unwrap();
        assert_eq!(g.res, [2, 2, 2]);
        assert_eq!(g.corners([0, 0, 0]), vals);
        let good = file([2, 2, 2], &vals);
        for len in 0..good.len() {
            assert!(parse(&good[..len], true).is_err(), "length {len}");
        }
        assert!(parse(&file([2, 2, 2], &[1.0; 8]), true)
            .unwrap_err()
            .contains("no voxel"));
        assert!(parse(&file([1, 2, 2], &[1.0; 4]), true)
            .unwrap_err()
            .contains("at least 2"));
        let mut nan = vals;
        nan[3] = f32::NAN;
        assert!(parse(&file([2, 2, 2], &nan), true)
            .unwrap_err()
            .contains("value 3"));
    }

    #[test]
    fn reads_the_suites_torus() {
        let path = "/work/shared/mitsuba-render-tests/docs/scenes/sdfgrid/torus_sdfgrid.vol";
        let Ok(bytes) = std::fs::read(path) else {
            return; // the suite is not on this machine
        };
        let g = parse(&bytes, true).unwrap();
        assert_eq!(g.res, [40, 40, 40]);
        assert!(!g.surface_voxels().is_empty());
    }
}
