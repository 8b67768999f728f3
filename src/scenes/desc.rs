//! Scene descriptions: everything a scene is made of, as plain data that serde
//! reads from and writes to scene files (see `scenes::file`, with the feature
//! `scene-files`).
//!
//! The canonical scenes are themselves built from a [`SceneDesc`]
//! ([`crate::scenes::SceneKind::desc`]), so a canonical scene written to a
//! file and read back runs to the same result, bit for bit.
//!
//! Units are SI (metres, kilograms, seconds, radians); y is up. Rotations are
//! axis-angle vectors, as in rapier's builders: the axis scaled by the angle
//! in radians.

use serde::{Deserialize, Serialize};

use parry3d::shape::SharedShape;
use rapier3d::prelude::{ColliderBuilder, RigidBodyBuilder};

use crate::cloth::{Material, PinPreset, Wind};
use crate::error::ClothError;
use crate::math::{Pose, Rotation, Vector};
use crate::solver::SolverSettings;

/// The frame step of every scene, in seconds.
pub const FRAME_DT: f32 = 1.0 / 60.0;
/// Collision thickness of every scene, in metres.
pub const THICKNESS: f32 = 0.01;
/// Total cloth mass of every scene, in kg.
pub const CLOTH_MASS: f32 = 1.0;

/// A whole scene: the cloth, what it collides with, the forces and how to step it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneDesc {
    /// The scene's name, as reports show it.
    pub name: String,
    /// One line saying what a user sees.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// The cloth (the first, when the scene has several).
    pub cloth: ClothDesc,
    /// More cloths in the same scene. The scene steps all its cloths as one
    /// (`Cloth::join`): they share the first cloth's material, the solver,
    /// the obstacles and the rapier world, and they meet through
    /// self-collision, which is on for all when any of them has it. Their
    /// particles are numbered after the first cloth's, in order (for
    /// `attachments`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cloths: Vec<ClothDesc>,
    /// Shapes the cloth collides with, outside any rapier world.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub obstacles: Vec<ObstacleDesc>,
    /// Rigid bodies of a rapier world the cloth lives in (each with one
    /// collider). When there are any, the scene steps a rapier world with the
    /// cloth coupled to it, and `obstacles` become fixed or kinematic bodies of it.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bodies: Vec<BodyDesc>,
    /// Particles held at points of rapier bodies.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub attachments: Vec<AttachmentDesc>,
    /// Shapes drawn with the scene that nothing collides with: the ground
    /// under a ball, the posts and rails that pins hang from (the viewer
    /// draws them; the simulation ignores them).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub props: Vec<ObstacleDesc>,
    /// Wind on the cloth's triangles.
    #[serde(default = "calm")]
    pub wind: Wind,
    /// Gravity, in m/s².
    #[serde(
        default = "default_gravity",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub gravity: Vector,
    /// Air drag, in 1/s: each particle feels `-drag · m · v`.
    #[serde(
        default = "default_air_drag",
        deserialize_with = "crate::error::de::non_negative"
    )]
    pub air_drag: f32,
    /// Collision thickness, in metres.
    #[serde(
        default = "default_thickness",
        deserialize_with = "crate::error::de::non_negative"
    )]
    pub thickness: f32,
    /// Coulomb friction between the cloth and every obstacle or collider that
    /// does not set its own.
    #[serde(
        default = "default_friction",
        deserialize_with = "crate::error::de::non_negative"
    )]
    pub friction: f32,
    /// How the cloth is stepped: integrator, substeps, iterations. Every
    /// field has a default, so a file may give only those it changes.
    #[serde(default)]
    pub solver: SolverSettings,
    /// Frame step, in seconds.
    #[serde(
        default = "default_dt",
        deserialize_with = "crate::error::de::positive"
    )]
    pub dt: f32,
    /// Frames a run lasts.
    #[serde(
        default = "default_frames",
        deserialize_with = "crate::error::de::at_least_one"
    )]
    pub frames: u32,
}

