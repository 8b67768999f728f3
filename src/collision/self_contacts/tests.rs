//! Self-collision's unit tests: the looks, the pass and their bits.

use super::contacts::{motion_box, SelfContacts};
use super::edge_pairs::{fold_share, FULL_FOLD, SHARP_FOLD};
use super::geometry::{closest, rim_taper};
use super::lists::PartPairs;
use super::look::Look;
use super::pairs::SelfPair;
use super::params::{LookBasis, SelfContactParams};
use super::pass_plane::PARALLEL_MIN_PAIRS;
use crate::cloth::ClothBuilder;
use crate::math::{simd_available, Vector};
use crate::parallel::Team;

impl SelfContacts {
    /// Every pair of the last look, in triangle order.
    fn all_pairs(&self) -> Vec<SelfPair> {
        let blocks = &self.blocks[..self.used_blocks];
        let pairs: Vec<SelfPair> = blocks.iter().flat_map(|b| b.0.clone()).collect();
        assert_eq!(pairs.len(), self.pairs);
        pairs
    }
}

/// The box around 21 motions (two vector steps and a tail) is the
/// least and greatest of each coordinate; a motion that is not finite,
/// in a vector step or in the tail, gives none.
#[test]
fn the_box_around_the_motions_holds_each_and_none_for_a_lost_particle() {
    let f = |s: f32| -> Vec<Vector> {
        (0..21)
            .map(|i| {
                let t = (i as f32 + s) * 0.731;
                Vector::new(t.sin(), (1.3 * t).cos(), (0.7 * t).sin() * 3.0)
            })
            .collect()
    };
    let (x, at) = (f(0.0), f(5.0));
    let d: Vec<Vector> = x.iter().zip(&at).map(|(&x, &at)| x - at).collect();
    let lo = d.iter().fold(Vector::INFINITY, |l, &d| l.min(d));
    let hi = d.iter().fold(Vector::NEG_INFINITY, |h, &d| h.max(d));
    assert_eq!(motion_box(&x, &at), Some((lo, hi)));
    // Each coordinate's extremes where they are, in the steps or the tail.
    for (k, a) in [(2, 0), (12, 1), (19, 2), (7, 2)] {
        let mut y = x.clone();
        y[k][a] += 100.0;
        let (_, high) = motion_box(&y, &at).unwrap();
        assert_eq!(high[a], d[k][a] + 100.0, "particle {k}, axis {a}");
        y[k][a] -= 200.0;
        let (low, _) = motion_box(&y, &at).unwrap();
        assert_eq!(low[a], d[k][a] - 100.0, "particle {k}, axis {a}");
    }
    for (k, bad) in [
        (3, f32::NAN),
        (18, f32::NAN),
        (9, f32::INFINITY),
        (20, f32::NEG_INFINITY),
    ] {
        let mut y = x.clone();
        y[k].y = bad;
        assert_eq!(motion_box(&y, &at), None, "particle {k} at {bad}");
    }
}

