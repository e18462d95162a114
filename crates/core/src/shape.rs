//! Shapes as a scene describes them, in world space: triangle meshes (with Mitsuba's rectangle
//! and cube as meshes) and exact spheres. The scene indexes them for ray queries; area lights
//! sample them.

pub use crate::geometry::quadric::Affine;
pub use crate::geometry::sdf::SdfGrid;
use crate::math::{Color, Vec2, Vec3, PI};

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (same length as `positions`), if the mesh has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex texture coordinates, if the mesh has them (Mitsuba's convention: v already
    /// flipped for OBJ files, so that v = 0 is the image's top row).
    pub uvs: Option<Vec<Vec2>>,
    pub indices: Vec<[u32; 3]>,
    /// Named quantities the mesh file carries (Mitsuba's mesh attributes), read by
    /// `mesh_attribute` textures.
    pub attributes: Vec<MeshAttribute>,
}

/// A per-vertex or per-face quantity of a mesh, under Mitsuba's name: `vertex_<p>` or `face_<p>`
/// for the file's properties `<p>_0`, `<p>_1`, … (or a lone `<p>`).
#[derive(Clone, Debug)]
pub struct MeshAttribute {
    pub name: String,
    /// One value per triangle (a face's value copied to each triangle it was split into) when
    /// true; one per vertex otherwise.
    pub per_face: bool,
    /// A one-channel attribute is stored as grey (Mitsuba broadcasts it to every channel).
    pub values: Vec<Color>,
}

impl TriangleMesh {
    /// Index into `attributes` of the one called `name`.
    pub fn attribute_index(&self, name: &str) -> Option<u32> {
        self.attributes
            .iter()
            .position(|a| a.name == name)
            .map(|k| k as u32)
    }

    /// Attribute `k` at barycentrics `b` of triangle `i`: a face attribute is the triangle's
    /// value, a vertex attribute the barycentric blend of its corners' (Mitsuba's
    /// `eval_attribute`).
    #[inline]
    pub fn attribute(&self, k: u32, i: usize, b: [f32; 3]) -> Color {
        let a = &self.attributes[k as usize];
        if a.per_face {
            a.values[i]
        } else {
            let [v0, v1, v2] = self.indices[i];
            b[0] * a.values[v0 as usize]
                + b[1] * a.values[v1 as usize]
                + b[2] * a.values[v2 as usize]
        }
    }

    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[i];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    pub fn triangle_area(&self, i: usize) -> f32 {
        let [a, b, c] = self.triangle(i);
        0.5 * (b - a).cross(c - a).length()
    }

    /// Interpolated shading normal, if the mesh has normals and they do not cancel out.
    pub fn shading_normal(&self, i: usize, b0: f32, b1: f32, b2: f32) -> Option<Vec3> {
        let normals = self.normals.as_ref()?;
        let [a, b, c] = self.indices[i];
        let n = b0 * normals[a as usize] + b1 * normals[b as usize] + b2 * normals[c as usize];
        (n.length_squared() > 0.0).then(|| n.normalize())
    }

    /// Texture coordinates at barycentrics (b0, b1, b2) of triangle `i`: interpolated from the
    /// mesh's, or (b1, b2) when it has none (Mitsuba's parameterisation of a bare mesh).
    pub fn uv(&self, i: usize, b0: f32, b1: f32, b2: f32) -> Vec2 {
        match &self.uvs {
            Some(uvs) => {
                let [a, b, c] = self.indices[i];
                b0 * uvs[a as usize] + b1 * uvs[b as usize] + b2 * uvs[c as usize]
            }
            None => Vec2::new(b1, b2),
        }
    }

    /// An axis-aligned unit square [-1,1]² in the z = 0 plane with normal +z (Mitsuba's rectangle).
    pub fn unit_rectangle() -> TriangleMesh {
        TriangleMesh {
            positions: vec![
                Vec3::new(-1.0, -1.0, 0.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(-1.0, 1.0, 0.0),
            ],
            normals: None,
            // Mitsuba's rectangle: uv = ((x + 1)/2, (y + 1)/2).
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ]),
            indices: vec![[0, 1, 2], [0, 2, 3]],
            attributes: Vec::new(),
        }
    }

    /// The cube [-1,1]³ with outward normals (Mitsuba's cube).
    pub fn unit_cube() -> TriangleMesh {
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        let mut indices = Vec::new();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n =
                    Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
                let u = Vec3::from_array(std::array::from_fn(|k| {
                    if k == (axis + 1) % 3 {
                        1.0
                    } else {
                        0.0
                    }
                }));
                let v = n.cross(u);
                let base = positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    let p = n + u * a + v * b;
                    positions.push(p);
                    uvs.push(mitsuba_cube_uv(n, p));
                }
                indices.push([base, base + 1, base + 2]);
                indices.push([base, base + 2, base + 3]);
            }
        }
        TriangleMesh {
            positions,
            normals: None,
            uvs: Some(uvs),
            indices,
            attributes: Vec::new(),
        }
    }

    /// Applies a point transform (and its normal transform) to the mesh.
    pub fn transformed(mut self, m: &glam::Mat4) -> TriangleMesh {
        for p in &mut self.positions {
            *p = m.transform_point3(*p);
        }
        if let Some(ns) = &mut self.normals {
            let nm = m.inverse().transpose();
            for n in ns.iter_mut() {
                *n = nm.transform_vector3(*n).normalize_or_zero();
            }
        }
        // A mirroring transform turns the winding inside out; keep normals where they were.
        if m.determinant() < 0.0 {
            for t in &mut self.indices {
                t.swap(1, 2);
            }
        }
        self
    }
}

