//! How many substeps a frame step is split into.

use serde::{Deserialize, Serialize};

/// How many substeps a frame step is split into.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Substeps {
    /// Exactly this many (at least 1).
    Fixed(u32),
    /// As many as the integrator needs to stay within its stability limit,
    /// estimated from the stiffest spring and the lightest particle.
    Auto,
}

impl std::fmt::Display for Substeps {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Substeps::Fixed(k) => write!(f, "{k}"),
            Substeps::Auto => write!(f, "auto"),
        }
    }
}

impl std::str::FromStr for Substeps {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Substeps::Auto);
        }
        match s.parse::<u32>() {
            Ok(k) if k >= 1 => Ok(Substeps::Fixed(k)),
            _ => Err(format!(
                "invalid substeps '{s}': expected a whole number >= 1 or 'auto'"
            )),
        }
    }
}

/// serde check: `Fixed(0)` is no number of substeps.
pub(crate) fn de_substeps<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Substeps, D::Error> {
    use serde::de::Error;
    match Substeps::deserialize(d)? {
        Substeps::Fixed(0) => Err(D::Error::custom(
            "invalid substeps Fixed(0): expected Auto or Fixed(k) with k >= 1",
        )),
        s => Ok(s),
    }
}

/// The longest substep (s) self-collision takes: the fold scene's layers
/// cross at longer ones (fast mass-spring: 700 self-intersections at 4
/// substeps of a 1/60 s frame, 22 at 8, none at 16; implicit Euler none
/// from 8); xpbd and symplectic Euler take 50–70 on their own.
pub const MAX_SELF_SUBSTEP: f32 = 1.0 / 960.0;

/// The fewest substeps self-collision takes in a frame of `dt` seconds.
pub(crate) fn self_collision_substeps(dt: f32) -> u32 {
    let k = (dt / MAX_SELF_SUBSTEP).ceil();
    if k.is_finite() {
        k.clamp(1.0, 1.0e6) as u32
    } else {
        1
    }
}
