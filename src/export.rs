//! Mesh export: the cloth as Wavefront OBJ, one file per frame, for Blender's
//! OBJ-sequence import and game engines; and as glTF 2.0 binary (`.glb`),
//! one mesh with the frames as morph targets and an animation.

use std::fmt::Write as _;
use std::path::Path;

use crate::cloth::Cloth;
use crate::math::Vector;

/// The cloth's current mesh as OBJ text: positions (`v`, metres), texture
/// coordinates (`vt`), vertex normals (`vn`) and faces (`f v/vt/vn`,
/// counter-clockwise seen from the front). A grid cloth writes its cells as
/// quads, each starting at a corner of the diagonal it is drawn split along,
/// so that [`Cloth::from_mesh`] reads back its triangles, its stretch
/// springs (the cells' sides) and its shear springs (both diagonals); any
/// other cloth (a mesh cloth, or a grid that has torn) writes its triangles.
pub fn obj_string(cloth: &Cloth) -> String {
    let mut out = String::with_capacity(cloth.particle_count() * 96);
    let _ = writeln!(
        out,
        "# cloth3d: {} particles, {} triangles",
        cloth.particle_count(),
        cloth.triangles().len()
    );
    let _ = writeln!(out, "o cloth");
    for p in cloth.positions() {
        let _ = writeln!(out, "v {} {} {}", p.x, p.y, p.z);
    }
    for [u, v] in cloth.uvs() {
        // OBJ's v runs upwards; the grid's rows run downwards.
        let _ = writeln!(out, "vt {} {}", u, 1.0 - v);
    }
    for n in cloth.vertex_normals() {
        let _ = writeln!(out, "vn {} {} {}", n.x, n.y, n.z);
    }
    match cloth.grid() {
        Some(grid) => {
            for quad in grid_quads(grid.cols, grid.rows) {
                let [a, b, c, d] = quad.map(|i| i + 1);
                let _ = writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c} {d}/{d}/{d}");
            }
        }
        None => {
            for t in cloth.triangles() {
                let [a, b, c] = t.map(|i| i + 1);
                let _ = writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
            }
        }
    }
    out
}

/// A grid's cells as quads (0-based particle indices), each listed from a
/// corner of the diagonal the grid's triangles split it along (the grid
/// alternates it, cell by cell), in the triangles' turning sense.
fn grid_quads(cols: usize, rows: usize) -> impl Iterator<Item = [u32; 4]> {
    let id = move |r: usize, c: usize| (r * cols + c) as u32;
    (0..rows.saturating_sub(1)).flat_map(move |r| {
        (0..cols.saturating_sub(1)).map(move |c| {
            let (p00, p01, p10, p11) = (id(r, c), id(r, c + 1), id(r + 1, c), id(r + 1, c + 1));
            if (r + c) % 2 == 0 {
                [p00, p10, p11, p01]
            } else {
                [p10, p11, p01, p00]
            }
        })
    })
}

/// Writes the cloth's current mesh to `path` as OBJ.
pub fn write_obj(cloth: &Cloth, path: &Path) -> std::io::Result<()> {
    std::fs::write(path, obj_string(cloth))
}

/// Frames of a cloth recorded for a glTF animation.
///
/// The glTF file holds the mesh as it is at the end (so a viewer that plays
/// no animation shows the final frame) and one morph target per recorded
/// frame; an animation of the mesh's morph weights with `STEP`
/// interpolation switches from one frame's target to the next, `dt` seconds
/// apart. Blender imports the targets as shape keys with their animation.
#[derive(Debug, Clone, Default)]
pub struct Animation {
    dt: f32,
    positions: Vec<Vec<Vector>>,
    normals: Vec<Vec<Vector>>,
}

impl Animation {
    /// An empty recording, frames `dt` seconds apart.
    pub fn new(dt: f32) -> Self {
        Self {
            dt,
            positions: Vec::new(),
            normals: Vec::new(),
        }
    }

    /// Records the cloth as it is now as the next frame. When the cloth has
    /// torn since the last frame, the frames before gain its new particles,
    /// each where the particle it split from was, so every frame keeps the
    /// same vertices.
    pub fn push(&mut self, cloth: &Cloth) {
        let n = cloth.particle_count();
        let frames = self.positions.iter_mut().zip(&mut self.normals);
        // A frame of another particle count that no split explains (another
        // cloth's) stays as it is, and `to_glb` leaves it out.
        for (positions, normals) in frames.filter(|(p, _)| p.len() < n) {
            for &[from, new] in cloth.topology().splits() {
                let (from, new) = (from as usize, new as usize);
                if new == positions.len() && from < new {
                    positions.push(positions[from]);
                    normals.push(normals[from]);
                }
            }
        }
        self.positions.push(cloth.positions().to_vec());
        self.normals.push(cloth.vertex_normals());
    }

    /// Frames recorded.
    pub fn frames(&self) -> usize {
        self.positions.len()
    }

