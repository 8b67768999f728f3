//! The preconditioner of the implicit integrator's conjugate gradient.

use serde::{Deserialize, Serialize};

use crate::error::ClothError;

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
