//! The lanes' contacts against parry's and the stage's, and their bits
//! either way.

use super::chunk::{Chunk, Law};
use super::contacts::*;
use super::shape::StillShape;
use super::still_cuboid::*;
use crate::collision::contact::{contact, contact_prepared, Analytic, PoseF64};
use crate::collision::DynamicBody;
use crate::collision::{Obstacle, EDGE_SAMPLES};
use crate::math::Pose;
use crate::math::Vector;
use crate::parallel::Team;
use crate::solver::grid_sweep::{GridPlan, Lanes};
use crate::solver::lane_convex::{convex_plane, cylinder_plane, hull_plane};
use parry3d::shape::{SharedShape, TriMeshFlags};

const THICKNESS: f32 = 0.01;

/// A ball of radius 0.5 at (0, 1, 0) over a floor at y = 0.
fn ball_and_floor() -> [Obstacle; 2] {
    let ball = Obstacle::ball(Vector::new(0.0, 1.0, 0.0), 0.5).with_friction(0.4);
    let floor = Obstacle::new(SharedShape::halfspace(Vector::Y), Pose::IDENTITY);
    [ball, floor.with_friction(0.8)]
}

/// `n` lanes scattered around the ball and through the floor (some at
/// the ball's centre, every fifth pinned): positions, then start
/// positions a little above.
fn lanes(n: usize) -> Lanes {
    let mut lanes = Lanes::default();
    lanes.resize(n);
    let [x, y, z, sx, sy, sz, w] = lanes.arrays_mut();
    for k in 0..n {
        let s = k as f32;
        let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin()).normalize();
        let p = Vector::new(0.0, 1.0, 0.0) + dir * (0.2 + 0.5 * ((0.37 * s) % 1.0));
        let p = if k % 9 == 4 {
            Vector::new(0.0, 1.0, 0.0)
        } else {
            p
        };
        let p = if k % 7 == 2 {
            Vector::new(0.1 * s % 1.0, -0.02, 0.3)
        } else {
            p
        };
        (x[k], y[k], z[k]) = (p.x, p.y, p.z);
        (sx[k], sy[k], sz[k]) = (p.x + 0.003, p.y + 0.004, p.z - 0.002);
        w[k] = if k % 5 == 0 { 0.0 } else { 2.0 };
    }
    lanes
}

/// A pass of `contacts` over `lanes` lane by lane, without AVX2, with
/// friction when `friction`; returns the farthest push (m).
fn portable_pass(contacts: &mut LaneContacts, lanes: &mut Lanes, friction: bool) -> f32 {
    let [x, y, z, sx, sy, sz, w] = lanes.arrays_mut();
    let law = Law {
        shapes: &contacts.shapes,
        friction: friction.then_some(&contacts.friction[..]),
        shifts: (friction && contacts.moving()).then_some(&contacts.shifts[..]),
        planes: contacts.planes.each_ref().map(|r| &r[..]),
        lanes: contacts.lanes,
    };
    let chunk = Chunk {
        first: 0,
        x,
        y,
        z,
        start: [&*sx, &*sy, &*sz],
        w: &*w,
        depth: &mut contacts.depth,
        touch: &mut contacts.touch,
    };
    run(chunk, &law, false)
}

fn bits(lanes: &mut Lanes) -> Vec<u32> {
    lanes
        .arrays_mut()
        .iter()
        .flat_map(|a| a.iter().map(|v| v.to_bits()))
        .collect()
}

/// Lane `k`'s position in `bits` ([`bits`]) of `n` lanes.
fn position_in(bits: &[u32], n: usize, k: usize) -> Vector {
    Vector::new(
        f32::from_bits(bits[k]),
        f32::from_bits(bits[n + k]),
        f32::from_bits(bits[2 * n + k]),
    )
}

/// `n` lanes, lane `k` at `at(k)`: its position and start (m) and
/// inverse mass (1/kg).
fn placed(n: usize, at: impl Fn(usize) -> (Vector, Vector, f32)) -> Lanes {
    let mut l = Lanes::default();
    l.resize(n);
    let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
    for k in 0..n {
        let (p, start, inverse_mass) = at(k);
        (x[k], y[k], z[k]) = (p.x, p.y, p.z);
        (sx[k], sy[k], sz[k]) = (start.x, start.y, start.z);
        w[k] = inverse_mass;
    }
    l
}

/// Every free lane ends out of the ball and above the floor by the
/// thickness, through the nearest point (at the centre: the top);
/// pinned lanes and lanes already out keep their bits; the records say
/// how far each was pushed and by which; the portable and the AVX2
/// passes agree to the bit.
#[test]
fn projection_puts_every_free_lane_out_and_records_the_push() {
    // Four chunks and a short vector step at the end.
    let n = 3 * CHUNK + 13;
    let obstacles = ball_and_floor();
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(&obstacles, (THICKNESS, 0.001), n));
    let mut l = lanes(n);
    let before = bits(&mut l);
    let pushed = contacts.project(&mut l, Team::ALONE);
    let [x, y, z, _, _, _, w] = l.arrays_mut();
    let centre = Vector::new(0.0, 1.0, 0.0);
    let (mut moved, mut deepest) = (0, 0.0f32);
    for k in 0..n {
        let p = Vector::new(x[k], y[k], z[k]);
        let old = position_in(&before, n, k);
        if w[k] == 0.0 {
            assert_eq!(p, old, "pinned lane {k} moved");
            assert_eq!(contacts.touch[k], 0);
            continue;
        }
        let d = (p - centre).length();
        assert!(
            d >= 0.51 - 1e-5 && p.y >= THICKNESS - 1e-6,
            "lane {k} at {p:?}"
        );
        let push = (p - old).length();
        if push > 0.0 {
            moved += 1;
            assert!(contacts.touch[k] != 0, "lane {k} pushed, not marked");
            deepest = deepest.max(push);
            // Out through the nearest point: along the radius, or up
            // (a push of a few ulps, from the rounding of a lane just
            // at the surface, has no direction to speak of).
            let dir = (p - old) / push;
            let radial = (old - centre).normalize_or(Vector::Y);
            assert!(
                push < 1e-5 || dir.dot(radial) > 0.999 || dir.dot(Vector::Y) > 0.999,
                "lane {k} pushed along {dir:?} from {old:?} to {p:?}"
            );
        } else {
            assert_eq!(contacts.touch[k], 0, "lane {k} marked, not pushed");
            assert_eq!(contacts.depth[k], 0.0);
        }
    }
    assert!(moved > n / 4 && moved < n, "{moved} of {n} pushed");
    assert_eq!(contacts.touching() as usize, moved, "the lanes in contact");
    assert!(
        (pushed - deepest).abs() < 1e-5,
        "{pushed} against {deepest}"
    );
    // The same passes lane by lane, without AVX2: the projection, then
    // the projection with friction.
    let mut portable = LaneContacts::default();
    portable.begin(&obstacles, (THICKNESS, 0.001), n);
    let mut m = lanes(n);
    let again = portable_pass(&mut portable, &mut m, false);
    assert_eq!(again.to_bits(), pushed.to_bits());
    assert_eq!(bits(&mut m), bits(&mut l));
    assert_eq!(portable.depth, contacts.depth);
    assert_eq!(portable.touch, contacts.touch);
    // With friction: the same, and it moves only lanes a pass touched.
    let untouched: Vec<usize> = (0..n).filter(|&k| contacts.touch[k] == 0).collect();
    let before = bits(&mut l);
    contacts.project_with_friction(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, true);
    let after = bits(&mut l);
    assert_eq!(bits(&mut m), after);
    assert!(after != before, "friction moved nothing");
    for k in untouched {
        for a in 0..3 {
            assert_eq!(
                after[a * n + k],
                before[a * n + k],
                "untouched lane {k} moved"
            );
        }
    }
}

