//! Mitsuba's `.serialized` meshes (format documented in Mitsuba 3's serialized shape plugin):
//! little endian; per mesh an uncompressed header (u16 0x041C, u16 version 3 or 4) followed by a
//! zlib stream holding u32 flags, (version 4) a NUL-terminated name, u64 vertex and triangle
//! counts, positions, then normals / texture coordinates / colours when the flags say so (f32, or
//! f64 with flag 0x2000), then u32 vertex indices. A file of several meshes ends with a
//! dictionary: one offset per mesh (u64 in version 4, u32 in version 3) and a u32 mesh count.
//! Texture coordinates are stored as Mitsuba uses them (no v flip, unlike OBJ and PLY files).

use super::le_bytes::{f32s, f64s_as_f32, u16_at, u32_at, u32s, u64_at};
use crate::error::Ctx;
use crate::toml_scene::schema::S;
use crate::SceneError;
use flate2::read::ZlibDecoder;
use lt_core::math::{Vec2, Vec3};
use lt_core::scene::TriangleMesh;
use std::io::Read;

const MAGIC: u16 = 0x041C;
const HAS_NORMALS: u32 = 0x0001;
const HAS_TEXCOORDS: u32 = 0x0002;
const HAS_COLORS: u32 = 0x0008;
/// "Use face normals": the same as the shape's `face_normals = true`.
const FACE_NORMALS: u32 = 0x0010;
const DOUBLE_PRECISION: u32 = 0x2000;

/// A mesh read from a `.serialized` file, with whether the file asks for face normals.
#[derive(Debug)]
pub(crate) struct Serialized {
    pub mesh: TriangleMesh,
    pub face_normals: bool,
}

/// Loads mesh `shape_index` of `file`. Errors name the file and the problem.
pub(crate) fn load_serialized(
    ctx: &Ctx,
    file: &S<String>,
    shape_index: u32,
) -> Result<Serialized, SceneError> {
    let (path, bytes) = ctx.read_mesh(file)?;
    parse(&bytes, shape_index).map_err(|msg| {
        ctx.at(
            file.span(),
            format!("malformed serialized mesh file {}: {msg}", path.display()),
        )
    })
}

/// The byte offset of mesh `index`'s header, from the end-of-file dictionary (mesh 0 is at 0).
fn mesh_offset(b: &[u8], version: u16, index: u32) -> Result<usize, String> {
    if index == 0 {
        return Ok(0);
    }
    let truncated = || "its end-of-file dictionary of meshes is truncated".to_string();
    let count = u32_at(b, b.len().checked_sub(4).ok_or_else(truncated)?).ok_or_else(truncated)?;
    if index >= count {
        return Err(format!(
            "`shape_index` {index} is out of range: the file holds {count} mesh(es)"
        ));
    }
    let slot = if version == 4 { 8 } else { 4 };
    let from_end = slot * (count - index) as usize + 4;
    let at = b.len().checked_sub(from_end).ok_or_else(truncated)?;
    let offset = if version == 4 {
        u64_at(b, at).ok_or_else(truncated)?
    } else {
        u32_at(b, at).ok_or_else(truncated)? as u64
    };
    usize::try_from(offset)
        .ok()
        .filter(|&o| o < b.len())
        .ok_or_else(|| format!("mesh {index}'s offset {offset} lies beyond the file's end"))
}

/// The decompressed stream, read exactly, with errors that say what was being read.
struct Stream<'a> {
    z: ZlibDecoder<&'a [u8]>,
    /// At most this many more bytes can come out (zlib expands at most ~1032:1), so a corrupt
    /// count is refused before it allocates.
    budget: u64,
}

impl Stream<'_> {
    fn bytes(&mut self, n: u64, what: &str) -> Result<Vec<u8>, String> {
        if n > self.budget {
            return Err(format!(
                "{what} would need {n} bytes, more than the compressed data can hold (corrupt counts?)"
            ));
        }
        self.budget -= n;
        let mut v = vec![0; n as usize];
        self.z
            .read_exact(&mut v)
            .map_err(|e| format!("cannot read {what}: {e} (truncated or corrupt file?)"))?;
        Ok(v)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        Ok(u32_at(&self.bytes(4, what)?, 0).expect("4 bytes read"))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        Ok(u64_at(&self.bytes(8, what)?, 0).expect("8 bytes read"))
    }

    /// `count` × `dim` reals, f32 or f64 in the file, as f32 (Mitsuba rounds doubles the same).
    fn reals(
        &mut self,
        count: u64,
        dim: u64,
        double: bool,
        what: &str,
    ) -> Result<Vec<f32>, String> {
        let size = if double { 8 } else { 4 };
        let n = count
            .checked_mul(dim * size)
            .ok_or_else(|| format!("{what}: the vertex count {count} is absurd"))?;
        let raw = self.bytes(n, what)?;
        let values = if double {
            f64s_as_f32(&raw)
        } else {
            f32s(&raw)
        };
        if values.iter().any(|x| !x.is_finite()) {
            return Err(format!("{what}: a value is NaN or infinite"));
        }
        Ok(values)
    }
}

