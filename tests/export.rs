//! Exports that other tools read: glTF (parsed back with the gltf crate),
//! OBJ, the `--plot` picture, and progress that never reaches piped output.

use std::process::Command;

mod common;

use common::{cloth3d, cloth3d_ok};

use cloth3d::export::Animation;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

/// What a glb holds: the mesh's positions, each morph target added to them,
/// the index count, and the document.
type Glb = (Vec<[f32; 3]>, Vec<Vec<[f32; 3]>>, usize, gltf::Document);

/// Reads a glb back with the gltf crate.
fn read_glb(bytes: &[u8]) -> Glb {
    let glb = gltf::Gltf::from_slice(bytes).expect("a valid glb");
    let blob = glb.blob.clone().expect("a BIN chunk");
    let doc = glb.document;
    let mesh = doc.meshes().next().expect("a mesh");
    let prim = mesh.primitives().next().expect("a primitive");
    let reader = prim.reader(|_| Some(&blob[..]));
    let base: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
    let normals = reader.read_normals().expect("normals").count();
    assert_eq!(normals, base.len());
    assert_eq!(
        reader.read_tex_coords(0).expect("uvs").into_f32().count(),
        base.len()
    );
    let indices = reader.read_indices().expect("indices").into_u32().count();
    let frames = reader
        .read_morph_targets()
        .map(|(p, _, _)| {
            p.expect("position deltas")
                .zip(&base)
                .map(|(d, b)| [b[0] + d[0], b[1] + d[1], b[2] + d[2]])
                .collect()
        })
        .collect();
    (base, frames, indices, doc)
}

#[test]
fn glb_parses_back_with_the_final_positions_and_every_frame() {
    let mut scene = Scene::build(
        SceneKind::Pins,
        &SceneOptions {
            n: Some(9),
            ..Default::default()
        },
    )
    .unwrap();
    let mut anim = Animation::new(scene.dt);
    let mut history = Vec::new();
    for _ in 0..12 {
        scene.step_frame().unwrap();
        anim.push(&scene.cloth);
        history.push(scene.cloth.positions().to_vec());
    }
    let bytes = anim.to_glb(&scene.cloth);
    let (base, frames, indices, doc) = read_glb(&bytes);
    assert_eq!(base.len(), scene.cloth.particle_count());
    assert_eq!(indices, 3 * scene.cloth.triangles().len());
    for (a, b) in base.iter().zip(scene.cloth.positions()) {
        assert_eq!(*a, [b.x, b.y, b.z], "the mesh is the final frame, exactly");
    }
    assert_eq!(frames.len(), 12);
    for (k, frame) in frames.iter().enumerate() {
        for (a, b) in frame.iter().zip(&history[k]) {
            let d = (Vector::from(*a) - *b).length();
            assert!(d < 1e-5, "frame {k}: {d}");
        }
    }
    // The animation switches the weights frame by frame, 1/60 s apart.
    let animation = doc.animations().next().expect("an animation");
    let channel = animation.channels().next().unwrap();
    assert_eq!(
        channel.target().property(),
        gltf::animation::Property::MorphTargetWeights
    );
    assert_eq!(channel.sampler().input().count(), 12);
    assert_eq!(channel.sampler().output().count(), 12 * 12);
    // Frames fell under gravity: the first and the last differ.
    assert_ne!(frames[0], frames[11]);

    // A single mesh (no frames recorded) is a valid file too.
    let (base, frames, _, doc) = read_glb(&cloth3d::export::glb(&scene.cloth));
    assert_eq!(base.len(), scene.cloth.particle_count());
    assert!(frames.is_empty() && doc.animations().next().is_none());
}

#[test]
fn run_export_glb_and_obj_agree_with_the_final_cloth() {
    let dir = std::env::temp_dir().join(format!("cloth3d-export-{}", std::process::id()));
    let glb = dir.join("drape.glb");
    std::fs::create_dir_all(&dir).unwrap();
    cloth3d_ok(&[
        "run",
        "drape",
        "--n",
        "10",
        "--frames",
        "20",
        "--json",
        "--export-glb",
        glb.to_str().unwrap(),
        "--export-obj",
        dir.to_str().unwrap(),
    ]);
    let (base, frames, _, _) = read_glb(&std::fs::read(&glb).unwrap());
    assert_eq!(base.len(), 100);
    assert_eq!(frames.len(), 20);
    let obj = std::fs::read_to_string(dir.join("frame_0020.obj")).unwrap();
    let vertices: Vec<[f32; 3]> = obj
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| {
            let v: Vec<f32> = l
                .split_whitespace()
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect();
            [v[0], v[1], v[2]]
        })
        .collect();
    assert_eq!(vertices, base, "OBJ and glTF hold the same final positions");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `cloth3d run tear --json` tears the sheet in two, and its exports show
