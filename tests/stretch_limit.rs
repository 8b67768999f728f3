//! The material's stretch limit: woven presets hold their stretch springs
//! within 4.5% through a landing that stretches plain springs further, with
//! the small-steps solver and with symplectic Euler; a bad limit is refused.

use cloth3d::cloth::WOVEN_STRETCH_LIMIT;
use cloth3d::metrics::max_stretch;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};

/// The largest stretch over every frame of the drape at N = 48 landing on its ball.
fn landing_stretch(integrator: Integrator, material: Material) -> f32 {
    landing_stretch_at(48, integrator, material).0
}

/// The largest stretch over every frame of the drape at N = `n` landing
/// on its ball (45 frames), and the substeps of its last frame.
fn landing_stretch_at(n: usize, integrator: Integrator, material: Material) -> (f32, u32) {
    let options = SceneOptions {
        n: Some(n),
        integrator: Some(integrator),
        material: Some(material),
        frames: Some(45),
        ..Default::default()
    };
    let mut scene = Scene::build(SceneKind::Drape, &options).unwrap();
    let (mut worst, mut substeps) = (0.0f32, 0);
    for _ in 0..45 {
        substeps = scene.step_frame().unwrap().substeps;
        worst = worst.max(max_stretch(&scene.cloth));
    }
    (worst, substeps)
}

/// A large cloth lands with its edges whipping round the ball: a long run
/// of springs along an edge over the limit, which the Gauss–Seidel passes
/// of the limit carry back a spring or two a pass. The small-steps solver
/// then calls them again while a spring is still far over, and steps the
/// 128 × 128 drape in 12 substeps a frame whatever the material's
/// stiffness (`stability.rs`, `XPBD_LIMITED_CHAIN_SUBSTEPS_PER_SECOND`;
/// measured with one call: 6.7% at 16; the 24 substeps it took before
/// held 4.8%).
#[test]
fn a_large_cloth_lands_within_its_limit_at_the_automatic_substeps() {
    let materials = [
        (Material::cotton(), 12),
        (Material::silk(), 12),
        (Material::canvas(), 12),
    ];
    for (material, substeps) in materials {
        let name = material.name.clone();
        let (worst, taken) = landing_stretch_at(128, Integrator::Xpbd, material);
        assert_eq!(taken, substeps, "{name}");
        assert!(worst < 0.05, "{name}: {worst}");
    }
}

/// Cotton, and a cotton whose stretch springs are half as stiff (the
/// limit is the material's, whatever its springs): the landing holds both
/// within the limit, and the softer one without it stretches further.
#[test]
fn cotton_stays_within_its_stretch_limit_through_the_landing() {
    let cotton = Material::cotton();
    assert_eq!(cotton.stretch_limit, Some(WOVEN_STRETCH_LIMIT));
    let mut soft = cotton.clone();
    soft.stretch.stiffness *= 0.5;
    for integrator in [Integrator::Xpbd, Integrator::SymplecticEuler] {
        // The limit is held after every substep and again after the
        // contacts, which may still stretch a spring by a hair.
        for material in [&cotton, &soft] {
            let limited = landing_stretch(integrator, material.clone());
            assert!(limited < 0.05, "{integrator}: {limited}");
        }
        // Without it the same landing stretches further: the limit acts
        // (measured on the soft one: 7.9% for xpbd and 9.3% for
        // symplectic Euler; under 5% with it).
        let limited = landing_stretch(integrator, soft.clone());
        let free = landing_stretch(integrator, soft.clone().with_stretch_limit(None));
        assert!(
            free > limited + 0.005,
            "{integrator}: {free} without, {limited} with"
        );
    }
}

/// The `curtain`'s ball moves 33 mm a frame through the cloth: an
/// integrator with one substep a frame (fast mass-spring, implicit Euler)
/// had its contacts push a patch of cloth out of the ball after the
/// substep's limit, each particle alone, and the springs from it ended
/// far over the limit: 141% and 11.4% at N = 24 (214% and 18% at the
/// scene's 40). The cloth now follows what pushed it
/// (`solver/contact_follow.rs`): every integrator holds the limit through
/// the push, and nothing is left inside the ball.
#[test]
fn a_curtain_pushed_by_its_moving_ball_stays_within_the_limit_with_every_integrator() {
    for integrator in Integrator::ALL {
        let options = SceneOptions {
            n: Some(24),
            integrator: Some(integrator),
            ..Default::default()
        };
        let mut scene = Scene::build(SceneKind::Curtain, &options).unwrap();
        let (mut stretch, mut deepest) = (0.0f32, 0.0f32);
        // The ball reaches the cloth in frame 30 and has passed by frame 55.
        for _ in 0..60 {
            scene.step_frame().unwrap();
            stretch = stretch.max(max_stretch(&scene.cloth));
            deepest = deepest.max(scene.max_penetration());
        }
        assert!(stretch < 0.05, "{integrator}: {stretch}");
        assert!(deepest <= 1.0e-3, "{integrator}: {deepest} m inside");
        // The ball did reach it: the cloth was pushed along z.
        let z = scene
            .cloth
            .positions()
            .iter()
            .map(|x| x.z)
            .fold(f32::MIN, f32::max);
        assert!(
            z > 0.1,
            "{integrator}: the curtain reached z = {z} m at most"
        );
    }
}

#[test]
fn a_stretch_limit_must_be_a_positive_strain() {
    for bad in [0.0, -0.1, f32::NAN, f32::INFINITY] {
        let m = Material::cotton().with_stretch_limit(Some(bad));
        assert!(m.validate().is_err(), "{bad}");
        assert!(ClothBuilder::new(4, 4).material(m).build().is_err());
    }
    assert!(Material::rubber().stretch_limit.is_none());
}

/// The root-free test of the solver's divergence check says what the
/// largest strain says, either side of it, for each kind of spring.
#[test]
fn strain_below_agrees_with_the_largest_strain() {
    let mut cloth = ClothBuilder::new(5, 4).build().unwrap();
    let far = cloth.positions()[7] + Vector::new(0.13, -0.05, 0.02);
    cloth.set_position(7, far).unwrap();
    for kind in [SpringKind::Stretch, SpringKind::Shear, SpringKind::Bend] {
        let most = cloth.max_strain(kind);
        assert!(most > 0.05, "{kind:?}: {most}");
        for s in [0.5 * most, 0.99 * most, 1.01 * most, 2.0 * most] {
            assert_eq!(
                cloth.strain_below(kind, s),
                most < s,
                "{kind:?} at {s} (largest {most})"
            );
        }
    }
}
