//! Co-simulation with a real rapier3d world: colliders as obstacles, moving
//! and fast obstacles, two-way coupling, attachments.

use cloth3d::prelude::*;
use cloth3d::rapier::{RapierCoupling, RapierSets};
use cloth3d::scenes::run;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use rapier3d::prelude::*;

#[test]
fn every_kind_of_collider_holds_the_cloth() {
    let cube = [
        Vector::new(-0.2, -0.2, -0.2),
        Vector::new(0.2, -0.2, -0.2),
        Vector::new(-0.2, 0.2, -0.2),
        Vector::new(0.2, 0.2, -0.2),
        Vector::new(-0.2, -0.2, 0.2),
        Vector::new(0.2, -0.2, 0.2),
        Vector::new(-0.2, 0.2, 0.2),
        Vector::new(0.2, 0.2, 0.2),
    ];
    let tent = (
        vec![
            Vector::new(-0.5, -0.2, -0.5),
            Vector::new(0.5, -0.2, -0.5),
            Vector::new(-0.5, 0.2, 0.0),
            Vector::new(0.5, 0.2, 0.0),
            Vector::new(-0.5, -0.2, 0.5),
            Vector::new(0.5, -0.2, 0.5),
        ],
        vec![[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]],
    );
    let colliders = [
        ("ball", ColliderBuilder::ball(0.2)),
        ("cuboid", ColliderBuilder::cuboid(0.2, 0.2, 0.2)),
        ("capsule", ColliderBuilder::capsule_x(0.2, 0.2)),
        ("convex", ColliderBuilder::convex_hull(&cube).unwrap()),
        ("trimesh", ColliderBuilder::trimesh(tent.0, tent.1).unwrap()),
        (
            "compound",
            ColliderBuilder::compound(vec![
                (Pose::translation(-0.15, 0.0, 0.0), SharedShape::ball(0.2)),
                (
                    Pose::translation(0.15, 0.0, 0.0),
                    SharedShape::cuboid(0.1, 0.2, 0.1),
                ),
            ]),
        ),
    ];
    for (name, collider) in colliders {
        let mut world = PhysicsWorld::new();
        world.insert(RigidBodyBuilder::fixed(), collider);
        let mut cloth = Simulation::new(
            ClothBuilder::new(20, 20)
                .size(0.8, 0.8)
                .horizontal(Vector::new(0.0, 0.5, 0.0))
                .build()
                .unwrap(),
        );
        let mut coupling = RapierCoupling::new();
        for _ in 0..90 {
            let report = coupling.step_world(&mut cloth, &mut world).unwrap();
            assert!(report.colliders <= 1);
            world.step();
        }
        assert!(cloth.is_finite(), "{name}");
        // The centre of the cloth rests on top of the collider (its top is at y = 0.2).
        let middle = cloth.positions()[10 * 20 + 10];
        assert!(
            middle.y > 0.19 && middle.y < 0.25,
            "{name}: middle at {middle:?}"
        );
    }
}

#[test]
fn collision_groups_decide_what_the_cloth_sees_and_removed_colliders_are_fine() {
    let mut world = PhysicsWorld::new();
    let (_, ghost) = world.insert(
        RigidBodyBuilder::fixed(),
        ColliderBuilder::cuboid(1.0, 0.1, 1.0).collision_groups(InteractionGroups::new(
            Group::GROUP_2,
            Group::GROUP_2,
            InteractionTestMode::And,
        )),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(10, 10)
            .horizontal(Vector::new(0.0, 0.3, 0.0))
            .build()
            .unwrap(),
    );
    let mut coupling = RapierCoupling::new();
    coupling.groups =
        InteractionGroups::new(Group::GROUP_1, Group::GROUP_1, InteractionTestMode::And);
    for _ in 0..60 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
    }
    assert!(
        cloth.centroid().y < -0.5,
        "the cloth fell through a collider it must not see"
    );
    // Seen again once the groups match; then removed between steps: no panic, it falls.
    let mut cloth = Simulation::new(
        ClothBuilder::new(10, 10)
            .horizontal(Vector::new(0.0, 0.3, 0.0))
            .build()
            .unwrap(),
    );
    coupling.groups = InteractionGroups::all();
    for _ in 0..30 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
    }
    assert!(cloth.centroid().y > 0.09, "{:?}", cloth.centroid());
    world.remove_collider(ghost);
    for _ in 0..30 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
    }
    assert!(cloth.centroid().y < 0.0);
}

