//! The canonical scenes of SCENES.md, built in one place for the examples,
//! the command, the tests and the benches; and scenes of the user's own,
//! described in the same terms ([`SceneDesc`]) and read from RON files
//! ([`mod@file`]).

pub mod desc;
pub mod file;

pub use desc::{
    AttachmentDesc, BodyDesc, BodyKind, ClothDesc, MaterialDesc, ObstacleDesc, PinsDesc, Placement,
    SceneDesc, ShapeDesc, Waypoint,
};

use serde::{Deserialize, Serialize};

use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use crate::cloth::{Cloth, ClothBuilder, Material, PinPreset, Substeps, Wind};
use crate::collision::Obstacle;
use crate::error::ClothError;
use crate::integrators::Integrator;
use crate::math::{Pose, Rotation, Vector};
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
        crate::error::by_name(&Self::ALL, Self::name, "scene", name)
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
    /// The integrator (default: the scene's, symplectic Euler but for
    /// `hammock`'s implicit Euler); without `substeps`, it brings its own
    /// default substeps ([`Integrator::default_substeps`]).
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
    /// The scene's moving bodies, kinematic and dynamic (the curtain's ball,
    /// the hammock's boxes), in the order of the description.
    pub bodies: Vec<RigidBodyHandle>,
    /// Every body of the description, in its order (attachments refer to these).
    pub all_bodies: Vec<RigidBodyHandle>,
    /// Kinematic bodies that follow a path, with the description they follow.
    pub paths: Vec<(RigidBodyHandle, BodyDesc)>,
    /// How fast each of `bodies` moved during the last frame: the distance
    /// its centre travelled over the frame step, in m/s. (For a body resting
    /// in a contact that rapier keeps resolving, its stored `linvel` is not
    /// its motion: rapier removes the position-correction velocity after
    /// moving the body.)
    pub last_speeds: Vec<f32>,
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

