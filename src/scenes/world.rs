//! A scene at run time: its cloth and solver, and either its obstacles (moved
//! by their velocities) or a rapier world with kinematic paths, stepped frame
//! by frame.

use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};

use super::catalogue::SceneKind;
use super::desc::{BodyDesc, BodyKind, ClothDesc, Placement, SceneDesc};
use super::error::SceneError;
use super::options::SceneOptions;
use crate::cloth::{Cloth, ClothBuilder, MassSpec, PinPreset};
use crate::collision::Obstacle;
use crate::error::ClothError;
use crate::math::{Pose, Rotation, Vector};
use crate::metrics::max_penetration;
use crate::rapier::{RapierCoupling, RapierSets};
use crate::solver::{ClothSolver, StepReport};

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

/// A scene ready to run: its cloth and solver, obstacles or rapier world, and frame step.
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
    /// The solver that steps it, with the description's settings.
    pub solver: ClothSolver,
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

impl Scene {
    /// Builds a canonical scene with the given options.
    pub fn build(kind: SceneKind, options: &SceneOptions) -> Result<Scene, SceneError> {
        let desc = kind.desc(options)?;
        // The scenes with variants pin their cloth with the chosen one.
        let variant = (!kind.variants().is_empty()).then_some(desc.cloth.pins.preset);
        let mut scene = Scene::from_desc(desc)?;
        scene.kind = Some(kind);
        scene.variant = variant;
        Ok(scene)
    }

    /// A canonical scene by name, or else a RON scene file by path (see
    /// `scenes::file`, with the feature `scene-files`), with `options` applied.
    pub fn open(name_or_path: &str, options: &SceneOptions) -> Result<Scene, SceneError> {
        if let Ok(kind) = SceneKind::from_name(name_or_path) {
            return Scene::build(kind, options);
        }
        let path = std::path::Path::new(name_or_path);
        #[cfg(feature = "scene-files")]
        if path.exists() || name_or_path.ends_with(".ron") {
            return super::file::load_with(path, |mut desc| {
                desc.apply(options)?;
                Scene::from_desc(desc)
            });
        }
        #[cfg(not(feature = "scene-files"))]
        if path.exists() || name_or_path.ends_with(".ron") {
            return Err(SceneError::Io {
                path: name_or_path.to_string(),
                message: "reading scene files needs cloth3d's `scene-files` feature".into(),
            });
        }
        Err(SceneError::from(ClothError::UnknownName {
            what: "scene",
            name: name_or_path.to_string(),
            valid: format!(
                "{}, or the path of a .ron scene file",
                SceneKind::ALL.map(|s| s.name()).join(", ")
            ),
        }))
    }