#[test]
fn a_look_is_due_once_two_particles_may_have_closed_in_by_the_margin() {
    let cloth = ClothBuilder::new(4, 4).build().unwrap();
    let topology = &*cloth.topology;
    let x = cloth.positions().to_vec();
    let basis = |thickness: f32| LookBasis {
        topology,
        particles: x.len(),
        revision: cloth.mass_revision,
        thickness,
        margin: 0.01,
    };
    let mut contacts = SelfContacts::default();
    let mut look = None;
    contacts.begin_step(&mut look, &basis(0.002), Team::ALONE);
    assert!(contacts.due(&look, &x), "no look yet");
    contacts.find(&mut look, (&x, &[], 0.0), &basis(0.002), Team::ALONE);
    assert!(!contacts.due(&look, &x));
    // The whole cloth falling: no two particles closed in.
    let fell: Vec<Vector> = x.iter().map(|&p| p - Vector::Y * 0.3).collect();
    assert!(!contacts.due(&look, &fell));
    // One particle of 16 moved: it closed in on the others by its
    // motion, which may reach the margin (1 cm).
    let moved = |dy: f32| {
        let mut y = x.clone();
        y[5].y += dy;
        y
    };
    assert!(!contacts.due(&look, &moved(0.0099)), "9.9 mm");
    assert!(contacts.due(&look, &moved(0.0101)), "10.1 mm");
    assert!(contacts.due(&look, &moved(f32::NAN)), "lost: look again");
    // Two neighbours moved 4 mm apart along x and y each (5.7 mm
    // each, 11.3 mm from each other): due, though each moved less
    // than the margin.
    let apart = |pair, d| moved_apart(&x, pair, d);
    assert!(contacts.due(&look, &apart((5, 6), 0.004)));
    assert!(!contacts.due(&look, &apart((5, 6), 0.0034)), "9.6 mm apart");
    // Four particles moved out along ±x and ±z: the box around the
    // motions is 2√2 times one motion wide, but no two particles closed
    // in by more than twice one motion, which the mean tells.
    let cross = |d: f32| {
        let mut y = x.clone();
        y[1].x += d;
        y[2].x -= d;
        y[4].z += d;
        y[8].z -= d;
        y
    };
    assert!(!contacts.due(&look, &cross(0.0045)), "9 mm at most");
    assert!(contacts.due(&look, &cross(0.0051)), "10.2 mm");
    // The look carries over to the next step, unless the thickness
    // (or the margin, or the particles) changed.
    contacts.begin_step(&mut look, &basis(0.002), Team::ALONE);
    assert!(!contacts.due(&look, &x));
    contacts.begin_step(&mut look, &basis(0.003), Team::ALONE);
    assert!(look.is_none() && contacts.due(&look, &x));
}

/// Positions `x` with particle `i` moved by `d` metres along x and y
/// and particle `j` by as much the other way.
fn moved_apart(x: &[Vector], (i, j): (usize, usize), d: f32) -> Vec<Vector> {
    let mut y = x.to_vec();
    y[i] += Vector::new(d, d, 0.0);
    y[j] -= Vector::new(d, d, 0.0);
    y
}

/// Two particles inside a cloth, further apart than a triangle reaches
/// from either, moved apart by more than the margin: no triangle of one
/// closed in on the other, and no look is due; two neighbours moved
/// alike, or the far two moved far enough for the edges between them
/// to have stretched as far, and one is.
#[test]
fn far_particles_moved_apart_need_no_look() {
    let cloth = ClothBuilder::new(8, 8).build().unwrap();
    let topology = &*cloth.topology;
    let x = cloth.positions().to_vec();
    let basis = LookBasis {
        topology,
        particles: x.len(),
        revision: cloth.mass_revision,
        thickness: 0.002,
        margin: 0.01,
    };
    let mut contacts = SelfContacts::default();
    let mut look = None;
    contacts.begin_step(&mut look, &basis, Team::ALONE);
    contacts.find(&mut look, (&x, &[], 0.0), &basis, Team::ALONE);
    // 4 mm along x and y each: 11.3 mm from each other. Particles 9
    // and 54 lie five cells apart along the diagonal, off the border.
    let apart = |pair, d| moved_apart(&x, pair, d);
    assert!(!contacts.due(&look, &apart((9, 54), 0.004)), "far apart");
    assert!(contacts.due(&look, &apart((9, 10), 0.004)), "neighbours");
    assert!(contacts.due(&look, &apart((9, 54), 0.2)), "20 cm each");
}

