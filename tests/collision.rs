//! Collision against the analytic surface projection of balls and boxes, and
//! scene-level checks: staying on the sphere, not cutting the cube's edges,
//! capsules, triangle meshes, moving obstacles and many obstacles.

use cloth3d::collision::{contact, penetration_depth};
use cloth3d::metrics::max_penetration;
use cloth3d::prelude::*;
use cloth3d::scenes::run;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use glam::{DQuat, DVec3};
use parry3d::query::PointQuery;
use parry3d::shape::{Ball, Cuboid, SharedShape};

/// A small deterministic generator (xorshift), so failures reproduce.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn vector(&mut self, r: f32) -> Vector {
        Vector::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
    fn pose(&mut self) -> Pose {
        let axis = self.vector(1.0).normalize_or(Vector::X);
        Pose::from_parts(
            self.vector(3.0),
            Rotation::from_axis_angle(axis, self.range(0.0, std::f32::consts::TAU)),
        )
    }
}

/// `p` in the frame of `pose`, in double precision.
fn to_local(pose: &Pose, p: Vector) -> DVec3 {
    let q: DQuat = pose.rotation.as_dquat().normalize();
    q.inverse() * (p.as_dvec3() - pose.translation.as_dvec3())
}

/// A local point or direction back to world coordinates.
fn to_world(pose: &Pose, p: DVec3, is_point: bool) -> Vector {
    let q: DQuat = pose.rotation.as_dquat().normalize();
    let t = if is_point {
        pose.translation.as_dvec3()
    } else {
        DVec3::ZERO
    };
    (q * p + t).as_vec3()
}

fn assert_close(a: Vector, b: Vector, tol: f32, what: &str) {
    assert!(
        (a - b).length() <= tol,
        "{what}: {a:?} vs {b:?} ({} apart)",
        (a - b).length()
    );
}

#[test]
fn ball_contact_matches_the_analytic_projection() {
    let mut rng = Rng(0x9e3779b97f4a7c15);
    for checked in 0..4000 {
        let r = rng.range(0.05, 1.0);
        let pose = rng.pose();
        let c = pose.translation;
        // Inside, outside, and within a hair of the surface.
        let dir = rng.vector(1.0).normalize_or(Vector::Y);
        let dist = match checked % 3 {
            0 => rng.range(0.01, 0.99) * r,
            1 => rng.range(1.01, 3.0) * r,
            _ => r + rng.range(-1e-3, 1e-3),
        };
        let p = c + dir * dist;
        let got = contact(&Ball::new(r), &pose, p).unwrap();
        // c + r (p - c)/|p - c|, in double precision from the same inputs.
        let d = p.as_dvec3() - c.as_dvec3();
        let expected_point = (c.as_dvec3() + d * (r as f64 / d.length())).as_vec3();
        let expected_normal = d.normalize().as_vec3();
        assert_close(got.point, expected_point, 1e-5, "ball point");
        assert_close(got.normal, expected_normal, 1e-5, "ball normal");
        assert!((got.signed_distance as f64 - (d.length() - r as f64)).abs() < 1e-5);
        // The same surface point as parry's own projection.
        let parry = Ball::new(r).project_point(&pose, p, false);
        assert_close(got.point, parry.point, 1e-5, "parry's ball projection");
    }
    // The degenerate centre: a finite answer that pushes out along +y.
    let pose = Pose::from_translation(Vector::new(1.0, 2.0, 3.0));
    let got = contact(&Ball::new(0.3), &pose, pose.translation).unwrap();
    assert_close(got.normal, Vector::Y, 1e-5, "centre normal");
    assert_close(
        got.point,
        pose.translation + Vector::Y * 0.3,
        1e-4,
        "centre point",
    );
    assert!((got.signed_distance + 0.3).abs() < 1e-4);
    assert!((penetration_depth(&Ball::new(0.3), &pose, pose.translation) - 0.3).abs() < 1e-4);
}

