//! The error of building and stepping a cloth, and the checks that produce it.
//! (Scene files have their own, `crate::scenes::SceneError`.)

use thiserror::Error;

/// Everything that can go wrong when building or stepping a cloth.
///
/// Each message says what was wrong and what is allowed, so it can be shown
/// to a user as it is.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ClothError {
    /// The grid has fewer than 2 columns or rows.
    #[error("invalid grid {cols}×{rows}: a cloth needs at least 2×2 particles")]
    GridTooSmall {
        /// Requested number of columns.
        cols: usize,
        /// Requested number of rows.
        rows: usize,
    },
    /// The grid is larger than the index type allows.
    #[error("invalid grid {cols}×{rows}: at most {max} particles are supported")]
    GridTooLarge {
        /// Requested number of columns.
        cols: usize,
        /// Requested number of rows.
        rows: usize,
        /// The largest particle count allowed.
        max: usize,
    },
    /// A numeric parameter is NaN, infinite or outside its allowed range.
    #[error("invalid {name} = {value}: expected {expected}")]
    InvalidParameter {
        /// Which parameter (for example `dt` or `stretch stiffness`).
        name: &'static str,
        /// The value that was given.
        value: f64,
        /// What is allowed, in words (for example `a finite number > 0`).
        expected: &'static str,
    },
    /// A vector or pose parameter has a NaN or infinite component.
    #[error("invalid {name}: every component must be finite")]
    NonFinite {
        /// Which parameter.
        name: &'static str,
    },
    /// A particle index is out of range.
    #[error("particle index {index} out of range: the cloth has {count} particles (0..{count})")]
    ParticleOutOfRange {
        /// The index given.
        index: usize,
        /// The number of particles.
        count: usize,
    },
    /// A (row, column) pair is outside the grid.
    #[error("grid cell (row {row}, column {col}) out of range: the grid has {rows} rows and {cols} columns")]
    CellOutOfRange {
        /// Row given.
        row: usize,
        /// Column given.
        col: usize,
        /// Rows of the grid.
        rows: usize,
        /// Columns of the grid.
        cols: usize,
    },
    /// The operation needs a grid cloth (rows and columns) but this one was built from parts.
    #[error("this cloth was built from parts and has no grid: use particle indices")]
    NotAGrid,
    /// A spring or triangle refers to itself or repeats a particle.
    #[error("invalid {what} {index}: {reason}")]
    InvalidTopology {
        /// `spring` or `triangle`.
        what: &'static str,
        /// Its index in the list given.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// Lists given together have different lengths.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// What was given.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// An obstacle cannot be used.
    #[error("invalid obstacle {index}: {reason}")]
    InvalidObstacle {
        /// Index of the obstacle in the slice given to the step.
        index: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// The state stopped being finite during a step; the cloth was restored to
    /// its state before the step.
    #[error("the {integrator} integrator diverged at dt = {dt} s with {substeps} substeps (state restored to before the step); try --substeps {suggested_substeps} or a larger value{}", implicit_advice(integrator))]
    Diverged {
        /// Name of the integrator that diverged.
        integrator: &'static str,
        /// Frame step used, in seconds.
        dt: f32,
        /// Substeps used.
        substeps: u32,
        /// Substep count estimated to be stable for this cloth.
        suggested_substeps: u32,
    },
    /// The integrator cannot carry dynamic bodies: at its large steps a body
    /// resting on the cloth falls through it. Nothing was stepped.
    #[error("{integrator} cannot carry dynamic bodies ({body} is one): at its large steps a body on the cloth falls through it; use xpbd or symplectic-euler, or make the body fixed or kinematic")]
    CannotCarryBodies {
        /// Name of the integrator.
        integrator: &'static str,
        /// Which body: `obstacle 3`, or a rapier collider's handle.
        body: String,
    },
    /// Self-collision is on but the substeps are too long: layers would
    /// pass through each other between the passes that keep them apart
    /// (at one step a frame a folding cloth crosses itself hundreds of
    /// times). Nothing was stepped.
    #[error("self-collision needs substeps of at most {max_substep_ms:.2} ms, but {integrator} takes {substeps} a frame of {dt:.4} s; use --substeps {needed} or more, or xpbd or symplectic-euler with automatic substeps")]
    SelfCollisionNeedsSubsteps {
        /// Name of the integrator.
        integrator: &'static str,
        /// The frame step, in seconds.
        dt: f32,
        /// Substeps it would take.
        substeps: u32,
        /// Substeps it needs at least.
        needed: u32,
        /// The longest substep self-collision allows, in milliseconds.
        max_substep_ms: f32,
    },
    /// A name (scene, integrator, material, variant) is not known.
    #[error("unknown {what} '{name}': valid choices are {valid}")]
    UnknownName {
        /// What kind of name (`scene`, `integrator`, ...).
        what: &'static str,
        /// The name given.
        name: String,
        /// The valid choices, comma-separated.
        valid: String,
    },
    /// A rapier handle refers to a body or collider that no longer exists.
    #[error("stale rapier handle: the {what} {handle} no longer exists in the set")]
    StaleHandle {
        /// `rigid body` or `collider`.
        what: &'static str,
        /// The handle, formatted.
        handle: String,
    },
    /// The linear solver of an implicit integrator could not be built.
    #[error("linear solver failed: {0}")]
    Solver(String),
}

/// For an explicit integrator, the advice to switch to one stable at any step.
fn implicit_advice(integrator: &str) -> &'static str {
    if matches!(integrator, "implicit-euler" | "fast-mass-spring" | "xpbd") {
        ""
    } else {
        ", or an integrator stable at any step (xpbd; implicit-euler or fast-mass-spring without dynamic bodies)"
    }
}