#[test]
fn a_moving_body_drags_the_cloth_by_friction() {
    // A kinematic conveyor: a slab moving along +x at 0.5 m/s.
    let mut world = PhysicsWorld::new();
    let (slab, _) = world.insert(
        RigidBodyBuilder::kinematic_velocity_based().linvel(Vector::new(0.5, 0.0, 0.0)),
        ColliderBuilder::cuboid(3.0, 0.1, 3.0),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(8, 8)
            .size(0.4, 0.4)
            .horizontal(Vector::new(0.0, 0.115, 0.0))
            .build()
            .unwrap(),
    );
    let mut coupling = RapierCoupling::new();
    coupling.friction = 1.0;
    for _ in 0..60 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
    }
    let moved = world.bodies[slab].translation().x;
    assert!((moved - 0.5).abs() < 0.02);
    assert!(
        (cloth.centroid().x - moved).abs() < 0.05,
        "the cloth stayed behind: {:?}",
        cloth.centroid()
    );
}

#[test]
fn a_tablecloth_on_a_rising_kinematic_table_rises_with_it_and_never_sinks_in() {
    // A lift: a kinematic slab (its top at y = 0.05) rising at 0.6 m/s
    // with a tablecloth lying on it; the small-steps solver holds it in
    // its lanes where it is at each substep's end. The cloth is stepped
    // before the world, as a game loop may: at the first frame rapier's
    // broad phase is still empty.
    let mut world = PhysicsWorld::new();
    let (slab, _) = world.insert(
        RigidBodyBuilder::kinematic_velocity_based().linvel(Vector::new(0.0, 0.6, 0.0)),
        ColliderBuilder::cuboid(1.0, 0.05, 1.0),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(24, 24)
            .size(0.8, 0.8)
            .horizontal(Vector::new(0.0, 0.062, 0.0))
            .build()
            .unwrap(),
    );
    let thickness = cloth.params.thickness;
    let mut coupling = RapierCoupling::new();
    let mut deepest = f32::NEG_INFINITY;
    for _ in 0..60 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
        // The cloth after the step against the slab where rapier put it
        // after the same 1/60 s.
        let top = world.bodies[slab].translation().y + 0.05;
        let lowest = cloth
            .positions()
            .iter()
            .map(|p| p.y)
            .fold(f32::MAX, f32::min);
        deepest = deepest.max(top + thickness - lowest);
    }
    let top = world.bodies[slab].translation().y + 0.05;
    assert!((top - 0.65).abs() < 0.01, "the slab rose to {top}");
    assert!(
        deepest <= 0.001,
        "a particle sank {deepest} m into the thickness"
    );
    let c = cloth.centroid();
    assert!(
        (c.y - (top + thickness)).abs() < 0.005 && c.x.abs() < 0.01 && c.z.abs() < 0.01,
        "the cloth at {c:?} did not ride the slab (top {top})"
    );
}

/// A dynamic crate with a cloth lying on it falls onto the floor; the
/// cloth, slowed by the air, trails a few centimetres above it. `push_out`
/// says whether the loop pushes the cloth out of the bodies after rapier's
/// step. Returns the deepest any particle lay inside the crate after any
/// frame (m), the cloth's largest stretch after any frame, and the crate's
/// height and speed at the end.
fn crate_landing(push_out: bool) -> (f32, f32, f32, f32) {
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.05, 0.0)),
        ColliderBuilder::cuboid(2.0, 0.05, 2.0),
    );
    let half = 0.15;
    let (crate_body, crate_collider) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::cuboid(half, half, half).mass(5.0),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(24, 24)
            .size(0.6, 0.6)
            .horizontal(Vector::new(0.0, 1.0 + half + 0.02, 0.0))
            .build()
            .unwrap(),
    );
    let mut coupling = RapierCoupling::new();
    let (mut deepest, mut stretch) = (0.0f32, 0.0f32);
    for _ in 0..60 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
        if push_out {
            coupling.push_out_of_world(&mut cloth, &world);
        }
        let collider = &world.colliders[crate_collider];
        let inside = cloth
            .positions()
            .iter()
            .map(|&p| {
                cloth3d::collision::penetration_depth(collider.shape(), collider.position(), p)
            })
            .fold(0.0, f32::max);
        deepest = deepest.max(inside);
        stretch = stretch.max(cloth.max_strain(SpringKind::Stretch));
    }
    let body = &world.bodies[crate_body];
    (
        deepest,
        stretch,
        body.translation().y,
        body.linvel().length(),
    )
}

