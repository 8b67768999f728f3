//! A solver's scratch memory, kept between steps so that a warmed-up step
//! allocates nothing; outside the cloth (as Jolt keeps its
//! `SoftBodyUpdateContext` outside the body). Nothing here changes results:
//! a solver with fresh scratch continues bit for bit.

use super::fast_mass_spring::FastMassSpringState;
use super::implicit_euler::ImplicitState;
use super::strain_limit::LimitScratch;
use super::tearing::Tearing;
use super::tethers::Tethers;
use super::xpbd::XpbdScratch;
use crate::collision::{CollisionStage, SelfContacts};
use crate::math::Vector;

/// Buffers of the explicit integrators (accelerations and Runge–Kutta stages).
#[derive(Debug, Default)]
pub(crate) struct ExplicitScratch {
    pub a: Vec<Vector>,
    pub a2: Vec<Vector>,
    pub xt: Vec<Vector>,
    pub vt: Vec<Vector>,
    pub sx: Vec<Vector>,
    pub sv: Vec<Vector>,
}

/// Everything a solver keeps between steps that is not state.
#[derive(Debug, Default)]
pub(crate) struct Workspace {
    /// Positions, velocities and previous positions at the start of the
    /// step, to put the cloth back when the step diverges.
    pub backup_x: Vec<Vector>,
    pub backup_v: Vec<Vector>,
    pub backup_prev: Vec<Vector>,
    /// Positions before self-collision's pass, to tell which particles it
    /// moved (`strain_limit::limit_stretch_after_moves`).
    pub before_self: Vec<Vector>,
    pub explicit: ExplicitScratch,
    pub implicit: ImplicitState,
    pub fms: FastMassSpringState,
    pub xpbd: XpbdScratch,
    /// The collision stage: obstacle motion, contacts, impulses.
    pub collision: CollisionStage,
    /// The self-collision stage: pairs of a particle and a triangle of the same cloth.
    pub self_contacts: SelfContacts,
    /// The tearing stage: its scratch and the last step's tears.
    pub tearing: Tearing,
    /// The tethers of the cloth last stepped (rebuilt when its pins change).
    pub tethers: Tethers,
    /// The stretch limit's scratch for the integrators that do not hold
    /// it themselves, the rounds after the contacts and the passes after
    /// self-collision: its weights near pins (`pin_support.rs`) and the
    /// springs its next pass looks at.
    pub limit_scratch: LimitScratch,
    /// The longest stretch or shear rest length (m) of the cloth last
    /// stepped, and its mass revision then.
    pub longest_rest: Option<(u64, f32)>,
    /// Whether the last step touched an obstacle: a step that does shares
    /// its loops among threads from fewer particles (`schedule.rs`,
    /// `shares_well`). Scratch: the threads change no bit.
    pub touched_last_step: bool,
}

impl Workspace {
    /// Makes sure every per-particle buffer holds `n` entries.
    pub fn resize(&mut self, n: usize) {
        let e = &mut self.explicit;
        for buf in [
            &mut e.a,
            &mut e.a2,
            &mut e.xt,
            &mut e.vt,
            &mut e.sx,
            &mut e.sv,
            &mut self.backup_x,
            &mut self.backup_v,
            &mut self.backup_prev,
            &mut self.before_self,
        ] {
            buf.resize(n, Vector::ZERO);
        }
    }
}
