//! The solver: what steps a cloth. Its settings, the state it carries
//! between steps, its scratch, its counters, the step schedule
//! (`schedule.rs`: the stages of a step in one readable order) and the
//! integrators, one file per method.

mod chain_transpose;
mod cloth_solver;
mod contact_follow;
mod explicit_euler;
mod fast_mass_spring;
mod filter;
mod general_sweep;
mod global_matrix;
mod grid_chains;
mod grid_leftover;
mod grid_sweep;
mod implicit_euler;
mod integrate;
mod integrator;
mod lane_contacts;
mod lane_convex;
mod lane_mesh;
mod lane_motion;
mod ordering;
mod pin_support;
mod preconditioner;
mod report;
mod rk4;
mod schedule;
mod settings;
mod sleep;
mod spring_space;
mod stability;
mod stage_times;
mod staggered;
mod state;
mod strain_limit;
mod substep;
mod substeps;
mod symplectic_euler;
mod tearing;
mod tethers;
mod verlet;
mod workspace;
mod xpbd;

pub use cloth_solver::ClothSolver;
pub use integrator::Integrator;
pub use preconditioner::Preconditioner;
pub use report::{SolverCounters, StepReport, MAX_DISTANCE, MAX_SPEED, MAX_STRAIN};
pub use settings::SolverSettings;
pub use sleep::{SleepState, CALM_STEPS, SLEEP_SPEED};
pub use stability::{stable_substep, stable_substeps, stiffness_bounds};
pub use stage_times::StageTimes;
pub use state::SolverState;
pub use substeps::{Substeps, MAX_SELF_SUBSTEP};
pub use tearing::TearEvent;