fn parse(b: &[u8], shape_index: u32) -> Result<Serialized, String> {
    let magic = u16_at(b, 0).ok_or("it is shorter than its 4-byte header")?;
    if magic != MAGIC {
        return Err(format!(
            "it does not start with the format identifier 0x041C (found {magic:#06x})"
        ));
    }
    let version = u16_at(b, 2).ok_or("it is shorter than its 4-byte header")?;
    if version != 3 && version != 4 {
        return Err(format!(
            "version {version} is not one Mitsuba reads (3 or 4)"
        ));
    }
    let start = mesh_offset(b, version, shape_index)?;
    // Each mesh repeats the header (Mitsuba skips it without looking; so do we, after checking).
    if u16_at(b, start) != Some(MAGIC) {
        return Err(format!(
            "mesh {shape_index} at byte {start} does not start with the format identifier"
        ));
    }
    let data = b.get(start + 4..).ok_or("it ends inside a mesh header")?;
    let mut s = Stream {
        z: ZlibDecoder::new(data),
        budget: 1100 * data.len() as u64 + 1024,
    };
    let flags = s.u32("the flags")?;
    if version == 4 {
        // The mesh's name, NUL-terminated: read and dropped.
        let mut len = 0;
        while s.bytes(1, "the mesh name")?[0] != 0 {
            len += 1;
            if len > 1 << 16 {
                return Err("the mesh name has no end".into());
            }
        }
    }
    let nv = s.u64("the vertex count")?;
    let nf = s.u64("the triangle count")?;
    if nv > u32::MAX as u64 {
        return Err(format!("{nv} vertices: more than 32-bit indices address"));
    }
    let double = flags & DOUBLE_PRECISION != 0;
    let positions: Vec<Vec3> = s
        .reals(nv, 3, double, "the vertex positions")?
        .chunks_exact(3)
        .map(Vec3::from_slice)
        .collect();
    let normals = if flags & HAS_NORMALS != 0 {
        let ns = s.reals(nv, 3, double, "the vertex normals")?;
        Some(ns.chunks_exact(3).map(Vec3::from_slice).collect())
    } else {
        None
    };
    let uvs = if flags & HAS_TEXCOORDS != 0 {
        let t = s.reals(nv, 2, double, "the texture coordinates")?;
        Some(t.chunks_exact(2).map(Vec2::from_slice).collect())
    } else {
        None
    };
    if flags & HAS_COLORS != 0 {
        // Vertex colours: skipped, as Mitsuba does.
        s.reals(nv, 3, double, "the vertex colours")?;
    }
    let n = nf
        .checked_mul(12)
        .ok_or_else(|| format!("the triangle count {nf} is absurd"))?;
    let raw = s.bytes(n, "the triangle indices")?;
    let mut indices = Vec::with_capacity(nf as usize);
    for (i, t) in u32s(&raw).chunks_exact(3).enumerate() {
        let tri = [t[0], t[1], t[2]];
        if let Some(&k) = tri.iter().find(|&&k| k as u64 >= nv) {
            return Err(format!(
                "triangle {i}: vertex index {k} is out of range (0..{nv})"
            ));
        }
        indices.push(tri);
    }
    if indices.is_empty() {
        return Err("the mesh has no triangles".into());
    }
    Ok(Serialized {
        mesh: TriangleMesh {
            positions,
            normals,
            uvs,
            indices,
            attributes: Vec::new(),
        },
        face_normals: flags & FACE_NORMALS != 0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use flate2::write::ZlibEncoder;
    use std::io::Write;

    /// One version-4 mesh stream: header + compressed body.
    fn mesh_stream(flags: u32, name: &str, pos: &[f32], extra: &[f32], tris: &[u32]) -> Vec<u8> {
        let mut body = flags.to_le_bytes().to_vec();
        body.extend(name.as_bytes());
        body.push(0);
        body.extend(((pos.len() / 3) as u64).to_le_bytes());
        body.extend(((tris.len() / 3) as u64).to_le_bytes());
        for x in pos.iter().chain(extra) {
            body.extend(x.to_le_bytes());
        }
        for i in tris {
            body.extend(i.to_le_bytes());
        }
        let mut z = ZlibEncoder::new(Vec::new(), flate2::Compression::default());
        z.write_all(&body).unwrap();
        let mut out = vec![0x1C, 0x04, 4, 0];
        out.extend(z.finish().unwrap());
        out
    }

    /// Meshes concatenated, then the dictionary of their offsets and their count.
    fn file(meshes: &[Vec<u8>]) -> Vec<u8> {
        let mut out = Vec::new();
        let mut offsets = Vec::new();
        for m in meshes {
            offsets.push(out.len() as u64);
            out.extend(m);
        }
        for o in offsets {
            out.extend(o.to_le_bytes());
        }
        out.extend((meshes.len() as u32).to_le_bytes());
        out
    }

    const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];

    #[test]
    fn reads_the_suites_rectangle_with_normals_and_uvs() {
        let path =
            "/work/shared/mitsuba-render-tests/tests/serialized/rectangle_normals_uv.serialized";
        let Ok(bytes) = std::fs::read(path) else {
            return; // the suite is not on this machine
        };
        let s = parse(&bytes, 0).unwrap();
        let m = &s.mesh;
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions[1], Vec3::new(-2.85, 0.0, 0.599999));
        assert_eq!(m.normals.as_ref().unwrap()[2], Vec3::Y);
        // As stored (the OBJ beside it has v = 0.988416, flipped on reading: 1 − v).
        let uv = m.uvs.as_ref().unwrap()[0];
        assert!(
            (uv - Vec2::new(0.950589, 1.0 - 0.988416))
                .abs()
                .max_element()
                < 1e-6
        );
        assert!(!s.face_normals);
    }

    #[test]
    fn shape_index_picks_the_mesh_and_flags_are_honoured() {
        let uv = [0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let a = mesh_stream(0x1000, "a", &TRI, &[], &[0, 1, 2]);
        let scaled: Vec<f32> = TRI.iter().map(|x| 2.0 * x).collect();
        let b = mesh_stream(HAS_TEXCOORDS | FACE_NORMALS, "b", &scaled, &uv, &[0, 2, 1]);
        let f = file(&[a, b]);
        let m0 = parse(&f, 0).unwrap();
        assert_eq!(m0.mesh.positions[1], Vec3::X);
        assert!(m0.mesh.uvs.is_none() && m0.mesh.normals.is_none() && !m0.face_normals);
        let m1 = parse(&f, 1).unwrap();
        assert_eq!(m1.mesh.positions[1], 2.0 * Vec3::X);
        assert_eq!(m1.mesh.indices, vec![[0, 2, 1]]);
        assert_eq!(m1.mesh.uvs.unwrap()[2], Vec2::Y);
        assert!(m1.face_normals);
        let e = parse(&f, 2).err().unwrap();
        assert!(e.contains("out of range"), "{e}");
    }

    #[test]
    fn corrupt_files_are_errors_not_panics() {
        let good = file(&[mesh_stream(0, "m", &TRI, &[], &[0, 1, 2])]);
        assert!(parse(&good, 0).is_ok());
        // Truncated at every length: an error, never a panic, unless all the mesh's data is
        // decoded (only the stream's tail — checksum, dictionary — cut off).
        let whole = parse(&good, 0).unwrap().mesh.positions;
        for len in 0..good.len() - 12 {
            if let Ok(m) = parse(&good[..len], 0) {
                assert!(
                    m.mesh.positions == whole && m.mesh.indices == vec![[0, 1, 2]],
                    "{len}"
                );
            }
        }
        assert!(parse(&good[..good.len() - 20], 0).is_err());
        let mut bad_magic = good.clone();
        bad_magic[0] = 0;
        assert!(parse(&bad_magic, 0).unwrap_err().contains("identifier"));
        let bad_index = file(&[mesh_stream(0, "m", &TRI, &[], &[0, 1, 3])]);
        let e = parse(&bad_index, 0).unwrap_err();
        assert!(e.contains("vertex index 3"), "{e}");
        // Flipped bits inside the compressed body.
        for k in 4..good.len() - 12 {
            let mut c = good.clone();
            c[k] ^= 0x5A;
            let _ = parse(&c, 0);
        }
    }
}
