//! Topology is shared between cloths built alike: one copy in memory, each
//! cloth with its own particles, stepped by its own solver.

use std::sync::Arc;

use cloth3d::prelude::*;

#[test]
fn cloths_built_alike_share_one_topology_and_move_apart() {
    let build = |y: f32| {
        ClothBuilder::new(12, 12)
            .horizontal(Vector::new(0.0, y, 0.0))
            .pins(PinPreset::TwoCorners)
            .build()
            .unwrap()
    };
    let (mut a, mut b, mut own) = (build(0.6), build(1.6), build(1.6));
    b.share_topology(Arc::clone(a.topology())).unwrap();
    assert!(Arc::ptr_eq(a.topology(), b.topology()));
    assert!(!Arc::ptr_eq(a.topology(), own.topology()));
    let mut solvers = [
        ClothSolver::default(),
        ClothSolver::default(),
        ClothSolver::default(),
    ];
    for _ in 0..30 {
        for (cloth, solver) in [&mut a, &mut b, &mut own].into_iter().zip(&mut solvers) {
            solver.step(cloth, 1.0 / 60.0, &[]).unwrap();
        }
    }
    // Each moved on its own: b hangs 1 m above a, as it started.
    let offset = b
        .positions()
        .iter()
        .zip(a.positions())
        .map(|(pb, pa)| (*pb - *pa - Vector::new(0.0, 1.0, 0.0)).length())
        .fold(0.0, f32::max);
    assert!(offset < 1e-3, "{offset}");
    assert!(a.centroid().y < 0.5, "a fell: {}", a.centroid().y);
    // Sharing changes nothing: b computes the bits of a cloth with its own copy.
    assert_eq!(b.positions(), own.positions());
    assert_eq!(b.velocities(), own.velocities());
    // Still one topology, unchanged by stepping.
    assert!(Arc::ptr_eq(a.topology(), b.topology()));
}

#[test]
fn a_different_topology_is_refused() {
    let mut a = ClothBuilder::new(12, 12).build().unwrap();
    let other = ClothBuilder::new(12, 13).build().unwrap();
    let before = Arc::clone(a.topology());
    assert!(matches!(
        a.share_topology(Arc::clone(other.topology())),
        Err(ClothError::InvalidTopology { .. })
    ));
    assert!(Arc::ptr_eq(a.topology(), &before), "the cloth kept its own");
}
