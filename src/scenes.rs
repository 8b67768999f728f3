//! The canonical scenes of SCENES.md, built in one place for the examples,
//! the command, the tests and the benches.

use serde::{Deserialize, Serialize};

use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use crate::cloth::{Cloth, ClothBuilder, Material, PinPreset, Substeps, Wind};
use crate::collision::Obstacle;
use crate::error::{positive, ClothError};
use crate::integrators::Integrator;
use crate::math::{Pose, Vector};
use crate::pipeline::StepReport;
use crate::rapier::RapierCoupling;

/// The frame step of every scene, in seconds.
pub const FRAME_DT: f32 = 1.0 / 60.0;
/// Collision thickness of every scene, in metres.
pub const THICKNESS: f32 = 0.01;
/// Total cloth mass of every scene, in kg.
pub const CLOTH_MASS: f32 = 1.0;

/// The canonical scenes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum SceneKind {
    /// An N×N tablecloth falling on a fixed ball.
    Drape,
    /// An N×N tablecloth falling on a fixed cube.
    Box,
    /// A 32×20 flag pinned along its pole, in the wind.
    Flag,
    /// A 33×33 horizontal cloth hanging from a pin figure.
    Pins,
    /// A 40×40 curtain on its rail pushed aside by a kinematic rapier ball.
    Curtain,
    /// A 32×32 hammock on its four corners catching three dynamic rapier boxes.
    Hammock,
}

impl SceneKind {
    /// Every scene.
    pub const ALL: [SceneKind; 6] = [
        SceneKind::Drape,
        SceneKind::Box,
        SceneKind::Flag,
        SceneKind::Pins,
        SceneKind::Curtain,
        SceneKind::Hammock,
    ];

    /// The scene's name.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Drape => "drape",
            SceneKind::Box => "box",
            SceneKind::Flag => "flag",
            SceneKind::Pins => "pins",
            SceneKind::Curtain => "curtain",
            SceneKind::Hammock => "hammock",
        }
    }

    /// One line saying what a user sees.
    pub fn description(self) -> &'static str {
        match self {
            SceneKind::Drape => "a tablecloth falls on a ball and rests on top",
            SceneKind::Box => "a tablecloth falls on a cube; nothing passes through its edges",
            SceneKind::Flag => "a flag pinned to its pole flaps in the wind",
            SceneKind::Pins => "a cloth hangs from a pinning figure (variants)",
            SceneKind::Curtain => "a curtain is pushed aside by a moving kinematic rapier ball",
            SceneKind::Hammock => "a hammock catches three dynamic rapier boxes (two-way coupling)",
        }
    }

    /// Looks a scene up by name.
    pub fn from_name(name: &str) -> Result<Self, ClothError> {
        Self::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| ClothError::UnknownName {
                what: "scene",
                name: name.to_string(),
                valid: Self::ALL.map(|s| s.name()).join(", "),
            })
    }

    /// The pin variants the scene accepts (empty when it takes none).
    pub fn variants(self) -> &'static [PinPreset] {
        match self {
            SceneKind::Pins => &[
                PinPreset::Center,
                PinPreset::CenterRow,
                PinPreset::FourCenter,
                PinPreset::TwoCorners,
                PinPreset::FourCorners,
            ],
            _ => &[],
        }
    }

    /// Frames a run lasts by default (120, or 240 for `flag`).
    pub fn default_frames(self) -> u32 {
        match self {
            SceneKind::Flag | SceneKind::Hammock => 240,
            _ => 120,
        }
    }

    /// Default grid (columns, rows).
    pub fn default_grid(self) -> (usize, usize) {
        match self {
            SceneKind::Drape | SceneKind::Box => (64, 64),
            SceneKind::Flag => (32, 20),
            SceneKind::Pins => (33, 33),
            SceneKind::Curtain => (40, 40),
            SceneKind::Hammock => (32, 32),
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = ClothError;
    fn from_str(s: &str) -> Result<Self, ClothError> {
        Self::from_name(s)
    }
}

/// Choices a user can override when building a scene; `None` keeps the scene's default.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SceneOptions {
    /// Particles along a row; rows follow the scene's aspect ratio.
    pub n: Option<usize>,
    /// The integrator (default: symplectic Euler).
    pub integrator: Option<Integrator>,
    /// The material (default: cotton).
    pub material: Option<Material>,
    /// The pin variant of the `pins` scene (default: `center`).
    pub variant: Option<PinPreset>,
    /// Frame step in seconds (default 1/60).
    pub dt: Option<f32>,
    /// Substeps per frame (default: auto).
    pub substeps: Option<Substeps>,
    /// Frames to run (default: the scene's length).
    pub frames: Option<u32>,
    /// Friction of every obstacle (default 0.5).
    pub friction: Option<f32>,
}