#[test]
fn a_cloth_on_a_falling_crate_stays_outside_it_as_the_floor_stops_it() {
    // The floor stops the crate within rapier's step, after the cloth's:
    // the crate, 7 cm higher than its fall would have taken it, rose into
    // the cloth falling behind it (4.4 cm inside after that frame).
    let (deepest, stretch, y, speed) = crate_landing(true);
    assert!(
        deepest < 0.001,
        "the cloth lay {deepest} m inside the crate"
    );
    // The cloth around the pushed top followed it within the limit (97%
    // at the crate's edges when only the top was pushed).
    assert!(stretch < 0.05, "the cloth stretched {stretch}");
    assert!(
        (y - 0.15).abs() < 0.01 && speed < 0.05,
        "the crate at {y} m, {speed} m/s"
    );
    // Without the push the landing frame ends with the cloth inside (the
    // next step pushes it out first): the case above is a real one.
    let (deepest, _, _, _) = crate_landing(false);
    assert!(
        deepest > 0.02,
        "the cloth lay only {deepest} m inside the crate"
    );
}

#[test]
fn momentum_is_exchanged_not_created() {
    // No gravity: a cloth thrown at a free dynamic ball. Whatever they do,
    // the total momentum stays, with every integrator that carries dynamic
    // bodies (the large-step ones refuse them: tests/user_drops.rs).
    for integrator in Integrator::ALL {
        if integrator.carries_dynamic_bodies() {
            momentum_exchange(integrator);
        }
    }
    one_way_coupling_pushes_nothing();
}

fn momentum_exchange(integrator: Integrator) {
    let mut world = PhysicsWorld::new();
    world.gravity = Vector::ZERO;
    let (ball, _) = world.insert(
        RigidBodyBuilder::dynamic().translation(Vector::new(0.0, 0.0, 0.0)),
        ColliderBuilder::ball(0.2).density(100.0),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(12, 12)
            .size(0.6, 0.6)
            .horizontal(Vector::new(0.0, 0.4, 0.0))
            .build()
            .unwrap(),
    );
    cloth.params.gravity = Vector::ZERO;
    cloth.params.air_drag = 0.0;
    cloth.set_integrator(integrator);
    cloth.solver.settings.substeps = integrator.default_substeps();
    for i in 0..cloth.particle_count() {
        cloth.set_velocity(i, Vector::new(0.0, -2.0, 0.0)).unwrap();
    }
    let total = |cloth: &Cloth, world: &PhysicsWorld| {
        cloth.momentum() + world.bodies[ball].linvel() * world.bodies[ball].mass()
    };
    let p0 = total(&cloth, &world);
    let mut coupling = RapierCoupling::new();
    let mut exchanged = Vector::ZERO;
    for _ in 0..60 {
        exchanged += coupling
            .step_world(&mut cloth, &mut world)
            .unwrap()
            .impulse_to_bodies;
        world.step();
        let p = total(&cloth, &world);
        assert!(
            (p - p0).length() < 1e-3 * p0.length(),
            "{integrator}: momentum {p0:?} became {p:?}"
        );
    }
    // Something really was exchanged: the ball was pushed down.
    assert!(
        exchanged.y < -0.1 * p0.length(),
        "{integrator}: exchanged {exchanged:?}"
    );
    assert!(world.bodies[ball].linvel().y < -0.05, "{integrator}");
}

