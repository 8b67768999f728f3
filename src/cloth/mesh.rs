//! Cloth of any shape: built from a polygon mesh (triangles and quads, as an
//! artist's OBJ holds them) instead of a grid. Stretch springs run along
//! the polygons' sides, shear springs across both diagonals of each quad,
//! and bend springs across every interior side, between the two corners
//! facing it; each face's area is shared equally by its corners, a third
//! of a triangle's and a quarter of a quad's, and a particle weighs its
//! share times the density (or scaled to a total mass). A grid's cells
//! share theirs the same way, so a grid read back as a mesh weighs the same.

use std::collections::HashMap;
use std::sync::Arc;

use super::builder::MassSpec;
use super::cloth::Cloth;
use super::material::Material;
use super::springs::{Spring, SpringKind};
use crate::error::{finite_vec, positive, ClothError};
use crate::math::Vector;

/// A polygon mesh to build a cloth from: positions (m), faces as lists of
/// three or four vertex indices (counter-clockwise seen from the front) and
/// texture coordinates, one per vertex (optional).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ClothMesh {
    /// Vertex positions, in metres.
    pub positions: Vec<Vector>,
    /// Faces: triangles (three indices) or quads (four).
    pub faces: Vec<Vec<u32>>,
    /// Texture coordinates per vertex, in 0..=1 (empty: none).
    pub uvs: Vec<[f32; 2]>,
}

impl ClothMesh {
    /// The triangles of the faces (a quad `a b c d` is split along `a c`),
    /// and each quad's corners.
    fn triangles(&self) -> Result<Faces, ClothError> {
        let n = self.positions.len();
        let (mut triangles, mut quads) = (Vec::new(), Vec::new());
        for (index, f) in self.faces.iter().enumerate() {
            let bad = |reason: String| ClothError::InvalidTopology {
                what: "face",
                index,
                reason,
            };
            if let Some(&i) = f.iter().find(|&&i| i as usize >= n) {
                return Err(bad(format!("vertex {i} out of range 0..{n}")));
            }
            let mut sorted = f.clone();
            sorted.sort_unstable();
            sorted.dedup();
            if sorted.len() != f.len() {
                return Err(bad(format!("{f:?} repeats a vertex")));
            }
            match f[..] {
                [a, b, c] => triangles.push([a, b, c]),
                [a, b, c, d] => {
                    triangles.push([a, b, c]);
                    triangles.push([a, c, d]);
                    quads.push([a, b, c, d]);
                }
                _ => {
                    return Err(bad(format!(
                        "has {} corners: a cloth mesh takes triangles and quads",
                        f.len()
                    )))
                }
            }
        }
        Ok((triangles, quads))
    }
}

/// A mesh's triangles, and the corners of its quads.
type Faces = (Vec<[u32; 3]>, Vec<[u32; 4]>);

/// Sorted pair, to name an edge whichever way it is walked.
fn edge(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

impl Cloth {
    /// A cloth of the shape of `mesh` (see the module docs for its
    /// springs and masses), of `material`, at rest where the mesh is.
    /// Every index and position is checked; a vertex in no face is refused
    /// (it would have no mass).
    pub fn from_mesh(
        mesh: &ClothMesh,
        material: Material,
        mass: MassSpec,
    ) -> Result<Cloth, ClothError> {
        let n = mesh.positions.len();
        for p in &mesh.positions {
            finite_vec("mesh position", *p)?;
        }
        if !mesh.uvs.is_empty() && mesh.uvs.len() != n {
            return Err(ClothError::LengthMismatch {
                what: "texture coordinates",
                expected: n,
                got: mesh.uvs.len(),
            });
        }
        let (triangles, quads) = mesh.triangles()?;
        let x = &mesh.positions;
        // Masses: each face's area (a quad's is its two triangles') shared
        // equally by its corners.
        let mut area = vec![0.0f32; n];
        for face in &mesh.faces {
            let (first, k) = (x[face[0] as usize], face.len());
            let mut face_area = 0.0;
            for w in face[1..].windows(2) {
                let (b, c) = (x[w[0] as usize], x[w[1] as usize]);
                face_area += (b - first).cross(c - first).length() / 2.0;
            }
            for &i in face {
                area[i as usize] += face_area / k as f32;
            }
        }
        if let Some(i) = area.iter().position(|&a| a.is_nan() || a <= 0.0) {
            return Err(ClothError::InvalidTopology {
                what: "vertex",
                index: i,
                reason: "belongs to no face of positive area, so it has no mass".into(),
            });
        }
        let total_area: f32 = area.iter().sum();
        let scale = match mass {
            MassSpec::Total(m) => positive("total mass", m)? / total_area,
            MassSpec::FromDensity => material.density,
        };
        let masses = area.iter().map(|a| a * scale).collect();
        // Springs. Each side of a face once; quad diagonals are shear.
        let diagonals: Vec<(u32, u32)> = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [edge(a, c), edge(b, d)])
            .collect();
        let split_along: std::collections::HashSet<(u32, u32)> =
            quads.iter().map(|&[a, _, c, _]| edge(a, c)).collect();
        // Per side: the corners facing it, from each triangle it borders.
        let mut facing: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for t in &triangles {
            for k in 0..3 {
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                facing.entry(edge(a, b)).or_default().push(c);
            }
        }
        let mut sides: Vec<(u32, u32)> = facing.keys().copied().collect();
        sides.sort_unstable();
        let rest = |a: u32, b: u32| (x[b as usize] - x[a as usize]).length();
        let spring = |(a, b): (u32, u32), kind| Spring {
            a,
            b,
            rest_length: rest(a, b),
            kind,
        };
        let mut springs: Vec<Spring> = sides
            .iter()
            .filter(|e| !split_along.contains(e))
            .map(|&e| spring(e, SpringKind::Stretch))
            .collect();
        springs.extend(diagonals.iter().map(|&e| spring(e, SpringKind::Shear)));
        let mut bends: Vec<(u32, u32)> = sides
            .iter()
            .filter(|e| !split_along.contains(e))
            .filter_map(|e| match facing[e][..] {
                [p, q] if p != q => Some(edge(p, q)),
                _ => None,
            })
            .collect();
        bends.sort_unstable();
        bends.dedup();
        springs.extend(bends.into_iter().map(|e| spring(e, SpringKind::Bend)));
        let mut cloth = Cloth::from_parts(x.clone(), masses, springs, triangles, material)?;
        if !mesh.uvs.is_empty() {
            Arc::make_mut(&mut cloth.topology).uvs = mesh.uvs.clone();
        }
        Ok(cloth)
    }
}