/// The cloth of a scene: a rectangular grid, or the shape of a mesh.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothDesc {
    /// Particles along a row (at least 2; not used with a `mesh`).
    #[serde(default, deserialize_with = "crate::error::de::grid_side")]
    pub cols: usize,
    /// Particles along a column (at least 2; not used with a `mesh`).
    #[serde(default, deserialize_with = "crate::error::de::grid_side")]
    pub rows: usize,
    /// An OBJ file to take the cloth's shape from instead of a grid (a
    /// path relative to the scene file): its triangles and quads become
    /// the cloth (`Cloth::from_mesh`), moved by `placement` (the mesh keeps
    /// its own orientation, but for `Pose`'s rotation). `cols`, `rows`,
    /// `size`, pin presets and pinned cells are then not used; pin its
    /// vertices by index (`pins.particles`) or inside a box (`pins.inside`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// Width (along the rows) and height, in metres.
    #[serde(default = "unit_size", deserialize_with = "positive_pair")]
    pub size: (f32, f32),
    /// Where the cloth starts.
    pub placement: Placement,
    /// Total mass in kg, spread by area (each cell's shared by its corners); `None` takes it from the material's
    /// areal density times the area.
    #[serde(
        default = "default_mass",
        deserialize_with = "crate::error::de::opt_positive"
    )]
    pub mass: Option<f32>,
    /// The material.
    #[serde(default)]
    pub material: MaterialDesc,
    /// Pinned particles.
    #[serde(default, skip_serializing_if = "PinsDesc::is_empty")]
    pub pins: PinsDesc,
    /// Keep the cloth from passing through itself: its particles stay the
    /// scene's thickness away from its own triangles, with the scene's
    /// friction between layers (off by default: it costs time).
    #[serde(default, skip_serializing_if = "is_false")]
    pub self_collision: bool,
    /// Distance the cloth's layers keep, in metres (default: the scene's
    /// thickness, but at most a quarter of the grid spacing; see
    /// [`crate::cloth::Cloth::self_thickness`]).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_positive"
    )]
    pub self_thickness: Option<f32>,
    /// Tethers: every free particle stays within its rest distance, through
    /// the mesh, of the nearest pinned particle (off by default; on for all
    /// of a scene's cloths when any of them has it).
    #[serde(default, skip_serializing_if = "is_false")]
    pub tethers: bool,
    /// Cuts made before the cloth moves: each splits the particles of a
    /// straight run of grid cells across the run, so the cloth starts with
    /// a slit there (a tear starts at its ends).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cuts: Vec<CutDesc>,
}

/// A straight cut along a grid row or column: the particles from `from` to
/// `to` (both included, `(row, column)`, in one row or one column) are each
/// split in two across the cut (see `Cloth::split_particle`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CutDesc {
    /// First cell, `(row, column)`.
    pub from: (usize, usize),
    /// Last cell, `(row, column)`: in the same row or the same column.
    pub to: (usize, usize),
}

impl CutDesc {
    /// The cells of the cut and whether it runs along a column, or an error
    /// saying why there is no such cut on a `cols × rows` grid.
    pub(crate) fn cells(
        &self,
        cols: usize,
        rows: usize,
    ) -> Result<(Vec<(usize, usize)>, bool), String> {
        let ((r0, c0), (r1, c1)) = (self.from, self.to);
        if r0.max(r1) >= rows || c0.max(c1) >= cols {
            return Err(format!(
                "cell ({}, {}) is outside the {cols} × {rows} grid",
                r0.max(r1),
                c0.max(c1)
            ));
        }
        if r0 != r1 && c0 != c1 {
            return Err("a cut runs along one row or one column".into());
        }
        let along_column = c0 == c1;
        let cells = if along_column {
            (r0.min(r1)..=r0.max(r1)).map(|r| (r, c0)).collect()
        } else {
            (c0.min(c1)..=c0.max(c1)).map(|c| (r0, c)).collect()
        };
        Ok((cells, along_column))
    }
}

