//! Cloth meshes from OBJ files (read with the `tobj` crate): the shapes
//! artists make (capes, skirts, banners) as a [`ClothMesh`], with their
//! quads kept as quads so that they get shear springs, as a grid's cells do.

use std::path::Path;

use super::error::SceneError;
use crate::cloth::ClothMesh;
use crate::math::Vector;

/// The mesh of OBJ `text` (every object in it, one after the other).
/// `path` names the file in errors.
pub fn obj_mesh(text: &str, path: &str) -> Result<ClothMesh, SceneError> {
    let options = tobj::LoadOptions {
        // Quads stay quads; positions and texture coordinates keep their
        // own indices, so that a seam in the texture does not cut the cloth.
        triangulate: false,
        single_index: false,
        ..Default::default()
    };
    let io = |message: String| SceneError::Io {
        path: path.to_string(),
        message,
    };
    let (models, _) =
        tobj::load_obj_buf(&mut text.as_bytes(), &options, |_| Ok(Default::default()))
            .map_err(|e| io(format!("not a readable OBJ mesh: {e}")))?;
    let mut mesh = ClothMesh::default();
    let mut uvs: Vec<Option<[f32; 2]>> = Vec::new();
    for model in &models {
        let m = &model.mesh;
        let offset = mesh.positions.len() as u32;
        mesh.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vector::new(p[0], p[1], p[2])),
        );
        uvs.resize(mesh.positions.len(), None);
        let arities: Vec<u32> = if m.face_arities.is_empty() {
            vec![3; m.indices.len() / 3]
        } else {
            m.face_arities.clone()
        };
        let mut at = 0usize;
        for arity in arities {
            let end = at + arity as usize;
            let (Some(face), uv_face) = (m.indices.get(at..end), m.texcoord_indices.get(at..end))
            else {
                return Err(io("a face runs past the mesh's indices".into()));
            };
            mesh.faces.push(face.iter().map(|&i| i + offset).collect());
            if let Some(uv_face) = uv_face {
                for (&i, &t) in face.iter().zip(uv_face) {
                    let t = t as usize;
                    if let (Some(slot), Some(uv)) = (
                        uvs.get_mut((i + offset) as usize),
                        m.texcoords.get(2 * t..2 * t + 2),
                    ) {
                        slot.get_or_insert([uv[0], 1.0 - uv[1]]);
                    }
                }
            }
            at = end;
        }
    }
    if mesh.faces.is_empty() {
        return Err(io("the mesh has no faces".into()));
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