impl SceneKind {
    /// The scene's description with `options` applied: what [`Scene::build`]
    /// builds and what `cloth3d export-scene` writes.
    pub fn desc(self, options: &SceneOptions) -> Result<SceneDesc, ClothError> {
        let variant = self.check_variant(options.variant)?;
        let (cols, rows) = self.default_grid();
        let horizontal = |y: f32| Placement::Horizontal {
            center: Vector::new(0.0, y, 0.0),
        };
        let mut cloth = match self {
            SceneKind::Drape | SceneKind::Box | SceneKind::Pins => {
                ClothDesc::new(cols, rows, horizontal(0.6))
            }
            SceneKind::Flag => {
                let mut c = ClothDesc::new(
                    cols,
                    rows,
                    Placement::Vertical {
                        center: Vector::new(0.8, 1.2, 0.0),
                    },
                );
                c.size = (1.6, 1.0);
                c
            }
            SceneKind::Curtain => ClothDesc::new(
                cols,
                rows,
                Placement::Vertical {
                    center: Vector::new(0.0, 1.0, 0.0),
                },
            ),
            SceneKind::Hammock => {
                let mut c = ClothDesc::new(cols, rows, horizontal(0.5));
                // Hammock cotton is strongly damped along its threads (above
                // a spring's critical damping at N = 32): with plain cotton's
                // damping the boxes bob for many seconds.
                let mut m = Material::cotton();
                m.name = "damped cotton".into();
                m.stretch.damping = 3.0;
                m.shear.damping = 3.0;
                c.material = MaterialDesc::Custom(m);
                c
            }
        };
        cloth.pins = PinsDesc::preset(match self {
            SceneKind::Flag => PinPreset::FlagColumn,
            SceneKind::Pins => variant.unwrap_or(PinPreset::Center),
            SceneKind::Curtain => PinPreset::CurtainRow,
            SceneKind::Hammock => PinPreset::FourCorners,
            _ => PinPreset::None,
        });
        let mut desc = SceneDesc::new(self.name(), cloth);
        desc.description = self.description().to_string();
        desc.frames = self.default_frames();
        if self == SceneKind::Hammock {
            // Strong damping is what the implicit integrator is for; four
            // substeps keep the boxes' landing from stretching the cloth
            // through them (the boxes' contacts are not constraints of its solve).
            desc.integrator = Integrator::ImplicitEuler;
            desc.substeps = Substeps::Fixed(4);
        }
        match self {
            SceneKind::Drape => desc.obstacles.push(ObstacleDesc::fixed(
                ShapeDesc::Ball { radius: 0.3 },
                Vector::ZERO,
            )),
            SceneKind::Box => desc.obstacles.push(ObstacleDesc::fixed(
                ShapeDesc::Cuboid {
                    half_extents: Vector::splat(0.25),
                },
                Vector::ZERO,
            )),
            SceneKind::Flag => desc.wind = Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0),
            SceneKind::Pins => {}
            SceneKind::Curtain => {
                let mut ball = BodyDesc::new(
                    BodyKind::Kinematic,
                    ShapeDesc::Ball { radius: 0.2 },
                    Vector::new(0.0, 0.9, curtain_ball_z(0.0)),
                );
                ball.path = vec![
                    Waypoint {
                        time: 0.0,
                        translation: Vector::new(0.0, 0.9, curtain_ball_z(0.0)),
                    },
                    Waypoint {
                        time: 1.0,
                        translation: Vector::new(0.0, 0.9, curtain_ball_z(1.0)),
                    },
                ];
                desc.bodies.push(ball);
            }
            SceneKind::Hammock => {
                desc.bodies.push(BodyDesc::new(
                    BodyKind::Fixed,
                    ShapeDesc::Cuboid {
                        half_extents: Vector::new(3.0, 0.5, 3.0),
                    },
                    Vector::new(0.0, -0.5, 0.0),
                ));
                for x in [-0.25f32, 0.0, 0.25] {
                    let mut b = BodyDesc::new(
                        BodyKind::Dynamic,
                        ShapeDesc::Cuboid {
                            half_extents: Vector::splat(0.1),
                        },
                        Vector::new(x, 1.0, 0.0),
                    );
                    b.mass = Some(0.5);
                    desc.bodies.push(b);
                }
            }
        }
        desc.apply(&SceneOptions {
            variant: None,
            ..options.clone()
        })?;
        Ok(desc)
    }

    fn check_variant(self, variant: Option<PinPreset>) -> Result<Option<PinPreset>, ClothError> {
        match (self.variants(), variant) {
            ([], None) => Ok(None),
            ([], Some(v)) => Err(ClothError::UnknownName {
                what: "variant",
                name: v.name().to_string(),
                valid: format!("none (the {} scene has no variants)", self.name()),
            }),
            (allowed, Some(v)) if !allowed.contains(&v) => Err(ClothError::UnknownName {
                what: "variant",
                name: v.name().to_string(),
                valid: allowed
                    .iter()
                    .map(|p| p.name())
                    .collect::<Vec<_>>()
                    .join(", "),
            }),
            (allowed, v) => Ok(Some(v.unwrap_or(allowed[0]))),
        }
    }
}

impl SceneDesc {
    /// Applies the user's overrides: grid (rows follow the aspect ratio),
    /// integrator, material, pin preset, dt, substeps, frames, friction.
    pub fn apply(&mut self, options: &SceneOptions) -> Result<(), ClothError> {
        if let Some(n) = options.n {
            let (c, r) = (self.cloth.cols, self.cloth.rows);
            self.cloth.cols = n;
            self.cloth.rows = ((n as f32 * r as f32 / c as f32).round() as usize).max(2);
        }
        if let Some(i) = options.integrator {
            self.integrator = i;
            if options.substeps.is_none() {
                // The scene's substeps were chosen for its own integrator.
                self.substeps = i.default_substeps();
            }
        }
        if let Some(m) = &options.material {
            self.cloth.material = MaterialDesc::of(m);
        }
        if let Some(v) = options.variant {
            self.cloth.pins = PinsDesc::preset(v);
        }
        if let Some(dt) = options.dt {
            self.dt = crate::error::positive("dt", dt)?;
        }
        if let Some(s) = options.substeps {
            self.substeps = s;
        }
        if let Some(f) = options.frames {
            self.frames = f;
        }
        if let Some(f) = options.friction {
            self.friction = crate::error::non_negative("friction", f)?;
            for o in &mut self.obstacles {
                o.friction = None;
            }
        }
        Ok(())
    }
}