fn one_way_coupling_pushes_nothing() {
    // One-way coupling: the ball is not pushed.
    let mut world2 = PhysicsWorld::new();
    world2.gravity = Vector::ZERO;
    let (ball2, _) = world2.insert(
        RigidBodyBuilder::dynamic(),
        ColliderBuilder::ball(0.2).density(100.0),
    );
    let mut cloth2 = Simulation::new(
        ClothBuilder::new(12, 12)
            .size(0.6, 0.6)
            .horizontal(Vector::new(0.0, 0.4, 0.0))
            .build()
            .unwrap(),
    );
    cloth2.params.gravity = Vector::ZERO;
    for i in 0..cloth2.particle_count() {
        cloth2.set_velocity(i, Vector::new(0.0, -2.0, 0.0)).unwrap();
    }
    let mut one_way = RapierCoupling::new();
    one_way.two_way = false;
    for _ in 0..60 {
        one_way.step_world(&mut cloth2, &mut world2).unwrap();
        world2.step();
    }
    assert_eq!(world2.bodies[ball2].linvel(), Vector::ZERO);
}

#[test]
fn hammock_holds_the_boxes_and_sags_under_them() {
    let mut scene = Scene::build(SceneKind::Hammock, &SceneOptions::default()).unwrap();
    let frames = scene.frames;
    let m = run(&mut scene, frames).unwrap();
    assert!(m.finite);
    assert!(m.max_penetration_any_frame <= 0.002, "{m:?}");
    // The cotton stays within its limit as the boxes land: the contacts
    // with the boxes, resolved after the substep's limit, left it 5.14%
    // stretched at their impacts before the cloth followed them
    // (solver/contact_follow.rs).
    assert!(m.max_stretch_any_frame < 0.05, "{m:?}");
    // After 4 s the boxes have come to rest: none moved faster than 5 cm/s
    // during the last frame.
    assert!(m.bodies_max_speed.unwrap() < 0.05, "{m:?}");
    // The boxes lie on the cloth: above the ground, below the pinned height.
    let lowest_box = m.bodies_min_y.unwrap();
    assert!(lowest_box > 0.25 && lowest_box < 0.5, "{m:?}");
    // The cloth sags under them.
    assert!(m.min_y < 0.4 && m.centroid[1] < 0.45, "{m:?}");
    let side = scene.rapier.as_ref().unwrap();
    for h in &side.bodies {
        let b = &side.world.bodies[*h];
        assert!(
            b.translation().x.abs() < 0.4 && b.translation().z.abs() < 0.2,
            "a box slid off: {:?}",
            b.translation()
        );
    }
}

#[test]
fn hammock_at_twenty_hertz_holds_its_limit_where_rapier_shoves_a_box_into_it() {
    // At 20 Hz rapier's step shoves a box (its contact with the next one)
    // 2-3 cm into the hammock's side; pushing the cloth out of it there
    // left the side 17% stretched between the box and the pinned corners.
    // The push is taken back then, and the next step pushes the box.
    let options = SceneOptions {
        dt: Some(0.05),
        ..Default::default()
    };
    let mut scene = Scene::build(SceneKind::Hammock, &options).unwrap();
    let m = run(&mut scene, 160).unwrap();
    assert!(m.finite);
    assert!(m.max_stretch_any_frame < 0.05, "{m:?}");
    assert!(m.max_penetration_any_frame <= 0.002, "{m:?}");
    assert!(m.bodies_min_y.unwrap() > 0.3, "{m:?}");
}

#[test]
fn hammock_without_coupling_lets_the_boxes_fall_through() {
    // The same world with the cloth seeing no collider: the boxes reach the ground.
    // This is what makes the hammock test above able to fail.
    let mut scene = Scene::build(SceneKind::Hammock, &SceneOptions::default()).unwrap();
    let side = scene.rapier.as_mut().unwrap();
    side.coupling.groups = InteractionGroups::none();
    for _ in 0..120 {
        scene.step_frame().unwrap();
    }
    let side = scene.rapier.as_ref().unwrap();
    let lowest = side
        .bodies
        .iter()
        .map(|h| side.world.bodies[*h].translation().y)
        .fold(f32::MAX, f32::min);
    assert!(
        lowest < 0.15,
        "the boxes should lie on the ground, lowest at {lowest}"
    );
}

