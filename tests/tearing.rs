//! Tearing: a stretch spring strained past the material's tear strain splits
//! the cloth there; the mesh opens, the rest holds, and a torn cloth steps,
//! snapshots and exports like any other.

mod common;

use cloth3d::metrics::pieces;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use common::{bits, on_threads};

const COLS: usize = 17;
const ROWS: usize = 11;
/// The column the notch is cut in, halfway across.
const NOTCH_COL: usize = 8;

/// A 0.8 m × 0.5 m sheet without gravity, its left and right columns
/// pinned, cut in the middle of column 8 (rows 4–6) across the pull: a
/// notched specimen, as in a tensile test.
fn notched_sheet(tear: Option<f32>, integrator: Integrator) -> Simulation {
    let material = Material::cotton()
        .with_stretch_limit(None)
        .with_tear_strain(tear);
    let mut cloth = ClothBuilder::new(COLS, ROWS)
        .size(0.8, 0.5)
        .horizontal(Vector::ZERO)
        .material(material)
        .build()
        .unwrap();
    cloth.params.gravity = Vector::ZERO;
    for r in 0..ROWS {
        cloth.pin_cell(r, 0).unwrap();
        cloth.pin_cell(r, COLS - 1).unwrap();
    }
    for r in 4..=6 {
        let i = cloth.index(r, NOTCH_COL).unwrap();
        assert!(cloth.split_particle(i, Vector::X).unwrap().is_some());
    }
    Simulation::new(cloth).with_integrator(integrator)
}

/// Pulls the right column away at 0.2 m/s for `frames` frames; returns
/// every tear event.
fn pull(sim: &mut Simulation, frames: usize) -> Vec<TearEvent> {
    let dt = 1.0 / 60.0;
    let right: Vec<usize> = (0..ROWS).map(|r| sim.index(r, COLS - 1).unwrap()).collect();
    let mut events = Vec::new();
    for _ in 0..frames {
        for &i in &right {
            let p = sim.positions()[i] + Vector::new(0.2 * dt, 0.0, 0.0);
            sim.set_position(i, p).unwrap();
        }
        let report = sim.step(dt, &[]).unwrap();
        assert_eq!(report.torn_springs as usize, sim.tear_events().len());
        events.extend_from_slice(sim.tear_events());
    }
    events
}

/// The piece each particle is in (a representative particle's index).
fn piece_of(cloth: &Cloth) -> Vec<usize> {
    let n = cloth.particle_count();
    let mut piece: Vec<usize> = (0..n).collect();
    // Relax until every triangle's particles agree (small meshes only).
    loop {
        let mut changed = false;
        for t in cloth.triangles() {
            let m = t.iter().map(|&u| piece[u as usize]).min().unwrap();
            for &u in t {
                if piece[u as usize] != m {
                    piece[u as usize] = m;
                    changed = true;
                }
            }
        }
        if !changed {
            return piece;
        }
    }
}

