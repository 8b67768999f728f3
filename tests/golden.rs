//! Golden behaviour: what the solver computes, recorded before the
//! architecture moved, so that a redesign provably changes no number.
//!
//! Every canonical scene (pins with each variant) runs 60 frames with every
//! integrator at its default substeps; the bits of the final positions and
//! velocities, and of every rapier body's pose, are hashed and compared with
//! `tests/golden/behaviour.txt`. A commit that changes a number on purpose
//! regenerates the file (`CLOTH3D_BLESS=1 cargo test --release --test golden`)
//! and says why in its message.

use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use cloth3d::solver::Integrator;

const FRAMES: u32 = 60;
const GOLDEN: &str = "tests/golden/behaviour.txt";

/// FNV-1a over 32-bit words.
fn fnv(words: impl IntoIterator<Item = u32>) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for w in words {
        for b in w.to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// One line per run: scene, variant, integrator, the hash of the cloth's
/// state, the hash of the bodies' poses, and the centroid (for a reader).
fn run(kind: SceneKind, variant: Option<cloth3d::PinPreset>, integrator: Integrator) -> String {
    // drape and box at 24 × 24 and the stack's cloths at 16 × 16 keep the
    // explicit integrators' auto substeps affordable; every other scene runs
    // at its canonical size.
    let n = match kind {
        SceneKind::Drape | SceneKind::Box => Some(24),
        SceneKind::Stack => Some(16),
        _ => None,
    };
    let options = SceneOptions {
        n,
        integrator: Some(integrator),
        variant,
        ..Default::default()
    };
    let mut scene = Scene::build(kind, &options).unwrap();
    let mut diverged = false;
    for _ in 0..FRAMES {
        if scene.step_frame().is_err() {
            diverged = true;
            break;
        }
    }
    let cloth = &scene.cloth;
    let state = fnv(cloth
        .positions()
        .iter()
        .chain(cloth.velocities())
        .flat_map(|v| v.to_array())
        .map(f32::to_bits));
    let bodies = match &scene.rapier {
        None => 0,
        Some(side) => fnv(side.all_bodies.iter().flat_map(|h| {
            let b = &side.world.bodies[*h];
            let t = b.translation().to_array();
            let r = b.rotation().to_array();
            let v = b.linvel().to_array();
            t.into_iter()
                .chain(r)
                .chain(v)
                .map(f32::to_bits)
                .collect::<Vec<_>>()
        })),
    };
    let c = cloth.centroid();
    format!(
        "{} {} {} state={state:016x} bodies={bodies:016x} diverged={diverged} centroid=({:.4},{:.4},{:.4})",
        kind.name(),
        variant.map_or("-", |v| v.name()),
        integrator.name(),
        c.x,
        c.y,
        c.z
    )
}

#[test]
fn every_scene_with_every_integrator_computes_what_it_did() {
    let mut lines = Vec::new();
    for kind in SceneKind::ALL {
        let variants: Vec<Option<cloth3d::PinPreset>> = if kind.variants().is_empty() {
            vec![None]
        } else {
            kind.variants().iter().copied().map(Some).collect()
        };
        for variant in variants {
            for integrator in Integrator::ALL {
                lines.push(run(kind, variant, integrator));
            }
        }
    }
    let got = lines.join("\n") + "\n";
    if std::env::var_os("CLOTH3D_BLESS").is_some() {
        std::fs::write(GOLDEN, &got).unwrap();
        return;
    }
    let want = std::fs::read_to_string(GOLDEN).expect("tests/golden/behaviour.txt is missing");
    let mismatched: Vec<String> = want
        .lines()
        .zip(got.lines())
        .filter(|(w, g)| w != g)
        .map(|(w, g)| format!("want {w}\n got {g}"))
        .collect();
    assert_eq!(
        want.lines().count(),
        got.lines().count(),
        "run count changed"
    );
    assert!(
        mismatched.is_empty(),
        "{} of {} runs changed:\n{}",
        mismatched.len(),
        lines.len(),
        mismatched.join("\n")
    );
}