/// Where a cloth starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Placement {
    /// Flat, facing up, centred at `center` (metres); row 0 at `-z`.
    Horizontal {
        /// Centre, in metres.
        #[serde(deserialize_with = "crate::error::de::finite_vec")]
        center: Vector,
    },
    /// Upright in the x–y plane, centred at `center`, row 0 on top.
    Vertical {
        /// Centre, in metres.
        #[serde(deserialize_with = "crate::error::de::finite_vec")]
        center: Vector,
    },
    /// Any pose of the horizontal grid (see [`crate::cloth::ClothBuilder`]).
    Pose {
        /// Translation of the grid's centre, in metres.
        #[serde(deserialize_with = "crate::error::de::finite_vec")]
        translation: Vector,
        /// Rotation as an axis-angle vector, in radians.
        #[serde(default, deserialize_with = "crate::error::de::finite_vec")]
        rotation: Vector,
    },
}

/// A material: a preset by name or every value given.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum MaterialDesc {
    /// One of `silk`, `cotton`, `denim`, `leather`, `rubber`, `canvas`.
    Preset(#[serde(deserialize_with = "material_name")] String),
    /// Stiffness and damping per spring kind, density and colour.
    Custom(Material),
}

impl Default for MaterialDesc {
    fn default() -> Self {
        MaterialDesc::Preset("cotton".to_string())
    }
}

impl MaterialDesc {
    /// The material this describes.
    pub fn material(&self) -> Result<Material, ClothError> {
        match self {
            MaterialDesc::Preset(name) => Material::by_name(name),
            MaterialDesc::Custom(m) => {
                m.validate()?;
                Ok(m.clone())
            }
        }
    }

    /// Describes `material`: by its preset name when it is an unchanged preset.
    pub fn of(material: &Material) -> Self {
        match Material::by_name(&material.name) {
            Ok(preset) if preset == *material => MaterialDesc::Preset(material.name.clone()),
            _ => MaterialDesc::Custom(material.clone()),
        }
    }
}

/// Pinned particles: a preset figure, plus particles by index or by grid cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinsDesc {
    /// A pin figure (`None`, `FlagColumn`, `CurtainRow`, `TwoCorners`,
    /// `FourCorners`, `Center`, `CenterRow`, `FourCenter`).
    #[serde(default = "no_pins", skip_serializing_if = "is_no_pins")]
    pub preset: PinPreset,
    /// More pinned particles, by index (`row * cols + col`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub particles: Vec<usize>,
    /// More pinned particles, by `(row, column)`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cells: Vec<(usize, usize)>,
    /// More pinned particles: those inside the box from the first corner to
    /// the second (metres, where the cloth starts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inside: Option<(Vector, Vector)>,
}

impl Default for PinsDesc {
    fn default() -> Self {
        Self {
            preset: PinPreset::None,
            particles: Vec::new(),
            cells: Vec::new(),
            inside: None,
        }
    }
}

impl PinsDesc {
    /// True when nothing is pinned.
    pub fn is_empty(&self) -> bool {
        self.preset == PinPreset::None
            && self.particles.is_empty()
            && self.cells.is_empty()
            && self.inside.is_none()
    }

    /// Just a preset.
    pub fn preset(preset: PinPreset) -> Self {
        Self {
            preset,
            ..Self::default()
        }
    }
}

