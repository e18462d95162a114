//! Mitsuba's binary volume grids (`.vol`, the format of its `gridvolume` and `sdfgrid`): "VOL",
//! version byte 3, then little-endian i32 encoding (1 = f32, the only one read here), i32
//! x, y, z resolution and channel count, six f32 of a bounding box (xmin, ymin, zmin, xmax, ymax,
//! zmax: an sdfgrid spans its unit cube and ignores it, a gridvolume reads it under
//! `use_grid_bbox`), then the values, x fastest, then y, then z, channels interleaved.

use super::le_bytes::{f32s, i32_at};
use crate::error::Ctx;
use crate::format::S;
use crate::SceneError;
use lt_core::math::Vec3;
use lt_core::medium::VolumeGrid;
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

/// The grid of `file` for a `gridvolume` (1 or 3 channels).
pub(crate) fn load_volume_grid(ctx: &Ctx, file: &S<String>) -> Result<VolumeGrid, SceneError> {
    let (path, bytes) = ctx.read_mesh(file)?;
    parse_volume(&bytes).map_err(|msg| {
        ctx.at(
            file.span(),
            format!("malformed volume grid file {}: {msg}", path.display()),
        )
    })
}

const HEADER: usize = 48;

/// The 48-byte header: resolution and channel count as stored (not yet checked for range), and
/// the bounding box.
struct Header {
    dims: [i32; 3],
    channels: i32,
    bbox: [Vec3; 2],
}

fn parse_header(b: &[u8]) -> Result<Header, String> {
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
    let bytes = b.get(24..HEADER).ok_or_else(short)?;
    let bb = f32s(bytes);
    Ok(Header {
        dims: [dims[0], dims[1], dims[2]],
        channels: dims[3],
        bbox: [
            Vec3::new(bb[0], bb[1], bb[2]),
            Vec3::new(bb[3], bb[4], bb[5]),
        ],
    })
}

/// Bytes of header and values for `res` × `channels` f32, or None on overflow.
fn file_size(res: [usize; 3], channels: usize) -> Option<usize> {
    res.iter()
        .try_fold(channels, |n, &r| n.checked_mul(r))?
        .checked_mul(4)?
        .checked_add(HEADER)
}

fn parse(b: &[u8], smooth: bool) -> Result<SdfGrid, String> {
    let h = parse_header(b)?;
    let (dims, channels) = (h.dims, h.channels);
    if channels != 1 {
        return Err(format!("it has {channels} channels; an sdfgrid needs 1"));
    }
    if dims.iter().any(|&n| n < 2) {
        return Err(format!(
            "resolution {}×{}×{}: an sdfgrid needs at least 2 values per axis",
            dims[0], dims[1], dims[2]
        ));
    }
    let res = dims.map(|n| n as usize);
    let need = file_size(res, 1).ok_or("its resolution overflows")?;
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

/// A `gridvolume`'s grid: 1 or 3 channels, at least one value per axis, exactly as many bytes as
/// the header calls for (a longer file is as inconsistent as a shorter one), finite values.
fn parse_volume(b: &[u8]) -> Result<VolumeGrid, String> {
    let h = parse_header(b)?;
    let (dims, channels) = (h.dims, h.channels);
    if channels != 1 && channels != 3 {
        return Err(format!(
            "it has {channels} channels; a gridvolume reads 1 or 3"
        ));
    }
    if dims.iter().any(|&n| n < 1) {
        return Err(format!(
            "resolution {}×{}×{} has an empty or negative axis",
            dims[0], dims[1], dims[2]
        ));
    }
    let res = dims.map(|n| n as usize);
    let channels = channels as usize;
    let need = file_size(res, channels).ok_or("its resolution overflows")?;
    if b.len() != need {
        return Err(format!(
            "{} data: {}×{}×{} × {channels} channels of f32 need {} bytes after the header, the file has {}",
            if b.len() < need { "truncated" } else { "inconsistent header or trailing" },
            res[0],
            res[1],
            res[2],
            need - HEADER,
            b.len() - HEADER
        ));
    }
    let [lo, hi] = h.bbox;
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(format!("its bounding box {lo} – {hi} is not finite"));
    }
    VolumeGrid::new(res, channels, f32s(&b[HEADER..]), h.bbox)
}