    /// The glTF 2.0 binary (`.glb`) of `cloth` as it is now, animated through
    /// the recorded frames (frames of another particle count are skipped).
    pub fn to_glb(&self, cloth: &Cloth) -> Vec<u8> {
        let n = cloth.particle_count();
        let frames: Vec<usize> = (0..self.frames())
            .filter(|&f| self.positions[f].len() == n && self.normals[f].len() == n)
            .collect();
        let mut gltf = GlbBuilder::default();
        let base = cloth.positions();
        let base_normals = cloth.vertex_normals();
        let position = gltf.vec3(base, 34962);
        let normal = gltf.vec3(&base_normals, 34962);
        let uvs: Vec<f32> = cloth.uvs().iter().flatten().copied().collect();
        let uv = gltf.floats(&uvs, "VEC2", 34962, None);
        let indices: Vec<u32> = cloth.triangles().iter().flatten().copied().collect();
        let index = gltf.indices(&indices);
        let mut targets = Vec::new();
        let mut delta = vec![Vector::ZERO; n];
        let mut delta_n = vec![Vector::ZERO; n];
        for &f in &frames {
            for i in 0..n {
                delta[i] = self.positions[f][i] - base[i];
                delta_n[i] = self.normals[f][i] - base_normals[i];
            }
            let p = gltf.vec3(&delta, 34962);
            let q = gltf.vec3(&delta_n, 34962);
            targets.push(format!(r#"{{"POSITION":{p},"NORMAL":{q}}}"#));
        }
        let [r, g, b] = cloth.material.color;
        let mut primitive = format!(
            r#"{{"attributes":{{"POSITION":{position},"NORMAL":{normal},"TEXCOORD_0":{uv}}},"indices":{index},"material":0,"mode":4"#
        );
        let mut mesh_extra = String::new();
        let mut animation = String::new();
        if !frames.is_empty() {
            primitive += &format!(r#","targets":[{}]"#, targets.join(","));
            let weights = vec!["0"; frames.len()].join(",");
            mesh_extra = format!(r#","weights":[{weights}]"#);
            let times: Vec<f32> = (0..frames.len()).map(|k| k as f32 * self.dt).collect();
            let input = gltf.floats(
                &times,
                "SCALAR",
                0,
                Some((times[0], times[times.len() - 1])),
            );
            let mut w = vec![0.0f32; frames.len() * frames.len()];
            for k in 0..frames.len() {
                w[k * frames.len() + k] = 1.0;
            }
            let output = gltf.floats(&w, "SCALAR", 0, None);
            animation = format!(
                r#","animations":[{{"name":"cloth","channels":[{{"sampler":0,"target":{{"node":0,"path":"weights"}}}}],"samplers":[{{"input":{input},"output":{output},"interpolation":"STEP"}}]}}]"#
            );
        }
        primitive.push('}');
        let json = format!(
            r#"{{"asset":{{"version":"2.0","generator":"cloth3d"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"name":"cloth","mesh":0}}],"meshes":[{{"name":"cloth","primitives":[{primitive}]{mesh_extra}}}],"materials":[{{"name":"{}","doubleSided":true,"pbrMetallicRoughness":{{"baseColorFactor":[{r},{g},{b},1.0],"metallicFactor":0.0,"roughnessFactor":0.9}}}}]{animation},"buffers":[{{"byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
            cloth.material.name.replace(['"', '\\'], ""),
            gltf.bin.len(),
            gltf.views.join(","),
            gltf.accessors.join(","),
        );
        glb_container(json.into_bytes(), gltf.bin)
    }
}

/// The cloth's current mesh as a glTF 2.0 binary (`.glb`): positions,
/// normals, texture coordinates, triangles and a double-sided material of
/// the cloth's colour.
pub fn glb(cloth: &Cloth) -> Vec<u8> {
    Animation::new(0.0).to_glb(cloth)
}

/// Writes [`glb`] of the cloth to `path`.
pub fn write_glb(cloth: &Cloth, path: &Path) -> std::io::Result<()> {
    std::fs::write(path, glb(cloth))
}

/// Binary buffer, buffer views and accessors of a glTF file being written.
#[derive(Default)]
struct GlbBuilder {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl GlbBuilder {
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let target = if target == 0 {
            String::new()
        } else {
            format!(r#","target":{target}"#)
        };
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}{target}}}"#,
            bytes.len()
        ));
        self.views.len() - 1
    }

    fn accessor(&mut self, json: String) -> usize {
        self.accessors.push(json);
        self.accessors.len() - 1
    }

    /// A VEC3 float accessor with its bounds (glTF requires them for positions).
    fn vec3(&mut self, values: &[Vector], target: u32) -> usize {
        let mut bytes = Vec::with_capacity(values.len() * 12);
        let (mut lo, mut hi) = (Vector::splat(f32::MAX), Vector::splat(f32::MIN));
        for v in values {
            lo = lo.min(*v);
            hi = hi.max(*v);
            for c in [v.x, v.y, v.z] {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
        if values.is_empty() {
            (lo, hi) = (Vector::ZERO, Vector::ZERO);
        }
        let view = self.view(&bytes, target);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}}"#,
            values.len(),
            lo.x,
            lo.y,
            lo.z,
            hi.x,
            hi.y,
            hi.z
        ))
    }

    fn floats(
        &mut self,
        values: &[f32],
        kind: &str,
        target: u32,
        bounds: Option<(f32, f32)>,
    ) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let per = match kind {
            "VEC2" => 2,
            "VEC3" => 3,
            _ => 1,
        };
        let bounds = bounds
            .map(|(a, b)| format!(r#","min":[{a}],"max":[{b}]"#))
            .unwrap_or_default();
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5126,"count":{},"type":"{kind}"{bounds}}}"#,
            values.len() / per
        ))
    }

    fn indices(&mut self, values: &[u32]) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.view(&bytes, 34963);
        self.accessor(format!(
            r#"{{"bufferView":{view},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            values.len()
        ))
    }
}

/// The GLB container: header, JSON chunk (padded with spaces), BIN chunk (padded with zeros).
fn glb_container(mut json: Vec<u8>, mut bin: Vec<u8>) -> Vec<u8> {
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}
