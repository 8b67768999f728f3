//! Cloth meshes from OBJ files: the shapes artists make (capes, skirts,
//! banners) as a [`ClothMesh`], with their quads kept as quads so that they
//! get shear springs, as a grid's cells do.
//!
//! The reader is our own, of the part of OBJ a cloth needs (`v`, `vt` and
//! `f` with any of its index forms, negative indices included; everything
//! else is skipped): the `tobj` crate renumbers vertices in the order faces
//! use them, and pins and attachments name vertices by their number in the
//! file, as Blender shows them.

use std::path::Path;

use super::error::SceneError;
use crate::cloth::ClothMesh;
use crate::math::Vector;

/// The mesh of OBJ `text` (every object in it, in the file's vertex order).
/// `path` names the file in errors.
pub fn obj_mesh(text: &str, path: &str) -> Result<ClothMesh, SceneError> {
    let mut mesh = ClothMesh::default();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut uvs: Vec<Option<[f32; 2]>> = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let bad = |what: &str| SceneError::Io {
            path: path.to_string(),
            message: format!("line {}: {what}: {line}", k + 1),
        };
        let mut words = line.split_whitespace();
        let numbers = |words: std::str::SplitWhitespace<'_>| {
            words
                .map(|w| w.parse::<f32>().ok().filter(|x| x.is_finite()))
                .collect::<Option<Vec<f32>>>()
        };
        match words.next() {
            Some("v") => match numbers(words).as_deref() {
                Some([x, y, z, ..]) => {
                    mesh.positions.push(Vector::new(*x, *y, *z));
                    uvs.push(None);
                }
                _ => return Err(bad("a vertex needs three finite coordinates")),
            },
            Some("vt") => match numbers(words).as_deref() {
                // OBJ's v runs upwards; texture rows run downwards.
                Some([u, v, ..]) => texcoords.push([*u, 1.0 - *v]),
                Some([u]) => texcoords.push([*u, 1.0]),
                _ => return Err(bad("a texture coordinate needs finite numbers")),
            },
            Some("f") => {
                let mut face = Vec::new();
                for corner in words {
                    let mut parts = corner.split('/');
                    let index = |part: Option<&str>, count: usize| -> Option<usize> {
                        let i: i64 = part?.parse().ok()?;
                        // 1-based, or negative: counted back from the last.
                        let i = if i < 0 { count as i64 + i } else { i - 1 };
                        usize::try_from(i).ok().filter(|&i| i < count)
                    };
                    let v = index(parts.next(), mesh.positions.len())
                        .ok_or_else(|| bad("a face's vertex is out of range"))?;
                    if let Some(t) = parts.next().filter(|t| !t.is_empty()) {
                        let t = index(Some(t), texcoords.len())
                            .ok_or_else(|| bad("a face's texture coordinate is out of range"))?;
                        uvs[v].get_or_insert(texcoords[t]);
                    }
                    face.push(v as u32);
                }
                mesh.faces.push(face);
            }
            _ => {}
        }
    }
    if mesh.faces.is_empty() {
        return Err(SceneError::Io {
            path: path.to_string(),
            message: "the mesh has no faces".into(),
        });
    }
    // Texture coordinates only when every vertex has one.
    if uvs.iter().all(Option::is_some) {
        mesh.uvs = uvs.into_iter().flatten().collect();
    }
    Ok(mesh)
}

/// The mesh of the OBJ file at `path`.
pub fn load_obj(path: &Path) -> Result<ClothMesh, SceneError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError::Io {
        path: name.clone(),
        message: e.to_string(),
    })?;
    obj_mesh(&text, &name)
}