/// The analytic answer for a box of half-extents `h` in its own frame: the
/// clamp of the point when outside, the nearest face when inside.
fn box_projection(h: DVec3, p: DVec3) -> (DVec3, DVec3, f64) {
    let clamped = p.clamp(-h, h);
    if clamped != p {
        let d = p - clamped;
        return (clamped, d.normalize(), d.length());
    }
    let gaps = [h.x - p.x.abs(), h.y - p.y.abs(), h.z - p.z.abs()];
    let axis = (0..3).min_by(|&a, &b| gaps[a].total_cmp(&gaps[b])).unwrap();
    let mut normal = DVec3::ZERO;
    normal[axis] = p[axis].signum();
    let mut point = p;
    point[axis] = h[axis] * p[axis].signum();
    (point, normal, -gaps[axis])
}

#[test]
fn box_contact_matches_the_analytic_projection() {
    let mut rng = Rng(0x2545f4914f6cdd1d);
    for k in 0..6000 {
        let h = Vector::new(
            rng.range(0.05, 1.0),
            rng.range(0.05, 1.0),
            rng.range(0.05, 1.0),
        );
        let pose = rng.pose();
        // Points everywhere: deep inside, outside, near faces, edges and corners.
        let local = match k % 4 {
            0 => rng.vector(1.0) * h * 0.98,
            1 => rng.vector(1.0) * h * 2.5,
            // Near an edge: two coordinates near their bound.
            2 => Vector::new(
                h.x * rng.range(0.97, 1.03),
                h.y * rng.range(0.97, 1.03),
                rng.range(-h.z, h.z),
            ),
            // Near a corner.
            _ => {
                h * Vector::new(
                    rng.range(0.97, 1.03),
                    rng.range(0.97, 1.03),
                    rng.range(0.97, 1.03),
                )
            }
        };
        let p = pose.transform_point(local);
        let (lp, ln, ld) = box_projection(h.as_dvec3(), to_local(&pose, p));
        let got = contact(&Cuboid::new(h), &pose, p).unwrap();
        assert_close(got.point, to_world(&pose, lp, true), 1e-5, "box point");
        assert_close(got.normal, to_world(&pose, ln, false), 1e-5, "box normal");
        assert!(
            (got.signed_distance as f64 - ld).abs() < 1e-5,
            "{} vs {ld}",
            got.signed_distance
        );
        // The same surface point as parry's own projection.
        let parry = Cuboid::new(h).project_point(&pose, p, false);
        assert_close(got.point, parry.point, 1e-5, "parry's box projection");
    }
    // Exactly on a face: the face normal, never NaN.
    let h = Vector::new(0.5, 0.25, 0.75);
    let got = contact(
        &Cuboid::new(h),
        &Pose::IDENTITY,
        Vector::new(0.1, 0.25, -0.2),
    )
    .unwrap();
    assert_close(got.normal, Vector::Y, 1e-5, "on-face normal");
    // Exactly on an edge and a corner: a finite outward normal.
    for p in [Vector::new(0.5, 0.25, 0.1), Vector::new(0.5, 0.25, 0.75)] {
        let got = contact(&Cuboid::new(h), &Pose::IDENTITY, p).unwrap();
        assert!(got.normal.is_finite() && (got.normal.length() - 1.0).abs() < 1e-5);
        assert!(
            got.normal.dot(p) > 0.0,
            "edge/corner normal {:?} points inwards",
            got.normal
        );
    }
    // The centre of a cube has six nearest faces: any one of them will do.
    let got = contact(
        &Cuboid::new(Vector::splat(0.25)),
        &Pose::IDENTITY,
        Vector::ZERO,
    )
    .unwrap();
    assert!(got.normal.is_finite() && (got.signed_distance + 0.25).abs() < 1e-6);
}

/// One particle cloth-from-parts, for resolution tests.
fn particle_at(p: Vector, v: Vector) -> Simulation {
    let mut cloth = Simulation::new(
        Cloth::from_parts(vec![p], vec![0.01], vec![], vec![], Material::cotton()).unwrap(),
    );
    cloth.set_velocity(0, v).unwrap();
    cloth.params.gravity = Vector::ZERO;
    cloth.params.air_drag = 0.0;
    cloth.solver.settings.substeps = Substeps::Fixed(1);
    cloth
}