/// A shape, as parry builds it; every size in metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum ShapeDesc {
    /// A sphere.
    Ball {
        /// Radius, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        radius: f32,
    },
    /// A box.
    Cuboid {
        /// Half the size along each local axis, in metres.
        #[serde(deserialize_with = "crate::error::de::positive_vec")]
        half_extents: Vector,
    },
    /// A capsule along the local y axis.
    Capsule {
        /// Half the length of the segment, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        half_height: f32,
        /// Radius, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        radius: f32,
    },
    /// A cylinder along the local y axis.
    Cylinder {
        /// Half the height, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        half_height: f32,
        /// Radius, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        radius: f32,
    },
    /// A cone along the local y axis, apex up.
    Cone {
        /// Half the height, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        half_height: f32,
        /// Radius of the base, in metres.
        #[serde(deserialize_with = "crate::error::de::positive")]
        radius: f32,
    },
    /// The convex hull of points (local frame, metres).
    ConvexHull {
        /// The points.
        points: Vec<Vector>,
    },
    /// A triangle mesh (local frame, metres).
    TriMesh {
        /// Vertex positions.
        vertices: Vec<Vector>,
        /// Triangles as vertex indices.
        indices: Vec<[u32; 3]>,
    },
}

impl ShapeDesc {
    /// The parry shape.
    pub fn shape(&self) -> Result<SharedShape, String> {
        Ok(match self {
            ShapeDesc::Ball { radius } => SharedShape::ball(*radius),
            ShapeDesc::Cuboid { half_extents: h } => SharedShape::cuboid(h.x, h.y, h.z),
            ShapeDesc::Capsule {
                half_height,
                radius,
            } => SharedShape::capsule_y(*half_height, *radius),
            ShapeDesc::Cylinder {
                half_height,
                radius,
            } => SharedShape::cylinder(*half_height, *radius),
            ShapeDesc::Cone {
                half_height,
                radius,
            } => SharedShape::cone(*half_height, *radius),
            ShapeDesc::ConvexHull { points } => {
                if points.len() < 4 || points.iter().any(|p| !p.is_finite()) {
                    return Err("a convex hull needs at least 4 finite points".into());
                }
                SharedShape::convex_hull(points)
                    .ok_or("the points have no 3D convex hull (all on a plane?)")?
            }
            ShapeDesc::TriMesh { vertices, indices } => {
                if vertices.iter().any(|p| !p.is_finite()) {
                    return Err("every vertex must be finite".into());
                }
                if let Some(t) = indices
                    .iter()
                    .find(|t| t.iter().any(|&i| i as usize >= vertices.len()))
                {
                    return Err(format!(
                        "triangle {t:?} refers to a vertex out of range (the mesh has {})",
                        vertices.len()
                    ));
                }
                SharedShape::trimesh(vertices.clone(), indices.clone())
                    .map_err(|e| format!("invalid triangle mesh: {e:?}"))?
            }
        })
    }
}

/// A shape the cloth collides with, outside a rapier world.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleDesc {
    /// The shape.
    pub shape: ShapeDesc,
    /// Position of the shape's origin at the start, in metres.
    #[serde(default, deserialize_with = "crate::error::de::finite_vec")]
    pub translation: Vector,
    /// Orientation at the start, axis-angle in radians.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub rotation: Vector,
    /// Constant linear velocity, in m/s: the obstacle moves.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub linvel: Vector,
    /// Constant angular velocity about its origin, in rad/s.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub angvel: Vector,
    /// Friction with the cloth (default: the scene's).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_non_negative"
    )]
    pub friction: Option<f32>,
}

impl ObstacleDesc {
    /// A fixed shape at `translation`.
    pub fn fixed(shape: ShapeDesc, translation: Vector) -> Self {
        Self {
            shape,
            translation,
            rotation: Vector::ZERO,
            linvel: Vector::ZERO,
            angvel: Vector::ZERO,
            friction: None,
        }
    }

    /// The starting pose.
    pub fn pose(&self) -> Pose {
        Pose::from_parts(self.translation, Rotation::from_scaled_axis(self.rotation))
    }
}

/// What kind of rapier body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BodyKind {
    /// Never moves.
    Fixed,
    /// Moved by the scene: along its `path`, or with its constant velocity.
    Kinematic,
    /// Moved by forces: gravity, contacts, the cloth.
    Dynamic,
}