/// Eight lanes the ball pushed, then carried far from it, still take
/// the ball's normal and friction in the next pass; eight far from it
/// and never pushed by it pass it over: the vector and the portable
/// passes agree to the bit either way.
#[test]
fn lanes_far_from_the_ball_pass_it_over_to_the_same_bits() {
    let n = 4 * 8 + 3;
    let obstacles = ball_and_floor();
    let (mut vector, mut portable) = (LaneContacts::default(), LaneContacts::default());
    vector.begin(&obstacles, (THICKNESS, 0.001), n);
    portable.begin(&obstacles, (THICKNESS, 0.001), n);
    let place = || {
        placed(n, |k| {
            let s = k as f32 * 0.01;
            // Into the ball's top; through the floor far from it; above
            // the floor far from it; the rest by the ball.
            let p = match k / 8 {
                0 => Vector::new(s, 1.49, 0.0),
                1 => Vector::new(4.0 + s, 0.003, 0.5),
                2 => Vector::new(-4.0 - s, 0.3, 0.5),
                _ => Vector::new(0.0, 1.0 + s, 0.48),
            };
            (p, p + Vector::new(-0.002, 0.004, 0.0), 1.0)
        })
    };
    let (mut l, mut m) = (place(), place());
    vector.project(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, false);
    assert_eq!(bits(&mut l), bits(&mut m));
    assert!(
        vector.touch[..8].iter().all(|&t| t == 1),
        "{:?}",
        vector.touch
    );
    assert!(
        vector.touch[8..16].iter().all(|&t| t == 2),
        "{:?}",
        vector.touch
    );
    // The first eight carried 3 m away along x, starts and all.
    for lanes in [&mut l, &mut m] {
        let [x, _, _, sx, ..] = lanes.arrays_mut();
        for k in 0..8 {
            x[k] += 3.0;
            sx[k] += 3.0;
        }
    }
    let before = bits(&mut l);
    vector.project_with_friction(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, true);
    let after = bits(&mut l);
    assert_eq!(after, bits(&mut m));
    assert_eq!(
        (&vector.depth, &vector.touch),
        (&portable.depth, &portable.touch)
    );
    assert!(
        (0..8).any(|k| after[k] != before[k]),
        "friction by the ball's normal moved none of the carried lanes"
    );
    assert!(
        (16..24).all(|k| (0..3).all(|a| after[a * n + k] == before[a * n + k])),
        "lanes clear of both and never pushed moved"
    );
}

/// A lane pushed 1 mm out of the floor that slid 10 mm along it keeps
/// 10 − μ mm of the slide (μ = 0.8 for the floor); with room to stop
/// (a slide under μ times the push) it stops where it started along
/// the floor.
#[test]
fn friction_undoes_the_slide_up_to_the_coefficient_times_the_push() {
    let obstacles = ball_and_floor();
    let mut contacts = LaneContacts::default();
    let mut l = Lanes::default();
    l.resize(2);
    contacts.begin(&obstacles, (THICKNESS, 0.001), 2);
    {
        let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
        // Started at the thickness, now 1 mm inside it: slid 10 mm, 0.5 mm.
        for (k, slide) in [0.010f32, 0.0005].into_iter().enumerate() {
            (sx[k], sy[k], sz[k]) = (3.0, THICKNESS, 0.0);
            (x[k], y[k], z[k]) = (3.0 + slide, THICKNESS - 0.001, 0.0);
            w[k] = 1.0;
        }
    }
    contacts.project_with_friction(&mut l, Team::ALONE);
    assert_eq!(contacts.touch, [2, 2]);
    let [x, y, ..] = l.arrays_mut();
    assert!(
        (x[0] - (3.0 + 0.010 - 0.8 * 0.001)).abs() < 1e-6,
        "{}",
        x[0]
    );
    assert!((x[1] - 3.0).abs() < 1e-6, "{}", x[1]);
    assert!(y.iter().all(|&y| (y - THICKNESS).abs() < 1e-6));
}

/// A cuboid sliding along x without turning (a kinematic platform)
/// is held where it is at the substep's end: a lane that rested on its
/// top and sank a little is put back on it and, with friction enough,
/// carried along by the cuboid's move (its slide taken relative to the
/// surface), without friction left where it was; a lane that rested
/// against the face the cuboid moves into is pushed out with that
/// face. The portable and the AVX2 passes agree to the bit.
#[test]
fn a_sliding_cuboid_holds_its_lanes_on_its_moved_faces_and_carries_them_by_friction() {
    let half = Vector::new(0.5, 0.05, 0.5);
    let speed = 0.5;
    let (end, h) = (1.0e-3, 1.0e-3);
    let shift = speed * h;
    let (sink, n) = (0.0004, 19);
    // Even lanes rest on the top (and sank), odd ones against the +x face.
    let place = || {
        placed(n, |k| {
            let s = k as f32 / n as f32 - 0.5;
            if k % 2 == 0 {
                let start = Vector::new(0.8 * s, half.y + THICKNESS, 0.3 * s);
                (start - Vector::Y * sink, start, 1.0)
            } else {
                let start = Vector::new(half.x + THICKNESS, 0.8 * half.y * s, 0.6 * s);
                (start, start, 1.0)
            }
        })
    };
    for friction in [2.0, 0.0] {
        let table = Obstacle::cuboid(half, Pose::IDENTITY)
            .with_velocity(Vector::X * speed, Vector::ZERO)
            .with_friction(friction);
        let obstacles = std::slice::from_ref(&table);
        let mut contacts = LaneContacts::default();
        let holding = contacts.begin_holding(obstacles, (THICKNESS, 0.001), (end, h), n);
        assert_eq!(holding, Holding::All);
        let mut l = place();
        contacts.take_planes(obstacles, &mut l, Team::ALONE);
        let mut portable = place();
        contacts.project_with_friction(&mut l, Team::ALONE);
        let touch = contacts.touch.clone();
        contacts.depth.fill(0.0);
        contacts.touch.fill(0);
        portable_pass(&mut contacts, &mut portable, true);
        assert_eq!(bits(&mut l), bits(&mut portable), "AVX2 and portable");
        assert_eq!(touch, contacts.touch);
        let [x, y, z, sx, _, sz, _] = l.arrays_mut();
        for k in 0..n {
            if k % 2 == 0 {
                let carried = if friction > 0.0 { shift } else { 0.0 };
                assert!(
                    (y[k] - (half.y + THICKNESS)).abs() < 1e-6,
                    "lane {k}: {}",
                    y[k]
                );
                assert!(
                    (x[k] - (sx[k] + carried)).abs() < 1e-6,
                    "lane {k}: {}",
                    x[k]
                );
            } else {
                let face = shift + half.x + THICKNESS;
                assert!(
                    (x[k] - face).abs() < 1e-6,
                    "lane {k}: {} not at {face}",
                    x[k]
                );
            }
            assert!((z[k] - sz[k]).abs() < 1e-6, "lane {k} slid across");
        }
        assert!(touch.iter().all(|&t| t == 1), "{touch:?}");
    }
}

