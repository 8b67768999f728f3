//! Mesh export: the cloth as Wavefront OBJ, one file per frame, for Blender's
//! OBJ-sequence import and game engines.

use std::fmt::Write as _;
use std::path::Path;

use crate::cloth::Cloth;

/// The cloth's current mesh as OBJ text: positions (`v`, metres), texture
/// coordinates (`vt`), vertex normals (`vn`) and triangles (`f v/vt/vn`,
/// counter-clockwise seen from the front).
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
    for t in cloth.triangles() {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
    }
    out
}

/// Writes the cloth's current mesh to `path` as OBJ.
pub fn write_obj(cloth: &Cloth, path: &Path) -> std::io::Result<()> {
    std::fs::write(path, obj_string(cloth))
}