#[test]
fn a_particle_inside_is_put_on_the_surface_plus_the_thickness() {
    let pose = Pose::from_parts(Vector::new(0.2, -0.1, 0.3), Rotation::from_rotation_z(0.4));
    for (shape, p) in [
        (SharedShape::ball(0.5), Vector::new(0.3, 0.0, 0.4)),
        (
            SharedShape::cuboid(0.5, 0.3, 0.4),
            Vector::new(0.25, -0.05, 0.35),
        ),
        (SharedShape::ball(0.5), pose.translation),
    ] {
        let obstacle = Obstacle::new(shape.clone(), pose).with_friction(0.0);
        let mut cloth = particle_at(p, Vector::ZERO);
        let thickness = cloth.params.thickness;
        let before = contact(&*shape, &pose, p).unwrap();
        cloth.step(1e-4, std::slice::from_ref(&obstacle)).unwrap();
        let after = cloth.positions()[0];
        assert_close(
            after,
            before.point + before.normal * thickness,
            1e-4,
            "resolved position",
        );
        let c = contact(&*shape, &pose, after).unwrap();
        assert!((c.signed_distance - thickness).abs() < 1e-4);
    }
}

#[test]
fn velocity_into_the_surface_is_removed_and_friction_is_coulomb() {
    let floor = Obstacle::cuboid(
        Vector::new(10.0, 0.5, 10.0),
        Pose::from_translation(Vector::new(0.0, -0.5, 0.0)),
    );
    let h = 1.0e-3;
    // Static: tangential speed below μ × the normal speed removed: it sticks.
    let mut cloth = particle_at(Vector::new(0.0, 0.0105, 0.0), Vector::new(0.3, -2.0, 0.0));
    cloth.step(h, &[floor.clone().with_friction(0.5)]).unwrap();
    assert_close(cloth.velocities()[0], Vector::ZERO, 1e-5, "static friction");
    // Kinetic: it keeps sliding, slowed by μ × the normal speed removed.
    let mut cloth = particle_at(Vector::new(0.0, 0.0105, 0.0), Vector::new(3.0, -2.0, 0.0));
    cloth.step(h, &[floor.clone().with_friction(0.5)]).unwrap();
    assert_close(
        cloth.velocities()[0],
        Vector::new(2.0, 0.0, 0.0),
        1e-4,
        "kinetic friction",
    );
    // Frictionless: the tangential part is kept whole.
    let mut cloth = particle_at(Vector::new(0.0, 0.0105, 0.0), Vector::new(3.0, -2.0, 0.0));
    cloth.step(h, &[floor.with_friction(0.0)]).unwrap();
    assert_close(
        cloth.velocities()[0],
        Vector::new(3.0, 0.0, 0.0),
        1e-4,
        "no friction",
    );
}

#[test]
fn a_moving_obstacle_drags_the_cloth_by_friction() {
    let belt = Obstacle::cuboid(
        Vector::new(5.0, 0.5, 5.0),
        Pose::from_translation(Vector::new(0.0, -0.5, 0.0)),
    )
    .with_velocity(Vector::new(0.5, 0.0, 0.0), Vector::ZERO)
    .with_friction(1.0);
    let mut cloth = Simulation::new(
        ClothBuilder::new(8, 8)
            .size(0.4, 0.4)
            .horizontal(Vector::new(0.0, 0.012, 0.0))
            .build()
            .unwrap(),
    );
    for _ in 0..60 {
        // The belt surface moves, its pose stays: a conveyor.
        cloth.step(1.0 / 60.0, std::slice::from_ref(&belt)).unwrap();
    }
    let c = cloth.centroid();
    assert!(
        (c.x - 0.5).abs() < 0.05,
        "the cloth should ride the belt ~0.5 m: {c:?}"
    );
}