/// The lanes hold still convex shapes and meshes without an inside,
/// and balls, capsules, half-spaces and cuboids moving without
/// turning; no ball, capsule or cuboid the substep's motion (the
/// particles' and its own) could carry a particle far into.
#[test]
fn the_lanes_hold_still_or_sliding_shapes_the_motion_cannot_cross() {
    let [ball, floor] = ball_and_floor();
    // In substeps of a millisecond.
    let holds = |o: &[Obstacle], motion| LaneContacts::holds(o, motion, 1.0e-3);
    assert!(holds(&[ball.clone(), floor.clone()], 0.01));
    assert!(!holds(&[], 0.01), "nothing to hold");
    assert!(
        !holds(std::slice::from_ref(&ball), 0.2),
        "moves a radius in a few substeps"
    );
    assert!(
        holds(std::slice::from_ref(&floor), 10.0),
        "a floor whatever the motion"
    );
    // A ball moving without turning, by its move and the particles'
    // together (1 m/s: a millimetre a substep); not one that turns.
    let moving = ball.clone().with_velocity(Vector::X, Vector::ZERO);
    assert!(holds(&[moving.clone(), floor.clone()], 0.01));
    assert!(
        !holds(&[moving.clone(), floor.clone()], 0.1245),
        "0.1245 m + 1 mm a substep, four times over, is past its 0.5 m radius"
    );
    assert!(holds(std::slice::from_ref(&ball), 0.1245));
    let turning = ball.clone().with_velocity(Vector::ZERO, Vector::Y);
    assert!(!holds(&[turning, floor.clone()], 0.01));
    // A moving shape the lanes take from lists made for one pose.
    let rolling = Obstacle::new(SharedShape::cylinder(0.5, 0.3), Pose::IDENTITY)
        .with_velocity(Vector::X, Vector::ZERO);
    assert!(!holds(&[rolling, floor.clone()], 0.001));
    let mut dynamic = ball.clone();
    dynamic.body = Some(DynamicBody {
        inverse_mass: Vector::ONE,
        inverse_inertia: glam::Mat3::IDENTITY,
        center_of_mass: Vector::Y,
        acceleration: Vector::ZERO,
    });
    assert!(!holds(&[dynamic], 0.01));
    let table = Obstacle::cuboid(Vector::new(0.5, 0.02, 0.5), Pose::IDENTITY);
    assert!(holds(&[ball.clone(), table.clone()], 0.004));
    assert!(
        !holds(&[ball.clone(), table.clone()], 0.006),
        "a 2 cm top the motion could carry a particle through"
    );
    let capsule = Obstacle::new(SharedShape::capsule_y(0.5, 0.1), Pose::IDENTITY);
    assert!(holds(&[ball.clone(), capsule.clone()], 0.001));
    assert!(
        !holds(&[ball.clone(), capsule], 0.03),
        "a 10 cm bar the motion could carry a particle through"
    );
    // Other convex shapes by their own box's half extents.
    let cylinder = Obstacle::new(SharedShape::cylinder(0.5, 0.1), Pose::IDENTITY);
    assert!(holds(&[ball.clone(), cylinder.clone()], 0.001));
    assert!(
        !holds(&[ball.clone(), cylinder], 0.03),
        "a 10 cm rod the motion could carry a particle through"
    );
    let cone = Obstacle::new(SharedShape::cone(0.2, 0.15), Pose::IDENTITY);
    assert!(holds(std::slice::from_ref(&cone), 0.001));
    let triangle = Obstacle::new(
        SharedShape::triangle(Vector::ZERO, Vector::X, Vector::Z),
        Pose::IDENTITY,
    );
    assert!(
        LaneContacts::may_hold(std::slice::from_ref(&triangle))
            && !holds(std::slice::from_ref(&triangle), 0.001),
        "a triangle is flat"
    );
    // Not convex but held: a mesh of two triangles, whatever its
    // thickness (its planes face the side a lane starts on,
    // `lane_mesh.rs`); not so a mesh with an inside (oriented).
    let mesh = Obstacle::new(
        SharedShape::trimesh(
            vec![
                Vector::ZERO,
                Vector::X,
                Vector::Z,
                Vector::new(1.0, 0.5, 1.0),
            ],
            vec![[0, 1, 2], [1, 3, 2]],
        )
        .expect("a mesh"),
        Pose::IDENTITY,
    );
    assert!(holds(&[ball.clone(), mesh.clone()], 0.001));
    let tetrahedron = |flags| {
        let corners = vec![Vector::ZERO, Vector::X, Vector::Y, Vector::Z];
        let faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        SharedShape::trimesh_with_flags(corners, faces, flags).expect("a mesh")
    };
    let open = Obstacle::new(tetrahedron(TriMeshFlags::empty()), Pose::IDENTITY);
    assert!(LaneContacts::may_hold(std::slice::from_ref(&open)));
    let oriented = Obstacle::new(tetrahedron(TriMeshFlags::ORIENTED), Pose::IDENTITY);
    assert!(!LaneContacts::may_hold(&[ball, oriented.clone()]));
    // What it holds it holds whole, or nothing.
    let mut contacts = LaneContacts::default();
    assert!(
        contacts.begin(std::slice::from_ref(&floor), (THICKNESS, 0.01), 4) && !contacts.is_empty()
    );
    assert!(!contacts.begin(&[floor, oriented], (THICKNESS, 0.01), 4) && contacts.is_empty());
    assert_eq!(contacts.touching(), 0, "nothing held, nothing touching");
}

