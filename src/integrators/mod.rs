//! Time integrators: one file per method, one enum to choose among them at run time.

mod explicit_euler;
mod fast_mass_spring;
mod global_matrix;
mod implicit_euler;
mod ordering;
mod rk4;
mod spring_space;
mod symplectic_euler;
mod verlet;

use serde::{Deserialize, Serialize};

use crate::cloth::{Cloth, SpringKind};
use crate::error::ClothError;
use crate::forces::ForceModel;
use crate::math::Vector;

/// The time integrators; switch with [`Cloth::set_integrator`] at any time.
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
}

impl Integrator {
    /// Every integrator, in the order of the command line's list.
    pub const ALL: [Integrator; 6] = [
        Integrator::ExplicitEuler,
        Integrator::SymplecticEuler,
        Integrator::Verlet,
        Integrator::Rk4,
        Integrator::ImplicitEuler,
        Integrator::FastMassSpring,
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
        }
    }

    /// Looks an integrator up by name.
    pub fn from_name(name: &str) -> Result<Self, ClothError> {
        crate::error::by_name(&Self::ALL, Self::name, "integrator", name)
    }

    /// True for the explicit methods, whose step is limited by stability.
    pub fn is_explicit(self) -> bool {
        !matches!(self, Integrator::ImplicitEuler | Integrator::FastMassSpring)
    }

    /// The substeps this integrator wants by default: automatic (within the
    /// stability limit) for the explicit ones, one step a frame for the implicit ones.
    pub fn default_substeps(self) -> crate::cloth::Substeps {
        if self.is_explicit() {
            crate::cloth::Substeps::Auto
        } else {
            crate::cloth::Substeps::Fixed(1)
        }
    }

    /// Force evaluations per substep.
    pub fn force_evaluations(self) -> u32 {
        match self {
            Integrator::ExplicitEuler | Integrator::SymplecticEuler => 1,
            Integrator::Verlet => 2,
            Integrator::Rk4 => 4,
            Integrator::ImplicitEuler | Integrator::FastMassSpring => 1,
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

/// Preconditioner of the implicit integrator's conjugate gradient.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Preconditioner {
    /// The inverse of each particle's 3×3 diagonal block: cheap per
    /// iteration, but it needs about `√(h² k / m)` iterations, so very stiff
    /// springs stop short of convergence and the cloth looks stiffer than it is.
    #[default]
    BlockJacobi,
    /// The stiff spring kinds' rank-one blocks taken exactly (Woodbury, with
    /// a sparse Cholesky factor over those springs, refactored every
    /// linearisation), the rest by block Jacobi: iterations stop growing
    /// with stiffness, at about four times the cost of each.
    SpringSpace,
}

impl Preconditioner {
    /// Every preconditioner.
    pub const ALL: [Preconditioner; 2] = [Preconditioner::BlockJacobi, Preconditioner::SpringSpace];

    /// The name used by the command line.
    pub fn name(self) -> &'static str {
        match self {
            Preconditioner::BlockJacobi => "block-jacobi",
            Preconditioner::SpringSpace => "spring-space",
        }
    }

    /// Looks a preconditioner up by name.
    pub fn from_name(name: &str) -> Result<Self, ClothError> {
        crate::error::by_name(&Self::ALL, Self::name, "preconditioner", name)
    }
}

/// Scratch memory of the integrators, kept between steps so a step allocates
/// nothing once warmed up. Cloning a cloth gives the clone empty scratch.
#[derive(Debug, Default)]
pub struct Workspace {
    pub(crate) a: Vec<Vector>,
    pub(crate) a2: Vec<Vector>,
    pub(crate) xt: Vec<Vector>,
    pub(crate) vt: Vec<Vector>,
    pub(crate) sx: Vec<Vector>,
    pub(crate) sv: Vec<Vector>,
    pub(crate) backup_x: Vec<Vector>,
    pub(crate) backup_v: Vec<Vector>,
    pub(crate) backup_prev: Vec<Vector>,
    pub(crate) collider: crate::collision::Collider,
    pub(crate) implicit: implicit_euler::ImplicitState,
    pub(crate) fms: fast_mass_spring::FastMassSpringState,
}

impl Clone for Workspace {
    fn clone(&self) -> Self {
        Workspace::default()
    }
}

impl Workspace {
    /// Drops everything that depends on masses, pins or topology.
    pub(crate) fn invalidate(&mut self) {
        self.fms.invalidate();
    }

    /// How many times the fast mass-spring solver computed its Cholesky factor.
    pub(crate) fn factorizations(&self) -> u64 {
        self.fms.factorizations
    }

    /// Makes sure every buffer holds `n` entries.
    pub(crate) fn resize(&mut self, n: usize) {
        for buf in [
            &mut self.a,
            &mut self.a2,
            &mut self.xt,
            &mut self.vt,
            &mut self.sx,
            &mut self.sv,
            &mut self.backup_x,
            &mut self.backup_v,
            &mut self.backup_prev,
        ] {
            buf.resize(n, Vector::ZERO);
        }
    }
}