/// Fresh scratch finds the pairs of the last look again, at the
/// positions of that look (not the current ones), to the same list.
#[test]
fn fresh_scratch_finds_the_last_looks_pairs_again() {
    let cloth = ClothBuilder::new(6, 6).build().unwrap();
    let topology = &*cloth.topology;
    // Folded in two along a column, the halves 2 mm apart.
    let folded: Vec<Vector> = cloth
        .positions()
        .iter()
        .map(|&p| {
            if p.x > 0.0 {
                Vector::new(-p.x, p.y + 0.002, p.z)
            } else {
                p
            }
        })
        .collect();
    let basis = LookBasis {
        topology,
        particles: folded.len(),
        revision: cloth.mass_revision,
        thickness: 0.004,
        margin: 0.004,
    };
    let (mut contacts, mut look) = (SelfContacts::default(), None);
    contacts.begin_step(&mut look, &basis, Team::ALONE);
    contacts.find(&mut look, (&folded, &[], 0.0), &basis, Team::ALONE);
    assert!(
        !contacts.all_pairs().is_empty(),
        "the halves are within reach"
    );
    let mut fresh = SelfContacts::default();
    fresh.begin_step(&mut look, &basis, Team::ALONE);
    assert_eq!(fresh.all_pairs(), contacts.all_pairs());
    assert_eq!(fresh.edge_pairs, contacts.edge_pairs);
}

/// Three 14 × 14 sheets joined, crumpled and laid 4 mm apart, 5 mm
/// layers: pairs within reach everywhere, some closer than the
/// thickness.
fn crumpled_layers() -> (crate::cloth::Cloth, Vec<Vector>) {
    joined_sheets((14, 0.35), 3, |i, p| {
        let layer = (i / (14 * 14)) as f32;
        let bump = 0.004 * ((p.x * 23.0).sin() + (p.z * 17.0 + layer).cos());
        Vector::new(p.x + 0.003 * layer, 0.004 * layer + bump, p.z)
    })
}

/// `copies` square sheets of `side` particles a side and `size`
/// metres joined into one cloth, particle `i` of rest position `p`
/// placed at `place(i, p)`.
fn joined_sheets(
    (side, size): (usize, f32),
    copies: usize,
    place: impl Fn(usize, Vector) -> Vector,
) -> (crate::cloth::Cloth, Vec<Vector>) {
    let sheet = ClothBuilder::new(side, side)
        .size(size, size)
        .build()
        .unwrap();
    let cloth = crate::cloth::Cloth::join(vec![sheet; copies]).unwrap();
    let x = (cloth.positions().iter().enumerate())
        .map(|(i, &p)| place(i, p))
        .collect();
    (cloth, x)
}

/// The layers' thickness and the margin of [`looked_at`] (m).
const LAYERS: f32 = 0.005;

/// The pass's parameters for layers [`LAYERS`] thick, with `friction`
/// and a substep of `h` seconds.
fn layer_params(friction: f32, h: f32) -> SelfContactParams {
    SelfContactParams {
        thickness: LAYERS,
        friction,
        h,
    }
}

/// Self-collision of `cloth` after a look at `x` (with the AVX2
/// kernels unless `portable`).
fn looked_at(cloth: &crate::cloth::Cloth, x: &[Vector], portable: bool) -> SelfContacts {
    let basis = LookBasis {
        topology: &cloth.topology,
        particles: x.len(),
        revision: cloth.mass_revision,
        thickness: LAYERS,
        margin: LAYERS,
    };
    let mut contacts = SelfContacts {
        portable,
        ..SelfContacts::default()
    };
    let mut look = None;
    contacts.begin_step(&mut look, &basis, Team::ALONE);
    contacts.find(&mut look, (x, &[], 0.0), &basis, Team::ALONE);
    contacts
}