/// A turned capsule (a bar) and lanes around it, on its axis and
/// beyond its ends: every free lane ends at least its radius and the
/// thickness from the axis segment, a pushed one moved straight away
/// from the axis point nearest it (beyond an end, from the end: the
/// caps are balls); pinned lanes and lanes clear of it keep their
/// bits; the vector and the portable passes agree to the bit, with
/// friction too.
#[test]
fn a_capsule_puts_the_lanes_out_of_its_axis_by_the_thickness() {
    let turn =
        glam::Quat::from_rotation_x(std::f32::consts::FRAC_PI_2) * glam::Quat::from_rotation_z(0.4);
    let pose = Pose::from_parts(Vector::new(0.2, 0.4, -0.1), turn);
    let (half_height, radius) = (0.8, 0.05);
    let bar = Obstacle::new(SharedShape::capsule_y(half_height, radius), pose);
    let [a, b] = [-half_height, half_height].map(|y| pose.transform_point(Vector::Y * y));
    let nearest = |p: Vector| {
        let u = b - a;
        a + u * ((p - a).dot(u) / u.length_squared()).clamp(0.0, 1.0)
    };
    let n = CHUNK + 21;
    let place = || {
        placed(n, |k| {
            let s = k as f32;
            // Along the axis and 20% past either end, within 1.5 radii.
            let along = a + (b - a) * (1.4 * ((0.618 * s) % 1.0) - 0.2);
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin())
                .normalize_or(Vector::X);
            let p = along + dir * (1.5 * radius * ((0.37 * s) % 1.0));
            let p = if k % 11 == 3 { nearest(p) } else { p };
            let w = if k % 6 == 0 { 0.0 } else { 1.5 };
            (p, p + Vector::new(0.001, -0.002, 0.001), w)
        })
    };
    let obstacles = [bar.with_friction(0.6)];
    let (mut vector, mut portable) = (LaneContacts::default(), LaneContacts::default());
    assert!(vector.begin(&obstacles, (THICKNESS, 0.002), n));
    assert!(portable.begin(&obstacles, (THICKNESS, 0.002), n));
    let (mut l, mut m) = (place(), place());
    let before = bits(&mut l);
    vector.project(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, false);
    assert_eq!(bits(&mut l), bits(&mut m));
    let reach = radius + THICKNESS;
    let (mut pushed, mut clear) = (0, 0);
    {
        let [x, y, z, _, _, _, w] = l.arrays_mut();
        for k in 0..n {
            let p = Vector::new(x[k], y[k], z[k]);
            let old = position_in(&before, n, k);
            if w[k] == 0.0 || (old - nearest(old)).length() >= reach {
                assert_eq!(p, old, "lane {k} moved");
                clear += 1;
                continue;
            }
            let out = p - nearest(old);
            assert!(
                (out.length() - reach).abs() < 1e-5 && (p - nearest(p)).length() >= reach - 1e-5,
                "lane {k} at {p:?}, {} from the axis",
                (p - nearest(p)).length()
            );
            // Straight out from the nearest axis point (on the axis
            // itself: any way out).
            let from = old - nearest(old);
            if from.length() > 1e-4 {
                assert!(
                    from.normalize().dot(out.normalize()) > 0.999,
                    "lane {k} pushed along {out:?} from {old:?}"
                );
            }
            pushed += 1;
        }
    }
    assert!(
        pushed > n / 3 && clear > n / 8,
        "{pushed} pushed, {clear} clear"
    );
    assert_eq!(vector.touching() as usize, pushed);
    vector.project_with_friction(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, true);
    assert_eq!(bits(&mut l), bits(&mut m));
    assert_eq!(
        (&vector.depth, &vector.touch),
        (&portable.depth, &portable.touch)
    );
}

/// A turned table top (a cuboid) and lanes that start around and in
/// it and move 3 mm in a substep: each free lane that starts within
/// the cuboid's reach ends on its plane's side, outside the cuboid by
/// the thickness (the rounded cuboid is convex), or, having started
/// within the thickness, no deeper than it started; lanes starting beyond
/// the reach keep their bits; the planes and the pass are the same
/// bits in AVX2 and lane by lane.
#[test]
fn a_cuboids_planes_put_the_lanes_out_by_the_thickness() {
    let turn = glam::Quat::from_rotation_z(0.3) * glam::Quat::from_rotation_x(-0.2);
    let pose = Pose::from_parts(Vector::new(0.1, 1.0, -0.2), turn);
    let half = Vector::new(0.5, 0.05, 0.4);
    let table = Obstacle::cuboid(half, pose).with_friction(0.5);
    let n = 2 * CHUNK + 11;
    let motion = 0.003;
    let place = || {
        placed(n, |k| {
            let s = k as f32;
            // A point of the cuboid's surface grown by up to 4 cm, in
            // its frame, from a direction that covers faces, edges
            // and corners; every eleventh starts inside it.
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
            let local = (dir * half * 1.2).clamp(-half, half)
                + dir.normalize() * (0.04 * ((0.37 * s) % 1.0));
            let local = if k % 11 == 3 { local * 0.5 } else { local };
            let start = pose.transform_point(local);
            let moved = start - pose.rotation * dir.normalize() * motion;
            (moved, start, if k % 5 == 0 { 0.0 } else { 1.0 })
        })
    };
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, motion), n));
    assert!(contacts.holds_cuboid());
    let mut l = place();
    let before = bits(&mut l);
    contacts.take_planes(std::slice::from_ref(&table), &mut l, Team::ALONE);
    contacts.project(&mut l, Team::ALONE);
    let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
    let (mut held, mut far, mut inside) = (0, 0, 0);
    for k in 0..n {
        let p = Vector::new(x[k], y[k], z[k]);
        let start = Vector::new(sx[k], sy[k], sz[k]);
        let old = position_in(&before, n, k);
        let hit = contact_prepared(
            &*table.shape,
            Analytic::of(&*table.shape),
            &PoseF64::of(&table.pose),
            start,
        )
        .expect("a contact");
        let within = hit.signed_distance < 2.0 * (THICKNESS + motion) - 1e-4;
        let beyond = hit.signed_distance > 2.0 * (THICKNESS + motion) + 1e-4;
        if w[k] == 0.0 || beyond {
            assert_eq!(p, old, "lane {k} moved");
            far += usize::from(beyond);
            continue;
        }
        if within {
            held += 1;
            let out = contact_prepared(
                &*table.shape,
                Analytic::of(&*table.shape),
                &PoseF64::of(&table.pose),
                p,
            )
            .expect("a contact");
            // Out by the thickness; one that started within it no
            // deeper than it started (the stage takes it out).
            let floor = hit.signed_distance.min(THICKNESS);
            assert!(
                out.signed_distance > floor - 1e-5,
                "lane {k} from {start:?} ({}) ends {} from the cuboid",
                hit.signed_distance,
                out.signed_distance
            );
            inside += usize::from(hit.signed_distance < 0.0);
        }
    }
    assert!(
        held > n / 2 && far > 0 && inside > 0,
        "{held} held, {far} beyond, {inside} started inside"
    );
    // Lane by lane, without AVX2: the same planes and the same pass.
    let mut portable = LaneContacts::default();
    portable.begin(std::slice::from_ref(&table), (THICKNESS, motion), n);
    let mut m = place();
    {
        let [_, _, _, sx, sy, sz, w] = m.arrays_mut();
        let cuboid = cuboid_of(&portable);
        let [a, b, c, d] = &mut portable.planes;
        let mut out = [&mut a[..], &mut b[..], &mut c[..], &mut d[..]];
        planes_of(&cuboid, ([&*sx, &*sy, &*sz], &*w), &mut out, false);
    }
    assert_eq!(portable.planes, contacts.planes, "the planes' bits");
    portable_pass(&mut portable, &mut m, false);
    assert_eq!(bits(&mut m), bits(&mut l));
    contacts.project_with_friction(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, true);
    assert_eq!(bits(&mut m), bits(&mut l));
    assert_eq!(
        (&portable.depth, &portable.touch),
        (&contacts.depth, &contacts.touch)
    );
}

