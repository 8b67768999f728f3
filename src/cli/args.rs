//! The flags that change a scene, parsed and range-checked by clap, shared
//! by the `cloth3d` command and the showcase.

use crate::cloth::{Material, PinPreset};
use crate::scenes::{SceneKind, SceneOptions, SolverTuning};
use crate::solver::{Integrator, Preconditioner, Substeps};

/// The choices that change a scene: the same flags, with the same range
/// checks, for every command that builds one (`run`, `export-scene`,
/// `compare`) and for the showcase.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct SceneArgs {
    /// Particles along a row (rows follow the scene's aspect ratio).
    #[arg(long, value_parser = parse_n, allow_hyphen_values = true)]
    pub n: Option<usize>,
    /// Time integrator.
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<Integrator>,
    /// Material preset.
    #[arg(long, value_parser = parse_material)]
    pub material: Option<Material>,
    /// Frame step in seconds.
    #[arg(long, value_parser = parse_positive, allow_hyphen_values = true)]
    pub dt: Option<f32>,
    /// Substeps per frame: a whole number >= 1, or `auto`.
    #[arg(long, value_parser = parse_substeps)]
    pub substeps: Option<Substeps>,
    /// Frames to simulate.
    #[arg(long, value_parser = parse_frames, allow_hyphen_values = true)]
    pub frames: Option<u32>,
    /// Pin variant (the `pins` scene; for a scene file, any pin preset).
    #[arg(long, value_parser = parse_variant)]
    pub variant: Option<PinPreset>,
    /// Friction coefficient of the obstacles.
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub friction: Option<f32>,
    /// Keep the cloth from passing through itself: `--self-collision` (or
    /// `=on`) turns it on, `--self-collision=off` off (default: the scene's).
    #[arg(long, value_name = "on|off", num_args = 0..=1, require_equals = true, default_missing_value = "on", value_parser = parse_on_off)]
    pub self_collision: Option<bool>,
    /// Tethers: every free particle stays within its rest distance of the
    /// nearest pin: `--tethers` (or `=on`) on, `--tethers=off` off
    /// (default: the scene's).
    #[arg(long, value_name = "on|off", num_args = 0..=1, require_equals = true, default_missing_value = "on", value_parser = parse_on_off)]
    pub tethers: Option<bool>,
    /// Let a still cloth sleep (not stepped until something near it moves):
    /// `--sleep` (or `=on`) on, `--sleep=off` off (default: the scene's).
    #[arg(long, value_name = "on|off", num_args = 0..=1, require_equals = true, default_missing_value = "on", value_parser = parse_on_off)]
    pub sleep: Option<bool>,
    /// Air speed of the scene's wind in m/s (0: pressure alone, whatever
    /// the cloth's motion); see `Wind`.
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub wind_speed: Option<f32>,
    /// Gusts of the scene's wind: how much its speed varies, as a share of it.
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub turbulence: Option<f32>,
    /// Linearisations (Newton iterations) per substep (implicit-euler).
    #[arg(long, value_parser = parse_iterations, allow_hyphen_values = true)]
    pub newton_iterations: Option<u32>,
    /// Maximum conjugate-gradient iterations per linearisation (implicit-euler).
    #[arg(long, value_parser = parse_iterations, allow_hyphen_values = true)]
    pub cg_iterations: Option<u32>,
    /// Relative residual at which conjugate gradient stops (implicit-euler).
    #[arg(long, value_parser = parse_positive, allow_hyphen_values = true)]
    pub cg_tolerance: Option<f32>,
    /// Conjugate-gradient preconditioner (implicit-euler): block-jacobi or
    /// spring-space (converges for very stiff springs, costlier per iteration).
    #[arg(long, value_parser = parse_preconditioner)]
    pub preconditioner: Option<Preconditioner>,
    /// Local/global iterations per substep (fast-mass-spring).
    #[arg(long, value_parser = parse_iterations, allow_hyphen_values = true)]
    pub fms_iterations: Option<u32>,
    /// Spring sweeps per substep (xpbd).
    #[arg(long, value_parser = parse_iterations, allow_hyphen_values = true)]
    pub xpbd_iterations: Option<u32>,
    /// Direct solves of the stretch springs along rows and columns before
    /// each substep's sweeps (xpbd on a grid; default on).
    #[arg(long, value_name = "on|off", value_parser = parse_on_off)]
    pub xpbd_chains: Option<bool>,
}

