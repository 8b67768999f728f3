//! Force laws: internal forces balance, wind acts along the normal.

use cloth3d::forces::{spring_force, wind_force_on_moving_triangle, wind_force_on_triangle};
use cloth3d::prelude::*;

/// A cloth with scrambled positions and velocities, no external force.
fn scrambled_cloth() -> Simulation {
    let mut cloth = Simulation::new(ClothBuilder::new(9, 7).size(0.8, 0.6).build().unwrap());
    cloth.params.gravity = Vector::ZERO;
    cloth.params.air_drag = 0.0;
    cloth.material.stretch.damping = 0.3;
    cloth.material.shear.damping = 0.2;
    for i in 0..cloth.particle_count() {
        let s = i as f32;
        let p = cloth.positions()[i]
            + Vector::new((s * 1.7).sin(), (s * 0.9).cos(), (s * 2.3).sin()) * 0.03;
        cloth.set_position(i, p).unwrap();
        cloth
            .set_velocity(
                i,
                Vector::new((s * 0.7).cos(), (s * 1.3).sin(), (s * 0.4).cos()),
            )
            .unwrap();
    }
    cloth
}

#[test]
fn internal_spring_forces_sum_to_zero() {
    let cloth = scrambled_cloth();
    let f = cloth.forces();
    let sum: Vector = f.iter().copied().sum();
    let largest = f.iter().map(|f| f.length()).fold(0.0, f32::max);
    assert!(
        largest > 1.0,
        "the scrambled cloth should be under real tension ({largest} N)"
    );
    assert!(
        sum.length() < 1e-4 * largest * f.len() as f32,
        "net internal force {sum:?}"
    );
}

#[test]
fn momentum_is_conserved_without_external_forces() {
    let mut cloth = scrambled_cloth();
    cloth.solver.settings.substeps = Substeps::Auto;
    let p0 = cloth.momentum();
    for integrator in Integrator::ALL {
        cloth.set_integrator(integrator);
        for _ in 0..20 {
            cloth.step(1.0 / 60.0, &[]).unwrap();
        }
        let p = cloth.momentum();
        assert!(
            (p - p0).length() < 1e-3 * (1.0 + p0.length()),
            "{integrator}: momentum {p0:?} became {p:?}"
        );
    }
}

#[test]
fn spring_force_is_hooke_plus_damping_along_the_spring() {
    let params = SpringParams::new(50.0, 2.0);
    let xa = Vector::ZERO;
    let xb = Vector::new(0.0, 1.2, 0.0);
    let f = spring_force(xa, xb, Vector::ZERO, Vector::ZERO, 1.0, params);
    assert!(
        (f - Vector::new(0.0, 10.0, 0.0)).length() < 1e-4,
        "stretched by 0.2: {f:?}"
    );
    // Separating at 1 m/s along the spring: damping pulls a toward b by c·1.
    let f = spring_force(
        xa,
        xb,
        Vector::ZERO,
        Vector::new(0.3, 1.0, 0.0),
        1.2,
        params,
    );
    assert!(
        (f - Vector::new(0.0, 2.0, 0.0)).length() < 1e-4,
        "damping only: {f:?}"
    );
    // Coincident ends give no force rather than NaN.
    assert_eq!(
        spring_force(xa, xa, Vector::ZERO, Vector::X, 1.0, params),
        Vector::ZERO
    );
}