/// A turned cylinder and a cone beside it, and lanes that start around
/// and in them and move 3 mm in a substep: each free lane that starts
/// within a shape's reach ends outside it by the thickness, or, having
/// started within the thickness, no deeper than it started (the planes
/// are tangent planes of convex shapes); lanes starting beyond every
/// reach and pinned lanes keep their bits; the vector and the portable
/// passes agree to the bit.
#[test]
fn a_convex_shapes_planes_put_the_lanes_out_by_the_thickness() {
    let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
    let obstacles = [
        Obstacle::new(
            SharedShape::cylinder(0.3, 0.25),
            Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
        )
        .with_friction(0.5),
        Obstacle::new(
            SharedShape::cone(0.2, 0.15),
            Pose::from_translation(Vector::new(0.8, 1.0, 0.0)),
        ),
    ];
    let n = 2 * CHUNK + 11;
    let motion = 0.003;
    let place = || {
        placed(n, |k| {
            let s = k as f32;
            // Around one shape or the other, from 0.3 m inside its
            // origin out to its surface grown by up to 5 cm.
            let o = &obstacles[k % 2];
            let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin()).normalize();
            let origin = o.pose.translation;
            let surface = contact(&*o.shape, &o.pose, origin + dir)
                .expect("a contact")
                .point;
            let r = 0.7 + 0.45 * ((0.37 * s) % 1.0);
            let start =
                origin + (surface - origin) * r.min(1.0) + dir * (0.05 * (r - 1.0).max(0.0) / 0.15);
            let moved = start - dir * motion;
            (moved, start, if k % 5 == 0 { 0.0 } else { 1.0 })
        })
    };
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(&obstacles, (THICKNESS, motion), n));
    assert!(!contacts.holds_cuboid() && contacts.held_planes().is_some());
    let mut l = place();
    let before = bits(&mut l);
    contacts.take_planes(&obstacles, &mut l, Team::ALONE);
    contacts.project(&mut l, Team::ALONE);
    let [x, y, z, sx, sy, sz, w] = l.arrays_mut();
    let (mut held, mut far, mut inside) = (0, 0, 0);
    for k in 0..n {
        let p = Vector::new(x[k], y[k], z[k]);
        let start = Vector::new(sx[k], sy[k], sz[k]);
        let old = position_in(&before, n, k);
        let hits = obstacles
            .each_ref()
            .map(|o| contact(&*o.shape, &o.pose, start).expect("a contact"));
        let reach = 2.0 * (THICKNESS + motion);
        let beyond = hits.iter().all(|h| h.signed_distance > reach + 1e-4);
        if w[k] == 0.0 || beyond {
            assert_eq!(p, old, "lane {k} moved");
            far += usize::from(beyond);
            continue;
        }
        for (o, hit) in obstacles.iter().zip(&hits) {
            if hit.signed_distance >= reach - 1e-4 {
                continue;
            }
            held += 1;
            let out = contact(&*o.shape, &o.pose, p).expect("a contact");
            let floor = hit.signed_distance.min(THICKNESS);
            assert!(
                out.signed_distance > floor - 1e-4,
                "lane {k} from {start:?} ({}) ends {} from its shape",
                hit.signed_distance,
                out.signed_distance
            );
            inside += usize::from(hit.signed_distance < 0.0);
        }
    }
    assert!(
        held > n / 3 && far > n / 10 && inside > n / 10,
        "{held} held, {far} beyond, {inside} started inside"
    );
    let mut portable = LaneContacts::default();
    portable.begin(&obstacles, (THICKNESS, motion), n);
    let mut m = place();
    portable.take_planes(&obstacles, &mut m, Team::ALONE);
    portable_pass(&mut portable, &mut m, false);
    assert_eq!(bits(&mut m), bits(&mut l));
    contacts.project_with_friction(&mut l, Team::ALONE);
    portable_pass(&mut portable, &mut m, true);
    assert_eq!(bits(&mut m), bits(&mut l));
    assert_eq!(
        (&portable.depth, &portable.touch),
        (&contacts.depth, &contacts.touch)
    );
}

