//! Which time integrator a solver uses.

use serde::{Deserialize, Serialize};

use super::substeps::Substeps;
use crate::error::ClothError;

/// The time integrators; switch with [`super::ClothSolver::set_integrator`] at any time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Integrator {
    /// Forward Euler: `x += h v; v += h a(x, v)`. First order; gains energy
    /// on undamped oscillations, so it needs damping and many substeps.
    ExplicitEuler,
    /// Semi-implicit (symplectic) Euler: `v += h a(x, v); x += h v`. First
    /// order, energy stays bounded; the workhorse of real-time cloth.
    SymplecticEuler,
    /// Störmer–Verlet in velocity form: second order and symplectic; two force
    /// evaluations per substep.
    Verlet,
    /// Classical fourth-order Runge–Kutta: very accurate at small steps, four
    /// force evaluations per substep, slowly loses energy.
    Rk4,
    /// Backward Euler after Baraff and Witkin (1998): linearised forces,
    /// block-sparse system solved by preconditioned conjugate gradient, pins
    /// and contacts as constraints of the solve. Stable at any step; damps
    /// high frequencies.
    ImplicitEuler,
    /// The local/global solver of Liu et al. (2013) with a prefactored sparse
    /// Cholesky: stable at any step, a fixed cost per iteration, best when
    /// stiffness and pins rarely change.
    FastMassSpring,
    /// Extended position-based dynamics in small steps (Macklin et al. 2016,
    /// 2019): each spring a constraint of compliance `1/k` with its damping,
    /// one Gauss–Seidel sweep per substep, many cheap substeps; stable at any
    /// step, and every substep meets the obstacles. The real-time choice.
    Xpbd,
}

impl Integrator {
    /// Every integrator, in the order of the command line's list.
    pub const ALL: [Integrator; 7] = [
        Integrator::ExplicitEuler,
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
        Integrator::ImplicitEuler,
        Integrator::FastMassSpring,
        Integrator::Xpbd,
    ];

    /// The name used by the command line and scene files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::ExplicitEuler => "explicit-euler",
            Integrator::SymplecticEuler => "symplectic-euler",
            Integrator::Verlet => "verlet",
            Integrator::Rk4 => "rk4",
            Integrator::ImplicitEuler => "implicit-euler",
            Integrator::FastMassSpring => "fast-mass-spring",
            Integrator::Xpbd => "xpbd",
        }
    }

    /// Looks an integrator up by name.
    pub fn from_name(name: &str) -> Result<Self, ClothError> {
        crate::error::by_name(&Self::ALL, Self::name, "integrator", name)
    }

    /// True for the explicit force-based methods, whose step is limited by stability.
    pub fn is_explicit(self) -> bool {
        !matches!(
            self,
            Integrator::ImplicitEuler | Integrator::FastMassSpring | Integrator::Xpbd
        )
    }

    /// The substeps this integrator wants by default: automatic (within the
    /// stability limit) for the explicit ones, one step a frame for the implicit ones.
    pub fn default_substeps(self) -> Substeps {
        if self.is_explicit() || self == Integrator::Xpbd {
            Substeps::Auto
        } else {
            Substeps::Fixed(1)
        }
    }

    /// True for the methods that hold the material's stretch limit at the
    /// end of their own substep (the others get it from the schedule).
    pub fn limits_stretch_itself(self) -> bool {
        self == Integrator::Xpbd
    }

    /// True for the methods that keep dynamic bodies on the cloth. The
    /// large-step ones (implicit Euler, fast mass-spring) let a heavy body
    /// through at their default steps, so they refuse dynamic bodies
    /// ([`crate::ClothError::CannotCarryBodies`]).
    pub fn carries_dynamic_bodies(self) -> bool {
        !matches!(self, Integrator::ImplicitEuler | Integrator::FastMassSpring)
    }

    /// True for the methods that take contacts and friction into their own
    /// solve: contacts are detected ahead of each of their substeps.
    pub fn solves_contacts(self) -> bool {
        matches!(self, Integrator::ImplicitEuler | Integrator::FastMassSpring)
    }

    /// Force evaluations per substep.
    pub fn force_evaluations(self) -> u32 {
        match self {
            Integrator::ExplicitEuler | Integrator::SymplecticEuler => 1,
            Integrator::Verlet => 2,
            Integrator::Rk4 => 4,
            Integrator::ImplicitEuler | Integrator::FastMassSpring | Integrator::Xpbd => 1,
        }
    }
}

impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Integrator {
    type Err = ClothError;
    fn from_str(s: &str) -> Result<Self, ClothError> {
        Self::from_name(s)
    }
}