/// A look by runs of triangles, with its vector test and without,
/// finds the pairs of each triangle tested against every particle in
/// turn (the look's definition: inside the triangle's box, and a
/// pair), in triangle order, each triangle's in particle order.
#[test]
fn a_look_by_runs_finds_the_pairs_of_every_particle_against_every_triangle() {
    let (cloth, x) = crumpled_layers();
    let topology = &*cloth.topology;
    for portable in [false, true] {
        let contacts = looked_at(&cloth, &x, portable);
        let reference = Look {
            x: &x,
            from: &[],
            topology,
            thickness: LAYERS,
            reach: LAYERS + contacts.margin,
            margin: contacts.margin,
            simd: false,
        };
        let mut want = Vec::new();
        for t in 0..topology.triangles.len() {
            if contacts.patches.quiet_triangle(t) {
                continue;
            }
            if let Some(f) = reference.facing(t, &contacts.neighbours) {
                for (p, &xp) in x.iter().enumerate() {
                    reference.candidate(&f, (p as u32, xp), &contacts.neighbours, &mut want);
                }
            }
        }
        assert!(want.len() > 1000, "only {} pairs", want.len());
        assert_eq!(contacts.all_pairs(), want, "portable: {portable}");
    }
}

/// The border edges' look finds the same pairs with the AVX2 test of
/// a ring's edges as with the plain one.
#[test]
fn the_border_edges_pairs_are_the_same_either_way() {
    let (cloth, x) = crumpled_layers();
    let (simd, portable) = (looked_at(&cloth, &x, false), looked_at(&cloth, &x, true));
    assert!(
        portable.edge_pairs.len() > 100,
        "only {} edge pairs",
        portable.edge_pairs.len()
    );
    assert_eq!(simd.edge_pairs, portable.edge_pairs);
}

/// Two sheets' creases crossing: a 5 × 5 sheet of 30 mm cells folded
/// down along its middle row (53° between its halves), `crease_gap`
/// (m) above another folded up along its middle column, offset by half
/// a cell so that the creases' edges cross between particles, which
/// lie 7.5 mm plus the gap above or below the other's crease.
fn crossing_creases(crease_gap: f32) -> (crate::cloth::Cloth, Vec<Vector>) {
    let sheet = ClothBuilder::new(5, 5).size(0.12, 0.12).build().unwrap();
    let centre = sheet.centroid();
    let cloth = crate::cloth::Cloth::join(vec![sheet; 2]).unwrap();
    let slope = 0.5;
    let x = cloth
        .positions()
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let d = p - centre;
            if i < 25 {
                // Lowest along its middle row, `crease_gap` above the other's ridge.
                Vector::new(d.x, crease_gap + slope * d.z.abs(), d.z)
            } else {
                let (dx, dz) = (d.x + 0.015, d.z + 0.015);
                Vector::new(dx, -slope * d.x.abs(), dz)
            }
        })
        .collect();
    (cloth, x)
}

/// The creases' crossing edges (the upper sheet's along its middle
/// row, the lower's along its middle column) at positions `x`: the
/// upper one's height over the lower one's where they cross (m).
fn crease_gap(x: &[Vector]) -> f32 {
    let (a, b) = (x[12], x[13]);
    let (p, q) = (x[25 + 7], x[25 + 12]);
    let (s, t, _) = closest(a, b - a, p, q - p).expect("the creases cross");
    (a + (b - a) * s).y - (p + (q - p) * t).y
}

/// A sharp fold's edge is paired with another layer's fold edge near
/// it, and the pass keeps the creases from passing through each other
/// where no particle comes near the other sheet; a flat sheet has no
/// fold edges.
#[test]
fn sharp_folds_keep_crossing_creases_apart() {
    let (cloth, x) = crossing_creases(0.003);
    let contacts = looked_at(&cloth, &x, false);
    let crease = ([12, 13], [25 + 7, 25 + 12]);
    assert!(
        contacts
            .edge_pairs
            .iter()
            .any(|e| (e.edge, e.other) == crease),
        "{:?}",
        contacts.edge_pairs
    );
    let params = layer_params(0.0, 1.0e-3);
    // The upper sheet sinks 4 mm, through the lower one's crease, each
    // particle still over 5 mm from the other sheet's triangles.
    let topology = &*cloth.topology;
    let sunk = |contacts: &SelfContacts| {
        let mut particles = cloth.particles.clone();
        particles.x.copy_from_slice(&x);
        for p in &mut particles.x[..25] {
            p.y -= 0.004;
        }
        assert!(crease_gap(&particles.x) < -0.0009);
        for _ in 0..6 {
            contacts.resolve(&mut particles, topology, &params, Team::ALONE);
        }
        crease_gap(&particles.x)
    };
    let gap = sunk(&contacts);
    assert!(gap > 0.5 * LAYERS, "the creases {gap} m apart");
    // Without the edge pairs the face pairs leave them crossed.
    let mut faces_only = contacts.clone();
    faces_only.edge_pairs.clear();
    assert!(sunk(&faces_only) < 0.0);
    // A flat sheet folds nowhere.
    let flat = ClothBuilder::new(5, 5).build().unwrap();
    let x = flat.positions().to_vec();
    let contacts = looked_at(&flat, &x, false);
    assert!(contacts.folds.is_empty());
}

