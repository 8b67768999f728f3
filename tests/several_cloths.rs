//! Several cloths in one scene: joined into one simulated cloth, they meet
//! through self-collision and never pass through each other.

use cloth3d::cloth::{Grid, GridPiece};
use cloth3d::collision::self_intersections;
use cloth3d::metrics::pieces;
use cloth3d::prelude::*;

const SIDE: usize = 12;

/// A 0.5 m square of cotton, flat at height `y`, turned `turn` radians
/// about the vertical.
fn square(y: f32, turn: f32) -> Cloth {
    ClothBuilder::new(SIDE, SIDE)
        .size(0.5, 0.5)
        .pose(Pose::from_parts(
            Vector::new(0.0, y, 0.0),
            Rotation::from_rotation_y(turn),
        ))
        .self_collision(true)
        .build()
        .unwrap()
}

/// The ground: a wide box whose top is at y = 0.
fn ground() -> Obstacle {
    Obstacle::cuboid(
        Vector::new(2.0, 0.5, 2.0),
        Pose::from_translation(Vector::new(0.0, -0.5, 0.0)),
    )
}

/// Drops two squares, the upper turned 45°, onto the ground for `frames`
/// frames; returns the cloth and the most self-intersections of any frame.
fn drop_two(self_collision: bool, frames: usize) -> (Cloth, usize) {
    let mut cloth = Cloth::join(vec![square(0.05, 0.0), square(0.15, 0.785)]).unwrap();
    cloth.params.self_collision = self_collision;
    let mut solver = ClothSolver::default();
    let obstacles = [ground()];
    let mut worst = 0;
    for _ in 0..frames {
        solver.step(&mut cloth, 1.0 / 60.0, &obstacles).unwrap();
        worst = worst.max(self_intersections(&cloth));
    }
    (cloth, worst)
}

/// Two cloths dropped one on the other onto the ground never cross: no
/// self-intersection in any frame, and every particle of the upper cloth
/// lies above the lower cloth wherever the lower one is under it. Without
/// self-collision the same drop passes one through the other.
#[test]
fn two_cloths_dropped_on_each_other_never_cross() {
    let (cloth, worst) = drop_two(true, 90);
    assert!(cloth.is_finite());
    assert_eq!(worst, 0, "the cloths crossed");
    let x = cloth.positions();
    let n = SIDE * SIDE;
    let (lower, upper) = (&x[..n], &x[n..]);
    let mut checked = 0;
    let lower_triangles = &cloth.triangles()[..cloth.triangles().len() / 2];
    for u in upper {
        // The lower cloth's surface right under this particle, if any: its
        // height interpolated over the triangle that covers it seen from above.
        for t in lower_triangles {
            let [a, b, c] = t.map(|i| x[i as usize]);
            let (e1, e2, d) = (b - a, c - a, *u - a);
            let det = e1.x * e2.z - e1.z * e2.x;
            if det.abs() < 1e-12 {
                continue;
            }
            let (s, r) = (
                (d.x * e2.z - d.z * e2.x) / det,
                (e1.x * d.z - e1.z * d.x) / det,
            );
            if s >= 0.0 && r >= 0.0 && s + r <= 1.0 {
                let y = a.y + s * e1.y + r * e2.y;
                checked += 1;
                assert!(
                    u.y > y + 0.002,
                    "upper {u:?} is not above the lower cloth ({y})"
                );
            }
        }
    }
    assert!(
        checked > 50,
        "only {checked} particles lie over the lower cloth"
    );
    // Both lie on the ground, the lower one flat on it.
    assert!(
        lower.iter().all(|p| p.y < 0.02),
        "the lower cloth did not land"
    );

    let (_, crossings) = drop_two(false, 90);
    assert!(crossings > 50, "without self-collision: {crossings}");
}