/// The notched sheet, pulled, tears from the notch across the sheet along
/// the notch's column and nowhere else: every particle split is one of that
/// column's, each once, and the sheet ends in two pieces, one per held edge.
#[test]
fn a_notched_sheet_tears_across_the_notch_line_and_nowhere_else() {
    for integrator in [Integrator::Xpbd, Integrator::SymplecticEuler] {
        let mut sim = notched_sheet(Some(0.1), integrator);
        let events = pull(&mut sim, 120);
        assert!(sim.is_finite(), "{integrator}");
        // The rows the notch left whole: 0–3 and 7–10.
        let mut torn_rows: Vec<usize> = events
            .iter()
            .map(|e| {
                let p = e.particle as usize;
                assert!(p < COLS * ROWS, "{integrator}: tore at new particle {p}");
                assert_eq!(
                    p % COLS,
                    NOTCH_COL,
                    "{integrator}: tore off the line at {p}"
                );
                p / COLS
            })
            .collect();
        torn_rows.sort_unstable();
        assert_eq!(torn_rows, [0, 1, 2, 3, 7, 8, 9, 10], "{integrator}");
        assert_eq!(sim.particle_count(), COLS * ROWS + ROWS, "{integrator}");
        assert_eq!(pieces(&sim.cloth), 2, "{integrator}");
        let piece = piece_of(&sim.cloth);
        let (left, right) = (piece[0], piece[COLS - 1]);
        assert_ne!(left, right, "{integrator}");
        for r in 0..ROWS {
            for c in (0..COLS).filter(|&c| c != NOTCH_COL) {
                let expected = if c < NOTCH_COL { left } else { right };
                let i = sim.index(r, c).unwrap();
                assert_eq!(piece[i], expected, "{integrator}: particle ({r}, {c})");
            }
        }
        // Each of column 8's particles went one way, its new half the other.
        let splits = sim.topology().splits();
        assert_eq!(splits.len(), ROWS, "{integrator}");
        for &[from, new] in splits {
            let mut sides = [piece[from as usize], piece[new as usize]];
            sides.sort_unstable();
            let mut both = [left, right];
            both.sort_unstable();
            assert_eq!(sides, both, "{integrator}: split of {from}");
        }
        // Mass is shared, never made.
        let mass: f32 = sim.masses().iter().sum();
        let whole = ClothBuilder::new(COLS, ROWS)
            .size(0.8, 0.5)
            .build()
            .unwrap();
        assert!((mass - whole.total_mass()).abs() < 1e-5, "{mass}");
    }
}

/// Without a tear strain the same pull only stretches the sheet.
#[test]
fn without_a_tear_strain_nothing_tears() {
    let mut sim = notched_sheet(None, Integrator::Xpbd);
    let before = sim.particle_count();
    let events = pull(&mut sim, 120);
    assert!(events.is_empty());
    assert_eq!(sim.particle_count(), before);
    assert_eq!(pieces(&sim.cloth), 1);
    assert!(sim.max_strain(SpringKind::Stretch) > 0.2);
}

/// Splitting the middle particle of a flat 5×5 sheet across x: its
/// triangles right of it move to the new particle, the bend spring over it
/// is cut, the springs along the cut line are doubled, and the mass is shared.
#[test]
fn splitting_a_particle_opens_the_mesh_there() {
    let mut cloth = ClothBuilder::new(5, 5)
        .horizontal(Vector::ZERO)
        .build()
        .unwrap();
    let total = cloth.total_mass();
    let springs_before = cloth.springs().len();
    let split = cloth.split_particle(12, Vector::X).unwrap().unwrap();
    assert_eq!((split.particle, split.new_particle), (12, 25));
    assert_eq!(cloth.particle_count(), 26);
    assert_eq!(cloth.positions()[25], cloth.positions()[12]);
    assert!((cloth.total_mass() - total).abs() < 1e-6);
    let x = cloth.positions().to_vec();
    for t in cloth.triangles() {
        let c = (x[t[0] as usize] + x[t[1] as usize] + x[t[2] as usize]) / 3.0;
        if t.contains(&12) {
            assert!(c.x <= x[12].x, "{t:?} right of the cut stays with 12");
        }
        if t.contains(&25) {
            assert!(c.x > x[12].x, "{t:?} left of the cut moved to 25");
        }
    }
    let joined = |a: u32, b: u32| {
        cloth
            .springs()
            .iter()
            .any(|s| (s.a, s.b) == (a, b) || (s.a, s.b) == (b, a))
    };
    // The bend spring over 12 along x is cut; the one along z (the cut's
    // own line) is not.
    assert!(!joined(11, 13));
    assert!(joined(7, 17));
    assert!(joined(12, 11) && !joined(25, 11));
    assert!(joined(25, 13) && !joined(12, 13));
    // The edges along the cut belong to both sides.
    assert!(joined(12, 7) && joined(25, 7));
    assert!(joined(12, 17) && joined(25, 17));
    assert!(cloth.springs().len() > springs_before - 2);
    // A split cloth is no longer a grid, but its cells still name particles.
    assert!(cloth.grid().is_none());
    assert_eq!(cloth.index(2, 2).unwrap(), 12);
    // A corner's triangles all lie on one side of a plane through it.
    assert!(cloth.split_particle(0, Vector::X).unwrap().is_none());
    assert_eq!(cloth.particle_count(), 26);
}