/// A table built as one compound collider (a turned cuboid top on a
/// cylinder leg) is held piece by piece, to the same bits as the same
/// pieces as two obstacles: the planes, the pass with friction and its
/// records; a compound with a flat part is not held.
#[test]
fn a_compound_is_held_as_its_parts_are() {
    let turn = glam::Quat::from_rotation_y(0.3) * glam::Quat::from_rotation_x(0.1);
    let place = Pose::from_parts(Vector::new(0.2, 0.5, -0.1), turn);
    let (top_at, leg_at) = (
        Pose::from_translation(Vector::new(0.0, 0.25, 0.0)),
        Pose::from_translation(Vector::new(0.0, 0.0, 0.0)),
    );
    let (top, leg) = (
        SharedShape::cuboid(0.4, 0.02, 0.3),
        SharedShape::cylinder(0.25, 0.05),
    );
    let table = Obstacle::new(
        SharedShape::compound(vec![(top_at, top.clone()), (leg_at, leg.clone())]),
        place,
    )
    .with_friction(0.4);
    let apart = [
        Obstacle::new(top, place * top_at).with_friction(0.4),
        Obstacle::new(leg, place * leg_at).with_friction(0.4),
    ];
    let n = 2 * CHUNK + 11;
    let motion = 0.003;
    let at = |k: usize| {
        let s = k as f32;
        let (u, v) = ((1.3 * s).sin(), (2.1 * s).sin());
        // Half over the top, up to 2 cm above it, half around the leg,
        // up to 2 cm out; each moved 1 cm in (some of them beside the
        // top or below it, and some of those clear of everything).
        let (start, inward) = if k.is_multiple_of(2) {
            let y = 0.27 + 0.02 * ((0.37 * s) % 1.0);
            (Vector::new(0.45 * u, y, 0.35 * v), Vector::NEG_Y)
        } else {
            let across = Vector::new(u, 0.0, (0.7 * s).cos()).normalize();
            let r = 0.05 + 0.02 * ((0.37 * s) % 1.0);
            (across * r + Vector::Y * (0.22 * v), -across)
        };
        let start = place.transform_point(start);
        let moved = start + place.rotation * inward * 0.01;
        (moved, start, if k.is_multiple_of(5) { 0.0 } else { 1.0 })
    };
    let (mut whole, mut parts) = (LaneContacts::default(), LaneContacts::default());
    assert!(whole.begin(std::slice::from_ref(&table), (THICKNESS, motion), n));
    assert!(parts.begin(&apart, (THICKNESS, motion), n));
    assert_eq!(whole.shapes.len(), 2);
    let (mut l, mut m) = (placed(n, at), placed(n, at));
    let before = bits(&mut l);
    whole.take_planes(std::slice::from_ref(&table), &mut l, Team::ALONE);
    parts.take_planes(&apart, &mut m, Team::ALONE);
    assert_eq!(whole.planes, parts.planes, "the planes' bits");
    whole.project_with_friction(&mut l, Team::ALONE);
    parts.project_with_friction(&mut m, Team::ALONE);
    let after = bits(&mut l);
    assert_eq!(after, bits(&mut m));
    assert_eq!((&whole.depth, &whole.touch), (&parts.depth, &parts.touch));
    let moved = (0..n)
        .filter(|&k| position_in(&before, n, k) != position_in(&after, n, k))
        .count();
    assert!(moved > n / 2, "{moved} of {n} lanes put out");
    // A flat part (a triangle) is held by none (parry allows no mesh
    // in a compound).
    let with_triangle = Obstacle::new(
        SharedShape::compound(vec![
            (top_at, SharedShape::ball(0.1)),
            (
                leg_at,
                SharedShape::triangle(Vector::ZERO, Vector::X, Vector::Z),
            ),
        ]),
        place,
    );
    assert!(!LaneContacts::holds(&[with_triangle], motion, 1.0e-3));
}

/// A turned cylinder's planes in single precision agree with those
/// through the stage's contact (double precision) around it, in it
/// and beyond its rims: the same normals, offsets within 10 µm, none
/// where the other has none.
#[test]
fn a_cylinders_planes_are_those_of_its_contact() {
    let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
    let o = Obstacle::new(
        SharedShape::cylinder(0.3, 0.25),
        Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
    );
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&o), (THICKNESS, 0.003), 1));
    let [StillShape::Convex(convex)] = contacts.shapes[..] else {
        panic!("{:?}", contacts.shapes);
    };
    let cylinder = convex.cylinder.expect("a cylinder's own planes");
    let shape = &*o.shape;
    let analytic = Analytic::of(shape);
    let pose = PoseF64::placing(&o.pose, analytic);
    let (mut held, mut none) = (0, 0);
    for i in 0..13 {
        for j in 0..13 {
            for k in 0..13 {
                let local = Vector::new(i as f32 - 6.0, j as f32 - 6.0, k as f32 - 6.0) * 0.055
                    + Vector::new(0.001, 0.002, 0.003);
                let p = o.pose.transform_point(local).to_array();
                let ours = cylinder_plane(&convex, &cylinder, p);
                let stage = convex_plane(&convex, (shape, analytic, &pose), p);
                if stage.1 == f32::NEG_INFINITY {
                    assert_eq!(ours.1, f32::NEG_INFINITY, "{p:?}: {ours:?}");
                    none += 1;
                    continue;
                }
                held += 1;
                let (a, b) = (Vector::from(ours.0), Vector::from(stage.0));
                assert!(a.dot(b) > 0.9999, "{p:?}: {ours:?} against {stage:?}");
                assert!(
                    (ours.1 - stage.1).abs() < 1e-5,
                    "{p:?}: {ours:?} against {stage:?}"
                );
            }
        }
    }
    assert!(held > 500 && none > 500, "{held} held, {none} none");
}

/// A turned convex hull's planes from its faces agree with those
/// through the stage's contact (parry's projection), around it, in it
/// and beyond its edges and corners (there from the contact itself):
/// the same normals (either of two faces as near), offsets within 50
/// µm (parry's tolerance), none where the other has none.
#[test]
fn a_hulls_planes_are_those_of_its_contact() {
    let turn = glam::Quat::from_rotation_z(0.4) * glam::Quat::from_rotation_x(0.3);
    // A box with a corner cut off and a roof: faces of 3 to 5 corners.
    let points = [
        Vector::new(-0.3, -0.1, -0.2),
        Vector::new(0.3, -0.1, -0.2),
        Vector::new(-0.3, -0.1, 0.2),
        Vector::new(0.3, -0.1, 0.1),
        Vector::new(0.2, -0.1, 0.2),
        Vector::new(-0.3, 0.1, -0.2),
        Vector::new(0.3, 0.1, -0.2),
        Vector::new(-0.3, 0.1, 0.2),
        Vector::new(0.3, 0.1, 0.2),
        Vector::new(0.0, 0.2, 0.0),
    ];
    let o = Obstacle::new(
        SharedShape::convex_hull(&points).expect("a hull"),
        Pose::from_parts(Vector::new(0.0, 1.0, 0.0), turn),
    );
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&o), (THICKNESS, 0.003), 1));
    let [StillShape::Convex(convex)] = contacts.shapes[..] else {
        panic!("{:?}", contacts.shapes);
    };
    let faces = convex.hull.expect("a hull's faces");
    assert!(faces.1 - faces.0 >= 7, "{faces:?}");
    let shape = &*o.shape;
    let analytic = Analytic::of(shape);
    let pose = PoseF64::placing(&o.pose, analytic);
    let (mut by_face, mut by_contact, mut none) = (0, 0, 0);
    for i in 0..13 {
        for j in 0..13 {
            for k in 0..13 {
                let local = Vector::new(i as f32 - 6.0, j as f32 - 6.0, k as f32 - 6.0)
                    * Vector::new(0.055, 0.025, 0.04)
                    + Vector::new(0.001, 0.002, 0.003);
                let p = o.pose.transform_point(local).to_array();
                let face = hull_plane(&convex, (&contacts.hulls, faces), p);
                let stage = convex_plane(&convex, (shape, analytic, &pose), p);
                let Some(ours) = face else {
                    by_contact += 1;
                    continue;
                };
                if stage.1 == f32::NEG_INFINITY {
                    assert_eq!(ours.1, f32::NEG_INFINITY, "{p:?}: {ours:?}");
                    none += 1;
                    continue;
                }
                by_face += 1;
                let (a, b) = (Vector::from(ours.0), Vector::from(stage.0));
                if a.dot(b) < 0.9999 {
                    // Two faces as near: either holds it.
                    let (_, _, beyond) =
                        contacts.hulls.nearest_face(faces, Vector::from(p)).unwrap();
                    let c = contact(shape, &o.pose, Vector::from(p)).unwrap();
                    assert!(
                        (beyond - c.signed_distance).abs() < 5e-5,
                        "{p:?}: {ours:?} against {stage:?}"
                    );
                    continue;
                }
                assert!(a.dot(b) > 0.9999, "{p:?}: {ours:?} against {stage:?}");
                // parry's projection on a support map converges to
                // within its tolerance: 10 µm off at some points.
                assert!(
                    (ours.1 - stage.1).abs() < 5e-5,
                    "{p:?}: {ours:?} against {stage:?}"
                );
            }
        }
    }
    assert!(
        by_face > 300 && by_contact > 100 && none > 300,
        "{by_face} by a face, {by_contact} by the contact, {none} none"
    );
}

