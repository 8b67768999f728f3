//! Pins: presets, pinning at run time, and a hanging cloth coming to rest.

use cloth3d::prelude::*;

#[test]
fn presets_pin_the_figures_of_the_scenes() {
    let cells = |p: PinPreset| p.cells(33, 33);
    assert_eq!(cells(PinPreset::Center), vec![(16, 16)]);
    assert_eq!(cells(PinPreset::TwoCorners), vec![(0, 0), (0, 32)]);
    assert_eq!(
        cells(PinPreset::FourCorners),
        vec![(0, 0), (0, 32), (32, 0), (32, 32)]
    );
    assert_eq!(
        cells(PinPreset::FourCenter),
        vec![(8, 8), (8, 24), (24, 8), (24, 24)]
    );
    assert_eq!(cells(PinPreset::CenterRow).len(), 33);
    assert!(cells(PinPreset::CenterRow).iter().all(|&(r, _)| r == 16));
    assert!(PinPreset::FlagColumn
        .cells(32, 20)
        .iter()
        .all(|&(_, c)| c == 0));
    assert_eq!(PinPreset::CurtainRow.cells(40, 40).len(), 40);
    assert!(
        PinPreset::FourCorners.cells(0, 5).is_empty(),
        "no panic on an empty grid"
    );
    for p in PinPreset::ALL {
        assert_eq!(PinPreset::from_name(p.name()).unwrap(), p);
    }
}

#[test]
fn pinned_particles_never_move_and_unpinned_ones_fall() {
    let mut cloth = Simulation::new(
        ClothBuilder::new(10, 10)
            .pins(PinPreset::TwoCorners)
            .build()
            .unwrap(),
    );
    let pinned = cloth.pinned();
    assert_eq!(pinned, vec![0, 9]);
    let before: Vec<Vector> = pinned.iter().map(|&i| cloth.positions()[i]).collect();
    let far_corner = cloth.positions()[99];
    let mut swing = 0.0f32;
    for integrator in Integrator::ALL {
        cloth.set_integrator(integrator);
        for _ in 0..20 {
            cloth.step(1.0 / 60.0, &[]).unwrap();
            swing = swing.max((cloth.positions()[99] - far_corner).length());
        }
    }
    for (k, &i) in pinned.iter().enumerate() {
        assert_eq!(cloth.positions()[i], before[k], "pinned particle {i} moved");
    }
    // The far corner is free: it swings down through the pins' plane, a 1 m pendulum.
    assert!(swing > 0.5, "far corner moved only {swing} m");
    // Unpin at run time: the corner falls too.
    cloth.unpin_cell(0, 9).unwrap();
    for _ in 0..30 {
        cloth.step(1.0 / 60.0, &[]).unwrap();
    }
    assert!(cloth.positions()[9].y < before[1].y - 0.05);
    assert_eq!(cloth.positions()[0], before[0]);
    // Pin by index while moving: it stops where it is.
    cloth.pin(50).unwrap();
    let here = cloth.positions()[50];
    cloth.step(1.0 / 60.0, &[]).unwrap();
    assert_eq!(cloth.positions()[50], here);
}

#[test]
fn out_of_range_pins_are_errors() {
    let mut cloth = Simulation::new(ClothBuilder::new(4, 3).build().unwrap());
    assert!(matches!(
        cloth.pin(12),
        Err(ClothError::ParticleOutOfRange {
            index: 12,
            count: 12
        })
    ));
    assert!(matches!(
        cloth.pin_cell(3, 0),
        Err(ClothError::CellOutOfRange { .. })
    ));
    assert!(matches!(
        cloth.pin_cell(0, 4),
        Err(ClothError::CellOutOfRange { .. })
    ));
    assert!(ClothBuilder::new(4, 3).pin(99).build().is_err());
    assert!(
        cloth.pinned().is_empty(),
        "a failed pin must leave the cloth as it was"
    );
}

