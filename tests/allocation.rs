//! A warmed-up step allocates nothing, for every integrator.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

mod common;

use cloth3d::prelude::*;
use cloth3d::scenes::SceneKind;
use common::scene_with;

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_warmed_up_step_allocates_nothing() {
    for integrator in Integrator::ALL {
        for kind in [SceneKind::Drape, SceneKind::Flag] {
            let mut scene = scene_with(kind, 12, integrator);
            // Parallel evaluation would allocate in rayon's machinery.
            scene.solver.settings.parallel = false;
            // Warm up until the drape reaches its ball: the measured steps
            // then have contacts, friction and, for fast mass-spring,
            // refactorisations of the global matrix.
            for _ in 0..18 {
                (scene.solver)
                    .step(&mut scene.cloth, scene.dt, &scene.obstacles)
                    .unwrap();
            }
            let before = ALLOCATIONS.load(Ordering::Relaxed);
            let mut contacts = 0;
            for _ in 0..5 {
                contacts += (scene.solver)
                    .step(&mut scene.cloth, scene.dt, &scene.obstacles)
                    .unwrap()
                    .contacts;
            }
            let allocated = ALLOCATIONS.load(Ordering::Relaxed) - before;
            if kind == SceneKind::Drape {
                assert!(contacts > 0, "{integrator}: no contact measured");
            }
            assert_eq!(
                allocated,
                0,
                "{integrator} on {}: {allocated} allocations in 5 steps",
                kind.name()
            );
        }
    }
    warmed_up_self_collision_allocates_nothing();
}

/// Self-collision's looks and passes allocate nothing once they have seen
/// as many pairs: the fold's layers in contact, on one thread. (In the one
/// test: the counter is the process's.)
fn warmed_up_self_collision_allocates_nothing() {
    let mut scene = cloth3d::scenes::Scene::build(SceneKind::Fold, &Default::default()).unwrap();
    scene.solver.settings.parallel = false;
    // The halves meet under the bar from frame 20 on. Run past the frames
    // to be measured once, so that the pair lists have seen them, then
    // measure them again from the same cloth.
    for _ in 0..25 {
        scene.step_frame().unwrap();
    }
    let at_25 = scene.cloth.clone();
    for _ in 0..10 {
        scene.step_frame().unwrap();
    }
    scene.cloth = at_25;
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let mut touching = 0;
    for _ in 0..5 {
        touching += (scene.solver)
            .step(&mut scene.cloth, scene.dt, &scene.obstacles)
            .unwrap()
            .self_contacts;
    }
    let allocated = ALLOCATIONS.load(Ordering::Relaxed) - before;
    assert!(touching > 0, "the fold's layers do not touch");
    assert_eq!(allocated, 0, "{allocated} allocations in 5 steps");
}
