//! Every integrator on the same scene at the same frame step: the comparison
//! `cloth3d compare` prints and plots.

use std::time::Instant;

use image::{Rgb, RgbImage};
use serde::{Deserialize, Serialize};

use crate::error::ClothError;
use crate::integrators::Integrator;
use crate::scenes::{Scene, SceneKind, SceneOptions};

/// How one integrator did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// Integrator name.
    pub integrator: String,
    /// False when a step diverged (the run stops there).
    pub stable: bool,
    /// Substeps per frame.
    pub substeps: u32,
    /// Solver iterations per frame, for the iterative integrators.
    pub iterations: Option<u32>,
    /// Largest stretch-spring strain on the last frame.
    pub max_stretch: f32,
    /// Total energy on the last frame minus on the first, in joules (the
    /// cloth falls, so it is negative; compare it between integrators).
    pub energy_change: f64,
    /// Mean wall time of a frame, in seconds.
    pub frame_wall_s: f64,
    /// Total energy after every frame, in joules.
    pub energy: Vec<f64>,
    /// Largest stretch after every frame.
    pub stretch: Vec<f32>,
}

/// Runs every integrator on `kind` for `frames` frames at frame step `dt`:
/// explicit ones with automatic substeps, implicit ones with one step a frame.
pub fn compare(
    kind: SceneKind,
    options: &SceneOptions,
    frames: u32,
) -> Result<Vec<Comparison>, ClothError> {
    let mut rows = Vec::new();
    for integrator in Integrator::ALL {
        let mut scene = Scene::build(
            kind,
            &SceneOptions {
                integrator: Some(integrator),
                substeps: Some(integrator.default_substeps()),
                ..options.clone()
            },
        )?;
        let start_energy = scene.cloth.energy().total();
        let mut row = Comparison {
            integrator: integrator.name().into(),
            stable: true,
            substeps: scene.cloth.substeps_for(scene.dt),
            iterations: None,
            max_stretch: 0.0,
            energy_change: 0.0,
            frame_wall_s: 0.0,
            energy: Vec::new(),
            stretch: Vec::new(),
        };
        let mut wall = 0.0;
        let mut iterations = 0u64;
        for _ in 0..frames {
            let t = Instant::now();
            match scene.step_frame() {
                Ok(report) => {
                    iterations += report.iterations as u64;
                    row.substeps = report.substeps;
                }
                Err(ClothError::Diverged { .. }) => {
                    row.stable = false;
                    break;
                }
                Err(e) => return Err(e),
            }
            wall += t.elapsed().as_secs_f64();
            row.energy.push(scene.cloth.energy().total());
            row.stretch.push(crate::metrics::max_stretch(&scene.cloth));
        }
        let done = row.energy.len().max(1);
        row.frame_wall_s = wall / done as f64;
        row.iterations = (iterations > 0).then(|| (iterations / done as u64) as u32);
        row.max_stretch = row.stretch.last().copied().unwrap_or(0.0);
        row.energy_change = row.energy.last().map_or(0.0, |e| e - start_energy);
        rows.push(row);
    }
    Ok(rows)
}

/// A line colour per integrator, in the order of [`Integrator::ALL`].
pub const COLORS: [[u8; 3]; 6] = [
    [230, 80, 60],
    [60, 160, 230],
    [90, 200, 90],
    [200, 120, 230],
    [240, 190, 40],
    [40, 210, 200],
];

/// Draws energy (top) and max stretch (bottom) against time, one line per
/// integrator in [`COLORS`], on a `width × height` picture.
pub fn plot(rows: &[Comparison], width: u32, height: u32) -> RgbImage {
    let mut img = RgbImage::from_pixel(width, height, Rgb([24, 26, 32]));
    let half = height / 2;
    let frames = rows
        .iter()
        .map(|r| r.energy.len())
        .max()
        .unwrap_or(1)
        .max(2);
    let energy: Vec<Vec<f64>> = rows.iter().map(|r| r.energy.clone()).collect();
    let stretch: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| r.stretch.iter().map(|&s| s as f64).collect())
        .collect();
    for (top, values) in [(0, energy), (half, stretch)] {
        let (lo, hi) = values
            .iter()
            .flatten()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let (lo, hi) = if lo < hi {
            (lo, hi)
        } else {
            (lo - 1.0, lo + 1.0)
        };
        let margin = 12.0;
        let (w, h) = (width as f64 - 2.0 * margin, half as f64 - 2.0 * margin);
        // Frame and zero line.
        for x in margin as u32..(width - margin as u32) {
            img.put_pixel(x, top + half - margin as u32, Rgb([90, 90, 100]));
        }
        if lo < 0.0 && hi > 0.0 {
            let y0 = top as f64 + margin + h * (hi / (hi - lo));
            for x in (margin as u32..(width - margin as u32)).step_by(4) {
                img.put_pixel(x, y0 as u32, Rgb([70, 70, 80]));
            }
        }
        for (k, line) in values.iter().enumerate() {
            let color = Rgb(COLORS[k % COLORS.len()]);
            let point = |i: usize, v: f64| {
                let x = margin + w * i as f64 / (frames - 1) as f64;
                let y = top as f64 + margin + h * (hi - v) / (hi - lo);
                (x, y)
            };
            for i in 1..line.len() {
                let (a, b) = (point(i - 1, line[i - 1]), point(i, line[i]));
                draw_line(&mut img, a, b, color);
            }
        }
    }
    img
}

fn draw_line(img: &mut RgbImage, a: (f64, f64), b: (f64, f64), color: Rgb<u8>) {
    let steps = ((b.0 - a.0).abs().max((b.1 - a.1).abs()).ceil() as usize).clamp(1, 4096);
    for s in 0..=steps {
        let t = s as f64 / steps as f64;
        let (x, y) = (a.0 + (b.0 - a.0) * t, a.1 + (b.1 - a.1) * t);
        for (dx, dy) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0)] {
            let (px, py) = ((x + dx) as i64, (y + dy) as i64);
            if px >= 0 && py >= 0 && (px as u32) < img.width() && (py as u32) < img.height() {
                img.put_pixel(px as u32, py as u32, color);
            }
        }
    }
}