/// Two 5 × 5 sheets of 10 mm cells joined into one cloth (no sheet
/// shortcut: a grid's one-ring is paired), flat, the second 8 mm over
/// the first (within reach, beyond the thickness: the first is looked
/// at, and no pair between them acts).
fn joined_fine_sheets() -> (crate::cloth::Cloth, Vec<Vector>) {
    joined_sheets((5, 0.04), 2, |i, p| {
        Vector::new(p.x, if i < 25 { 0.0 } else { 0.008 }, p.z)
    })
}

/// A border folded over at a particle is paired with the triangles of
/// that particle it lies over, though it is their corner's neighbour,
/// and the pass keeps it on its side; a flat grid's one-ring pairs
/// (within the look's slack at 10 mm cells) never act.
#[test]
fn a_border_folded_over_at_a_corner_keeps_to_its_side() {
    let (cloth, flat) = joined_fine_sheets();
    let topology = &*cloth.topology;
    let params = layer_params(0.0, 1.0e-3);
    // Flat: pairs of a corner's one-ring exist, and the pass moves
    // nothing.
    let contacts = looked_at(&cloth, &flat, false);
    let one_ring = contacts
        .all_pairs()
        .iter()
        .filter(|p| {
            let tri = topology.triangles[p.triangle as usize];
            contacts.neighbours.adjacent(p.particle, tri)
        })
        .count();
    assert!(one_ring > 0, "no one-ring pairs");
    let mut particles = cloth.particles.clone();
    particles.x.copy_from_slice(&flat);
    let touching = contacts.resolve(&mut particles, topology, &params, Team::ALONE);
    assert_eq!((touching, &particles.x[..]), (0, &flat[..]));
    // The last row's particle 22 folded back over a triangle at its
    // neighbour 21 (and not at 22), 3 mm above its centre.
    let t = topology
        .triangles
        .iter()
        .position(|t| t.contains(&21) && !t.contains(&22) && t.iter().all(|&c| c < 25))
        .expect("a triangle at 21");
    let tri = topology.triangles[t];
    let centre = tri.iter().map(|&c| flat[c as usize]).sum::<Vector>() / 3.0;
    let mut x = flat.clone();
    x[22] = centre + Vector::new(0.0, 0.003, 0.0);
    let contacts = looked_at(&cloth, &x, false);
    assert!(contacts.all_pairs().contains(&SelfPair {
        particle: 22,
        triangle: t as u32,
        side: 1.0
    }));
    // Pulled 1 mm through it, it is pushed back out over a few passes.
    let mut particles = cloth.particles.clone();
    particles.x.copy_from_slice(&x);
    particles.x[22].y = -0.001;
    for _ in 0..4 {
        contacts.resolve(&mut particles, topology, &params, Team::ALONE);
    }
    let height = particles.x[22].y - particles.x[21].y;
    assert!(height > 0.5 * LAYERS, "{height} m above the triangle");
}