/// Advances the cloth by one substep `h` (seconds) with its integrator and
/// returns the solver iterations it took. Collisions are not handled here.
pub(crate) fn substep(
    cloth: &mut Cloth,
    h: f32,
    obstacles: &[crate::collision::Obstacle],
) -> Result<u32, ClothError> {
    let Cloth {
        particles,
        workspace,
        ..
    } = cloth;
    // Borrow the model immutably from the parts that integrators do not write.
    let model = ForceModel::new(
        &cloth.springs,
        &cloth.material,
        &cloth.triangles,
        &particles.mass,
        &particles.inv_mass,
        &cloth.params,
    );
    let (x, v) = (&mut particles.x, &mut particles.v);
    particles.x_prev.copy_from_slice(x);
    let params = &cloth.params;
    if !params.integrator.is_explicit() {
        // The implicit solvers take contacts (now or within the substep) into their solve.
        workspace.collider.detect_contacts(
            x,
            v,
            &particles.inv_mass,
            obstacles,
            params.thickness,
            h,
            params.gravity,
        );
    }
    match params.integrator {
        Integrator::ExplicitEuler => explicit_euler::step(&model, x, v, workspace, h),
        Integrator::SymplecticEuler => symplectic_euler::step(&model, x, v, workspace, h),
        Integrator::Verlet => verlet::step(&model, x, v, workspace, h),
        Integrator::Rk4 => rk4::step(&model, x, v, workspace, h),
        Integrator::ImplicitEuler => {
            let contacts = Contacts {
                collider: &mut workspace.collider,
                obstacles,
                thickness: params.thickness,
            };
            return Ok(implicit_euler::step(
                &model,
                x,
                v,
                &mut workspace.implicit,
                contacts,
                h,
                params.newton_iterations,
                params.preconditioner,
                params.cg_max_iterations,
                params.cg_tolerance,
            ));
        }
        Integrator::FastMassSpring => {
            let contacts = Contacts {
                collider: &mut workspace.collider,
                obstacles,
                thickness: params.thickness,
            };
            return fast_mass_spring::step(
                &model,
                x,
                v,
                &mut workspace.fms,
                &mut particles.held_force,
                contacts,
                h,
                params.fms_iterations,
            );
        }
    }
    Ok(0)
}

/// The obstacles and their contacts, for the implicit solvers to keep their
/// iterates outside.
pub(crate) struct Contacts<'a> {
    pub collider: &'a mut crate::collision::Collider,
    pub obstacles: &'a [crate::collision::Obstacle],
    pub thickness: f32,
}

/// Upper bounds on the squared highest angular frequency (1/s²) and on the
/// highest damping rate (1/s) of the cloth, by Gershgorin's theorem: at any
/// particle, twice the stiffness (damping) of the springs that can meet there
/// over the lightest free mass. Allocates nothing.
pub fn stiffness_bounds(cloth: &Cloth) -> (f32, f32) {
    let max_inv_mass = cloth
        .particles
        .inv_mass
        .iter()
        .copied()
        .fold(0.0f32, f32::max);
    let (mut k, mut c) = (0.0f32, 0.0f32);
    for kind in SpringKind::ALL {
        let sp = cloth.material.params(kind);
        let degree = cloth.springs.max_degree[kind.index()] as f32;
        k += sp.stiffness * degree;
        c += sp.damping * degree;
    }
    (
        2.0 * k * max_inv_mass,
        2.0 * c * max_inv_mass + cloth.params.air_drag,
    )
}

/// The largest substep (seconds) at which `integrator` is estimated to be
/// stable on this cloth.
pub fn stable_substep(cloth: &Cloth, integrator: Integrator) -> f32 {
    let (omega2, gamma) = stiffness_bounds(cloth);
    if omega2 <= 0.0 {
        return f32::INFINITY;
    }
    // Symplectic Euler on x'' = -ω² x - γ x' is stable while h² ω² + 2 h γ < 4.
    let symplectic = (-gamma + (gamma * gamma + 4.0 * omega2).sqrt()) / omega2;
    let safety = 0.9;
    let h = match integrator {
        Integrator::SymplecticEuler | Integrator::Verlet => symplectic,
        // RK4's stability region reaches 2.8 on the imaginary axis.
        Integrator::Rk4 => 1.4 * symplectic,
        // Forward Euler only damps a mode while h < γ/ω², that is c/k per spring.
        Integrator::ImplicitEuler | Integrator::FastMassSpring => return f32::INFINITY,
        Integrator::ExplicitEuler => {
            let ratio = SpringKind::ALL
                .iter()
                .map(|&k| {
                    let sp = cloth.material.params(k);
                    sp.damping / sp.stiffness
                })
                .fold(f32::INFINITY, f32::min);
            // A spring kind without damping is never damped by it: then only
            // air drag helps, and a step far below the symplectic one.
            if ratio > 0.0 {
                symplectic.min(ratio)
            } else {
                symplectic / 8.0
            }
        }
    };
    safety * h
}

/// The substeps that keep `integrator` within its stability limit for a frame step `dt`.
pub fn stable_substeps(cloth: &Cloth, integrator: Integrator, dt: f32) -> u32 {
    let h = stable_substep(cloth, integrator);
    let k = (dt / h).ceil();
    if k.is_finite() {
        k.clamp(1.0, 1.0e6) as u32
    } else {
        1
    }
}