#[cfg(test)]
mod tests {
    use super::*;
    use lt_core::math::Mat4;
    use lt_core::medium::{GridMedium, GridVolume, PhaseFunction, Volume, WrapMode};
    use std::sync::Arc;

    fn file(res: [i32; 3], values: &[f32]) -> Vec<u8> {
        file_with(res, 1, values)
    }

    fn file_with(res: [i32; 3], channels: i32, values: &[f32]) -> Vec<u8> {
        let mut b = b"VOL\x03".to_vec();
        for v in [1, res[0], res[1], res[2], channels] {
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

    #[test]
    fn reads_a_volume_and_refuses_inconsistent_ones() {
        let vals: Vec<f32> = (0..12).map(|i| i as f32).collect();
        let g = parse_volume(&file_with([2, 1, 2], 3, &vals)).unwrap();
        assert_eq!((g.res, g.channels), ([2, 1, 2], 3));
        assert_eq!(g.at(1, 0, 1), Vec3::new(9.0, 10.0, 11.0));
        assert_eq!(g.bbox, [Vec3::ZERO, Vec3::ONE]);
        let good = file_with([2, 1, 2], 3, &vals);
        for len in 0..good.len() {
            assert!(parse_volume(&good[..len]).is_err(), "length {len}");
        }
        let e = parse_volume(&good[..good.len() - 4]).unwrap_err();
        assert!(e.starts_with("truncated") && e.contains("48 bytes"), "{e}");
        let mut long = good.clone();
        long.extend([0; 4]);
        assert!(parse_volume(&long).unwrap_err().contains("inconsistent"));
        assert!(parse_volume(&file_with([2, 1, 2], 2, &vals[..8]))
            .unwrap_err()
            .contains("2 channels"));
        assert!(parse_volume(&file_with([0, 1, 2], 1, &[]))
            .unwrap_err()
            .contains("empty"));
        assert!(parse_volume(&file_with([-1, 1, 2], 1, &[]))
            .unwrap_err()
            .contains("negative"));
        let mut nan = vals.clone();
        nan[5] = f32::NAN;
        assert!(parse_volume(&file_with([2, 1, 2], 3, &nan))
            .unwrap_err()
            .contains("value 5"));
        let mut v2 = good.clone();
        v2[3] = 2;
        assert!(parse_volume(&v2).unwrap_err().contains("version"));
    }

    #[test]
    fn reads_the_suites_media_grids() {
        let dir = "/work/shared/mitsuba-render-tests/tests/scenes/participating_media/textures";
        let mut volumes = Vec::new();
        for (name, channels) in [("sigmat.vol", 1), ("albedo.vol", 3)] {
            let Ok(bytes) = std::fs::read(format!("{dir}/{name}")) else {
                return; // the suite is not on this machine
            };
            let g = parse_volume(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!((g.res, g.channels), ([16, 16, 16], channels), "{name}");
            let (lo, hi) = g.range();
            assert!(lo.min_element() >= 0.0 && hi.max_element() > 0.0, "{name}");
            // As test_hetero_sigmat_albedo_volpath.xml places them.
            let to_world =
                Mat4::from_translation(Vec3::splat(-0.5)) * Mat4::from_scale(Vec3::splat(1.5));
            let v = GridVolume::new(Arc::new(g), to_world, false, WrapMode::Clamp).unwrap();
            volumes.push(Volume::Grid(v));
        }
        let albedo = volumes.pop().unwrap();
        let sigma_t = volumes.pop().unwrap();
        GridMedium::new(sigma_t, 5.0, albedo, PhaseFunction::Isotropic).unwrap();
    }
}