#[test]
fn curtain_is_never_inside_the_ball_even_at_ten_metres_per_second() {
    let m = {
        let mut scene = Scene::build(SceneKind::Curtain, &SceneOptions::default()).unwrap();
        run(&mut scene, 120).unwrap()
    };
    assert!(m.max_penetration_any_frame <= 0.002, "{m:?}");
    // The ball pushed the curtain: it swung towards +z.
    // Now at 10 m/s: the ball crosses the curtain in a few frames.
    let mut scene = Scene::build(SceneKind::Curtain, &SceneOptions::default()).unwrap();
    let mut deepest = 0.0f32;
    let mut furthest = f32::MIN;
    for f in 0..60 {
        let t = (f + 1) as f32 / 60.0;
        let side = scene.rapier.as_mut().unwrap();
        let z = (-1.0 + 10.0 * t).min(1.0);
        side.world.bodies[side.bodies[0]].set_next_kinematic_translation(Vector::new(0.0, 0.9, z));
        side.coupling
            .step(
                &mut scene.cloth,
                &mut scene.solver,
                RapierSets::of(&mut side.world),
            )
            .unwrap();
        side.world.step();
        scene.frame += 1;
        deepest = deepest.max(scene.max_penetration());
        furthest = furthest.max(scene.cloth.centroid().z);
    }
    assert!(
        deepest <= 0.002,
        "a particle ended a frame {deepest} m inside the ball"
    );
    assert!(
        furthest > 0.1,
        "the ball should have carried the curtain along (+z {furthest})"
    );
}

#[test]
fn attached_particles_follow_their_body_and_pull_it() {
    // A kinematic body spinning and moving: the attached corner follows within 1 mm.
    let mut world = PhysicsWorld::new();
    let (paddle, _) = world.insert(
        RigidBodyBuilder::kinematic_velocity_based()
            .translation(Vector::new(-0.5, 1.0, -0.5))
            .linvel(Vector::new(0.3, 0.0, 0.0))
            .angvel(Vector::new(0.0, 1.5, 0.0)),
        ColliderBuilder::ball(0.05).sensor(true),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(10, 10)
            .horizontal(Vector::new(0.0, 1.0, 0.0))
            .build()
            .unwrap(),
    );
    let mut coupling = RapierCoupling::new();
    coupling.attach(0, paddle, Vector::ZERO).unwrap();
    coupling
        .attach(9, paddle, Vector::new(1.0, 0.0, 0.0))
        .unwrap();
    for _ in 0..90 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
        let body = &world.bodies[paddle];
        let target0 = body.position().transform_point(Vector::ZERO);
        let target9 = body.position().transform_point(Vector::new(1.0, 0.0, 0.0));
        assert!((cloth.positions()[0] - target0).length() < 1e-3);
        assert!((cloth.positions()[9] - target9).length() < 1e-3);
    }
    // A cape on a free dynamic body in zero gravity... with the cloth's weight:
    // the body is pulled down although gravity does not act on it.
    let mut world = PhysicsWorld::new();
    let (pole, _) = world.insert(
        RigidBodyBuilder::dynamic()
            .gravity_scale(0.0)
            .translation(Vector::new(0.0, 1.0, 0.0)),
        ColliderBuilder::ball(0.05).density(1000.0).sensor(true),
    );
    let mut cloth = Simulation::new(
        ClothBuilder::new(8, 8)
            .size(0.5, 0.5)
            .vertical(Vector::new(0.0, 0.75, 0.0))
            .build()
            .unwrap(),
    );
    let mut coupling = RapierCoupling::new();
    let top = 4;
    coupling
        .attach_here(&cloth, top, pole, &world.bodies)
        .unwrap();
    for _ in 0..30 {
        coupling.step_world(&mut cloth, &mut world).unwrap();
        world.step();
    }
    assert!(
        world.bodies[pole].linvel().y < -0.01,
        "the cloth's pull should drag the body down: {:?}",
        world.bodies[pole].linvel()
    );
    // A removed body is an error, never a panic.
    world.remove_body(pole);
    let err = coupling.step_world(&mut cloth, &mut world).unwrap_err();
    assert!(matches!(err, ClothError::StaleHandle { .. }), "{err}");
}
