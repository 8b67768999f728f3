//! Materials: stiffness and damping per spring kind, density and colour.

use serde::{Deserialize, Serialize};

use super::springs::SpringKind;
use crate::error::{non_negative, positive, ClothError};

/// Stiffness and damping of one kind of spring.
///
/// The force between the two ends of a spring is Hooke's `-k (|x_ij| - L)`
/// plus the damping `-c ((v_j - v_i)·d)` along the spring direction `d`.
/// Because a grid of springs behaves like a sheet whose stiffness is the
/// stiffness of one spring, the same values give the same cloth at any
/// resolution.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpringParams {
    /// Hooke stiffness `k`, in N/m.
    #[serde(deserialize_with = "crate::error::de::positive")]
    pub stiffness: f32,
    /// Damping `c` along the spring, in N·s/m.
    #[serde(deserialize_with = "crate::error::de::non_negative")]
    pub damping: f32,
}

impl SpringParams {
    /// Stiffness `k` in N/m and damping `c` in N·s/m.
    pub const fn new(stiffness: f32, damping: f32) -> Self {
        Self { stiffness, damping }
    }

    /// Checks both values (stiffness > 0, damping >= 0, both finite).
    pub fn validate(&self, kind: SpringKind) -> Result<(), ClothError> {
        let (k, c) = match kind {
            SpringKind::Stretch => ("stretch stiffness", "stretch damping"),
            SpringKind::Shear => ("shear stiffness", "shear damping"),
            SpringKind::Bend => ("bend stiffness", "bend damping"),
        };
        positive(k, self.stiffness)?;
        non_negative(c, self.damping)?;
        Ok(())
    }
}

/// A cloth material: spring parameters per kind, areal density and colour.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Material {
    /// Display name (`cotton`, `silk`, ...).
    pub name: String,
    /// Stretch springs (the four grid neighbours).
    pub stretch: SpringParams,
    /// Shear springs (the diagonals).
    pub shear: SpringParams,
    /// Bend springs (two apart along rows and columns).
    pub bend: SpringParams,
    /// Areal density in kg/m², used when a cloth is built without a total mass.
    #[serde(deserialize_with = "crate::error::de::positive")]
    pub density: f32,
    /// Display colour, linear RGB in 0..=1.
    #[serde(default = "default_color")]
    pub color: [f32; 3],
    /// Largest strain a stretch spring may reach (0.045: 4.5% past its rest
    /// length), or `None` for none. Woven cloth barely stretches, but a
    /// spring soft enough to step cheaply stretches under a sudden load (a
    /// landing, a heavy body); after each substep every solver shortens the
    /// stretch springs past the limit, a few Gauss–Seidel passes, before the
    /// contacts (Provot 1995, "Deformation constraints in a mass-spring
    /// model"). Below the limit the springs alone act.
    #[serde(default, deserialize_with = "crate::error::de::opt_positive")]
    pub stretch_limit: Option<f32>,
    /// Strain past which a stretch spring tears (0.3: 30% past its rest
    /// length), or `None`: the cloth never tears (the default). A tear splits
    /// the particle at one end of the spring in two, across the pull, so the
    /// mesh opens there (see `Cloth::split_particle`). With a stretch limit,
    /// a tear strain at or above it is never reached.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_positive"
    )]
    pub tear_strain: Option<f32>,
}

/// The stretch limit of the woven presets (silk, cotton, denim, leather,
/// canvas): 4.5%, so that cloth stays under 5% stretch however it lands.
pub const WOVEN_STRETCH_LIMIT: f32 = 0.045;

fn default_color() -> [f32; 3] {
    [0.8, 0.8, 0.8]
}