#[test]
fn cloth_pinned_along_its_top_row_comes_to_rest_with_bounded_stretch() {
    let mut cloth = Simulation::new(
        ClothBuilder::new(16, 16)
            .vertical(Vector::new(0.0, 1.0, 0.0))
            .pins(PinPreset::CurtainRow)
            .build()
            .unwrap(),
    );
    cloth.params.air_drag = 2.0;
    let top: Vec<Vector> = (0..16).map(|c| cloth.positions()[c]).collect();
    // Give it a push so it has something to come to rest from.
    for i in 16..cloth.particle_count() {
        cloth.set_velocity(i, Vector::new(0.0, 0.0, 1.0)).unwrap();
    }
    for _ in 0..600 {
        cloth.step(1.0 / 60.0, &[]).unwrap();
    }
    let e = cloth.energy();
    assert!(e.kinetic < 1e-4, "still moving: {} J kinetic", e.kinetic);
    let stretch = cloth.max_strain(SpringKind::Stretch);
    assert!(stretch > 0.0 && stretch < 0.05, "max stretch {stretch}");
    assert_eq!(&cloth.positions()[..16], &top[..]);
    // It hangs straight down from the rail.
    let bottom = cloth.positions()[15 * 16 + 8];
    assert!(
        bottom.z.abs() < 0.01 && bottom.y < 0.6,
        "bottom middle at {bottom:?}"
    );
}

/// Peak stretch over every frame of the `pins` scene at `n` particles a
/// row, hung by `pins`, with the crate's default integrator and settings.
fn peak_stretch_hung_by(pins: PinPreset, n: usize) -> f32 {
    peak_stretch_hung_with(pins, n, SolverSettings::default().integrator)
}

/// [`peak_stretch_hung_by`] with `integrator` at its default settings.
fn peak_stretch_hung_with(pins: PinPreset, n: usize, integrator: Integrator) -> f32 {
    use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
    let options = SceneOptions {
        n: Some(n),
        variant: Some(pins),
        integrator: Some(integrator),
        ..Default::default()
    };
    let mut scene = Scene::build(SceneKind::Pins, &options).unwrap();
    assert_eq!(scene.solver.settings.integrator, integrator);
    let start = scene.cloth.positions().to_vec();
    let mut peak = 0.0f32;
    for _ in 0..scene.frames {
        scene.step_frame().unwrap();
        peak = peak.max(scene.cloth.max_strain(SpringKind::Stretch));
    }
    // It fell onto its pins and sags or swings from them.
    let moved = start
        .iter()
        .zip(scene.cloth.positions())
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0f32, f32::max);
    assert!(moved > 0.05, "hung by {pins:?} at N = {n}: moved {moved} m");
    peak
}

#[test]
fn a_fine_sheet_hung_by_its_corners_swings_under_five_percent_stretch() {
    // A sheet caught by its corners as it falls hangs on long runs of
    // springs at their limit from each pin: these peaked at 9.8% and
    // 12.7% when the limit weighed every particle alike (they need the
    // pins' support carried out through the cloth, `pin_support.rs`).
    // At N = 128 two corners peaked at 13% with the 16 substeps of a
    // coarser sheet (they need the side rule's 28, `stability.rs`).
    for (pins, n) in [
        (PinPreset::TwoCorners, 64),
        (PinPreset::FourCorners, 96),
        (PinPreset::TwoCorners, 128),
    ] {
        let peak = peak_stretch_hung_by(pins, n);
        assert!(
            peak < 0.05,
            "hung by {pins:?} at N = {n}: peak stretch {peak}"
        );
    }
}

/// The `pins` sheet of `n` particles a side hung by two corners with
/// `integrator` peaks under 5% stretch over its run.
fn assert_hangs_under_five_percent(integrator: Integrator, n: usize) {
    let peak = peak_stretch_hung_with(PinPreset::TwoCorners, n, integrator);
    assert!(
        peak < 0.05,
        "{} at N = {n}: peak stretch {:.2}%",
        integrator.name(),
        100.0 * peak
    );
}

#[test]
fn every_integrator_holds_a_sheet_hung_by_two_corners_under_five_percent() {
    // The integrators that do not hold the limit in their own substep get
    // it after it, weighted by the pins' support and over-relaxed until it
    // holds (`strain_limit.rs`); with four plain passes weighted by mass
    // the 33² sheet peaked at 15–20% with each of them but explicit Euler.
    for integrator in Integrator::ALL {
        assert_hangs_under_five_percent(integrator, 33);
    }
}

#[test]
fn the_one_step_integrators_hold_a_finer_sheet_hung_by_two_corners_under_five_percent() {
    // One step a frame swings a 64² sheet further than 80 passes of the
    // limit carry the pins' support: 16.8% with fast mass-spring and 20.6%
    // with implicit Euler; the passes now go by the step's length
    // (`strain_limit::relaxed_passes`: 1280 for a 60 Hz step).
    for integrator in [Integrator::FastMassSpring, Integrator::ImplicitEuler] {
        assert_hangs_under_five_percent(integrator, 64);
    }
}
