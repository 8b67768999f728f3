//! One step of a cloth: validate, then per substep integrate and collide,
//! then check the new state and roll back if it diverged.

use serde::{Deserialize, Serialize};

use crate::cloth::{Cloth, SpringKind, Substeps};
use crate::collision::{Obstacle, ObstacleImpulse};
use crate::error::{positive, ClothError};
use crate::integrators::{self, stable_substeps};
use crate::math::Vector;

/// Speeds (m/s) and distances from the origin (m) beyond which a step is
/// taken to have exploded even if the numbers are still finite.
pub const MAX_SPEED: f32 = 1.0e4;
/// See [`MAX_SPEED`].
pub const MAX_DISTANCE: f32 = 1.0e7;
/// A stretch spring longer than `1 + MAX_STRAIN` times its rest length after a
/// step means the step exploded: no cloth stretches to eleven times its length.
pub const MAX_STRAIN: f32 = 10.0;

/// What a step did.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct StepReport {
    /// Substeps taken.
    pub substeps: u32,
    /// Solver iterations over the whole step (0 for explicit integrators).
    pub iterations: u32,
    /// Particle–obstacle contacts resolved, summed over substeps.
    pub contacts: u32,
}

impl Cloth {
    /// The number of substeps a frame step of `dt` seconds uses with the current parameters.
    pub fn substeps_for(&self, dt: f32) -> u32 {
        match self.params.substeps {
            Substeps::Fixed(k) => k.max(1),
            Substeps::Auto => stable_substeps(self, self.params.integrator, dt),
        }
    }

    /// Advances the cloth by `dt` seconds among `obstacles`.
    ///
    /// The step is split into substeps; each integrates the forces with the
    /// current integrator and then resolves contacts. If the new state is not
    /// finite, or has exploded (a speed over [`MAX_SPEED`], a distance over
    /// [`MAX_DISTANCE`], a stretch over [`MAX_STRAIN`]), the cloth is put back as
    /// it was before the step and [`ClothError::Diverged`] says which
    /// integrator diverged and how many substeps would be stable.
    pub fn step(&mut self, dt: f32, obstacles: &[Obstacle]) -> Result<StepReport, ClothError> {
        positive("dt", dt)?;
        self.params.validate()?;
        self.material.validate()?;
        for (i, o) in obstacles.iter().enumerate() {
            o.validate(i)?;
        }
        let k = self.substeps_for(dt);
        let h = dt / k as f32;
        let n = self.particles.len();
        self.workspace.resize(n);
        self.workspace.backup_x.copy_from_slice(&self.particles.x);
        self.workspace.backup_v.copy_from_slice(&self.particles.v);
        self.workspace
            .backup_prev
            .copy_from_slice(&self.particles.x_prev);
        let reach = self.params.thickness
            + if self.params.edge_collisions {
                max_rest_length(self)
            } else {
                0.0
            };
        self.workspace.collider.begin_step(obstacles, dt, reach, n);
        let mut report = StepReport {
            substeps: k,
            ..Default::default()
        };
        for s in 0..k {
            let t = (s + 1) as f32 * h;
            self.workspace.collider.set_time(obstacles, t, h);
            report.iterations += match integrators::substep(self, h, obstacles) {
                Ok(it) => it,
                Err(e) => {
                    self.restore_backup();
                    return Err(e);
                }
            };
            let Cloth {
                particles,
                springs,
                workspace,
                params,
                ..
            } = self;
            report.contacts += workspace.collider.resolve(
                particles,
                springs,
                obstacles,
                h,
                params.thickness,
                params.edge_collisions,
                params.integrator.is_explicit(),
            );
        }
        if !self.state_is_sane() {
            let integrator = self.params.integrator;
            self.restore_backup();
            let suggested = stable_substeps(self, integrator, dt).max(2 * k);
            return Err(ClothError::Diverged {
                integrator: integrator.name(),
                dt,
                substeps: k,
                suggested_substeps: suggested,
            });
        }
        self.time += dt as f64;
        Ok(report)
    }

    /// Momentum the cloth gave each obstacle during the last step (same order
    /// as the obstacles passed to [`Cloth::step`]).
    pub fn obstacle_impulses(&self) -> &[ObstacleImpulse] {
        &self.workspace.collider.impulses
    }

    /// How many times the fast mass-spring solver has computed its Cholesky
    /// factor for this cloth (it is reused while pins, masses, step and
    /// stiffness stay the same).
    pub fn factorizations(&self) -> u64 {
        self.workspace.factorizations()
    }

    /// How many times the fast mass-spring solver has recomputed its
    /// factor's numbers (same ordering and pattern) because the set of
    /// particles held by friction on an obstacle changed.
    pub fn refactorizations(&self) -> u64 {
        self.workspace.fms.refactorizations
    }

    fn restore_backup(&mut self) {
        let ws = &self.workspace;
        self.particles.x.copy_from_slice(&ws.backup_x);
        self.particles.v.copy_from_slice(&ws.backup_v);
        self.particles.x_prev.copy_from_slice(&ws.backup_prev);
    }

    fn state_is_sane(&self) -> bool {
        let ok_v = |v: &Vector| v.is_finite() && v.length_squared() < MAX_SPEED * MAX_SPEED;
        let ok_x = |x: &Vector| x.is_finite() && x.length_squared() < MAX_DISTANCE * MAX_DISTANCE;
        self.particles.x.iter().all(ok_x)
            && self.particles.v.iter().all(ok_v)
            && self.max_strain(SpringKind::Stretch) < MAX_STRAIN
    }
}

/// The longest rest length among the springs sampled by edge collisions.
fn max_rest_length(cloth: &Cloth) -> f32 {
    [SpringKind::Stretch, SpringKind::Shear]
        .iter()
        .flat_map(|&k| cloth.springs.range(k))
        .map(|s| cloth.springs.rest[s])
        .fold(0.0, f32::max)
}