/// Mitsuba's cube parameterisation: each face its own [0, 1]², oriented as in Mitsuba 3's cube
/// mesh (per face, its corners V0…V3 carry uv (0,1), (1,1), (1,0), (0,0)), so uv is affine on the
/// face: u along V2 − V3, v along V0 − V3 (edges of length 2). Listed per face: (normal, V0, V2, V3).
fn mitsuba_cube_uv(n: Vec3, p: Vec3) -> Vec2 {
    const FACES: [[[f32; 3]; 4]; 6] = [
        [
            [0., -1., 0.],
            [1., -1., -1.],
            [-1., -1., 1.],
            [-1., -1., -1.],
        ],
        [[0., 1., 0.], [1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]],
        [[1., 0., 0.], [1., -1., -1.], [1., 1., 1.], [1., -1., 1.]],
        [[0., 0., 1.], [1., -1., 1.], [-1., 1., 1.], [-1., -1., 1.]],
        [
            [-1., 0., 0.],
            [-1., -1., 1.],
            [-1., 1., -1.],
            [-1., -1., -1.],
        ],
        [
            [0., 0., -1.],
            [1., 1., -1.],
            [-1., -1., -1.],
            [-1., 1., -1.],
        ],
    ];
    let f = FACES
        .iter()
        .find(|f| Vec3::from_array(f[0]) == n)
        .expect("a cube face normal");
    let [v0, v2, v3] = [f[1], f[2], f[3]].map(Vec3::from_array);
    let q = p - v3;
    Vec2::new(q.dot(v2 - v3) / 4.0, q.dot(v0 - v3) / 4.0)
}

#[derive(Clone, Debug)]
pub enum ShapeGeometry {
    Mesh(TriangleMesh),
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// A sphere whose `to_world` also rotates it (or reflects it): the same surface, but its uv
    /// and ∂p/∂u follow the rotated object frame, as Mitsuba's do. `rotation` is orthonormal,
    /// object to world.
    RotatedSphere {
        center: Vec3,
        radius: f32,
        rotation: glam::Mat3,
    },
    /// Mitsuba's disk: the unit disk (z = 0, normal +z) under `to_world`, any invertible affine
    /// map (a non-uniform scale makes an ellipse).
    Disk {
        to_world: Affine,
    },
    /// Mitsuba's open cylinder: x² + y² = 1, 0 ≤ z ≤ 1 under `to_world`, a rotation (or
    /// reflection) times diag(r, r, l) plus a translation (what `quadric::is_round_cylinder_map`
    /// accepts; area sampling assumes it).
    Cylinder {
        to_world: Affine,
    },
    /// Mitsuba's `sdfgrid`: the grid's unit cube under `to_world` (any invertible affine map).
    /// Not an emitter (Mitsuba's cannot be one either).
    SdfGrid {
        grid: std::sync::Arc<SdfGrid>,
        to_world: Affine,
    },
}

impl ShapeGeometry {
    /// A sphere's world-to-object rotation (the identity for an unrotated one and for any other
    /// shape): its uv and tangents are read in that frame.
    #[inline]
    pub fn sphere_to_object(&self) -> glam::Mat3 {
        match self {
            ShapeGeometry::RotatedSphere { rotation, .. } => rotation.transpose(),
            _ => glam::Mat3::IDENTITY,
        }
    }
}

/// Mitsuba's sphere parameterisation from the unit outward normal in the sphere's object frame
/// (`ShapeGeometry::sphere_to_object`): u = φ / 2π with φ = atan2(y, x) in [0, 2π), v = θ / π.
pub fn sphere_uv(n: Vec3) -> Vec2 {
    let phi = n.y.atan2(n.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    Vec2::new(phi / (2.0 * PI), n.z.clamp(-1.0, 1.0).acos() / PI)
}