/// A particle that crossed a layer within the substep that asked for
/// the look keeps the side it came from: the look takes the sides from
/// where the particles were a substep before, and the pass pushes it
/// back out; taken from where it is, the side would keep it through.
#[test]
fn a_layer_crossed_within_the_substep_before_a_look_is_pushed_back() {
    let (cloth, mut x) = joined_fine_sheets();
    let topology = &*cloth.topology;
    // The upper sheet's middle particle 1 mm under the lower sheet,
    // having come down at 6 m/s over a substep of 1.5 ms (from 8 mm
    // over it).
    let (q, h) = (25 + 12, 1.5e-3);
    x[q].y = -0.001;
    let mut v = vec![Vector::ZERO; x.len()];
    v[q] = Vector::new(0.0, -6.0, 0.0);
    let basis = LookBasis {
        topology,
        particles: x.len(),
        revision: cloth.mass_revision,
        thickness: LAYERS,
        margin: LAYERS,
    };
    let params = layer_params(0.0, h);
    let pushed = |v: &[Vector]| {
        let mut contacts = SelfContacts::default();
        let mut look = None;
        contacts.begin_step(&mut look, &basis, Team::ALONE);
        contacts.find(&mut look, (&x, v, h), &basis, Team::ALONE);
        let sides: Vec<f32> = contacts
            .all_pairs()
            .iter()
            .filter(|p| p.particle == q as u32)
            .map(|p| p.side)
            .collect();
        let mut particles = cloth.particles.clone();
        particles.x.copy_from_slice(&x);
        for _ in 0..4 {
            contacts.resolve(&mut particles, topology, &params, Team::ALONE);
        }
        // Over the lower sheet's particle under it.
        (sides, particles.x[q].y - particles.x[12].y)
    };
    let (sides, y) = pushed(&v);
    assert!(
        !sides.is_empty() && sides.iter().all(|&s| s == 1.0),
        "{sides:?}"
    );
    assert!(y > 0.5 * LAYERS, "{y} m");
    // At rest (no velocity) the look takes the side it is on now.
    let (sides, y) = pushed(&vec![Vector::ZERO; x.len()]);
    assert!(
        !sides.is_empty() && sides.iter().all(|&s| s == -1.0),
        "{sides:?}"
    );
    assert!(y < 0.0, "{y} m");
}

/// The pass eight pairs at a time (a vector test passing over the
/// idle ones) gives the bits of the pass one pair at a time, pass
/// after pass, and as many pairs closer than the thickness; its two
/// parts on two threads too.
#[test]
fn the_pass_by_eights_gives_the_bits_of_one_pair_at_a_time() {
    let (cloth, x) = crumpled_layers();
    let topology = &*cloth.topology;
    let params = layer_params(0.3, 1.0e-3);
    let run = |portable: bool| {
        let contacts = looked_at(&cloth, &x, portable);
        let parts: Vec<Vec<&PartPairs>> =
            (0..3).map(|k| contacts.part_blocks(k).collect()).collect();
        let usable = parts
            .iter()
            .flatten()
            .all(|p| p.pairs.is_empty() || p.lanes.usable(p.pairs.len(), x.len()));
        assert_eq!(usable, !portable && simd_available());
        // Two parts apart, a few pairs across; every pair in one.
        let sizes: Vec<usize> = parts
            .iter()
            .map(|part| part.iter().map(|p| p.pairs.len()).sum())
            .collect();
        assert!(
            sizes[0] > 500 && sizes[1] > 500 && sizes[2] < sizes[0],
            "{sizes:?}"
        );
        assert_eq!(sizes.iter().sum::<usize>(), contacts.pairs);
        let mut particles = cloth.particles.clone();
        particles.x.copy_from_slice(&x);
        for (i, v) in particles.v.iter_mut().enumerate() {
            *v = Vector::new(0.0, -0.3 * ((i % 7) as f32 - 3.0), 0.1);
        }
        let bits = |v: &[Vector]| -> Vec<[u32; 3]> {
            v.iter().map(|p| p.to_array().map(f32::to_bits)).collect()
        };
        let pass = |team: Team| {
            let mut particles = particles.clone();
            let touching: Vec<u32> = (0..4)
                .map(|_| contacts.resolve(&mut particles, topology, &params, team))
                .collect();
            (touching, bits(&particles.x), bits(&particles.v))
        };
        let alone = pass(Team::ALONE);
        assert!(
            contacts.pairs >= PARALLEL_MIN_PAIRS,
            "{} pairs",
            contacts.pairs
        );
        // The two parts on two threads: the same bits.
        #[cfg(feature = "parallel")]
        assert_eq!(crate::parallel::on_threads(2, pass), alone);
        alone
    };
    let (batched, one) = (run(false), run(true));
    assert!(one.0[0] > 50, "only {:?} pairs touching", one.0);
    assert_eq!(batched, one);
}