/// A scene ready to run: its cloth, obstacles and frame step.
#[derive(Debug)]
pub struct Scene {
    /// The scene's name (a canonical scene's, or a scene file's `name`).
    pub name: String,
    /// Which canonical scene, if it is one.
    pub kind: Option<SceneKind>,
    /// The pin variant, for `pins`.
    pub variant: Option<PinPreset>,
    /// What the scene was built from.
    pub desc: SceneDesc,
    /// The cloth.
    pub cloth: Cloth,
    /// The obstacles (scenes without a rapier world).
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

fn field_error(field: impl Into<String>, err: impl std::fmt::Display) -> ClothError {
    ClothError::SceneFile {
        path: String::new(),
        line: 0,
        column: 0,
        field: field.into(),
        message: err.to_string(),
    }
}

impl Scene {
    /// Builds a canonical scene with the given options.
    pub fn build(kind: SceneKind, options: &SceneOptions) -> Result<Scene, ClothError> {
        let desc = kind.desc(options)?;
        // The scenes with variants pin their cloth with the chosen one.
        let variant = (!kind.variants().is_empty()).then_some(desc.cloth.pins.preset);
        let mut scene = Scene::from_desc(desc)?;
        scene.kind = Some(kind);
        scene.variant = variant;
        Ok(scene)
    }

    /// A canonical scene by name, or else a RON scene file by path (see
    /// [`file::load_scene`]), with `options` applied.
    pub fn open(name_or_path: &str, options: &SceneOptions) -> Result<Scene, ClothError> {
        if let Ok(kind) = SceneKind::from_name(name_or_path) {
            return Scene::build(kind, options);
        }
        let path = std::path::Path::new(name_or_path);
        if path.exists() || name_or_path.ends_with(".ron") {
            return file::load_scene(path, options);
        }
        Err(ClothError::UnknownName {
            what: "scene",
            name: name_or_path.to_string(),
            valid: format!(
                "{}, or the path of a .ron scene file",
                SceneKind::ALL.map(|s| s.name()).join(", ")
            ),
        })
    }

    /// Builds a scene from its description (a scene file's, or a canonical one's).
    ///
    /// A value the description cannot hold (a pin outside the grid, a mesh
    /// index out of range) is a [`ClothError::SceneFile`] naming the field.
    pub fn from_desc(desc: SceneDesc) -> Result<Scene, ClothError> {
        let c = &desc.cloth;
        let material = c
            .material
            .material()
            .map_err(|e| field_error("cloth.material", e))?;
        let mut builder = ClothBuilder::new(c.cols, c.rows)
            .size(c.size.0, c.size.1)
            .material(material)
            .pins(c.pins.preset);
        builder = match c.mass {
            Some(m) => builder.total_mass(m),
            None => builder.mass_from_density(),
        };
        builder = match c.placement {
            Placement::Horizontal { center } => builder.horizontal(center),
            Placement::Vertical { center } => builder.vertical(center),
            Placement::Pose {
                translation,
                rotation,
            } => builder.pose(Pose::from_parts(
                translation,
                Rotation::from_scaled_axis(rotation),
            )),
        };
        for &p in &c.pins.particles {
            builder = builder.pin(p);
        }
        let mut cloth = builder.build().map_err(|e| match e {
            ClothError::ParticleOutOfRange { .. } => field_error("cloth.pins.particles", e),
            ClothError::GridTooLarge { .. } | ClothError::GridTooSmall { .. } => {
                field_error("cloth.cols", e)
            }
            other => other,
        })?;
        for &(row, col) in &c.pins.cells {
            cloth
                .pin_cell(row, col)
                .map_err(|e| field_error("cloth.pins.cells", e))?;
        }
        cloth.params.wind = desc.wind;
        cloth.params.gravity = desc.gravity;
        cloth.params.air_drag = desc.air_drag;
        cloth.params.thickness = desc.thickness;
        cloth.params.integrator = desc.integrator;
        cloth.params.substeps = desc.substeps;
        cloth.params.validate()?;
        crate::error::positive("dt", desc.dt)?;

        let mut obstacles = Vec::with_capacity(desc.obstacles.len());
        for (i, o) in desc.obstacles.iter().enumerate() {
            let shape = o
                .shape
                .shape()
                .map_err(|e| field_error(format!("obstacles[{i}].shape"), e))?;
            let obstacle = Obstacle::new(shape, o.pose())
                .with_velocity(o.linvel, o.angvel)
                .with_friction(o.friction.unwrap_or(desc.friction));
            obstacle
                .validate(i)
                .map_err(|e| field_error(format!("obstacles[{i}]"), e))?;
            obstacles.push(obstacle);
        }

        let rapier = if desc.bodies.is_empty() {
            if let Some(i) = desc.attachments.first() {
                return Err(field_error(
                    "attachments",
                    format!(
                        "particle {} is attached to body {}, but the scene has no bodies",
                        i.particle, i.body
                    ),
                ));
            }
            None
        } else {
            let side = rapier_side(&desc, &cloth, &obstacles)?;
            obstacles.clear();
            Some(side)
        };
        Ok(Scene {
            name: desc.name.clone(),
            kind: None,
            variant: None,
            dt: desc.dt,
            frames: desc.frames,
            frame: 0,
            cloth,
            obstacles,
            rapier,
            desc,
        })
    }