#[test]
fn drape_stays_centred_on_the_sphere_for_five_seconds() {
    let mut scene = Scene::build(
        SceneKind::Drape,
        &SceneOptions {
            friction: Some(0.5),
            ..Default::default()
        },
    )
    .unwrap();
    let m = run(&mut scene, 300).unwrap();
    let horizontal = (m.centroid[0].powi(2) + m.centroid[2].powi(2)).sqrt();
    assert!(
        horizontal < 0.01,
        "centroid drifted {horizontal} m off the axis: {m:?}"
    );
    // Still resting on top: the highest particle is just above the sphere.
    let top = scene
        .cloth
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::MIN, f32::max);
    assert!((0.3..0.33).contains(&top), "top of the cloth at {top}");
    assert!(
        m.max_penetration <= 0.001 && m.max_penetration_any_frame <= 0.001,
        "{m:?}"
    );
}

/// Deepest point at 1/4, 1/2 and 3/4 along any stretch spring inside the obstacles.
fn deepest_spring_sample(scene: &Scene) -> f32 {
    let cloth = &scene.cloth;
    let x = cloth.positions();
    let mut deepest = 0.0f32;
    for s in cloth.springs().range(SpringKind::Stretch) {
        let sp = cloth.springs().get(s).unwrap();
        for t in [0.25, 0.5, 0.75] {
            let p = x[sp.a as usize] * (1.0 - t) + x[sp.b as usize] * t;
            for o in &scene.obstacles {
                deepest = deepest.max(penetration_depth(&*o.shape, &o.pose, p));
            }
        }
    }
    deepest
}

#[test]
fn box_springs_do_not_cut_through_the_cube_edges() {
    for n in [64, 12] {
        let mut scene = Scene::build(
            SceneKind::Box,
            &SceneOptions {
                n: Some(n),
                ..Default::default()
            },
        )
        .unwrap();
        let mut worst = 0.0f32;
        for _ in 0..180 {
            scene.step_frame().unwrap();
            worst = worst.max(deepest_spring_sample(&scene));
        }
        assert!(
            worst <= 0.01,
            "N = {n}: a spring point went {worst} m inside the cube"
        );
        assert!(scene.max_penetration() <= 0.001, "N = {n}");
    }
    // Without the spring samples a coarse cloth does cut the corners: the test can fail.
    let mut scene = Scene::build(
        SceneKind::Box,
        &SceneOptions {
            n: Some(12),
            ..Default::default()
        },
    )
    .unwrap();
    scene.solver.settings.edge_collisions = false;
    let mut worst = 0.0f32;
    for _ in 0..180 {
        scene.step_frame().unwrap();
        worst = worst.max(deepest_spring_sample(&scene));
    }
    assert!(
        worst > 0.0,
        "particles alone should let springs dip inside the cube"
    );
}

#[test]
fn capsules_and_triangle_meshes_work_through_the_same_path() {
    // A capsule lying along x, and a tent-shaped triangle mesh (a ridge along x).
    let capsule = Obstacle::new(SharedShape::capsule_x(0.4, 0.15), Pose::IDENTITY);
    let ridge = {
        let v = vec![
            Vector::new(-0.6, -0.3, -0.6),
            Vector::new(0.6, -0.3, -0.6),
            Vector::new(-0.6, 0.15, 0.0),
            Vector::new(0.6, 0.15, 0.0),
            Vector::new(-0.6, -0.3, 0.6),
            Vector::new(0.6, -0.3, 0.6),
        ];
        let idx = vec![[0, 2, 1], [1, 2, 3], [2, 4, 3], [3, 4, 5]];
        Obstacle::new(SharedShape::trimesh(v, idx).unwrap(), Pose::IDENTITY)
    };
    for obstacle in [capsule, ridge] {
        let mut cloth = Simulation::new(
            ClothBuilder::new(24, 24)
                .size(0.8, 0.8)
                .horizontal(Vector::new(0.0, 0.4, 0.0))
                .build()
                .unwrap(),
        );
        let mut lowest_middle = f32::MAX;
        for _ in 0..90 {
            cloth
                .step(1.0 / 60.0, std::slice::from_ref(&obstacle))
                .unwrap();
            lowest_middle = lowest_middle.min(cloth.positions()[12 * 24 + 12].y);
        }
        assert!(cloth.is_finite());
        // The middle of the cloth caught on the top of the obstacle at y = 0.15.
        assert!(
            lowest_middle > 0.14,
            "{:?}: the middle fell to {lowest_middle}",
            obstacle.shape.shape_type()
        );
        // Nothing went through a solid capsule; the mesh is a surface: nothing crossed it.
        if obstacle.shape.as_capsule().is_some() {
            assert!(max_penetration(&cloth, std::slice::from_ref(&obstacle)) <= 0.001);
        }
        let below = cloth.positions().iter().filter(|p| p.y < -0.3).count();
        assert_eq!(
            below,
            0,
            "{:?}: particles fell through",
            obstacle.shape.shape_type()
        );
    }
}