/// `Cloth::join`: particles, springs, triangles, masses and pins of each
/// piece follow those of the pieces before, in order; the pieces stay
/// apart (no spring between them).
#[test]
fn join_keeps_each_piece_and_numbers_them_in_order() {
    let mut a = square(0.0, 0.0);
    a.pin(3).unwrap();
    let mut b = ClothBuilder::new(5, 4).build().unwrap();
    b.pin(2).unwrap();
    let (na, nb) = (a.particle_count(), b.particle_count());
    let joined = Cloth::join(vec![a.clone(), b.clone()]).unwrap();
    assert_eq!(joined.particle_count(), na + nb);
    assert_eq!(
        joined.springs().len(),
        a.springs().len() + b.springs().len()
    );
    assert_eq!(
        joined.triangles().len(),
        a.triangles().len() + b.triangles().len()
    );
    assert_eq!(&joined.positions()[na..], b.positions());
    assert!((joined.total_mass() - a.total_mass() - b.total_mass()).abs() < 1e-5);
    assert_eq!(joined.pinned(), vec![3, na + 2]);
    assert!(joined
        .springs()
        .iter()
        .all(|s| ((s.a as usize) < na) == ((s.b as usize) < na)));
    assert_eq!(pieces(&joined), 2);
    assert!(joined.grid().is_none());
    // Each piece's grid, where it now lies (self-collision patches them);
    // joined again, offset again; through a snapshot, kept.
    let grids = |c: &Cloth| c.topology().grid_pieces().collect::<Vec<_>>();
    let piece = |first_particle, first_triangle, cols, rows| GridPiece {
        first_particle,
        first_triangle,
        grid: Grid { cols, rows },
    };
    let ta = a.triangles().len();
    assert_eq!(
        grids(&joined),
        [piece(0, 0, SIDE, SIDE), piece(na, ta, 5, 4)]
    );
    let again = Cloth::join(vec![b.clone(), joined.clone()]).unwrap();
    let tb = b.triangles().len();
    assert_eq!(
        grids(&again),
        [
            piece(0, 0, 5, 4),
            piece(nb, tb, SIDE, SIDE),
            piece(nb + na, tb + ta, 5, 4)
        ]
    );
    let back: Cloth = serde_json::from_str(&serde_json::to_string(&joined).unwrap()).unwrap();
    assert_eq!(grids(&back), grids(&joined));
    // One piece is itself.
    assert_eq!(Cloth::join(vec![b.clone()]).unwrap(), b);
    assert!(Cloth::join(vec![]).is_err());
}

/// Pieces of different materials are refused, naming the piece.
#[test]
fn join_refuses_pieces_of_another_material() {
    let silk = ClothBuilder::new(4, 4)
        .material(Material::silk())
        .build()
        .unwrap();
    let err = Cloth::join(vec![square(0.0, 0.0), silk]).unwrap_err();
    let text = err.to_string();
    assert!(text.contains("silk") && text.contains("cotton"), "{text}");
}

/// Cloths of one grid shape joined are stepped on their grids stacked
/// (`Topology::lane_grid`): with the chain solves, so with the substeps of
/// one of them alone, and each piece moves as it does alone (no spring
/// between them, the falling one not held by the hanging one), within a
/// millimetre.
#[test]
fn pieces_of_one_shape_joined_move_as_each_does_alone() {
    let sheet = |x: f32, pins: PinPreset| {
        let mut piece = ClothBuilder::new(SIDE, SIDE)
            .size(0.5, 0.5)
            .vertical(Vector::new(x, 1.0, 0.0))
            .pins(pins)
            .build()
            .unwrap();
        piece.params.self_collision = false;
        piece
    };
    // One hangs, the other falls: a spring between them, or a chain
    // through both, would hold the falling one up.
    let (left, right) = (
        sheet(-1.0, PinPreset::TwoCorners),
        sheet(1.0, PinPreset::None),
    );
    let mut joined = Cloth::join(vec![left.clone(), right.clone()]).unwrap();
    let lanes = joined.topology().lane_grid().expect("a stacked grid");
    assert_eq!((lanes.grid.cols, lanes.grid.rows), (SIDE, 2 * SIDE));
    assert_eq!(lanes.piece_rows, SIDE);
    // Of two shapes: none.
    let odd = ClothBuilder::new(SIDE, SIDE + 1).build().unwrap();
    let mixed = Cloth::join(vec![left.clone(), odd]).unwrap();
    assert!(mixed.topology().lane_grid().is_none());

    let lowest = |c: &Cloth| {
        c.positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::INFINITY, f32::min)
    };
    let start = lowest(&joined);
    let dt = 1.0 / 60.0;
    let auto = ClothSolver::default();
    let k = auto.substeps_for(&joined, dt);
    assert_eq!(
        k,
        auto.substeps_for(&left, dt),
        "the joined cloth takes the chains' substeps"
    );
    // All at those: a free fall's path depends on the substep.
    let fixed = || {
        ClothSolver::new(SolverSettings {
            substeps: Substeps::Fixed(k),
            ..SolverSettings::default()
        })
    };
    let mut solver = fixed();
    let mut alone = [left, right].map(|c| (c, fixed()));
    for _ in 0..90 {
        solver.step(&mut joined, dt, &[]).unwrap();
        for (cloth, solver) in &mut alone {
            solver.step(cloth, dt, &[]).unwrap();
        }
    }
    let n = SIDE * SIDE;
    let x = joined.positions();
    for (k, (cloth, _)) in alone.iter().enumerate() {
        let worst = cloth
            .positions()
            .iter()
            .zip(&x[k * n..(k + 1) * n])
            .map(|(a, b)| (*a - *b).length())
            .fold(0.0f32, f32::max);
        assert!(
            worst < 1e-3,
            "piece {k} is {worst} m from where it hangs alone"
        );
    }
    // They moved: one sagged, one fell.
    assert!(
        lowest(&joined) < start - 1.0,
        "{} from {start}",
        lowest(&joined)
    );
}

