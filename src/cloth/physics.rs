//! The physical parameters of a cloth's world: gravity, air drag, wind,
//! collision thickness and self-collision. How the equations are solved is the solver's
//! (`crate::solver::SolverSettings`), not the cloth's.

use serde::{Deserialize, Serialize};

use crate::error::{finite_vec, non_negative, ClothError};
use crate::math::Vector;

/// Wind blowing on every triangle: `F = c A (n·d) n`, with `c` the strength,
/// `A` the triangle's area, `d` the unit direction and `n` the unit normal,
/// shared equally among the triangle's three particles.
///
/// With an air `speed`, the same law acts on the air's velocity relative to
/// each triangle, `u = w(x, t) − v`: `d` becomes `u/|u|` and the pressure
/// `c |u|²/speed²`, so a cloth moving with the wind feels less of it and
/// one moving against it more (the air damps its flapping), plus a skin
/// `friction` along the surface, `c_f c |u|²/speed² A (û − (n·û) n)`, which
/// is what streams a flag out when it lies edge-on to the wind. `w` varies
/// in time and space with `turbulence`: gusts that travel downwind at the
/// air's speed, and side gusts, from a seeded pattern (deterministic).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wind {
    /// Direction the wind blows towards (need not be normalised; zero means no wind).
    #[serde(deserialize_with = "crate::error::de::finite_vec")]
    pub direction: Vector,
    /// Strength `c`, a pressure in N/m² (at the air `speed`, on a still cloth).
    #[serde(deserialize_with = "crate::error::de::non_negative")]
    pub strength: f32,
    /// Speed of the air in m/s; 0 (the default): the pressure law alone,
    /// whatever the cloth's motion.
    #[serde(default, deserialize_with = "crate::error::de::non_negative")]
    pub speed: f32,
    /// Skin friction `c_f`: the share of the pressure that drags along the
    /// surface (with a `speed`; 0 by default).
    #[serde(default, deserialize_with = "crate::error::de::non_negative")]
    pub friction: f32,
    /// Gusts: how much the air's speed varies, as a share of it (with a
    /// `speed`; 0 by default: steady).
    #[serde(default, deserialize_with = "crate::error::de::non_negative")]
    pub turbulence: f32,
    /// Seed of the gusts' pattern.
    #[serde(default)]
    pub seed: u32,
}

impl Wind {
    /// No wind.
    pub const NONE: Wind = Wind {
        direction: Vector::ZERO,
        strength: 0.0,
        speed: 0.0,
        friction: 0.0,
        turbulence: 0.0,
        seed: 0,
    };

    /// Wind towards `direction` with pressure `strength` in N/m², the same
    /// on a moving cloth as on a still one.
    pub fn new(direction: Vector, strength: f32) -> Self {
        Self {
            direction,
            strength,
            ..Self::NONE
        }
    }

    /// The same wind as air moving at `speed` m/s, with skin `friction` and
    /// gusts of relative size `turbulence` from pattern `seed` (see the
    /// type's docs).
    pub fn with_air(mut self, speed: f32, friction: f32, turbulence: f32, seed: u32) -> Self {
        (self.speed, self.friction, self.turbulence, self.seed) =
            (speed, friction, turbulence, seed);
        self
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
        non_negative("wind speed", self.wind.speed)?;
        non_negative("wind friction", self.wind.friction)?;
        non_negative("wind turbulence", self.wind.turbulence)?;
        non_negative("thickness", self.thickness)?;
        non_negative("self friction", self.self_friction)?;
        if let Some(t) = self.self_thickness {
            non_negative("self thickness", t)?;
        }
        Ok(())
    }
}