/// Over a triangle a particle keeps the whole thickness; out in the rim
/// the share falls as a quarter circle, to none at the rim's edge (over
/// one edge or two), with no step anywhere on the way out.
#[test]
fn the_rim_thins_the_layer_to_nothing_at_its_edge() {
    let slack = [0.2, 0.3, 0.25];
    assert_eq!(rim_taper([0.2, 0.3, 0.5], slack), 1.0);
    assert_eq!(rim_taper([0.0, 0.5, 0.5], slack), 1.0);
    // Half-way out over the first edge: √(1 − ¼).
    let half = rim_taper([-0.1, 0.6, 0.5], slack);
    assert!((half - 0.75f32.sqrt()).abs() < 1e-6, "{half}");
    assert_eq!(rim_taper([-0.2, 0.7, 0.5], slack), 0.0);
    // Out over two edges, at 0.6 of the rim over each: √(1 − 0.72).
    let corner = rim_taper([-0.12, -0.18, 1.3], slack);
    assert!((corner - 0.28f32.sqrt()).abs() < 1e-5, "{corner}");
    // Walking out over the first edge in small steps: falling, never by
    // more than a step's worth near the triangle.
    let mut last = 1.0;
    for k in 0..=100 {
        let u = -0.2 * k as f32 / 100.0;
        let share = rim_taper([u, 0.5 - u, 0.5], slack);
        assert!(
            share <= last && (k > 90 || last - share < 0.05),
            "{k}: {share}"
        );
        last = share;
    }
    assert_eq!(last, 0.0);
}

/// Two triangles folded about their common edge by `angle` (radians)
/// between their normals.
fn folded_pair(angle: f32) -> (Vec<[u32; 3]>, Vec<Vector>) {
    let (s, c) = angle.sin_cos();
    let x = vec![
        Vector::new(0.0, 0.0, 0.0),
        Vector::new(0.0, 0.0, 1.0),
        Vector::new(-1.0, 0.0, 0.5),
        // The second triangle's far corner turned about the edge (z).
        Vector::new(c, s, 0.5),
    ];
    (vec![[0, 1, 2], [1, 0, 3]], x)
}

/// A fold's edge keeps none of the thickness up to the look's threshold,
/// all of it from the full fold on, and grows in between.
#[test]
fn a_fold_keeps_more_of_the_thickness_the_sharper_it_is() {
    let share = |angle: f32| {
        let (triangles, x) = folded_pair(angle);
        fold_share([0, 1], &triangles, &x)
    };
    assert_eq!(share(0.0), 0.0);
    assert_eq!(share(SHARP_FOLD * 0.99), 0.0);
    let middle = share(0.5 * (SHARP_FOLD + FULL_FOLD));
    assert!(middle > 0.4 && middle < 0.6, "{middle}");
    assert_eq!(share(FULL_FOLD * 1.01), 1.0);
    assert_eq!(share(2.0), 1.0);
    // A triangle of no area counts as sharp, as the look counts it.
    let (triangles, mut x) = folded_pair(0.0);
    x[2] = x[0];
    assert_eq!(fold_share([0, 1], &triangles, &x), 1.0);
}