/// The rapier side of a scene: the world, the coupling, and the bodies the scene drives.
pub struct RapierSide {
    /// The rapier world.
    pub world: PhysicsWorld,
    /// The cloth–world coupling.
    pub coupling: RapierCoupling,
    /// The scene's bodies (the curtain's ball, the hammock's boxes).
    pub bodies: Vec<RigidBodyHandle>,
}

impl std::fmt::Debug for RapierSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RapierSide")
            .field("bodies", &self.world.bodies.len())
            .field("colliders", &self.world.colliders.len())
            .finish()
    }
}

/// Where the curtain's ball is (z, metres) `t` seconds into the scene.
pub fn curtain_ball_z(t: f32) -> f32 {
    (-1.0 + 2.0 * t).min(1.0)
}

/// A scene ready to run: its cloth, obstacles and frame step.
#[derive(Debug)]
pub struct Scene {
    /// Which scene.
    pub kind: SceneKind,
    /// The pin variant, for `pins`.
    pub variant: Option<PinPreset>,
    /// The cloth.
    pub cloth: Cloth,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Frame step, in seconds.
    pub dt: f32,
    /// Frames a run lasts.
    pub frames: u32,
    /// Frames stepped so far.
    pub frame: u32,
    /// The rapier world of the scenes that have one (`curtain`, `hammock`).
    pub rapier: Option<RapierSide>,
}

