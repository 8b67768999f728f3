//! The catalogue of canonical scenes (docs/SCENES.md): their names, what a
//! user sees in each, and the description each is built from.

use serde::{Deserialize, Serialize};

use super::desc::{
    AttachmentDesc, BodyDesc, BodyKind, ClothDesc, CutDesc, MaterialDesc, ObstacleDesc, PinsDesc,
    Placement, SceneDesc, ShapeDesc, Waypoint,
};
use super::error::SceneError;
use super::options::SceneOptions;
use crate::cloth::{Material, PinPreset, Wind};
use crate::error::ClothError;
use crate::math::Vector;

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
    /// A 48×48 cloth dropped over a thin bar onto the ground, folding onto
    /// itself (self-collision on).
    Fold,
    /// A 64×32 sheet held along its two short edges by kinematic rapier
    /// bars that move apart until it tears.
    Tear,
    /// Three 32×32 cloths dropped onto a ball one after the other, lying on
    /// each other (self-collision on).
    Stack,
}

impl SceneKind {
    /// Every scene.
    pub const ALL: [SceneKind; 9] = [
        SceneKind::Drape,
        SceneKind::Box,
        SceneKind::Flag,
        SceneKind::Pins,
        SceneKind::Curtain,
        SceneKind::Hammock,
        SceneKind::Fold,
        SceneKind::Tear,
        SceneKind::Stack,
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
            SceneKind::Fold => "fold",
            SceneKind::Tear => "tear",
            SceneKind::Stack => "stack",
        }
    }

    /// One line saying what a user sees.
    pub fn description(self) -> &'static str {
        match self {
            SceneKind::Drape => "a tablecloth falls on a ball and rests on top",
            SceneKind::Box => "a tablecloth falls on a cube; nothing passes through its edges",
            SceneKind::Flag => "a flag streams out from its pole and flutters in a gusty wind",
            SceneKind::Pins => "a cloth hangs from a pinning figure (variants)",
            SceneKind::Curtain => "a curtain is pushed aside by a moving kinematic rapier ball",
            SceneKind::Hammock => "a hammock catches three dynamic rapier boxes (two-way coupling)",
            SceneKind::Fold => {
                "a cloth falls over a thin bar and folds onto itself on the ground (self-collision)"
            }
            SceneKind::Tear => "two kinematic rapier bars pull a sheet apart until it tears",
            SceneKind::Stack => {
                "three cloths fall on a ball one after the other and lie on each other (self-collision)"
            }
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
            SceneKind::Flag => 240,
            // Plain cotton is lightly damped: the boxes bob a few seconds.
            SceneKind::Hammock => 480,
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
            SceneKind::Fold => (48, 48),
            SceneKind::Tear => (64, 32),
            SceneKind::Stack => (32, 32),
        }
    }
}

impl std::str::FromStr for SceneKind {
    type Err = ClothError;
    fn from_str(s: &str) -> Result<Self, ClothError> {
        Self::from_name(s)
    }
}

/// Height of the `fold` scene's bar (its axis, metres above the ground).
pub const FOLD_BAR_HEIGHT: f32 = 0.4;
/// Radius of the `fold` scene's bar, in metres.
pub const FOLD_BAR_RADIUS: f32 = 0.02;
/// How far (m, along x) the `fold` cloth's centre starts from the bar.
pub const FOLD_OFFSET: f32 = 0.12;

/// Half the distance (m, along x) between the `tear` scene's bars at the
/// start, and `t` seconds into the scene: they hold still for a quarter of
/// a second while the sheet settles, then move apart at 0.2 m/s each.
pub fn tear_bar_x(t: f32) -> f32 {
    TEAR_WIDTH / 2.0 + 0.2 * (t - 0.25).clamp(0.0, 1.75)
}

/// Heights (m) the `stack` scene's cloths start at, and the turn (radians,
/// about the vertical) of each, so that their corners fan out.
pub const STACK_LAYERS: [(f32, f32); 3] = [(0.55, 0.0), (0.8, 0.4), (1.05, 0.8)];

/// Width (m, along x, between the held edges) of the `tear` scene's sheet.
pub const TEAR_WIDTH: f32 = 1.2;
/// Strain past which the `tear` scene's cloth tears (15%).
pub const TEAR_STRAIN: f32 = 0.15;

/// Where the curtain's ball is (z, metres) `t` seconds into the scene.
pub fn curtain_ball_z(t: f32) -> f32 {
    (-1.0 + 2.0 * t).min(1.0)
}