#[test]
fn wind_pushes_along_the_normal_in_proportion_to_n_dot_d() {
    // A right triangle of area 0.5 m² in the x–y plane: unit normal +z.
    let (p0, p1, p2) = (Vector::ZERO, Vector::X, Vector::Y);
    let n = Vector::Z;
    for deg in [0.0f32, 20.0, 45.0, 70.0, 89.0, 120.0] {
        let angle = deg.to_radians();
        let d = Vector::new(angle.sin(), 0.0, angle.cos());
        let wind = Wind::new(d * 3.0, 8.0);
        let f = wind_force_on_triangle(p0, p1, p2, &wind);
        let expected = 8.0 * 0.5 * n.dot(d);
        assert!(
            f.cross(n).length() < 1e-5,
            "{deg}°: force {f:?} not along the normal"
        );
        assert!(
            (f.dot(n) - expected).abs() < 1e-5,
            "{deg}°: {} N, expected {expected} N",
            f.dot(n)
        );
    }
    // Wind in the triangle's plane exerts nothing.
    let f = wind_force_on_triangle(p0, p1, p2, &Wind::new(Vector::new(1.0, 1.0, 0.0), 8.0));
    assert!(f.length() < 1e-6, "in-plane wind gave {f:?}");
}

#[test]
fn wind_moves_a_free_cloth_along_the_normal_component() {
    let mut cloth = Simulation::new(
        ClothBuilder::new(6, 6)
            .vertical(Vector::ZERO)
            .build()
            .unwrap(),
    );
    cloth.params.gravity = Vector::ZERO;
    cloth.params.wind = Wind::new(Vector::new(1.0, 0.0, 1.0), 4.0);
    for _ in 0..10 {
        cloth.step(1.0 / 60.0, &[]).unwrap();
    }
    let c = cloth.centroid();
    // The cloth faces +z: it moves along +z only.
    assert!(c.z > 0.01, "centroid {c:?}");
    assert!(
        c.x.abs() < 1e-3 * c.z.abs().max(1.0),
        "moved sideways: {c:?}"
    );
}

/// With an air speed the law acts on the air's velocity relative to the
/// triangle: still, it is the plain law; moving with the air, nothing;
/// moving against it at the air's speed, four times the pressure; edge-on,
/// only the skin friction, along the wind.
#[test]
fn wind_acts_on_the_air_relative_to_the_triangle() {
    // A unit right triangle in the x–y plane facing +z: area 0.5 m².
    let p = [Vector::ZERO, Vector::X, Vector::Y];
    let wind = Wind::new(Vector::Z, 8.0).with_air(4.0, 0.2, 0.0, 1);
    let still = wind_force_on_moving_triangle(p, Vector::ZERO, &wind, 0.0);
    assert!(
        (still - Vector::new(0.0, 0.0, 4.0)).length() < 1e-5,
        "{still:?}"
    );
    let along = wind_force_on_moving_triangle(p, Vector::new(0.0, 0.0, 4.0), &wind, 0.0);
    assert!(along.length() < 1e-5, "{along:?}");
    let against = wind_force_on_moving_triangle(p, Vector::new(0.0, 0.0, -4.0), &wind, 0.0);
    assert!(
        (against - Vector::new(0.0, 0.0, 16.0)).length() < 1e-4,
        "{against:?}"
    );
    // Edge-on: the wind along x over a triangle facing +z.
    let edge_on = Wind::new(Vector::X, 8.0).with_air(4.0, 0.2, 0.0, 1);
    let skin = wind_force_on_moving_triangle(p, Vector::ZERO, &edge_on, 0.0);
    assert!(
        (skin - Vector::new(0.8, 0.0, 0.0)).length() < 1e-5,
        "{skin:?}"
    );
    // Gusts vary the force in time, the same way every run.
    let gusty = Wind::new(Vector::Z, 8.0).with_air(4.0, 0.2, 0.5, 7);
    let at = |t| wind_force_on_moving_triangle(p, Vector::ZERO, &gusty, t);
    assert_ne!(at(0.0), at(0.5));
    assert_eq!(at(0.5), at(0.5));
    // Without an air speed the law ignores the motion, as before.
    let plain = Wind::new(Vector::Z, 8.0);
    assert_eq!(
        wind_force_on_moving_triangle(p, Vector::new(0.0, 0.0, 4.0), &plain, 0.0),
        wind_force_on_triangle(p[0], p[1], p[2], &plain)
    );
}