/// One point of a kinematic body's path.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Waypoint {
    /// Time since the start of the scene, in seconds.
    pub time: f32,
    /// Where the body's origin is then, in metres.
    #[serde(deserialize_with = "crate::error::de::finite_vec")]
    pub translation: Vector,
}

/// A rapier rigid body with one collider.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyDesc {
    /// Fixed, kinematic or dynamic.
    pub kind: BodyKind,
    /// The collider's shape.
    pub shape: ShapeDesc,
    /// Position at the start, in metres.
    #[serde(default, deserialize_with = "crate::error::de::finite_vec")]
    pub translation: Vector,
    /// Orientation at the start, axis-angle in radians.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub rotation: Vector,
    /// Linear velocity at the start, in m/s.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub linvel: Vector,
    /// Angular velocity at the start, in rad/s.
    #[serde(
        default,
        skip_serializing_if = "is_zero",
        deserialize_with = "crate::error::de::finite_vec"
    )]
    pub angvel: Vector,
    /// Mass of a dynamic body, in kg (default: from `density`).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_positive"
    )]
    pub mass: Option<f32>,
    /// Density of a dynamic body, in kg/m³ (default 1000 when no mass is given).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_positive"
    )]
    pub density: Option<f32>,
    /// Friction with other bodies (rapier's coefficient; default rapier's 0.5).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "crate::error::de::opt_non_negative"
    )]
    pub friction: Option<f32>,
    /// For a kinematic body: where it is at given times, piecewise linear
    /// and held at the ends. Empty: it moves with `linvel` and `angvel`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub path: Vec<Waypoint>,
}

impl BodyDesc {
    /// A body of `kind` with `shape` at `translation`, nothing else set.
    pub fn new(kind: BodyKind, shape: ShapeDesc, translation: Vector) -> Self {
        Self {
            kind,
            shape,
            translation,
            rotation: Vector::ZERO,
            linvel: Vector::ZERO,
            angvel: Vector::ZERO,
            mass: None,
            density: None,
            friction: None,
            path: Vec::new(),
        }
    }

    /// Where a kinematic body's path puts it `t` seconds into the scene.
    pub fn path_at(&self, t: f32) -> Option<Vector> {
        let first = self.path.first()?;
        if t <= first.time {
            return Some(first.translation);
        }
        for w in self.path.windows(2) {
            if t <= w[1].time {
                let span = w[1].time - w[0].time;
                let s = if span > 0.0 {
                    (t - w[0].time) / span
                } else {
                    1.0
                };
                return Some(w[0].translation + (w[1].translation - w[0].translation) * s);
            }
        }
        self.path.last().map(|w| w.translation)
    }

    pub(crate) fn check(&self) -> Result<(), String> {
        if self.mass.is_some() && self.density.is_some() {
            return Err("give a mass or a density, not both".into());
        }
        if self.kind != BodyKind::Kinematic && !self.path.is_empty() {
            return Err("only a kinematic body follows a path".into());
        }
        if self.path.windows(2).any(|w| w[1].time < w[0].time)
            || self.path.iter().any(|w| !w.time.is_finite())
        {
            return Err("path times must be finite and in increasing order".into());
        }
        Ok(())
    }

    /// The rapier body and collider builders.
    pub(crate) fn builders(&self, shape: SharedShape) -> (RigidBodyBuilder, ColliderBuilder) {
        let start = self.path_at(0.0).unwrap_or(self.translation);
        let body = match self.kind {
            BodyKind::Fixed => RigidBodyBuilder::fixed(),
            BodyKind::Kinematic if self.path.is_empty() => {
                RigidBodyBuilder::kinematic_velocity_based()
            }
            BodyKind::Kinematic => RigidBodyBuilder::kinematic_position_based(),
            BodyKind::Dynamic => RigidBodyBuilder::dynamic(),
        }
        .translation(start)
        .rotation(self.rotation)
        .linvel(self.linvel)
        .angvel(self.angvel);
        let mut collider = ColliderBuilder::new(shape);
        if let Some(m) = self.mass {
            collider = collider.mass(m);
        } else if let Some(d) = self.density {
            collider = collider.density(d);
        }
        if let Some(f) = self.friction {
            collider = collider.friction(f);
        }
        (body, collider)
    }
}