    /// Advances the scene by one frame: the cloth, then rapier (when the scene
    /// has a world), see [`crate::rapier`] for why in that order.
    pub fn step_frame(&mut self) -> Result<StepReport, ClothError> {
        let report = match &mut self.rapier {
            None => {
                let report = self.cloth.step(self.dt, &self.obstacles)?;
                for o in &mut self.obstacles {
                    if o.linvel != Vector::ZERO || o.angvel != Vector::ZERO {
                        o.pose = o.pose_at(self.dt);
                    }
                }
                report
            }
            Some(side) => {
                let t = (self.frame + 1) as f32 * self.dt;
                for (handle, body) in &side.paths {
                    if let (Some(rb), Some(at)) =
                        (side.world.bodies.get_mut(*handle), body.path_at(t))
                    {
                        rb.set_next_kinematic_translation(at);
                    }
                }
                let before: Vec<Vector> = side
                    .bodies
                    .iter()
                    .map(|h| {
                        side.world
                            .bodies
                            .get(*h)
                            .map_or(Vector::ZERO, |b| b.translation())
                    })
                    .collect();
                let report = side
                    .coupling
                    .step_world(&mut self.cloth, &mut side.world)?
                    .step;
                side.world.step();
                side.last_speeds.clear();
                for (h, start) in side.bodies.iter().zip(before) {
                    if let Some(b) = side.world.bodies.get(*h) {
                        side.last_speeds
                            .push((b.translation() - start).length() / self.dt);
                    }
                }
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

/// The rapier world of a description with bodies: its bodies, its obstacles
/// as fixed (or velocity-driven kinematic) bodies, the attachments.
fn rapier_side(
    desc: &SceneDesc,
    cloth: &Cloth,
    obstacles: &[Obstacle],
) -> Result<RapierSide, ClothError> {
    let mut world = PhysicsWorld::new();
    world.integration_parameters.dt = desc.dt;
    world.gravity = desc.gravity;
    let mut coupling = RapierCoupling::new();
    coupling.friction = desc.friction;
    let mut all_bodies = Vec::with_capacity(desc.bodies.len());
    let mut bodies = Vec::new();
    let mut paths = Vec::new();
    for (i, b) in desc.bodies.iter().enumerate() {
        b.check()
            .map_err(|e| field_error(format!("bodies[{i}]"), e))?;
        let shape = b
            .shape
            .shape()
            .map_err(|e| field_error(format!("bodies[{i}].shape"), e))?;
        let (rb, collider) = b.builders(shape);
        let (handle, _) = world.insert(rb, collider);
        all_bodies.push(handle);
        if b.kind != BodyKind::Fixed {
            bodies.push(handle);
        }
        if !b.path.is_empty() {
            paths.push((handle, b.clone()));
        }
    }
    // In a rapier world the cloth has one friction for every collider: the scene's.
    for o in obstacles {
        let moving = o.linvel != Vector::ZERO || o.angvel != Vector::ZERO;
        let body = if moving {
            RigidBodyBuilder::kinematic_velocity_based()
                .pose(o.pose)
                .linvel(o.linvel)
                .angvel(o.angvel)
        } else {
            RigidBodyBuilder::fixed().pose(o.pose)
        };
        world.insert(body, ColliderBuilder::new(o.shape.clone()));
    }
    for (i, a) in desc.attachments.iter().enumerate() {
        let field = format!("attachments[{i}]");
        let &handle = all_bodies.get(a.body).ok_or_else(|| {
            field_error(
                field.clone(),
                format!(
                    "body {} out of range: the scene has {} bodies",
                    a.body,
                    all_bodies.len()
                ),
            )
        })?;
        let result = match a.local_point {
            Some(p) => coupling.attach(a.particle, handle, p),
            None => coupling.attach_here(cloth, a.particle, handle, &world.bodies),
        };
        result.map_err(|e| field_error(field, e))?;
    }
    Ok(RapierSide {
        world,
        coupling,
        bodies,
        all_bodies,
        paths,
        last_speeds: Vec::new(),
    })
}
