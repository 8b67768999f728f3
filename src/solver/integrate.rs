//! The integrate stage: one substep of the chosen method.

use super::fast_mass_spring;
use super::implicit_euler;
use super::integrator::Integrator;
use super::state::SolverState;
use super::substep::Substep;
use super::workspace::Workspace;
use super::{explicit_euler, rk4, symplectic_euler, verlet, xpbd};
use crate::collision::FrictionPolicy;
use crate::error::ClothError;
use crate::math::Vector;

/// What an integrator hands back with its substep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SubstepOutcome {
    /// Solver iterations it took (0 for the explicit methods).
    pub iterations: u32,
    /// Who applies Coulomb friction to this substep's contacts.
    pub friction: FrictionPolicy,
    /// When the integrator left every stretch spring within the material's
    /// limit: how much (m) any of them may still lengthen before it
    /// reaches it (`None`: not known).
    pub stretch_room: Option<f32>,
    /// The integrator left every stretch spring within the material's
    /// limit by the limit's own test (`strain_limit::limit_stretch`'s):
    /// after a stage that moves some particles, only the springs at those
    /// can be over it.
    pub stretch_settled: bool,
    /// The integrator held every obstacle's contacts inside the substep
    /// (xpbd's lanes, `lane_contacts`): the collision stage may wait
    /// for the step's last substep.
    pub contacts_held: bool,
    /// The integrator held the still obstacles' contacts inside the
    /// substep, among moving or dynamic bodies: the collision stage may
    /// pass over them but at the step's last substep.
    pub still_held: bool,
    /// At the step's last substep, when the integrator held the contacts:
    /// the particles it held in contact with an obstacle (0 otherwise).
    pub touching: u32,
}

/// Advances positions `x` and velocities `v` by one substep with the
/// settings' integrator. Contacts are the collision stage's: the methods
/// that solve them read them and record the impulses they gave. `x_prev`
/// holds the positions at the substep's start (the small-steps solver,
/// whose state may stay in its lanes between substeps, writes it when it
/// hands the state back).
pub(crate) fn integrate(
    sub: &Substep,
    (x, v, x_prev): (&mut [Vector], &mut [Vector], &mut [Vector]),
    state: &mut SolverState,
    ws: &mut Workspace,
) -> Result<SubstepOutcome, ClothError> {
    let (model, h) = (&sub.model, sub.ctx.h);
    // Friction by the collision stage after the substep.
    let explicit = |iterations| SubstepOutcome {
        iterations,
        friction: FrictionPolicy::Apply,
        stretch_room: None,
        stretch_settled: false,
        contacts_held: false,
        still_held: false,
        touching: 0,
    };
    let solved = |iterations| SubstepOutcome {
        iterations,
        friction: FrictionPolicy::AlreadySolved,
        stretch_room: None,
        stretch_settled: false,
        contacts_held: false,
        still_held: false,
        touching: 0,
    };
    Ok(match sub.settings.integrator {
        Integrator::ExplicitEuler => {
            explicit_euler::step(model, x, v, &mut ws.explicit, h);
            explicit(0)
        }
        Integrator::SymplecticEuler => {
            symplectic_euler::step(model, x, v, &mut ws.explicit, h);
            explicit(0)
        }
        Integrator::Verlet => {
            verlet::step(model, x, v, &mut ws.explicit, h);
            explicit(0)
        }
        Integrator::Rk4 => {
            rk4::step(model, x, v, &mut ws.explicit, h);
            explicit(0)
        }
        Integrator::Xpbd => {
            let outcome = xpbd::step(sub, (x, v, x_prev), &mut ws.xpbd, &ws.collision);
            // Where the lanes held the contacts they gave them friction
            // too: the collision stage's pass at the step's last substep
            // only checks them. Applied again there, friction undid a
            // second slide and stretched the springs around it (the drape
            // at N = 128 and 12 substeps: one spring at 6.15% where the
            // substep had left 4.63%). So too at the last substep where
            // they held the still obstacles among moving or dynamic
            // bodies; before it the stage answers for the bodies alone,
            // with friction.
            let last = sub.ctx.substep + 1 == sub.ctx.substeps;
            let friction = if outcome.contacts_held || (outcome.still_held && last) {
                FrictionPolicy::AlreadySolved
            } else {
                FrictionPolicy::Apply
            };
            SubstepOutcome {
                stretch_room: outcome.stretch_room,
                stretch_settled: outcome.stretch_settled,
                contacts_held: outcome.contacts_held,
                still_held: outcome.still_held,
                touching: outcome.touching,
                friction,
                ..explicit(0)
            }
        }
        Integrator::ImplicitEuler => solved(implicit_euler::step(
            sub,
            x,
            v,
            &mut ws.implicit,
            &mut ws.collision,
        )),
        Integrator::FastMassSpring => solved(fast_mass_spring::step(
            sub,
            x,
            v,
            &mut ws.fms,
            (&mut state.held_force, &mut state.fms_factor),
            &mut ws.collision,
        )?),
    })
}
