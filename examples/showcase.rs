//! The cloth3d showcase: every canonical scene in a window, with the spring
//! trace, picking, pinning, dragging and live controls.
//!
//! ```sh
//! cargo run --release --features viewer --example showcase
//! # headless, no display needed:
//! cargo run --release --features viewer --example showcase -- --screenshot drape.png --frames 120 --scene drape
//! # a scene file of your own (R reloads it after you edit it):
//! cargo run --release --features viewer --example showcase -- --scene examples/scenes/capsule_drape.ron
//! ```
//!
//! Keys: 1–9 scene · I integrator · M material · P pin preset · Space pause ·
//! N one frame · R reset · W wind · T spring trace · click a particle to
//! select it · X pin/unpin it · Ctrl+drag to pull it · Shift+drag to tear
//! the cloth along the cursor's path · H help.

use cloth3d::cli::args::SceneArgs;
use cloth3d::prelude::*;
use cloth3d::scenes::{Scene, SceneError, SceneKind, SceneOptions};
use cloth3d::viewer::{self, SceneView, TraceMode};
use kiss3d::egui;
use kiss3d::prelude::*;

/// The showcase's flags: the command's scene flags (same names, same range
/// checks), the scene to open, and the headless screenshot.
#[derive(clap::Parser)]
#[command(
    name = "showcase",
    about = "cloth3d's canonical scenes in a window (or one headless screenshot)"
)]
struct Args {
    /// A canonical scene's name or a scene file's path.
    #[arg(long, default_value = "drape")]
    scene: String,
    #[command(flatten)]
    options: SceneArgs,
    /// Render `--frames` frames (default 120) off screen to this PNG and exit.
    #[arg(long, value_name = "FILE.png")]
    screenshot: Option<String>,
    /// Screenshot size in pixels.
    #[arg(long, value_name = "WIDTHxHEIGHT", value_parser = parse_size, default_value = "1280x720")]
    size: (u32, u32),
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once('x')
        .ok_or("expected WIDTHxHEIGHT, for example 1280x720")?;
    let side = |v: &str| match v.parse::<u32>() {
        Ok(n) if (16..=8192).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{v}' must be a whole number of pixels from 16 to 8192"
        )),
    };
    Ok((side(w)?, side(h)?))
}

#[kiss3d::main]
async fn main() {
    use clap::Parser as _;
    let args = Args::parse();
    let options = args.options.options();
    if let Some(path) = &args.screenshot {
        let frames = options.frames.unwrap_or(120);
        let scene = match Scene::open(&args.scene, &options) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(2);
            }
        };
        match viewer::screenshot(scene, frames, std::path::Path::new(path), args.size).await {
            Ok(()) => println!("wrote {path}"),
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(1);
            }
        }
        return;
    }
    interactive(args.scene, options).await;
}

/// Everything the window shows and the keys change.
struct Showcase {
    /// What is on screen: a canonical scene's name or a scene file's path.
    source: String,
    options: SceneOptions,
    scene: Scene,
    view: SceneView,
    camera: OrbitCamera3d,
    paused: bool,
    trace: TraceMode,
    selected: Option<usize>,
    /// The pin preset chosen with P on a scene without variants.
    pins: Option<PinPreset>,
    dragging: Option<(usize, bool)>,
    /// Shift+drag: tearing along the cursor's path; the last particle the
    /// cursor passed over, where it was, and whether it was torn.
    ripping: Option<Option<(usize, Vector, bool)>>,
    wind_on: bool,
    help: bool,
    message: String,
    step_ms: f64,
    /// The last step's self-collision and its looks for pairs (ms).
    self_ms: (f64, f64),
    /// Substeps the last step took (automatic ones depend on the obstacles
    /// near the cloth); 0 before the first.
    substeps: u32,
    frame_ms: f64,
}

impl Showcase {
    fn load(
        root: &mut SceneNode3d,
        source: &str,
        options: SceneOptions,
    ) -> Result<(Scene, SceneView), SceneError> {
        let scene = Scene::open(source, &options)?;
        let view = SceneView::new(root, &scene);
        Ok((scene, view))
    }