impl SceneArgs {
    /// The scene options these flags give.
    pub fn options(&self) -> SceneOptions {
        SceneOptions {
            n: self.n,
            integrator: self.integrator,
            material: self.material.clone(),
            variant: self.variant,
            dt: self.dt,
            substeps: self.substeps,
            frames: self.frames,
            friction: self.friction,
            self_collision: self.self_collision,
            tethers: self.tethers,
            wind_speed: self.wind_speed,
            turbulence: self.turbulence,
            solver: SolverTuning {
                sleep: self.sleep,
                newton_iterations: self.newton_iterations,
                cg_iterations: self.cg_iterations,
                cg_tolerance: self.cg_tolerance,
                preconditioner: self.preconditioner,
                fms_iterations: self.fms_iterations,
                xpbd_iterations: self.xpbd_iterations,
                xpbd_chains: self.xpbd_chains,
                edge_collisions: None,
            },
        }
    }
}

/// A canonical scene by name.
pub fn parse_scene(s: &str) -> Result<SceneKind, String> {
    SceneKind::from_name(s).map_err(|e| e.to_string())
}
/// An integrator by name.
pub fn parse_integrator(s: &str) -> Result<Integrator, String> {
    Integrator::from_name(s).map_err(|e| e.to_string())
}
/// A preconditioner by name.
pub fn parse_preconditioner(s: &str) -> Result<Preconditioner, String> {
    Preconditioner::from_name(s).map_err(|e| e.to_string())
}
/// A material preset by name.
pub fn parse_material(s: &str) -> Result<Material, String> {
    Material::by_name(s).map_err(|e| e.to_string())
}
/// A pin preset by name.
pub fn parse_variant(s: &str) -> Result<PinPreset, String> {
    PinPreset::from_name(s).map_err(|e| e.to_string())
}
/// `on` or `off` (also `true`/`false`, `yes`/`no`, `1`/`0`).
pub fn parse_on_off(s: &str) -> Result<bool, String> {
    match s.to_ascii_lowercase().as_str() {
        "on" | "true" | "yes" | "1" => Ok(true),
        "off" | "false" | "no" | "0" => Ok(false),
        _ => Err(format!("'{s}' is neither on nor off")),
    }
}
/// Substeps: a whole number >= 1 or `auto`.
pub fn parse_substeps(s: &str) -> Result<Substeps, String> {
    s.parse()
}
/// Any number type, saying what was expected.
pub fn parse_number<T: std::str::FromStr>(s: &str, what: &str) -> Result<T, String> {
    s.parse().map_err(|_| format!("'{s}' is not {what}"))
}
/// A finite number > 0.
pub fn parse_positive(s: &str) -> Result<f32, String> {
    let v: f32 = parse_number(s, "a number")?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("'{s}' must be a finite number > 0"))
    }
}
/// A finite number >= 0.
pub fn parse_non_negative(s: &str) -> Result<f32, String> {
    let v: f32 = parse_number(s, "a number")?;
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("'{s}' must be a finite number >= 0"))
    }
}
/// Particles along a row: 2 to 4096.
pub fn parse_n(s: &str) -> Result<usize, String> {
    let n: usize = parse_number(s, "a whole number")?;
    if (2..=4096).contains(&n) {
        Ok(n)
    } else {
        Err(format!("'{s}' must be between 2 and 4096"))
    }
}
/// Iterations: at least 1.
pub fn parse_iterations(s: &str) -> Result<u32, String> {
    let f: u32 = parse_number(s, "a whole number")?;
    if f >= 1 {
        Ok(f)
    } else {
        Err("iterations must be at least 1".into())
    }
}
/// A whole number >= 0.
pub fn parse_count(s: &str) -> Result<u32, String> {
    parse_number(s, "a whole number")
}
/// Frames: at least 1.
pub fn parse_frames(s: &str) -> Result<u32, String> {
    let f: u32 = parse_number(s, "a whole number")?;
    if f >= 1 {
        Ok(f)
    } else {
        Err("frames must be at least 1".into())
    }
}