/// Bad input to a split is an error, and changes nothing.
#[test]
fn a_split_with_bad_input_is_refused() {
    let mut cloth = ClothBuilder::new(5, 5).build().unwrap();
    assert!(cloth.split_particle(25, Vector::X).is_err());
    assert!(cloth.split_particle(12, Vector::ZERO).is_err());
    assert!(cloth
        .split_particle(12, Vector::new(f32::NAN, 0.0, 1.0))
        .is_err());
    assert_eq!(cloth.particle_count(), 25);
    let bad = Material::cotton().with_tear_strain(Some(-0.1));
    let err = ClothBuilder::new(5, 5)
        .material(bad.clone())
        .build()
        .unwrap_err();
    assert!(err.to_string().contains("tear strain"), "{err}");
    cloth.material = bad;
    let err = Simulation::new(cloth).step(1.0 / 60.0, &[]).unwrap_err();
    assert!(err.to_string().contains("tear strain"), "{err}");
}

/// A snapshot of a torn simulation (cloth and solver, through JSON)
/// continues bit for bit, tearing further the same way.
#[test]
fn a_snapshot_after_a_tear_continues_bit_for_bit() {
    let mut sim = notched_sheet(Some(0.1), Integrator::Xpbd);
    let events = pull(&mut sim, 22);
    assert!(!events.is_empty(), "nothing tore before the snapshot");
    let json = serde_json::to_string(&sim).unwrap();
    let mut restored: Simulation = serde_json::from_str(&json).unwrap();
    assert_eq!(restored.particle_count(), sim.particle_count());
    let (a, b) = (pull(&mut sim, 60), pull(&mut restored, 60));
    assert_eq!(a, b);
    assert_eq!(bits(&sim.cloth), bits(&restored.cloth));
}

/// The `tear` scene: its bars pull the sheet apart; the tear runs from the
/// slit across the sheet along the slit's column and nowhere else, leaves
/// two pieces, and gives the same bits on two threads as on one.
#[test]
fn the_tear_scene_tears_in_two_the_same_on_any_thread_count() {
    let run = |threads: usize| {
        on_threads(threads, || {
            let mut scene = Scene::build(SceneKind::Tear, &SceneOptions::default()).unwrap();
            let mut torn = 0;
            for _ in 0..scene.frames {
                torn += scene.step_frame().unwrap().torn_springs;
                // The tear runs on from the slit down the middle column.
                for e in scene.solver.tear_events() {
                    assert_eq!(e.particle % 64, 31, "tore off the slit's line: {e:?}");
                }
            }
            (bits(&scene.cloth), torn, pieces(&scene.cloth))
        })
    };
    let one = run(1);
    // Every row but the slit's seven tore, once.
    assert_eq!(one.1, 32 - 7, "torn springs");
    assert_eq!(one.2, 2, "the sheet is not in two pieces");
    assert!(one == run(2), "two threads differ from one");
}

/// At other sizes too the `tear` scene tears along its slit's column alone,
/// into two pieces. As the sheet parts, its edge rows hold the whole load,
/// and at N = 96 a spring two columns from the tip tore with it in both
/// edge rows while the tearing stage waited only one ring around a split.
#[test]
fn the_tear_scene_tears_along_its_line_at_other_sizes() {
    for n in [32, 96] {
        let options = SceneOptions {
            n: Some(n),
            ..Default::default()
        };
        let mut scene = Scene::build(SceneKind::Tear, &options).unwrap();
        let cols = scene.cloth.topology().cells().unwrap().cols;
        let mid = ((cols - 1) / 2) as u32;
        let mut torn = 0;
        for _ in 0..scene.frames {
            torn += scene.step_frame().unwrap().torn_springs;
            for e in scene.solver.tear_events() {
                assert_eq!(
                    e.particle % cols as u32,
                    mid,
                    "N = {n}: off the line: {e:?}"
                );
            }
        }
        let rows = scene.cloth.topology().cells().unwrap().rows;
        // Every row but the slit's tore, once.
        let slit = 2 * (rows / 10) + 1;
        assert_eq!(torn as usize, rows - slit, "N = {n}: torn springs");
        assert_eq!(pieces(&scene.cloth), 2, "N = {n}: not in two pieces");
    }
}
