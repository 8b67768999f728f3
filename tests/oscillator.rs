//! A single spring-mass oscillator against its analytic solution: period,
//! damped decay, and energy over long runs.

mod common;

use cloth3d::prelude::*;
use common::{displacement, oscillator};

/// Times (s) at which the displacement crosses zero going upwards, found by
/// linear interpolation between steps.
fn upward_crossings(cloth: &mut Simulation, h: f32, steps: usize) -> Vec<f64> {
    let mut crossings = Vec::new();
    let mut prev = displacement(cloth);
    for s in 0..steps {
        cloth.step(h, &[]).unwrap();
        let now = displacement(cloth);
        if prev < 0.0 && now >= 0.0 {
            let frac = prev as f64 / (prev as f64 - now as f64);
            crossings.push((s as f64 + frac) * h as f64);
        }
        prev = now;
    }
    crossings
}

#[test]
fn period_matches_two_pi_sqrt_m_over_k() {
    let (m, k) = (0.5f32, 200.0f32);
    let expected = 2.0 * std::f64::consts::PI * (m as f64 / k as f64).sqrt();
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
    ] {
        let mut cloth = oscillator(m, k, 0.0, 0.05, integrator);
        let h = 1.0e-3;
        let crossings = upward_crossings(&mut cloth, h, 5000);
        assert!(
            crossings.len() >= 5,
            "{integrator}: only {} crossings",
            crossings.len()
        );
        let periods = crossings.len() - 1;
        let measured = (crossings[periods] - crossings[0]) / periods as f64;
        let error = (measured - expected).abs() / expected;
        assert!(
            error < 0.01,
            "{integrator}: period {measured:.5} s, expected {expected:.5} s ({:.3}% off)",
            100.0 * error
        );
    }
}

#[test]
fn damped_amplitude_follows_the_exponential_envelope() {
    // m x'' = -k x - c x': the envelope decays as exp(-c t / 2m).
    let (m, k, c) = (1.0f32, 100.0f32, 2.0f32);
    let a0 = 0.1f32;
    let rate = c as f64 / (2.0 * m as f64);
    let omega_d = ((k / m) as f64 - rate * rate).sqrt();
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
    ] {
        let mut cloth = oscillator(m, k, c, a0, integrator);
        let h = 2.0e-4;
        let mut peaks = Vec::new();
        let (mut before, mut current) = (f32::NEG_INFINITY, displacement(&cloth));
        for s in 0..20000 {
            cloth.step(h, &[]).unwrap();
            let next = displacement(&cloth);
            if current > before && current >= next && current > 0.0 && s > 0 {
                peaks.push((s as f64 * h as f64, current as f64));
            }
            before = current;
            current = next;
        }
        assert!(peaks.len() >= 4, "{integrator}: {} peaks", peaks.len());
        for &(t, a) in &peaks[..4] {
            // The exact solution x = A e^{-rt} (cos ω_d t + r/ω_d sin ω_d t) peaks at
            // ω_d t = 2πj, where its value is A e^{-rt}.
            let expected = a0 as f64 * (-rate * t).exp();
            let error = (a - expected).abs() / expected;
            assert!(
                error < 0.02,
                "{integrator}: peak {a:.5} at t = {t:.3} s, envelope {expected:.5} (ω_d = {omega_d:.2})"
            );
        }
        // The envelope really decays: the fourth peak is well below the first.
        assert!(peaks[3].1 < 0.6 * peaks[0].1);
    }
}

#[test]
fn symplectic_integrators_keep_energy_bounded_while_explicit_euler_gains() {
    let (m, k) = (1.0f32, 100.0f32);
    let h = 1.0e-3; // h ω = 0.01
    let mut totals = Vec::new();
    for integrator in [
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::ExplicitEuler,
    ] {
        let mut cloth = oscillator(m, k, 0.0, 0.1, integrator);
        let e0 = cloth.energy().total();
        let mut worst = 0.0f64;
        for _ in 0..10_000 {
            cloth.step(h, &[]).unwrap();
            worst = worst.max((cloth.energy().total() - e0).abs() / e0);
        }
        let drift = (cloth.energy().total() - e0) / e0;
        totals.push((integrator, worst, drift));
    }
    for &(integrator, worst, _) in &totals[..2] {
        assert!(
            worst < 0.01,
            "{integrator}: energy strayed {:.3}% from its start",
            100.0 * worst
        );
    }
    let (_, _, euler_drift) = totals[2];
    // (1 + h²ω²)^10000 = e^1: forward Euler almost triples the energy.
    assert!(
        euler_drift > 1.0,
        "explicit Euler gained only {:.1}%",
        100.0 * euler_drift
    );
}