impl Material {
    /// The names of the built-in presets, in the order [`Material::presets`] returns them.
    pub const PRESET_NAMES: [&'static str; 6] =
        ["silk", "cotton", "denim", "leather", "rubber", "canvas"];

    /// A user-defined material.
    pub fn new(
        name: impl Into<String>,
        stretch: SpringParams,
        shear: SpringParams,
        bend: SpringParams,
        density: f32,
        color: [f32; 3],
    ) -> Self {
        Self {
            name: name.into(),
            stretch,
            shear,
            bend,
            density,
            color,
            stretch_limit: None,
            tear_strain: None,
        }
    }

    /// The same material tearing where a stretch spring passes `strain` (a
    /// strain: 0.3 for 30%; `None`: it never tears).
    pub fn with_tear_strain(mut self, strain: Option<f32>) -> Self {
        self.tear_strain = strain;
        self
    }

    /// The same material with its stretch springs held within `limit` of
    /// their rest length (a strain: 0.045 for 4.5%; `None`: no limit).
    pub fn with_stretch_limit(mut self, limit: Option<f32>) -> Self {
        self.stretch_limit = limit;
        self
    }

    /// The longest a stretch spring may be over its rest length: 1 plus the
    /// limit, infinite without one.
    pub fn stretch_limit_factor(&self) -> f32 {
        self.stretch_limit.map_or(f32::INFINITY, |e| 1.0 + e)
    }

    /// Light, slippery and very flexible: folds into many small wrinkles.
    pub fn silk() -> Self {
        Self::new(
            "silk",
            SpringParams::new(600.0, 0.02),
            SpringParams::new(30.0, 0.005),
            SpringParams::new(0.3, 0.001),
            0.08,
            [0.85, 0.25, 0.45],
        )
        .with_stretch_limit(Some(WOVEN_STRETCH_LIMIT))
    }

    /// The default: a medium-weight woven cotton.
    pub fn cotton() -> Self {
        Self::new(
            "cotton",
            SpringParams::new(1500.0, 0.05),
            SpringParams::new(150.0, 0.02),
            SpringParams::new(2.0, 0.005),
            0.15,
            [0.90, 0.82, 0.62],
        )
        .with_stretch_limit(Some(WOVEN_STRETCH_LIMIT))
    }

    /// Heavy twill: stiff in stretch and noticeably stiff in bending.
    pub fn denim() -> Self {
        Self::new(
            "denim",
            SpringParams::new(4000.0, 0.15),
            SpringParams::new(600.0, 0.05),
            SpringParams::new(12.0, 0.02),
            0.40,
            [0.20, 0.33, 0.60],
        )
        .with_stretch_limit(Some(WOVEN_STRETCH_LIMIT))
    }

    /// Stiff, heavy and strongly damped: falls in few, broad folds.
    pub fn leather() -> Self {
        Self::new(
            "leather",
            SpringParams::new(8000.0, 0.5),
            SpringParams::new(3000.0, 0.2),
            SpringParams::new(60.0, 0.1),
            0.90,
            [0.45, 0.27, 0.14],
        )
        .with_stretch_limit(Some(WOVEN_STRETCH_LIMIT))
    }

    /// Very stretchy and bouncy: low stiffness, almost no damping.
    pub fn rubber() -> Self {
        Self::new(
            "rubber",
            SpringParams::new(200.0, 0.005),
            SpringParams::new(200.0, 0.005),
            SpringParams::new(5.0, 0.001),
            1.0,
            [0.15, 0.65, 0.30],
        )
    }

    /// Sail canvas: very stiff in stretch and shear, moderate bending.
    pub fn canvas() -> Self {
        Self::new(
            "canvas",
            SpringParams::new(10000.0, 0.2),
            SpringParams::new(5000.0, 0.1),
            SpringParams::new(20.0, 0.02),
            0.30,
            [0.93, 0.93, 0.88],
        )
        .with_stretch_limit(Some(WOVEN_STRETCH_LIMIT))
    }

    /// Every built-in preset.
    pub fn presets() -> Vec<Material> {
        vec![
            Self::silk(),
            Self::cotton(),
            Self::denim(),
            Self::leather(),
            Self::rubber(),
            Self::canvas(),
        ]
    }

    /// Looks a preset up by name (case-insensitive).
    pub fn by_name(name: &str) -> Result<Material, ClothError> {
        Self::presets()
            .into_iter()
            .find(|m| m.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| ClothError::UnknownName {
                what: "material",
                name: name.to_string(),
                valid: Self::PRESET_NAMES.join(", "),
            })
    }

    /// The parameters of one spring kind.
    pub fn params(&self, kind: SpringKind) -> SpringParams {
        match kind {
            SpringKind::Stretch => self.stretch,
            SpringKind::Shear => self.shear,
            SpringKind::Bend => self.bend,
        }
    }

    /// Mutable parameters of one spring kind.
    pub fn params_mut(&mut self, kind: SpringKind) -> &mut SpringParams {
        match kind {
            SpringKind::Stretch => &mut self.stretch,
            SpringKind::Shear => &mut self.shear,
            SpringKind::Bend => &mut self.bend,
        }
    }

    /// Checks every value: stiffness and density finite and > 0, damping finite and >= 0,
    /// colour components finite.
    pub fn validate(&self) -> Result<(), ClothError> {
        for kind in SpringKind::ALL {
            self.params(kind).validate(kind)?;
        }
        positive("density", self.density)?;
        if let Some(limit) = self.stretch_limit {
            positive("stretch limit", limit)?;
        }
        if let Some(strain) = self.tear_strain {
            positive("tear strain", strain)?;
        }
        if !self.color.iter().all(|c| c.is_finite()) {
            return Err(ClothError::NonFinite { name: "color" });
        }
        Ok(())
    }
}

impl Default for Material {
    fn default() -> Self {
        Self::cotton()
    }
}