/// A sheet folded over a turned cuboid's edge, each particle the
/// thickness out of it: the springs across the edge cut its rounding.
/// The lanes' edge pass puts every stretch and shear spring's samples
/// back to half the thickness out (as the collision stage's edge pass
/// would), moves no lane of a spring beyond a face, no pinned lane, and
/// leaves a spring whose pinned end is inside the cuboid.
#[test]
fn springs_over_a_cuboids_edge_are_put_off_it() {
    use crate::cloth::{ClothBuilder, SpringKind};
    let turn = glam::Quat::from_rotation_z(0.2) * glam::Quat::from_rotation_y(0.4);
    let pose = Pose::from_parts(Vector::new(0.1, 0.7, -0.2), turn);
    let half = Vector::new(0.3, 0.2, 0.25);
    let table = Obstacle::cuboid(half, pose);
    let (cols, rows, spacing) = (12, 8, 0.02);
    let cloth = ClothBuilder::new(cols, rows).build().unwrap();
    let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
    let n = cols * rows;
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, 0.001), n));
    // Over the +x edge of the top face: columns before the edge lie on
    // the top, those after hang down the side; one particle of the
    // row 2 pinned on the top, one of row 5 pinned inside the cuboid.
    let pinned_top = cloth.index(2, 3).unwrap();
    let pinned_in = cloth.index(5, 6).unwrap();
    let mut l = sheet_lanes(&cloth, &plan, |r, c| {
        let i = cloth.index(r, c).unwrap();
        let u = (c as f32 - 5.5) * spacing;
        let across = (r as f32 - 3.5) * spacing;
        let local = if i == pinned_in {
            Vector::new(half.x - 0.01, half.y - 0.01, across)
        } else if u < 0.0 {
            Vector::new(half.x + u, half.y + THICKNESS, across)
        } else {
            Vector::new(half.x + THICKNESS, half.y - u, across)
        };
        let pinned = i == pinned_top || i == pinned_in;
        (pose.transform_point(local), if pinned { 0.0 } else { 1.0 })
    });
    let springs = cloth.springs();
    let edge_springs = || {
        springs
            .range(SpringKind::Stretch)
            .chain(springs.range(SpringKind::Shear))
            .map(|s| {
                (
                    plan.lane(springs.a[s] as usize),
                    plan.lane(springs.b[s] as usize),
                )
            })
    };
    let distance = |p: Vector| {
        contact_prepared(
            &*table.shape,
            Analytic::of(&*table.shape),
            &PoseF64::of(&table.pose),
            p,
        )
        .unwrap()
        .signed_distance
    };
    // The least of a spring's samples' distances to the cuboid (m).
    let least = |l: &mut Lanes, (a, b): (usize, usize)| {
        let [x, y, z, ..] = l.arrays_mut();
        let (pa, pb) = (Vector::new(x[a], y[a], z[a]), Vector::new(x[b], y[b], z[b]));
        EDGE_SAMPLES
            .iter()
            .map(|&t| distance(pa * (1.0 - t) + pb * t))
            .fold(f32::INFINITY, f32::min)
    };
    let margin = 0.5 * THICKNESS;
    let inside = |(a, b): (usize, usize)| [a, b].contains(&plan.lane(pinned_in));
    let cut_before = edge_springs()
        .filter(|&s| !inside(s) && least(&mut l, s) < 0.5 * margin)
        .count();
    assert!(cut_before >= rows, "{cut_before} springs cut the edge");
    let before = bits(&mut l);
    let moved = contacts.keep_springs_off_cuboids(&plan, &mut l);
    assert!(moved > 0.0);
    let after = bits(&mut l);
    let lane_moved = |k: usize| (0..3).any(|a| before[a * n + k] != after[a * n + k]);
    for s in edge_springs() {
        let d = least(&mut l, s);
        if inside(s) {
            // Left: its pinned end cannot be put out.
            assert!(d < 0.0, "spring {s:?} {d} m out");
            continue;
        }
        assert!(d > 0.9 * margin, "spring {s:?} {d} m out");
    }
    for r in 0..rows {
        for c in 0..cols {
            let i = cloth.index(r, c).unwrap();
            let k = plan.lane(i);
            // Pinned lanes stay; so do lanes two columns or more from
            // the edge, whose springs all lie beyond one face.
            if i == pinned_top || i == pinned_in || !(4..=7).contains(&c) {
                assert!(!lane_moved(k), "lane of ({r}, {c}) moved");
            }
        }
    }
}

/// A sheet laid flat on a cuboid's face within the thickness (a cloth
/// put on a ramp by hand): every spring lies over the face, no nearer
/// than its ends, and the lanes' edge pass leaves it to the contacts
/// (pushed out by the springs at once, it was thrown off the ramp).
#[test]
fn a_sheet_within_the_thickness_of_a_face_is_left_to_the_contacts() {
    use crate::cloth::ClothBuilder;
    let pose = Pose::from_parts(
        Vector::new(0.0, -0.5, 0.0),
        glam::Quat::from_rotation_z(-0.3),
    );
    let ramp = Obstacle::cuboid(Vector::new(2.0, 0.5, 2.0), pose);
    let (cols, rows) = (10, 10);
    let cloth = ClothBuilder::new(cols, rows).build().unwrap();
    let plan = GridPlan::new(cloth.grid().unwrap(), cloth.springs()).unwrap();
    let n = cols * rows;
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&ramp), (THICKNESS, 0.001), n));
    let mut l = sheet_lanes(&cloth, &plan, |r, c| {
        let local = Vector::new(
            (c as f32 - 4.5) * 0.05,
            0.5 + 0.2 * THICKNESS,
            (r as f32 - 4.5) * 0.05,
        );
        (pose.transform_point(local), 1.0)
    });
    let before = bits(&mut l);
    assert_eq!(contacts.keep_springs_off_cuboids(&plan, &mut l), 0.0);
    assert_eq!(bits(&mut l), before);
}