/// Finds the choice among `all` whose `name` is `name` (case-insensitive),
/// or says which `what` names are valid.
pub(crate) fn by_name<T: Copy>(
    all: &[T],
    name_of: fn(T) -> &'static str,
    what: &'static str,
    name: &str,
) -> Result<T, ClothError> {
    all.iter()
        .copied()
        .find(|&c| name_of(c).eq_ignore_ascii_case(name))
        .ok_or_else(|| ClothError::UnknownName {
            what,
            name: name.to_string(),
            valid: all
                .iter()
                .map(|&c| name_of(c))
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// serde checks for numeric fields of scene files and snapshots, so that a bad
/// value is reported with its line and field while the file is read.
pub(crate) mod de {
    use serde::{de::Error, Deserialize, Deserializer};

    /// A finite `f32 > 0`.
    pub fn positive<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
        let v = f32::deserialize(d)?;
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(D::Error::custom(format!(
                "invalid value {v}: expected a finite number > 0"
            )))
        }
    }

    /// A finite `f32 >= 0`.
    pub fn non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
        let v = f32::deserialize(d)?;
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(D::Error::custom(format!(
                "invalid value {v}: expected a finite number >= 0"
            )))
        }
    }

    /// An optional finite `f32 > 0`.
    pub fn opt_positive<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
        match Option::<f32>::deserialize(d)? {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(D::Error::custom(format!(
                "invalid value {v}: expected a finite number > 0"
            ))),
            v => Ok(v),
        }
    }

    /// An optional finite `f32 >= 0`.
    pub fn opt_non_negative<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
        match Option::<f32>::deserialize(d)? {
            Some(v) if !(v.is_finite() && v >= 0.0) => Err(D::Error::custom(format!(
                "invalid value {v}: expected a finite number >= 0"
            ))),
            v => Ok(v),
        }
    }

    /// A grid dimension: at least 2 particles.
    pub fn grid_side<'de, D: Deserializer<'de>>(d: D) -> Result<usize, D::Error> {
        let v = usize::deserialize(d)?;
        if v >= 2 {
            Ok(v)
        } else {
            Err(D::Error::custom(format!(
                "invalid value {v}: a cloth needs at least 2 particles along each side"
            )))
        }
    }

    /// A count of at least 1.
    pub fn at_least_one<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
        let v = u32::deserialize(d)?;
        if v >= 1 {
            Ok(v)
        } else {
            Err(D::Error::custom(
                "invalid value 0: expected a whole number >= 1",
            ))
        }
    }

    /// A vector with finite components.
    pub fn finite_vec<'de, D: Deserializer<'de>>(d: D) -> Result<crate::math::Vector, D::Error> {
        let v = crate::math::Vector::deserialize(d)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(D::Error::custom("every component must be finite"))
        }
    }

    /// A vector with finite, strictly positive components (half-extents).
    pub fn positive_vec<'de, D: Deserializer<'de>>(d: D) -> Result<crate::math::Vector, D::Error> {
        let v = crate::math::Vector::deserialize(d)?;
        if v.is_finite() && v.min_element() > 0.0 {
            Ok(v)
        } else {
            Err(D::Error::custom(format!(
                "invalid value ({}, {}, {}): every component must be a finite number > 0",
                v.x, v.y, v.z
            )))
        }
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn positive(name: &'static str, value: f32) -> Result<f32, ClothError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(ClothError::InvalidParameter {
            name,
            value: value as f64,
            expected: "a finite number > 0",
        })
    }
}

/// Checks that `value` is finite and not negative.
pub(crate) fn non_negative(name: &'static str, value: f32) -> Result<f32, ClothError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(ClothError::InvalidParameter {
            name,
            value: value as f64,
            expected: "a finite number >= 0",
        })
    }
}

/// Checks that every component of `v` is finite.
pub(crate) fn finite_vec(
    name: &'static str,
    v: crate::math::Vector,
) -> Result<crate::math::Vector, ClothError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(ClothError::NonFinite { name })
    }
}