#[test]
fn many_small_balls_hold_the_cloth_through_the_bounding_volume_tree() {
    let mut balls = Vec::new();
    for i in 0..10 {
        for j in 0..10 {
            let (x, z) = (-0.45 + 0.1 * i as f32, -0.45 + 0.1 * j as f32);
            balls.push(Obstacle::ball(Vector::new(x, 0.0, z), 0.03));
        }
    }
    let mut cloth = Simulation::new(
        ClothBuilder::new(64, 64)
            .horizontal(Vector::new(0.0, 0.1, 0.0))
            .build()
            .unwrap(),
    );
    for _ in 0..60 {
        cloth.step(1.0 / 60.0, &balls).unwrap();
    }
    assert!(cloth.is_finite());
    assert!(max_penetration(&cloth, &balls) <= 0.001);
    // Held up by the bed of balls (tops at 0.03) rather than falling through.
    let c = cloth.centroid();
    assert!(c.y > -0.1 && c.y < 0.05, "centroid {c:?}");
}

/// Found by the property test: a spring from a pin to a free particle lying
/// in a thin box made the edge pass lever the free particle 5 cm inside.
#[test]
fn the_edge_pass_never_leaves_a_particle_inside() {
    let mut m = Material::silk();
    m.stretch.stiffness *= 3.5064273;
    let mut cloth = Simulation::new(
        ClothBuilder::new(3, 2)
            .size(0.8, 0.6)
            .material(m)
            .pins(PinPreset::FlagColumn)
            .build()
            .unwrap(),
    )
    .with_integrator(Integrator::Verlet);
    let pose = Pose::from_parts(
        Vector::new(0.0, 0.0, 0.23261665),
        Rotation::from_xyzw(0.0, 0.9224687, 0.33418396, 0.19331966),
    );
    let obstacle = Obstacle::new(
        SharedShape::cuboid(0.18145694, 0.058075402, 0.2778111),
        pose,
    );
    for _ in 0..20 {
        cloth
            .step(0.0039010306, std::slice::from_ref(&obstacle))
            .unwrap();
        for (i, &p) in cloth.positions().iter().enumerate() {
            if !cloth.is_pinned(i) {
                let depth = penetration_depth(&*obstacle.shape, &pose, p);
                assert!(depth <= 1e-3, "particle {i} is {depth} m inside");
            }
        }
    }
}

/// A coarse cloth whose cell is wider than a small ball falls onto it
/// between its particles: its springs catch the ball (the edge pass), where
/// its particles alone let it through. The drape's ball skips the edge pass
/// (its springs are too short to dip into it); this ball must not.
#[test]
fn a_coarse_cloth_catches_a_small_ball_between_its_particles() {
    let fall = |edges: bool| {
        // Particles 0.3 m apart; the middle cell's diagonals cross over the ball.
        let mut cloth = Simulation::new(
            ClothBuilder::new(4, 4)
                .size(0.9, 0.9)
                .horizontal(Vector::new(0.0, 0.2, 0.0))
                .build()
                .unwrap(),
        );
        cloth.solver.settings.edge_collisions = edges;
        let ball = [Obstacle::ball(Vector::ZERO, 0.08)];
        for _ in 0..60 {
            cloth.step(1.0 / 60.0, &ball).unwrap();
        }
        cloth.centroid().y
    };
    let caught = fall(true);
    assert!(
        caught > -0.5,
        "the cloth fell past the ball: centroid at {caught} m"
    );
    let through = fall(false);
    assert!(
        through < -2.0,
        "particles alone should let the ball through: centroid at {through} m"
    );
}