/// A particle held at a point of a rapier body.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AttachmentDesc {
    /// The particle, by index (`row * cols + col`).
    pub particle: usize,
    /// The body, by its place in the scene's `bodies` (from 0).
    pub body: usize,
    /// The point in the body's frame, in metres; `None`: where the particle starts.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub local_point: Option<Vector>,
}

impl SceneDesc {
    /// A scene with `cloth` and the defaults of SCENES.md: gravity, 1/60 s
    /// frames, 120 frames, the small-steps solver (xpbd) with automatic substeps,
    /// thickness 1 cm, friction 0.5, no wind, no obstacle.
    pub fn new(name: impl Into<String>, cloth: ClothDesc) -> Self {
        Self {
            name: name.into(),
            description: String::new(),
            cloth,
            cloths: Vec::new(),
            props: Vec::new(),
            obstacles: Vec::new(),
            bodies: Vec::new(),
            attachments: Vec::new(),
            wind: Wind::NONE,
            gravity: default_gravity(),
            air_drag: default_air_drag(),
            thickness: default_thickness(),
            friction: default_friction(),
            solver: SolverSettings::default(),
            dt: default_dt(),
            frames: default_frames(),
        }
    }
}

impl ClothDesc {
    /// A `cols × rows`, 1 kg, 1 × 1 m cotton cloth placed as given, nothing pinned.
    pub fn new(cols: usize, rows: usize, placement: Placement) -> Self {
        Self {
            cols,
            rows,
            size: unit_size(),
            placement,
            mass: default_mass(),
            material: MaterialDesc::default(),
            pins: PinsDesc::default(),
            self_collision: false,
            self_thickness: None,
            mesh: None,
            tethers: false,
            cuts: Vec::new(),
        }
    }
}

fn calm() -> Wind {
    Wind::NONE
}
fn default_gravity() -> Vector {
    Vector::new(0.0, -9.81, 0.0)
}
fn default_air_drag() -> f32 {
    crate::cloth::PhysicsParams::default().air_drag
}
fn default_thickness() -> f32 {
    THICKNESS
}
fn default_friction() -> f32 {
    0.5
}
fn default_dt() -> f32 {
    FRAME_DT
}
fn default_frames() -> u32 {
    120
}
fn unit_size() -> (f32, f32) {
    (1.0, 1.0)
}
fn default_mass() -> Option<f32> {
    Some(CLOTH_MASS)
}
fn no_pins() -> PinPreset {
    PinPreset::None
}
fn is_no_pins(p: &PinPreset) -> bool {
    *p == PinPreset::None
}
fn is_false(b: &bool) -> bool {
    !*b
}
fn is_zero(v: &Vector) -> bool {
    *v == Vector::ZERO
}

fn positive_pair<'de, D: serde::Deserializer<'de>>(d: D) -> Result<(f32, f32), D::Error> {
    use serde::de::Error;
    let (a, b) = <(f32, f32)>::deserialize(d)?;
    if a.is_finite() && a > 0.0 && b.is_finite() && b > 0.0 {
        Ok((a, b))
    } else {
        Err(D::Error::custom(format!(
            "invalid size ({a}, {b}): both must be finite numbers > 0"
        )))
    }
}

fn material_name<'de, D: serde::Deserializer<'de>>(d: D) -> Result<String, D::Error> {
    use serde::de::Error;
    let name = String::deserialize(d)?;
    Material::by_name(&name)
        .map(|_| name)
        .map_err(|e| D::Error::custom(e.to_string()))
}
