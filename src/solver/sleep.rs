//! Sleeping (as Jolt's bodies sleep): a cloth whose particles all stay
//! slower than [`SLEEP_SPEED`] for [`CALM_STEPS`] steps in a row is put to
//! sleep: its velocities are zeroed and its steps only check whether it
//! must wake, which costs a pass over the velocities and positions, not a
//! solve. It wakes when something could move it: a particle given a
//! velocity (a drag, an attachment's body moving), a pin or mass changed,
//! its material or physical parameters (gravity, wind, ...) changed, or an
//! obstacle near it moving.

use serde::{Deserialize, Serialize};

use crate::cloth::{Cloth, Material, PhysicsParams};
use crate::collision::Obstacle;
use crate::math::Vector;

/// Speed under which a particle counts as still, in m/s.
pub const SLEEP_SPEED: f32 = 0.03;
/// Steps in a row with every particle still after which a cloth sleeps.
pub const CALM_STEPS: u32 = 30;
/// How far (m) around the cloth a moving obstacle wakes it.
const WAKE_MARGIN: f32 = 0.05;

/// Whether a cloth sleeps and what it fell asleep with (part of the
/// solver's state: it changes results, so snapshots carry it).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SleepState {
    /// Steps in a row with every particle slower than [`SLEEP_SPEED`].
    calm_steps: u32,
    /// What the cloth fell asleep with, while it sleeps.
    asleep: Option<Box<Sleeper>>,
}

/// What a cloth fell asleep with: a change to any of it wakes the cloth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Sleeper {
    pins: u64,
    params: PhysicsParams,
    material: Material,
}

/// A hash of the particles' inverse masses: it changes with any pin or mass.
fn pins_of(cloth: &Cloth) -> u64 {
    cloth
        .inverse_masses()
        .iter()
        .fold(0xcbf2_9ce4_8422_2325u64, |h, w| {
            (h ^ w.to_bits() as u64).wrapping_mul(0x0100_0000_01b3)
        })
}

impl SleepState {
    /// True while the cloth sleeps.
    pub fn is_asleep(&self) -> bool {
        self.asleep.is_some()
    }

    /// True while the cloth is awake and has not been still (nothing to
    /// keep in a snapshot).
    pub fn is_awake(&self) -> bool {
        self.asleep.is_none() && self.calm_steps == 0
    }

    /// Wakes the cloth (it steps again from the next step).
    pub fn wake(&mut self) {
        self.asleep = None;
        self.calm_steps = 0;
    }

    /// Whether the sleeping cloth stays asleep for this step among
    /// `obstacles`; wakes it when not.
    pub(crate) fn stays_asleep(&mut self, cloth: &Cloth, obstacles: &[Obstacle]) -> bool {
        let Some(sleeper) = &self.asleep else {
            return false;
        };
        let still = sleeper.params == cloth.params
            && sleeper.material == cloth.material
            && sleeper.pins == pins_of(cloth)
            && cloth.velocities().iter().all(|&v| v == Vector::ZERO)
            && !moves_near(obstacles, cloth);
        if !still {
            self.wake();
        }
        still
    }

    /// After a step: counts the steps in a row the cloth has been still and
    /// puts it to sleep (zeroing its velocities) after [`CALM_STEPS`].
    pub(crate) fn after_step(&mut self, cloth: &mut Cloth) {
        let fastest = cloth
            .velocities()
            .iter()
            .map(|v| v.length_squared())
            .fold(0.0f32, f32::max);
        if fastest < SLEEP_SPEED * SLEEP_SPEED {
            self.calm_steps += 1;
        } else {
            self.calm_steps = 0;
        }
        if self.calm_steps >= CALM_STEPS {
            cloth.stop();
            self.asleep = Some(Box::new(Sleeper {
                pins: pins_of(cloth),
                params: cloth.params.clone(),
                material: cloth.material.clone(),
            }));
        }
    }
}

/// True when one of the `obstacles` moves and comes within
/// [`WAKE_MARGIN`] of the cloth's bounds.
fn moves_near(obstacles: &[Obstacle], cloth: &Cloth) -> bool {
    let mut moving = obstacles
        .iter()
        .filter(|o| o.linvel != Vector::ZERO || o.angvel != Vector::ZERO)
        .peekable();
    if moving.peek().is_none() {
        return false;
    }
    // The cloth's bounds, once, padded.
    let x = cloth.positions();
    let pad = Vector::splat(WAKE_MARGIN + cloth.params.thickness);
    let lo = x
        .iter()
        .fold(Vector::splat(f32::INFINITY), |a, &p| a.min(p))
        - pad;
    let hi = x
        .iter()
        .fold(Vector::splat(f32::NEG_INFINITY), |a, &p| a.max(p))
        + pad;
    moving.any(|o| {
        let aabb = o.shape.compute_aabb(&o.pose);
        let (olo, ohi) = (Vector::from(aabb.mins), Vector::from(aabb.maxs));
        olo.cmple(hi).all() && ohi.cmpge(lo).all()
    })
}