/// The lanes of a grid `cloth` in `plan`'s order, the particle of row
/// `r` and column `c` at `place(r, c)` (position in m, inverse mass).
fn sheet_lanes(
    cloth: &crate::cloth::Cloth,
    plan: &GridPlan,
    place: impl Fn(usize, usize) -> (Vector, f32),
) -> Lanes {
    let grid = cloth.grid().unwrap();
    let mut l = Lanes::default();
    l.resize(cloth.particle_count());
    let [x, y, z, _, _, _, w] = l.arrays_mut();
    for r in 0..grid.rows {
        for c in 0..grid.cols {
            let (p, inverse_mass) = place(r, c);
            let k = plan.lane(cloth.index(r, c).unwrap());
            (x[k], y[k], z[k], w[k]) = (p.x, p.y, p.z, inverse_mass);
        }
    }
    l
}

/// The one cuboid the lanes hold.
fn cuboid_of(contacts: &LaneContacts) -> StillCuboid {
    match contacts.shapes[..] {
        [StillShape::Cuboid(c)] => c,
        _ => panic!("not one cuboid"),
    }
}

/// A turned cuboid's grown box ([`StillCuboid::box_meets`]) holds
/// every point within the margin of it, so that the springs' pass may
/// pass over a cuboid whose box is clear of the lanes'; and the far
/// test of its planes ([`far_from_cuboid`]) holds only for points
/// beyond its reach, whose plane is none.
#[test]
fn a_cuboids_box_and_far_test_leave_out_only_what_is_beyond_it() {
    let turn = glam::Quat::from_rotation_z(2.0)
        * glam::Quat::from_rotation_y(-0.7)
        * glam::Quat::from_rotation_x(0.4);
    let table = Obstacle::cuboid(
        Vector::new(0.3, 0.05, 0.2),
        Pose::from_parts(Vector::new(0.2, 0.9, -0.1), turn),
    );
    let mut contacts = LaneContacts::default();
    assert!(contacts.begin(std::slice::from_ref(&table), (THICKNESS, 0.002), 1));
    let cuboid = cuboid_of(&contacts);
    let margin = 0.5 * THICKNESS;
    let (mut met, mut clear, mut far) = (0, 0, 0);
    for k in 0..20_000 {
        let s = k as f32;
        let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
        let p = table.pose.translation + dir * (0.5 * ((0.37 * s) % 1.0));
        let distance = contact_prepared(
            &*table.shape,
            Analytic::of(&*table.shape),
            &PoseF64::of(&table.pose),
            p,
        )
        .expect("a contact")
        .signed_distance;
        if cuboid.box_meets((p, p), margin) {
            met += 1;
        } else {
            clear += 1;
            assert!(distance > margin, "{p:?} {distance} m from it, box clear");
        }
        let plane = cuboid_plane(&cuboid, [p.x, p.y, p.z]);
        if far_from_cuboid(&cuboid, [p.x, p.y, p.z]) {
            far += 1;
            assert!(distance > cuboid.reach, "{p:?} {distance} m from it, far");
            assert_eq!(plane, ([0.0; 3], f32::NEG_INFINITY));
        } else if distance < cuboid.reach * 0.999 {
            assert!(plane.1.is_finite(), "{p:?} {distance} m from it, no plane");
        }
    }
    assert!(
        met > 1000 && clear > 1000 && far > 1000,
        "{met} {clear} {far}"
    );
    // Points of its surface, corners and edges among them, moved out
    // by nine tenths of the margin: in the box, each of them.
    let half = Vector::new(0.3, 0.05, 0.2);
    for k in 0..2000 {
        let s = k as f32;
        let dir = Vector::new((1.3 * s).sin(), (0.7 * s).cos(), (2.1 * s).sin());
        let local = (dir * half * 3.0).clamp(-half, half) + dir.normalize() * 0.9 * margin;
        let p = table.pose.transform_point(local);
        assert!(cuboid.box_meets((p, p), margin), "{local:?} out of the box");
    }
}

/// Springs between points the lanes left outside: never into a floor;
/// into a lone ball only when long enough that a chord between two
/// points on the surface moved out by the thickness dips within half
/// the thickness of it; not known for a ball beside another shape.
#[test]
fn short_springs_stay_out_of_a_lone_ball_and_any_spring_out_of_floors() {
    let [ball, floor] = ball_and_floor();
    let stays = |o: &[Obstacle], l: f32| LaneContacts::springs_stay_out(o, l, THICKNESS);
    assert!(stays(std::slice::from_ref(&floor), 1.0e3));
    assert!(!stays(&[ball.clone(), floor.clone()], 1.0e-3));
    let table = Obstacle::cuboid(Vector::splat(0.5), Pose::IDENTITY);
    assert!(!stays(&[table], 1.0e-3), "edges: the stage's edge pass");
    assert!(!stays(std::slice::from_ref(&ball), f32::NAN));
    // Chords of the ball (radius 0.5 at (0, 1, 0)) moved out by the
    // thickness, through a tilted plane, sampled along their length.
    let centre = Vector::new(0.0, 1.0, 0.0);
    let out = 0.5 + THICKNESS;
    let (mut some_in, mut some_out) = (false, false);
    for k in 1..60 {
        let l = 0.005 * k as f32;
        let half_angle = (0.5 * l / out).asin();
        let tilt = Vector::new(0.3, 1.0, -0.2).normalize();
        let side = tilt.cross(Vector::X).normalize();
        let a = centre + (tilt * half_angle.cos() + side * half_angle.sin()) * out;
        let b = centre + (tilt * half_angle.cos() - side * half_angle.sin()) * out;
        let closest = (0..=64)
            .map(|t| (a + (b - a) * (t as f32 / 64.0) - centre).length())
            .fold(f32::INFINITY, f32::min);
        let clear = closest >= 0.5 + 0.5 * THICKNESS;
        // Within rounding of the border, either answer.
        if (closest - (0.5 + 0.5 * THICKNESS)).abs() > 1.0e-5 {
            assert_eq!(stays(std::slice::from_ref(&ball), l), clear, "l = {l}");
        }
        some_in |= !clear;
        some_out |= clear;
    }
    assert!(some_in && some_out, "chords on both sides of the border");
}