/// Two sheets of the `stack` (32 × 32 cotton, 0.9 m) dropped one 1.5 cm
/// over the other, turned 0.4 rad, onto a fixed cylinder 0.3 m across (a
/// round table): over its sharp rim the collision stage pushes the lower
/// sheet out by millimetres at once, at the step's last substep, and that
/// carried it through the upper one, which lay on it (before the layers
/// were parted again after such a push: 34 self-intersections at the end,
/// 51 in the worst frame). They end uncrossed, the upper lying on the
/// lower over the table, and nothing enters the table.
#[test]
fn two_cloths_dropped_on_a_round_table_stay_apart_over_its_rim() {
    use cloth3d::scenes::{ObstacleDesc, Placement, Scene, SceneKind, SceneOptions, ShapeDesc};
    let options = SceneOptions {
        n: Some(32),
        ..Default::default()
    };
    let mut desc = SceneKind::Stack.desc(&options).unwrap();
    let at = |y: f32, turn: f32| Placement::Pose {
        translation: Vector::new(0.0, y, 0.0),
        rotation: Vector::new(0.0, turn, 0.0),
    };
    desc.cloth.placement = at(0.3, 0.0);
    desc.cloths.truncate(1);
    desc.cloths[0].placement = at(0.315, 0.4);
    let (radius, half_height) = (0.15, 0.15);
    desc.obstacles = vec![ObstacleDesc::fixed(
        ShapeDesc::Cylinder {
            half_height,
            radius,
        },
        Vector::ZERO,
    )];
    let mut scene = Scene::from_desc(desc).unwrap();
    let mut worst = 0;
    for _ in 0..180 {
        scene.step_frame().unwrap();
        worst = worst.max(self_intersections(&scene.cloth));
    }
    assert_eq!(self_intersections(&scene.cloth), 0, "crossed at the end");
    assert!(worst <= 10, "{worst} self-intersections in a frame");
    assert!(scene.max_penetration() <= 1.0e-3);
    // The upper sheet lies on the lower one over the table top: each of
    // its particles there is higher than every lower particle within a
    // cell of it (seen from above).
    let x = scene.cloth.positions();
    let n = x.len() / 2;
    let (lower, upper) = (&x[..n], &x[n..]);
    let cell = 0.9 / 31.0;
    let mut checked = 0;
    for u in upper.iter().filter(|u| u.x.hypot(u.z) < radius - cell) {
        for l in lower.iter().filter(|l| (l.x - u.x).hypot(l.z - u.z) < cell) {
            checked += 1;
            assert!(u.y > l.y, "upper {u:?} under lower {l:?}");
        }
    }
    assert!(checked > 50, "only {checked} pairs over the table");
}