    fn switch(&mut self, root: &mut SceneNode3d, source: String, keep_camera: bool) {
        if source != self.source {
            self.options.variant = None;
        }
        match Self::load(root, &source, self.options.clone()) {
            Ok((scene, view)) => {
                let old = std::mem::replace(&mut self.view, view);
                old.remove();
                self.scene = scene;
                if !keep_camera || source != self.source {
                    self.camera = viewer::camera_for(&self.scene);
                }
                self.source = source;
                self.selected = None;
                self.pins = None;
                self.dragging = None;
                self.ripping = None;
                self.wind_on = !self.scene.cloth.params.wind.is_calm();
                self.message.clear();
            }
            Err(e) => self.message = e.to_string(),
        }
    }
}

fn next_in<T: Copy + PartialEq>(all: &[T], current: T) -> T {
    let i = all.iter().position(|x| *x == current).unwrap_or(0);
    all[(i + 1) % all.len()]
}

async fn interactive(source: String, options: SceneOptions) {
    let mut window = Window::new_with_size("cloth3d showcase", 1280, 720).await;
    window.set_background_color(viewer::BACKGROUND);
    let mut root = SceneNode3d::empty();
    viewer::add_lights(&mut root);
    let (scene, view) = match Showcase::load(&mut root, &source, options.clone()) {
        Ok(x) => x,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let mut app = Showcase {
        source,
        options,
        wind_on: !scene.cloth.params.wind.is_calm(),
        camera: viewer::camera_for(&scene),
        scene,
        view,
        paused: false,
        trace: TraceMode::Off,
        selected: None,
        pins: None,
        dragging: None,
        ripping: None,
        help: true,
        message: String::new(),
        step_ms: 0.0,
        self_ms: (0.0, 0.0),
        substeps: 0,
        frame_ms: 0.0,
    };
    let font = Font::default();
    let mut cursor = Vec2::ZERO;
    let mut last_frame = std::time::Instant::now();
    // The flag's breeze.
    let default_wind = Wind::new(Vector::new(1.0, 0.0, 0.3), 8.0).with_air(3.6, 0.2, 0.4, 7);
    while window.render_3d(&mut root, &mut app.camera).await {
        app.frame_ms = last_frame.elapsed().as_secs_f64() * 1000.0;
        last_frame = std::time::Instant::now();
        let size = Vec2::new(window.size()[0] as f32, window.size()[1] as f32);
        let mut step_once = false;
        let ui_mouse = window.is_egui_capturing_mouse();
        for mut event in window.events().iter() {
            match event.value {
                WindowEvent::CursorPos(x, y, _) => {
                    cursor = Vec2::new(x as f32, y as f32);
                    if app.dragging.is_some() {
                        event.inhibited = true;
                    }
                }
                WindowEvent::MouseButton(MouseButton::Button1, Action::Press, mods)
                    if !ui_mouse =>
                {
                    let (origin, dir) = app.camera.unproject(cursor, size);
                    let picked = viewer::pick(&app.scene.cloth, origin, dir, 0.03);
                    if mods.contains(Modifiers::Shift) {
                        app.ripping = Some(None);
                        event.inhibited = true;
                    } else if let Some(i) = picked {
                        app.selected = Some(i);
                        if mods.contains(Modifiers::Control) {
                            let was_pinned = app.scene.cloth.is_pinned(i);
                            let _ = app.scene.cloth.pin(i);
                            app.dragging = Some((i, was_pinned));
                            event.inhibited = true;
                        }
                    }
                }
                WindowEvent::MouseButton(MouseButton::Button1, Action::Release, _) => {
                    if app.ripping.take().is_some() {
                        event.inhibited = true;
                    }
                    if let Some((i, was_pinned)) = app.dragging.take() {
                        if !was_pinned {
                            let _ = app.scene.cloth.unpin(i);
                        }
                        event.inhibited = true;
                    }
                }
                WindowEvent::Key(key, Action::Press, _) if !window_is_typing(&window) => {
                    let kinds = SceneKind::ALL;
                    let scene_key = [
                        Key::Key1,
                        Key::Key2,
                        Key::Key3,
                        Key::Key4,
                        Key::Key5,
                        Key::Key6,
                        Key::Key7,
                        Key::Key8,
                        Key::Key9,
                    ]
                    .iter()
                    .position(|k| *k == key);
                    if let Some(s) = scene_key {
                        app.switch(&mut root, kinds[s].name().to_string(), false);
                        continue;
                    }
                    match key {
                        Key::Space => app.paused = !app.paused,
                        Key::N => {
                            app.paused = true;
                            step_once = true;
                        }
                        Key::R => app.switch(&mut root, app.source.clone(), true),
                        Key::T => app.trace = app.trace.next(),
                        Key::H => app.help = !app.help,
                        Key::W => {
                            app.wind_on = !app.wind_on;
                            app.scene.cloth.params.wind = if app.wind_on {
                                default_wind
                            } else {
                                Wind::NONE
                            };
                        }
                        Key::I => {
                            let next =
                                next_in(&Integrator::ALL, app.scene.solver.settings.integrator);
                            app.scene.solver.set_integrator(next);
                            app.scene.solver.settings.substeps = next.default_substeps();
                            app.options.integrator = Some(next);
                        }
                        Key::M => {
                            let names = Material::PRESET_NAMES;
                            let next = next_in(
                                &names,
                                names
                                    .iter()
                                    .copied()
                                    .find(|n| *n == app.scene.cloth.material.name)
                                    .unwrap_or("cotton"),
                            );
                            if let Ok(m) = Material::by_name(next) {
                                app.scene.cloth.material = m.clone();
                                app.options.material = Some(m);
                            }
                        }
                        Key::P => {
                            let variants = app.scene.kind.map_or(&[][..], |k| k.variants());
                            if variants.is_empty() {
                                // Scenes without variants: change the pins of the cloth on screen.
                                let current = app.pins.unwrap_or(PinPreset::None);
                                let next = next_in(&PinPreset::ALL, current);
                                let _ = app.scene.cloth.apply_pin_preset(next);
                                app.pins = Some(next);
                                app.message = format!("pins: {}", next.name());
                            } else {
                                let current = app.options.variant.unwrap_or(variants[0]);
                                app.options.variant = Some(next_in(variants, current));
                                app.switch(&mut root, app.source.clone(), true);
                            }
                        }
                        Key::X => {
                            if let Some(i) = app.selected {
                                let _ = if app.scene.cloth.is_pinned(i) {
                                    app.scene.cloth.unpin(i)
                                } else {
                                    app.scene.cloth.pin(i)
                                };
                            }
                        }
                        _ => {}
                    }
                }
                _ => {}
            }
        }

        // Dragging: the grabbed particle follows the cursor on a plane facing the camera.
        if let Some((i, _)) = app.dragging {
            let (origin, dir) = app.camera.unproject(cursor, size);
            let p = app.scene.cloth.positions()[i];
            let normal = (app.camera.eye() - p).normalize_or(Vec3::Z);
            let denom = dir.dot(normal);
            if denom.abs() > 1e-6 {
                let t = (p - origin).dot(normal) / denom;
                let target = origin + dir * t;
                let _ = app.scene.cloth.set_velocity(i, (target - p) / app.scene.dt);
            }
        }

        // Tearing by hand: each particle the cursor passes over splits
        // across the cursor's path (seen from the camera), so the cloth opens
        // along it.
        if let Some(last) = app.ripping {
            let (origin, dir) = app.camera.unproject(cursor, size);
            if let Some(i) = viewer::pick(&app.scene.cloth, origin, dir, 0.03) {
                let p = app.scene.cloth.positions()[i];
                match last {
                    Some((j, q, torn)) if j != i => {
                        let normal = (p - q).cross(dir);
                        let first = (!torn).then_some(j);
                        for k in first.into_iter().chain([i]) {
                            if let Ok(Some(split)) = app.scene.cloth.split_particle(k, normal) {
                                app.message = format!(
                                    "tore particle {} (new particle {})",
                                    split.particle, split.new_particle
                                );
                            }
                        }
                        app.ripping = Some(Some((i, p, true)));
                    }
                    None => app.ripping = Some(Some((i, p, false))),
                    _ => {}
                }
            }
        }

        if !app.paused || step_once {
            let start = std::time::Instant::now();
            match app.scene.step_frame() {
                Ok(report) => {
                    app.substeps = report.substeps;
                    let t = report.times;
                    app.self_ms = (1000.0 * t.self_collision, 1000.0 * t.self_looks);
                }
                Err(e) => {
                    app.message = e.to_string();
                    app.paused = true;
                }
            }
            app.step_ms = start.elapsed().as_secs_f64() * 1000.0;
            if let Some((i, _)) = app.dragging {
                let _ = app.scene.cloth.set_velocity(i, Vector::ZERO);
            }
        }
        app.view.sync(&app.scene);

        viewer::draw_trace(&mut window, &app.scene.cloth, app.trace);
        viewer::draw_pins(&mut window, &app.scene.cloth);
        if let Some(i) = app.selected {
            viewer::draw_neighbours(&mut window, &app.scene.cloth, i);
        }
        overlay_text(&mut window, &font, &app);
        controls(&mut window, &mut app);
    }
}

fn window_is_typing(window: &Window) -> bool {
    window.is_egui_capturing_keyboard()
}

fn overlay_text(window: &mut Window, font: &std::sync::Arc<Font>, app: &Showcase) {
    let cloth = &app.scene.cloth;
    let e = cloth.energy();
    let lines = [
        format!(
            "{}{}  |  {}  |  {}  |  {} particles, {} springs",
            app.scene.name,
            app.scene.variant.map(|v| format!(" ({})", v.name())).unwrap_or_default(),
            app.scene.solver.integrator(),
            cloth.material.name,
            cloth.particle_count(),
            cloth.springs().len()
        ),
        format!(
            "frame {:.1} ms  step {:.2} ms{}  substeps {}  |  energy {:.3} J (kinetic {:.3})  |  stretch {:.2}%{}",
            app.frame_ms,
            app.step_ms,
            if cloth.params.self_collision {
                format!(
                    " (self-collision {:.2}, its looks {:.2})",
                    app.self_ms.0, app.self_ms.1
                )
            } else {
                String::new()
            },
            if app.substeps > 0 {
                app.substeps
            } else {
                app.scene.solver.substeps_for(cloth, app.scene.dt)
            },
            e.total(),
            e.kinetic,
            100.0 * cloth.max_strain(SpringKind::Stretch),
            if app.paused { "  |  PAUSED" } else { "" }
        ),
        format!("trace: {}  |  wind: {}", app.trace.name(), if app.wind_on { "on" } else { "off" }),
        app.message.clone(),
    ];
    for (k, line) in lines.iter().enumerate() {
        window.draw_text(
            line,
            Vec2::new(12.0, 8.0 + 24.0 * k as f32),
            20.0,
            font,
            WHITE,
        );
    }
    if app.help {
        let help = "1-9 scene  I integrator  M material  P pins  Space pause  N step  R reset  W wind  T trace  click select  X pin  Ctrl+drag pull  Shift+drag tear  H help";
        let y = window.size()[1] as f32 * window.scale_factor() as f32 - 30.0;
        window.draw_text(
            help,
            Vec2::new(12.0, y),
            18.0,
            font,
            Color::new(0.8, 0.8, 0.85, 1.0),
        );
    }
}

/// Live controls: every change applies at the next frame, no restart.
fn controls(window: &mut Window, app: &mut Showcase) {
    let cloth = &mut app.scene.cloth;
    let solver = &mut app.scene.solver;
    let mut dt = app.scene.dt;
    window.draw_ui(|ctx| {
        egui::Window::new("controls")
            .default_pos([10.0, 110.0])
            .show(ctx, |ui| {
                for kind in SpringKind::ALL {
                    let p = cloth.material.params_mut(kind);
                    ui.label(format!("{} springs", kind.name()));
                    ui.add(
                        egui::Slider::new(&mut p.stiffness, 0.1..=1.0e6)
                            .logarithmic(true)
                            .text("k (N/m)"),
                    );
                    ui.add(
                        egui::Slider::new(&mut p.damping, 0.0..=50.0)
                            .logarithmic(true)
                            .text("c (N·s/m)"),
                    );
                }
                let mut mass = cloth.total_mass();
                if ui
                    .add(
                        egui::Slider::new(&mut mass, 0.05..=20.0)
                            .logarithmic(true)
                            .text("mass (kg)"),
                    )
                    .changed()
                {
                    let _ = cloth.set_total_mass(mass);
                }
                ui.add(
                    egui::Slider::new(&mut cloth.params.air_drag, 0.0..=5.0).text("air drag (1/s)"),
                );
                ui.add(
                    egui::Slider::new(&mut cloth.params.wind.strength, 0.0..=40.0)
                        .text("wind (N/m²)"),
                );
                ui.add(
                    egui::Slider::new(&mut cloth.params.wind.speed, 0.0..=15.0)
                        .text("air speed (m/s; 0: pressure only)"),
                );
                if cloth.params.wind.speed > 0.0 {
                    ui.add(
                        egui::Slider::new(&mut cloth.params.wind.friction, 0.0..=1.0)
                            .text("skin friction"),
                    );
                    ui.add(
                        egui::Slider::new(&mut cloth.params.wind.turbulence, 0.0..=1.0)
                            .text("gusts"),
                    );
                }
                let mut heading = cloth
                    .params
                    .wind
                    .direction
                    .z
                    .atan2(cloth.params.wind.direction.x);
                if ui
                    .add(
                        egui::Slider::new(
                            &mut heading,
                            -std::f32::consts::PI..=std::f32::consts::PI,
                        )
                        .text("wind heading (rad)"),
                    )
                    .changed()
                {
                    cloth.params.wind.direction = Vector::new(heading.cos(), 0.0, heading.sin());
                }
                let mut friction = app.scene.obstacles.first().map_or(0.5, |o| o.friction);
                if ui
                    .add(egui::Slider::new(&mut friction, 0.0..=2.0).text("friction"))
                    .changed()
                {
                    for o in &mut app.scene.obstacles {
                        o.friction = friction;
                    }
                    if let Some(side) = &mut app.scene.rapier {
                        side.coupling.friction = friction;
                    }
                }
                ui.checkbox(&mut cloth.params.self_collision, "self-collision");
                if cloth.params.self_collision {
                    ui.add(
                        egui::Slider::new(&mut cloth.params.self_friction, 0.0..=2.0)
                            .text("friction between layers"),
                    );
                }
                ui.checkbox(&mut cloth.params.tethers, "tethers to the pins");
                let asleep = if solver.is_asleep() { " (asleep)" } else { "" };
                ui.checkbox(
                    &mut solver.settings.sleep,
                    format!("sleep when still{asleep}"),
                );
                ui.add(egui::Slider::new(&mut dt, 1.0 / 240.0..=1.0 / 20.0).text("dt (s)"));
                let mut auto = solver.settings.substeps == Substeps::Auto;
                let mut k = match solver.settings.substeps {
                    Substeps::Fixed(k) => k,
                    Substeps::Auto => solver.substeps_for(cloth, dt),
                };
                ui.checkbox(&mut auto, "automatic substeps");
                if !auto {
                    ui.add(egui::Slider::new(&mut k, 1..=400).text("substeps"));
                }
                solver.settings.substeps = if auto {
                    Substeps::Auto
                } else {
                    Substeps::Fixed(k)
                };
                egui::ComboBox::from_label("integrator")
                    .selected_text(solver.settings.integrator.name())
                    .show_ui(ui, |ui| {
                        for i in Integrator::ALL {
                            if ui
                                .selectable_label(solver.settings.integrator == i, i.name())
                                .clicked()
                            {
                                solver.set_integrator(i);
                            }
                        }
                    });
                egui::ComboBox::from_label("material")
                    .selected_text(cloth.material.name.clone())
                    .show_ui(ui, |ui| {
                        for m in Material::presets() {
                            if ui
                                .selectable_label(cloth.material.name == m.name, &m.name)
                                .clicked()
                            {
                                cloth.material = m;
                            }
                        }
                    });
            });
    });
    app.scene.dt = dt;
    if let Some(side) = &mut app.scene.rapier {
        side.world.integration_parameters.dt = dt;
    }
}