impl SceneKind {
    /// The scene's description with `options` applied: what [`super::Scene::build`]
    /// builds and what `cloth3d export-scene` writes.
    pub fn desc(self, options: &SceneOptions) -> Result<SceneDesc, SceneError> {
        let variant = self.check_variant(options.variant)?;
        let (cols, rows) = self.default_grid();
        let horizontal = |y: f32| Placement::Horizontal {
            center: Vector::new(0.0, y, 0.0),
        };
        // The cloths after the first, for the scenes that have several.
        let mut stacked = Vec::new();
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
                // Cotton's own weight, 0.24 kg (not the scenes' 1 kg).
                c.mass = None;
                c
            }
            SceneKind::Curtain => ClothDesc::new(
                cols,
                rows,
                Placement::Vertical {
                    center: Vector::new(0.0, 1.0, 0.0),
                },
            ),
            SceneKind::Hammock => ClothDesc::new(cols, rows, horizontal(0.5)),
            SceneKind::Fold => {
                // Off the bar's axis, so one side hangs longer and lands first.
                let mut c = ClothDesc::new(
                    cols,
                    rows,
                    Placement::Horizontal {
                        center: Vector::new(FOLD_OFFSET, FOLD_BAR_HEIGHT + 0.1, 0.0),
                    },
                );
                c.self_collision = true;
                c
            }
            SceneKind::Stack => {
                let layer = |(height, turn): (f32, f32)| {
                    let mut c = ClothDesc::new(
                        cols,
                        rows,
                        Placement::Pose {
                            translation: Vector::new(0.0, height, 0.0),
                            rotation: Vector::new(0.0, turn, 0.0),
                        },
                    );
                    c.size = (0.9, 0.9);
                    c.self_collision = true;
                    c
                };
                let [first, more @ ..] = STACK_LAYERS;
                stacked = more.map(layer).to_vec();
                layer(first)
            }
            SceneKind::Tear => {
                let mut c = ClothDesc::new(cols, rows, horizontal(1.0));
                c.size = (TEAR_WIDTH, TEAR_WIDTH / 2.0);
                // Cotton without its stretch limit, which would hold every
                // spring under the tear strain.
                c.material = MaterialDesc::Custom(
                    Material::cotton()
                        .with_stretch_limit(None)
                        .with_tear_strain(Some(TEAR_STRAIN)),
                );
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
        desc.cloths = stacked;
        desc.description = self.description().to_string();
        desc.frames = self.default_frames();
        match self {
            SceneKind::Drape | SceneKind::Stack => desc.obstacles.push(ObstacleDesc::fixed(
                ShapeDesc::Ball { radius: 0.3 },
                Vector::ZERO,
            )),
            SceneKind::Box => desc.obstacles.push(ObstacleDesc::fixed(
                ShapeDesc::Cuboid {
                    half_extents: Vector::splat(0.25),
                },
                Vector::ZERO,
            )),
            SceneKind::Flag => {
                // A light breeze: 3.6 m/s of air (its dynamic pressure is
                // the 8 N/m²), acting on the flag's motion relative to it,
                // with skin friction and gusts.
                desc.wind = Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0).with_air(3.6, 0.2, 0.4, 7);
                // The pole, just behind the pinned column.
                desc.obstacles.push(ObstacleDesc::fixed(
                    ShapeDesc::Capsule {
                        half_height: 0.9,
                        radius: 0.02,
                    },
                    Vector::new(-0.035, 0.9, 0.0),
                ));
            }
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
            SceneKind::Fold => {
                desc.obstacles.push(ObstacleDesc::fixed(
                    ShapeDesc::Cuboid {
                        half_extents: Vector::new(2.0, 0.1, 2.0),
                    },
                    Vector::new(0.0, -0.1, 0.0),
                ));
                let mut bar = ObstacleDesc::fixed(
                    ShapeDesc::Capsule {
                        half_height: 0.8,
                        radius: FOLD_BAR_RADIUS,
                    },
                    Vector::new(0.0, FOLD_BAR_HEIGHT, 0.0),
                );
                // The capsule's axis (local y) along z.
                bar.rotation = Vector::new(std::f32::consts::FRAC_PI_2, 0.0, 0.0);
                desc.obstacles.push(bar);
            }
            SceneKind::Tear => {
                // Two bars just above the sheet's short edges, each holding
                // the particles of its edge.
                for side in [-1.0f32, 1.0] {
                    let at = |t: f32| Vector::new(side * tear_bar_x(t), 1.04, 0.0);
                    let mut bar = BodyDesc::new(
                        BodyKind::Kinematic,
                        ShapeDesc::Cuboid {
                            half_extents: Vector::new(0.02, 0.02, TEAR_WIDTH / 4.0 + 0.02),
                        },
                        at(0.0),
                    );
                    bar.path = [0.0, 0.25, 2.0]
                        .map(|time| Waypoint {
                            time,
                            translation: at(time),
                        })
                        .to_vec();
                    desc.bodies.push(bar);
                }
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
        desc.props = self.props(&desc);
        if self == SceneKind::Tear {
            // Each bar holds its edge's particles (at the grid chosen), and
            // a slit across the middle fifth of the sheet, halfway between
            // them, is where the tear starts.
            let (cols, rows) = (desc.cloth.cols, desc.cloth.rows);
            let (mid, half) = ((cols - 1) / 2, rows / 10);
            desc.cloth.cuts.push(CutDesc {
                from: (rows / 2 - half, mid),
                to: ((rows / 2 + half).min(rows - 1), mid),
            });
            for (body, col) in [(0, 0), (1, cols - 1)] {
                for row in 0..rows {
                    desc.attachments.push(AttachmentDesc {
                        particle: row * cols + col,
                        body,
                        local_point: None,
                    });
                }
            }
        }
        Ok(desc)
    }

    /// What holds the scene's cloth and obstacles, drawn but not simulated:
    /// the ground, the stands under the balls and the cube, the flag's
    /// ground, the rods the pins hang from, the curtain's rail, the
    /// hammock's posts, the fold's bar stands.
    fn props(self, desc: &SceneDesc) -> Vec<ObstacleDesc> {
        let ground = |y: f32| {
            ObstacleDesc::fixed(
                ShapeDesc::Cuboid {
                    half_extents: Vector::new(2.0, 0.01, 2.0),
                },
                Vector::new(0.0, y - 0.01, 0.0),
            )
        };
        // An upright rod from `bottom` to `top` at (x, z).
        let rod = |x: f32, z: f32, bottom: f32, top: f32, radius: f32| {
            ObstacleDesc::fixed(
                ShapeDesc::Cylinder {
                    half_height: 0.5 * (top - bottom),
                    radius,
                },
                Vector::new(x, 0.5 * (top + bottom), z),
            )
        };
        let c = &desc.cloth;
        match self {
            // The ball and the cube on a stand on the floor.
            SceneKind::Drape | SceneKind::Stack => {
                vec![ground(-1.0), rod(0.0, 0.0, -1.0, -0.25, 0.03)]
            }
            SceneKind::Box => vec![ground(-1.0), rod(0.0, 0.0, -1.0, -0.25, 0.03)],
            SceneKind::Flag | SceneKind::Tear => vec![ground(0.0)],
            SceneKind::Curtain => {
                // The rail along the top row, on two stands.
                let (w, top) = (0.5 * c.size.0, 1.0 + 0.5 * c.size.1);
                let mut rail = ObstacleDesc::fixed(
                    ShapeDesc::Capsule {
                        half_height: w + 0.05,
                        radius: 0.012,
                    },
                    Vector::new(0.0, top + 0.015, 0.0),
                );
                rail.rotation = Vector::new(0.0, 0.0, std::f32::consts::FRAC_PI_2);
                vec![
                    ground(0.0),
                    rail,
                    rod(-w - 0.06, 0.0, 0.0, top + 0.03, 0.015),
                    rod(w + 0.06, 0.0, 0.0, top + 0.03, 0.015),
                ]
            }
            SceneKind::Pins => {
                // A rod from each pin up to the ceiling's height.
                let (cols, rows) = (c.cols, c.rows);
                let (w, h) = c.size;
                c.pins
                    .preset
                    .cells(cols, rows)
                    .into_iter()
                    .map(|(r, col)| {
                        let x = -0.5 * w + col as f32 * w / (cols - 1) as f32;
                        let z = -0.5 * h + r as f32 * h / (rows - 1) as f32;
                        rod(x, z, 0.61, 1.2, 0.006)
                    })
                    .collect()
            }
            SceneKind::Hammock => {
                // A post under each corner, just outside it.
                let s = 0.5 * c.size.0 + 0.03;
                [(-s, -s), (-s, s), (s, -s), (s, s)]
                    .map(|(x, z)| rod(x, z, 0.0, 0.52, 0.025))
                    .to_vec()
            }
            SceneKind::Fold => {
                // A stand under each end of the bar.
                [-0.8f32, 0.8]
                    .map(|z| rod(0.0, z, 0.0, FOLD_BAR_HEIGHT, 0.015))
                    .to_vec()
            }
        }
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
