//! Writes the example cloth meshes (`examples/meshes/*.obj`) that the scene
//! files `skirt.ron` and `banner.ron` load: a skirt (a ring of quads around
//! a body) and a swallow-tailed banner (quads, with triangles along its
//! notch). Run it again to make them afresh:
//!
//! ```sh
//! cargo run --example make_meshes
//! ```

use std::f32::consts::TAU;
use std::fmt::Write as _;

/// A polygon mesh: positions (m), texture coordinates and faces (0-based).
struct Mesh {
    positions: Vec<[f32; 3]>,
    uvs: Vec<[f32; 2]>,
    faces: Vec<Vec<usize>>,
}

impl Mesh {
    /// Drops the vertices no face uses (keeping the others' order) and writes OBJ.
    fn obj(mut self, header: &str) -> String {
        let mut used = vec![false; self.positions.len()];
        for f in &self.faces {
            for &i in f {
                used[i] = true;
            }
        }
        let mut new_index = vec![usize::MAX; used.len()];
        let mut kept = 0;
        for (i, &u) in used.iter().enumerate() {
            if u {
                new_index[i] = kept;
                kept += 1;
            }
        }
        fn keep<T>(v: &mut Vec<T>, used: &[bool]) {
            let mut k = 0;
            v.retain(|_| {
                k += 1;
                used[k - 1]
            });
        }
        keep(&mut self.positions, &used);
        keep(&mut self.uvs, &used);
        let mut out = String::new();
        let _ = writeln!(out, "{header}");
        for p in &self.positions {
            let _ = writeln!(out, "v {:.5} {:.5} {:.5}", p[0], p[1], p[2]);
        }
        for t in &self.uvs {
            let _ = writeln!(out, "vt {:.5} {:.5}", t[0], t[1]);
        }
        for f in &self.faces {
            let corners: Vec<String> = f
                .iter()
                .map(|&i| format!("{0}/{0}", new_index[i] + 1))
                .collect();
            let _ = writeln!(out, "f {}", corners.join(" "));
        }
        out
    }
}

/// A skirt: a truncated cone of quads, 24 around and 10 down, from a 0.14 m
/// waist at y = 1.0 to a 0.32 m hem 0.5 m lower. Its waist ring is the
/// first 24 vertices.
fn skirt() -> Mesh {
    let (around, down) = (24, 11);
    let mut m = Mesh {
        positions: Vec::new(),
        uvs: Vec::new(),
        faces: Vec::new(),
    };
    for j in 0..down {
        let s = j as f32 / (down - 1) as f32;
        let radius = 0.14 + 0.18 * s;
        for i in 0..around {
            let a = TAU * i as f32 / around as f32;
            m.positions
                .push([radius * a.cos(), 1.0 - 0.5 * s, radius * a.sin()]);
            m.uvs.push([i as f32 / around as f32, 1.0 - s]);
        }
    }
    let id = |j: usize, i: usize| j * around + i % around;
    for j in 0..down - 1 {
        for i in 0..around {
            // Counter-clockwise seen from outside.
            m.faces
                .push(vec![id(j, i), id(j, i + 1), id(j + 1, i + 1), id(j + 1, i)]);
        }
    }
    m
}

/// A banner 1.0 m wide and 0.6 m tall in the x–y plane, 21 × 13 vertices,
/// its top row (the first 21 vertices) at y = 0; a swallowtail notch cut
/// into the middle of its lower edge, with triangles along the notch.
fn banner() -> Mesh {
    let (cols, rows) = (21usize, 13usize);
    let mut m = Mesh {
        positions: Vec::new(),
        uvs: Vec::new(),
        faces: Vec::new(),
    };
    for r in 0..rows {
        for c in 0..cols {
            let (u, v) = (c as f32 / (cols - 1) as f32, r as f32 / (rows - 1) as f32);
            m.positions.push([u - 0.5, -0.6 * v, 0.0]);
            m.uvs.push([u, 1.0 - v]);
        }
    }
    let id = |r: usize, c: usize| r * cols + c;
    // The notch: a V from the lower edge's middle up to row 6.
    let depth = |c: usize| {
        let from_middle = (c as f32 - 10.0).abs();
        (rows - 1) as f32 - (6.0 - from_middle).max(0.0)
    };
    for r in 0..rows - 1 {
        for c in 0..cols - 1 {
            let (a, b, cc, d) = (id(r, c), id(r + 1, c), id(r + 1, c + 1), id(r, c + 1));
            let (left, right) = (depth(c), depth(c + 1));
            let bottom = (r + 1) as f32;
            if bottom <= left.min(right) {
                m.faces.push(vec![a, b, cc, d]);
            } else if bottom <= left.max(right) && r as f32 >= left.min(right) {
                // Along the notch: the half of the cell outside it.
                if left > right {
                    m.faces.push(vec![a, b, d]);
                } else {
                    m.faces.push(vec![a, cc, d]);
                }
            }
        }
    }
    m
}

fn main() -> std::io::Result<()> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/meshes");
    std::fs::create_dir_all(&dir)?;
    let made = "made by `cargo run --example make_meshes`";
    std::fs::write(
        dir.join("skirt.obj"),
        skirt().obj(&format!(
            "# A skirt of 24 × 10 quads ({made}); its waist ring is vertices 1–24."
        )),
    )?;
    std::fs::write(
        dir.join("banner.obj"),
        banner().obj(&format!(
            "# A swallow-tailed banner, quads and triangles ({made}); its top row is vertices 1–21."
        )),
    )?;
    println!("wrote {}", dir.display());
    Ok(())
}
