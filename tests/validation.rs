//! Bad input gets a clear error value, never a panic.

use cloth3d::prelude::*;

#[test]
fn builder_rejects_bad_grids_sizes_and_masses() {
    assert!(matches!(
        ClothBuilder::new(1, 5).build(),
        Err(ClothError::GridTooSmall { cols: 1, rows: 5 })
    ));
    assert!(matches!(
        ClothBuilder::new(5, 0).build(),
        Err(ClothError::GridTooSmall { .. })
    ));
    assert!(matches!(
        ClothBuilder::new(usize::MAX, 3).build(),
        Err(ClothError::GridTooLarge { .. })
    ));
    for (w, h) in [
        (0.0, 1.0),
        (1.0, -2.0),
        (f32::NAN, 1.0),
        (1.0, f32::INFINITY),
    ] {
        let err = ClothBuilder::new(4, 4).size(w, h).build().unwrap_err();
        assert!(
            matches!(err, ClothError::InvalidParameter { .. }),
            "{w}×{h}: {err}"
        );
    }
    for m in [0.0, -1.0, f32::NAN] {
        let err = ClothBuilder::new(4, 4).total_mass(m).build().unwrap_err();
        assert!(err.to_string().contains("total mass"), "{err}");
    }
    let err = ClothBuilder::new(4, 4)
        .pose(Pose::from_translation(Vector::new(f32::NAN, 0.0, 0.0)))
        .build()
        .unwrap_err();
    assert!(matches!(err, ClothError::NonFinite { .. }));
}

#[test]
fn materials_reject_bad_stiffness_damping_and_density() {
    let mut m = Material::cotton();
    m.stretch.stiffness = 0.0;
    let err = ClothBuilder::new(4, 4).material(m).build().unwrap_err();
    assert!(err.to_string().contains("stretch stiffness"), "{err}");
    let mut m = Material::cotton();
    m.bend.damping = -1.0;
    assert!(ClothBuilder::new(4, 4)
        .material(m)
        .build()
        .unwrap_err()
        .to_string()
        .contains("bend damping"));
    let mut m = Material::cotton();
    m.density = f32::NAN;
    assert!(m.validate().is_err());
    assert!(Material::by_name("kevlar")
        .unwrap_err()
        .to_string()
        .contains("silk"));
    for m in Material::presets() {
        m.validate().unwrap();
        assert_eq!(Material::by_name(&m.name).unwrap(), m);
    }
}

#[test]
fn step_rejects_bad_parameters_and_keeps_the_cloth() {
    let mut cloth = Simulation::new(ClothBuilder::new(5, 5).build().unwrap());
    let before = cloth.clone();
    for dt in [0.0, -0.01, f32::NAN, f32::INFINITY] {
        assert!(cloth.step(dt, &[]).is_err(), "dt = {dt}");
    }
    cloth.params.gravity = Vector::new(0.0, f32::NAN, 0.0);
    assert!(matches!(
        cloth.step(0.01, &[]),
        Err(ClothError::NonFinite { .. })
    ));
    cloth.params.gravity = Vector::new(0.0, -9.81, 0.0);
    cloth.solver.settings.substeps = Substeps::Fixed(0);
    assert!(cloth.step(0.01, &[]).is_err());
    cloth.solver.settings.substeps = Substeps::Auto;
    cloth.material.shear.stiffness = -5.0;
    assert!(cloth.step(0.01, &[]).is_err());
    cloth.material.shear.stiffness = 150.0;
    let bad = Obstacle::ball(Vector::new(f32::NAN, 0.0, 0.0), 0.3);
    assert!(matches!(
        cloth.step(0.01, &[bad]),
        Err(ClothError::InvalidObstacle { index: 0, .. })
    ));
    let bad = Obstacle::ball(Vector::ZERO, 0.3).with_friction(-1.0);
    assert!(cloth.step(0.01, &[bad]).is_err());
    assert_eq!(
        cloth.positions(),
        before.positions(),
        "a rejected step must not move anything"
    );
    assert!(cloth.step(0.01, &[]).is_ok());
}

#[test]
fn a_diverging_step_restores_the_cloth_and_suggests_substeps() {
    let mut cloth = Simulation::new(
        ClothBuilder::new(24, 24)
            .pins(PinPreset::TwoCorners)
            .build()
            .unwrap(),
    )
    .with_integrator(Integrator::ExplicitEuler);
    cloth.material.stretch.stiffness = 1.0e5;
    cloth.solver.settings.substeps = Substeps::Fixed(1);
    let mut before = cloth.positions().to_vec();
    let mut result = Ok(Default::default());
    for _ in 0..30 {
        before = cloth.positions().to_vec();
        result = cloth.step(1.0 / 60.0, &[]);
        if result.is_err() {
            break;
        }
    }
    let err = result.unwrap_err();
    match err {
        ClothError::Diverged {
            integrator,
            substeps,
            suggested_substeps,
            ..
        } => {
            assert_eq!(integrator, "explicit-euler");
            assert_eq!(substeps, 1);
            assert!(suggested_substeps > 1);
        }
        other => panic!("expected Diverged, got {other}"),
    }
    assert_eq!(cloth.positions(), &before[..]);
    assert!(cloth.is_finite());
    // The user changes the parameters and steps again.
    cloth.set_integrator(Integrator::SymplecticEuler);
    cloth.solver.settings.substeps = Substeps::Auto;
    cloth.step(1.0 / 60.0, &[]).unwrap();
    assert!(cloth.is_finite());
}

#[test]
fn from_parts_checks_every_index() {
    let spring = |a, b, rest_length| Spring {
        a,
        b,
        rest_length,
        kind: SpringKind::Stretch,
    };
    let pos = vec![Vector::ZERO, Vector::X];
    let mk = |springs, tris, masses: Vec<f32>| {
        Cloth::from_parts(pos.clone(), masses, springs, tris, Material::cotton())
    };
    assert!(mk(vec![spring(0, 2, 1.0)], vec![], vec![1.0, 1.0]).is_err());
    assert!(mk(vec![spring(1, 1, 1.0)], vec![], vec![1.0, 1.0]).is_err());
    assert!(mk(vec![spring(0, 1, 0.0)], vec![], vec![1.0, 1.0]).is_err());
    assert!(mk(vec![], vec![[0, 1, 5]], vec![1.0, 1.0]).is_err());
    assert!(mk(vec![], vec![], vec![1.0]).is_err());
    assert!(mk(vec![], vec![], vec![1.0, 0.0]).is_err());
    assert!(mk(vec![spring(0, 1, 1.0)], vec![], vec![1.0, 2.0]).is_ok());
}

#[test]
fn divergence_advice_fits_the_integrator() {
    let err = |integrator| ClothError::Diverged {
        integrator,
        dt: 1.0 / 60.0,
        substeps: 1,
        suggested_substeps: 4,
    };
    let explicit = err("symplectic-euler").to_string();
    assert!(
        explicit.contains("--substeps 4") && explicit.contains("stable at any step (xpbd"),
        "{explicit}"
    );
    let implicit = err("implicit-euler").to_string();
    assert!(
        implicit.contains("--substeps 4") && !implicit.contains("fast-mass-spring"),
        "{implicit}"
    );
}