impl Scene {
    /// Builds a scene with the given options.
    pub fn build(kind: SceneKind, options: &SceneOptions) -> Result<Scene, ClothError> {
        let (dc, dr) = kind.default_grid();
        let (cols, rows) = match options.n {
            Some(n) => (
                n,
                ((n as f32 * dr as f32 / dc as f32).round() as usize).max(2),
            ),
            None => (dc, dr),
        };
        let dt = positive("dt", options.dt.unwrap_or(FRAME_DT))?;
        let friction = options.friction.unwrap_or(0.5);
        if !(friction.is_finite() && friction >= 0.0) {
            return Err(ClothError::InvalidParameter {
                name: "friction",
                value: friction as f64,
                expected: "a finite number >= 0",
            });
        }
        let variant = match (kind.variants(), options.variant) {
            ([], None) => None,
            ([], Some(v)) => {
                return Err(ClothError::UnknownName {
                    what: "variant",
                    name: v.name().to_string(),
                    valid: format!("none (the {} scene has no variants)", kind.name()),
                })
            }
            (allowed, Some(v)) if !allowed.contains(&v) => {
                return Err(ClothError::UnknownName {
                    what: "variant",
                    name: v.name().to_string(),
                    valid: allowed
                        .iter()
                        .map(|p| p.name())
                        .collect::<Vec<_>>()
                        .join(", "),
                })
            }
            (allowed, v) => Some(v.unwrap_or(allowed[0])),
        };
        let mut builder = ClothBuilder::new(cols, rows)
            .total_mass(CLOTH_MASS)
            .material(options.material.clone().unwrap_or_default());
        let mut obstacles = Vec::new();
        let mut wind = Wind::NONE;
        match kind {
            SceneKind::Drape => {
                builder = builder
                    .size(1.0, 1.0)
                    .horizontal(Vector::new(0.0, 0.6, 0.0));
                obstacles.push(Obstacle::ball(Vector::ZERO, 0.3));
            }
            SceneKind::Box => {
                builder = builder
                    .size(1.0, 1.0)
                    .horizontal(Vector::new(0.0, 0.6, 0.0));
                obstacles.push(Obstacle::cuboid(Vector::splat(0.25), Pose::IDENTITY));
            }
            SceneKind::Flag => {
                builder = builder
                    .size(1.6, 1.0)
                    .vertical(Vector::new(0.8, 1.2, 0.0))
                    .pins(PinPreset::FlagColumn);
                wind = Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0);
            }
            SceneKind::Pins => {
                builder = builder
                    .size(1.0, 1.0)
                    .horizontal(Vector::new(0.0, 0.6, 0.0))
                    .pins(variant.unwrap_or(PinPreset::Center));
            }
            SceneKind::Curtain => {
                builder = builder
                    .size(1.0, 1.0)
                    .vertical(Vector::new(0.0, 1.0, 0.0))
                    .pins(PinPreset::CurtainRow);
            }
            SceneKind::Hammock => {
                builder = builder
                    .size(1.0, 1.0)
                    .horizontal(Vector::new(0.0, 0.5, 0.0))
                    .pins(PinPreset::FourCorners);
            }
        }
        let rapier = match kind {
            SceneKind::Curtain => Some(curtain_world(dt, friction)),
            SceneKind::Hammock => Some(hammock_world(dt, friction)),
            _ => None,
        };
        let mut cloth = builder.build()?;
        cloth.params.wind = wind;
        cloth.params.thickness = THICKNESS;
        cloth.params.integrator = options.integrator.unwrap_or(Integrator::SymplecticEuler);
        cloth.params.substeps = options.substeps.unwrap_or(Substeps::Auto);
        cloth.params.validate()?;
        for o in &mut obstacles {
            o.friction = friction;
        }
        Ok(Scene {
            kind,
            variant,
            cloth,
            obstacles,
            dt,
            frames: options.frames.unwrap_or(kind.default_frames()),
            frame: 0,
            rapier,
        })
    }

    /// Advances the scene by one frame: the cloth, then rapier (when the scene
    /// has a world), see [`crate::rapier`] for why in that order.
    pub fn step_frame(&mut self) -> Result<StepReport, ClothError> {
        let report = match &mut self.rapier {
            None => self.cloth.step(self.dt, &self.obstacles)?,
            Some(side) => {
                if self.kind == SceneKind::Curtain {
                    let t = (self.frame + 1) as f32 * self.dt;
                    if let Some(ball) = side
                        .bodies
                        .first()
                        .and_then(|h| side.world.bodies.get_mut(*h))
                    {
                        ball.set_next_kinematic_translation(Vector::new(
                            0.0,
                            0.9,
                            curtain_ball_z(t),
                        ));
                    }
                }
                let report = side
                    .coupling
                    .step_world(&mut self.cloth, &mut side.world)?
                    .step;
                side.world.step();
                report
            }
        };
        self.frame += 1;
        Ok(report)
    }

    /// The obstacles as they are now: the scene's own, or the rapier world's colliders.
    pub fn current_obstacles(&self) -> Vec<Obstacle> {
        match &self.rapier {
            None => self.obstacles.clone(),
            Some(side) => side
                .world
                .colliders
                .iter()
                .map(|(_, c)| Obstacle::new(c.shared_shape().clone(), *c.position()))
                .collect(),
        }
    }

    /// The deepest any particle lies inside any obstacle's surface, in metres.
    pub fn max_penetration(&self) -> f32 {
        match &self.rapier {
            None => crate::metrics::max_penetration(&self.cloth, &self.obstacles),
            Some(_) => crate::metrics::max_penetration(&self.cloth, &self.current_obstacles()),
        }
    }
}

/// The curtain's world: a kinematic ball of radius 0.2 at (0, 0.9, -1).
fn curtain_world(dt: f32, friction: f32) -> RapierSide {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = dt;
    let (ball, _) = world.insert(
        RigidBodyBuilder::kinematic_position_based().translation(Vector::new(
            0.0,
            0.9,
            curtain_ball_z(0.0),
        )),
        ColliderBuilder::ball(0.2),
    );
    let mut coupling = RapierCoupling::new();
    coupling.friction = friction;
    RapierSide {
        world,
        coupling,
        bodies: vec![ball],
    }
}

/// The hammock's world: three 0.5 kg boxes of half-extent 0.1 dropped from
/// y = 1 at x = -0.25, 0, 0.25, and a fixed ground with its top at y = 0.
fn hammock_world(dt: f32, friction: f32) -> RapierSide {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = dt;
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.5, 0.0)),
        ColliderBuilder::cuboid(3.0, 0.5, 3.0),
    );
    let half = 0.1f32;
    let density = 0.5 / (8.0 * half * half * half);
    let bodies = [-0.25f32, 0.0, 0.25]
        .iter()
        .map(|&x| {
            world
                .insert(
                    RigidBodyBuilder::dynamic().translation(Vector::new(x, 1.0, 0.0)),
                    ColliderBuilder::cuboid(half, half, half).density(density),
                )
                .0
        })
        .collect();
    let mut coupling = RapierCoupling::new();
    coupling.friction = friction;
    RapierSide {
        world,
        coupling,
        bodies,
    }
}
