//! The physical parameters of a cloth's world: gravity, air drag, wind,
//! collision thickness and self-collision. How the equations are solved is the solver's
//! (`crate::solver::SolverSettings`), not the cloth's.

use serde::{Deserialize, Serialize};

use crate::error::{finite_vec, non_negative, ClothError};
use crate::math::Vector;

/// Wind blowing on every triangle: `F = c A (n·d) n`, with `c` the strength,
/// `A` the triangle's area, `d` the unit direction and `n` the unit normal,
/// shared equally among the triangle's three particles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wind {
    /// Direction the wind blows towards (need not be normalised; zero means no wind).
    #[serde(deserialize_with = "crate::error::de::finite_vec")]
    pub direction: Vector,
    /// Strength `c`, a pressure in N/m².
    #[serde(deserialize_with = "crate::error::de::non_negative")]
    pub strength: f32,
}

impl Wind {
    /// No wind.
    pub const NONE: Wind = Wind {
        direction: Vector::ZERO,
        strength: 0.0,
    };

    /// Wind towards `direction` with pressure `strength` in N/m².
    pub fn new(direction: Vector, strength: f32) -> Self {
        Self {
            direction,
            strength,
        }
    }

    /// True when it exerts no force.
    pub fn is_calm(&self) -> bool {
        self.strength == 0.0 || self.direction.length_squared() == 0.0
    }
}

/// The physical parameters of a cloth; all can change between steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsParams {
    /// Gravity, in m/s².
    pub gravity: Vector,
    /// Air drag: each particle feels `-drag · m · v`; in 1/s.
    pub air_drag: f32,
    /// Wind on the triangles.
    pub wind: Wind,
    /// Collision thickness: particles are kept this far outside obstacles
    /// (and, with self-collision, from the cloth's own triangles), in metres.
    pub thickness: f32,
    /// Keep the cloth from passing through itself (off by default: it costs
    /// a look over the triangles every few substeps).
    #[serde(default)]
    pub self_collision: bool,
    /// Coulomb friction between touching layers of the cloth.
    #[serde(default = "default_self_friction")]
    pub self_friction: f32,
    /// Distance the cloth's layers keep from each other, in metres; `None`:
    /// the collision thickness, but at most a quarter of the shortest
    /// stretch spring ([`crate::cloth::Cloth::self_thickness`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub self_thickness: Option<f32>,
    /// Tethers (long-range attachments): every free particle stays within
    /// its rest distance, through the mesh, of the nearest pinned particle,
    /// so a pinned cloth does not stretch under its own weight (off by
    /// default).
    #[serde(default, skip_serializing_if = "is_false")]
    pub tethers: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn default_self_friction() -> f32 {
    0.3
}

impl Default for PhysicsParams {
    fn default() -> Self {
        Self {
            gravity: Vector::new(0.0, -9.81, 0.0),
            air_drag: 0.02,
            wind: Wind::NONE,
            thickness: 0.01,
            self_collision: false,
            self_friction: default_self_friction(),
            self_thickness: None,
            tethers: false,
        }
    }
}

impl PhysicsParams {
    /// Checks every value and says which one is wrong.
    pub fn validate(&self) -> Result<(), ClothError> {
        finite_vec("gravity", self.gravity)?;
        non_negative("air drag", self.air_drag)?;
        finite_vec("wind direction", self.wind.direction)?;
        non_negative("wind strength", self.wind.strength)?;
        non_negative("thickness", self.thickness)?;
        non_negative("self friction", self.self_friction)?;
        if let Some(t) = self.self_thickness {
            non_negative("self thickness", t)?;
        }
        Ok(())
    }
}