    /// Builds a scene from its description (a scene file's, or a canonical one's).
    ///
    /// A value the description cannot hold (a pin outside the grid, a mesh
    /// index out of range) is a [`SceneError::File`] naming the field.
    pub fn from_desc(desc: SceneDesc) -> Result<Scene, SceneError> {
        // The scene's cloths, joined into one so that they meet through
        // self-collision (on when any of them has it).
        let mut pieces = vec![build_cloth(&desc.cloth, "cloth")?];
        for (i, c) in desc.cloths.iter().enumerate() {
            pieces.push(build_cloth(c, &format!("cloths[{i}]"))?);
        }
        let any = |on: fn(&ClothDesc) -> bool| on(&desc.cloth) || desc.cloths.iter().any(on);
        let (self_collision, tethers) = (any(|c| c.self_collision), any(|c| c.tethers));
        let mut cloth = Cloth::join(pieces).map_err(|e| match e {
            ClothError::InvalidTopology { index, .. } => {
                SceneError::field(format!("cloths[{}].material", index.saturating_sub(1)), e)
            }
            other => SceneError::from(other),
        })?;
        let c = &desc.cloth;
        cloth.params.wind = desc.wind;
        cloth.params.gravity = desc.gravity;
        cloth.params.air_drag = desc.air_drag;
        cloth.params.thickness = desc.thickness;
        cloth.params.self_collision = self_collision;
        cloth.params.tethers = tethers;
        cloth.params.self_friction = desc.friction;
        cloth.params.self_thickness = c.self_thickness;
        cloth.params.validate()?;
        desc.solver
            .validate()
            .map_err(|e| SceneError::field("solver", e))?;
        let solver = ClothSolver::new(desc.solver.clone());
        crate::error::positive("dt", desc.dt)?;

        let mut obstacles = Vec::with_capacity(desc.obstacles.len());
        for (i, o) in desc.obstacles.iter().enumerate() {
            let shape = o
                .shape
                .shape()
                .map_err(|e| SceneError::field(format!("obstacles[{i}].shape"), e))?;
            let obstacle = Obstacle::new(shape, o.pose())
                .with_velocity(o.linvel, o.angvel)
                .with_friction(o.friction.unwrap_or(desc.friction));
            obstacle
                .validate(i)
                .map_err(|e| SceneError::field(format!("obstacles[{i}]"), e))?;
            obstacles.push(obstacle);
        }

        let rapier = if desc.bodies.is_empty() {
            if let Some(i) = desc.attachments.first() {
                return Err(SceneError::field(
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
            solver,
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
                let report = self
                    .solver
                    .step(&mut self.cloth, self.dt, &self.obstacles)?;
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
                    .step(
                        &mut self.cloth,
                        &mut self.solver,
                        RapierSets::of(&mut side.world),
                    )?
                    .step;
                side.world.step();
                // The cloth out of the bodies rapier's step moved into it,
                // for the frame's picture and metrics.
                side.coupling.push_out_of_bodies(
                    &mut self.cloth,
                    &mut self.solver,
                    &side.world.colliders,
                );
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
            None => max_penetration(&self.cloth, &self.obstacles),
            Some(_) => max_penetration(&self.cloth, &self.current_obstacles()),
        }
    }
}

/// The rapier world of a description with bodies: its bodies, its obstacles
/// as fixed (or velocity-driven kinematic) bodies, the attachments.
fn rapier_side(
    desc: &SceneDesc,
    cloth: &Cloth,
    obstacles: &[Obstacle],
) -> Result<RapierSide, SceneError> {
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
            .map_err(|e| SceneError::field(format!("bodies[{i}]"), e))?;
        let shape = b
            .shape
            .shape()
            .map_err(|e| SceneError::field(format!("bodies[{i}].shape"), e))?;
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
            SceneError::field(
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
        result.map_err(|e| SceneError::field(field, e))?;
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

/// Builds one cloth of a description; `at` names it in errors (`cloth`,
/// `cloths[0]`).
fn build_cloth(c: &ClothDesc, at: &str) -> Result<Cloth, SceneError> {
    let material = c
        .material
        .material()
        .map_err(|e| SceneError::field(format!("{at}.material"), e))?;
    let mut cloth = match &c.mesh {
        Some(path) => mesh_cloth(c, path, material, at)?,
        None => grid_cloth(c, material, at)?,
    };
    if let Some((lo, hi)) = c.pins.inside {
        let inside: Vec<usize> = (0..cloth.particle_count())
            .filter(|&i| {
                let p = cloth.positions()[i];
                p.cmpge(lo.min(hi)).all() && p.cmple(lo.max(hi)).all()
            })
            .collect();
        if inside.is_empty() {
            return Err(SceneError::field(
                format!("{at}.pins.inside"),
                "no particle of the cloth lies inside the box",
            ));
        }
        for i in inside {
            cloth.pin(i)?;
        }
    }
    Ok(cloth)
}

/// The cloth of a mesh description: the OBJ file's shape, placed.
fn mesh_cloth(
    c: &ClothDesc,
    path: &str,
    material: crate::cloth::Material,
    at: &str,
) -> Result<Cloth, SceneError> {
    if c.pins.preset != PinPreset::None || !c.pins.cells.is_empty() || !c.cuts.is_empty() {
        return Err(SceneError::field(
            format!("{at}.pins"),
            "a mesh cloth has no grid cells: pin its vertices by index (particles) or inside a box (inside)",
        ));
    }
    let mut mesh = read_mesh(path)?;
    let pose = match c.placement {
        Placement::Horizontal { center } | Placement::Vertical { center } => {
            Pose::from_translation(center)
        }
        Placement::Pose {
            translation,
            rotation,
        } => Pose::from_parts(translation, Rotation::from_scaled_axis(rotation)),
    };
    for p in &mut mesh.positions {
        *p = pose.transform_point(*p);
    }
    let mass = match c.mass {
        Some(m) => MassSpec::Total(m),
        None => MassSpec::FromDensity,
    };
    let mut cloth = Cloth::from_mesh(&mesh, material, mass)
        .map_err(|e| SceneError::field(format!("{at}.mesh"), e))?;
    for &p in &c.pins.particles {
        cloth
            .pin(p)
            .map_err(|e| SceneError::field(format!("{at}.pins.particles"), e))?;
    }
    Ok(cloth)
}

/// The mesh of the OBJ file at `path`.
#[cfg(feature = "scene-files")]
fn read_mesh(path: &str) -> Result<crate::cloth::ClothMesh, SceneError> {
    super::mesh_file::load_obj(std::path::Path::new(path))
}

/// Without the `scene-files` feature there is no mesh reader.
#[cfg(not(feature = "scene-files"))]
fn read_mesh(path: &str) -> Result<crate::cloth::ClothMesh, SceneError> {
    Err(SceneError::Io {
        path: path.to_string(),
        message: "reading meshes needs cloth3d's `scene-files` feature".into(),
    })
}

/// The cloth of a grid description.
fn grid_cloth(
    c: &ClothDesc,
    material: crate::cloth::Material,
    at: &str,
) -> Result<Cloth, SceneError> {
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
        ClothError::ParticleOutOfRange { .. } => {
            SceneError::field(format!("{at}.pins.particles"), e)
        }
        ClothError::GridTooLarge { .. } | ClothError::GridTooSmall { .. } => {
            SceneError::field(format!("{at}.cols"), e)
        }
        other => SceneError::from(other),
    })?;
    for &(row, col) in &c.pins.cells {
        cloth
            .pin_cell(row, col)
            .map_err(|e| SceneError::field(format!("{at}.pins.cells"), e))?;
    }
    for (i, cut) in c.cuts.iter().enumerate() {
        let field = || format!("{at}.cuts[{i}]");
        let (cells, along_column) = cut
            .cells(c.cols, c.rows)
            .map_err(|e| SceneError::field(field(), e))?;
        for (row, col) in cells {
            // Across the cut: along the grid's rows for a cut down a
            // column, along its columns for one across a row.
            let (r2, c2) = match along_column {
                true if col + 1 < c.cols => (row, col + 1),
                true => (row, col - 1),
                false if row + 1 < c.rows => (row + 1, col),
                false => (row - 1, col),
            };
            let at = |r, c| cloth.index(r, c).map(|i| cloth.positions()[i]);
            let normal = at(r2, c2)
                .and_then(|p| Ok(p - at(row, col)?))
                .map_err(|e| SceneError::field(field(), e))?;
            let i = cloth
                .index(row, col)
                .map_err(|e| SceneError::field(field(), e))?;
            cloth
                .split_particle(i, normal)
                .map_err(|e| SceneError::field(field(), e))?;
        }
    }
    Ok(cloth)
}