/// the opening: the OBJ and the glb hold the split particles as vertices of
/// their own, no triangle bridges the gap between the pieces, and the glb
/// keeps every frame, those before the tear included.
#[test]
fn run_tear_reports_torn_springs_and_exports_the_opening() {
    let dir = std::env::temp_dir().join(format!("cloth3d-tear-{}", std::process::id()));
    let glb = dir.join("tear.glb");
    std::fs::create_dir_all(&dir).unwrap();
    let out = cloth3d_ok(&[
        "run",
        "tear",
        "--json",
        "--export-glb",
        glb.to_str().unwrap(),
        "--export-obj",
        dir.to_str().unwrap(),
    ]);
    let m: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(m["finite"], true);
    assert!(m["torn_springs"].as_u64().unwrap() > 0, "{out}");
    assert_eq!(m["pieces"], 2, "{out}");
    let frames = m["frames"].as_u64().unwrap() as usize;
    let grid = 64 * 32;

    let obj = std::fs::read_to_string(dir.join(format!("frame_{frames:04}.obj"))).unwrap();
    let numbers = |l: &str| -> Vec<f32> {
        l.split_whitespace()
            .skip(1)
            .map(|x| x.split('/').next().unwrap().parse().unwrap())
            .collect()
    };
    let vertices: Vec<Vector> = obj
        .lines()
        .filter(|l| l.starts_with("v "))
        .map(|l| Vector::from_slice(&numbers(l)))
        .collect();
    assert!(vertices.len() > grid, "{} vertices", vertices.len());
    let faces: Vec<[usize; 3]> = obj
        .lines()
        .filter(|l| l.starts_with("f "))
        .map(|l| {
            let f = numbers(l);
            [f[0] as usize - 1, f[1] as usize - 1, f[2] as usize - 1]
        })
        .collect();
    // The grid spacing is 1.9 cm and the cotton stretches under 15% before
    // it tears; the opening is tens of centimetres wide.
    let longest = |p: &[Vector], f: &[usize; 3]| {
        (0..3)
            .map(|k| (p[f[k]] - p[f[(k + 1) % 3]]).length())
            .fold(0.0f32, f32::max)
    };
    for f in &faces {
        assert!(
            longest(&vertices, f) < 0.05,
            "triangle {f:?} bridges the opening"
        );
    }
    let (base, recorded, indices, _) = read_glb(&std::fs::read(&glb).unwrap());
    assert_eq!(base.len(), vertices.len());
    assert_eq!(indices, 3 * faces.len());
    assert_eq!(recorded.len(), frames, "a frame was left out");
    // The first frame, before any tear, is the whole sheet: its new
    // particles sit on the particles they split from.
    let first: Vec<Vector> = recorded[0].iter().map(|&p| Vector::from(p)).collect();
    for f in &faces {
        assert!(
            longest(&first, f) < 0.05,
            "frame 1: triangle {f:?} is torn open"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_plot_draws_three_curves() {
    let plot = std::env::temp_dir().join(format!("cloth3d-plot-{}.png", std::process::id()));
    let stdout = cloth3d_ok(&[
        "run",
        "drape",
        "--n",
        "12",
        "--frames",
        "40",
        "--json",
        "--plot",
        plot.to_str().unwrap(),
    ]);
    assert_eq!(stdout.lines().count(), 1);
    let img = image::open(&plot).unwrap().to_rgb8();
    assert_eq!((img.width(), img.height()), (900, 900));
    // Energy, stretch and penetration each in their panel, in their colour.
    let colors = [
        cloth3d::cli::plot::COLORS[1],
        cloth3d::cli::plot::COLORS[0],
        cloth3d::cli::plot::COLORS[2],
    ];
    for (panel, color) in colors.iter().enumerate() {
        let rows = panel as u32 * 300..(panel as u32 + 1) * 300;
        let count = img
            .enumerate_pixels()
            .filter(|(_, y, p)| rows.contains(y) && p.0 == *color)
            .count();
        assert!(count > 100, "panel {panel}: {count} pixels of its curve");
        for (other, c) in colors.iter().enumerate() {
            if other != panel {
                let stray = img
                    .enumerate_pixels()
                    .filter(|(_, y, p)| rows.contains(y) && p.0 == *c)
                    .count();
                assert!(stray < count / 4, "panel {panel} has colour {other}");
            }
        }
    }
    let _ = std::fs::remove_file(&plot);
}

#[test]
fn progress_shows_on_a_terminal_only() {
    // Piped: no progress text anywhere.
    let out = cloth3d(&["run", "pins", "--n", "8", "--frames", "30"]);
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!String::from_utf8_lossy(&out.stdout).contains("frames,"));
    // On a terminal (util-linux `script` gives the command a pseudo-terminal):
    // a bar, unless --quiet.
    let exe = env!("CARGO_BIN_EXE_cloth3d");
    let on_tty = |extra: &str| {
        Command::new("script")
            .args([
                "-qec",
                &format!("{exe} run drape --n 24 --frames 60 {extra}"),
                "/dev/null",
            ])
            .output()
    };
    match on_tty("") {
        Err(e) => panic!("`script` (util-linux) is needed for this test: {e}"),
        Ok(out) => {
            assert!(out.status.success());
            let text = String::from_utf8_lossy(&out.stdout);
            assert!(text.contains("/60 frames"), "{text}");
            let quiet = on_tty("--quiet").unwrap();
            let text = String::from_utf8_lossy(&quiet.stdout);
            assert!(!text.contains("/60 frames"), "{text}");
            assert!(
                text.contains("max_stretch") || text.contains("stretch"),
                "{text}"
            );
        }
    }
}
