//! The kiss3d viewer (feature `viewer`): the cloth as a shaded double-sided
//! mesh, obstacles drawn from their shapes and poses, the spring trace
//! coloured by kind or by strain, particle picking, and headless screenshots.
//!
//! The showcase example (`examples/showcase.rs`) drives it; the solver knows
//! nothing of it.

use kiss3d::prelude::*;

use crate::cloth::{Cloth, SpringKind};
use crate::collision::Obstacle;
use crate::math::Vector;
use crate::scenes::{Scene, SceneKind};

/// Colour of stretch springs in the trace.
pub const STRETCH_COLOR: Color = Color::new(0.95, 0.35, 0.25, 1.0);
/// Colour of shear springs in the trace.
pub const SHEAR_COLOR: Color = Color::new(0.3, 0.85, 0.35, 1.0);
/// Colour of bend springs in the trace.
pub const BEND_COLOR: Color = Color::new(0.35, 0.55, 1.0, 1.0);
/// Background colour.
pub const BACKGROUND: Color = Color::new(0.11, 0.12, 0.15, 1.0);
/// Colour of obstacles.
pub const OBSTACLE_COLOR: Color = Color::new(0.62, 0.64, 0.68, 1.0);
/// Colour of the props: the ground, posts, rails and stands nothing collides with.
pub const PROP_COLOR: Color = Color::new(0.40, 0.42, 0.46, 1.0);

/// The colour of a spring kind in the trace.
pub fn kind_color(kind: SpringKind) -> Color {
    match kind {
        SpringKind::Stretch => STRETCH_COLOR,
        SpringKind::Shear => SHEAR_COLOR,
        SpringKind::Bend => BEND_COLOR,
    }
}

/// What the spring trace shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceMode {
    /// No spring lines.
    Off,
    /// Every spring, coloured by kind (stretch red, shear green, bend blue).
    Kinds,
    /// Stretch springs coloured by strain: blue compressed, white at rest, red stretched 5% or more.
    Strain,
}

impl TraceMode {
    /// The next mode, for a toggle key.
    pub fn next(self) -> Self {
        match self {
            TraceMode::Off => TraceMode::Kinds,
            TraceMode::Kinds => TraceMode::Strain,
            TraceMode::Strain => TraceMode::Off,
        }
    }

    /// Name shown on screen.
    pub fn name(self) -> &'static str {
        match self {
            TraceMode::Off => "off",
            TraceMode::Kinds => "springs by kind",
            TraceMode::Strain => "strain",
        }
    }
}

/// The cloth's display colour.
pub fn cloth_color(cloth: &Cloth) -> Color {
    let [r, g, b] = cloth.material.color;
    Color::new(r, g, b, 1.0)
}

/// A scene's nodes in a kiss3d scene graph: the cloth mesh and one node per obstacle.
pub struct SceneView {
    group: SceneNode3d,
    cloth: SceneNode3d,
    obstacles: Vec<Option<SceneNode3d>>,
    /// The topology the mesh's faces were taken from (its address): a torn
    /// cloth gets a new one, with more particles and triangles.
    shown_topology: usize,
}

impl SceneView {
    /// Adds the nodes of `scene` under `root`.
    pub fn new(root: &mut SceneNode3d, scene: &Scene) -> Self {
        let mut group = root.add_group();
        let cloth = &scene.cloth;
        let coords: Vec<Vec3> = cloth.positions().to_vec();
        let faces: Vec<[u32; 3]> = cloth.triangles().to_vec();
        let uvs: Vec<Vec2> = cloth.uvs().iter().map(|&[u, v]| Vec2::new(u, v)).collect();
        let mesh = GpuMesh3d::new(coords, faces, Some(cloth.vertex_normals()), Some(uvs), true);
        let cloth_node = group
            .add_mesh(Rc::new(RefCell::new(mesh)), Vec3::ONE)
            .set_color(cloth_color(cloth))
            .enable_backface_culling(false);
        let obstacles = scene
            .current_obstacles()
            .iter()
            .map(|o| obstacle_node(&mut group, o))
            .collect();
        // The props: drawn once, they never move.
        for prop in &scene.desc.props {
            let Ok(shape) = prop.shape.shape() else {
                continue;
            };
            let o = Obstacle::new(shape, prop.pose());
            if let Some(mut node) = obstacle_node(&mut group, &o) {
                node.set_pose(o.pose);
                node.set_color_recursive(PROP_COLOR);
            }
        }
        let mut view = SceneView {
            group,
            cloth: cloth_node,
            obstacles,
            shown_topology: std::sync::Arc::as_ptr(cloth.topology()) as usize,
        };
        view.sync(scene);
        view
    }

    /// Moves the mesh vertices and the obstacles to where the scene has them now.
    pub fn sync(&mut self, scene: &Scene) {
        let topology = scene.cloth.topology();
        if std::sync::Arc::as_ptr(topology) as usize != self.shown_topology {
            // The cloth tore: new particles, triangles moved to them.
            self.shown_topology = std::sync::Arc::as_ptr(topology) as usize;
            let n = scene.cloth.particle_count();
            self.cloth.modify_faces(&mut |f: &mut Vec<[u32; 3]>| {
                f.clear();
                f.extend_from_slice(topology.triangles());
            });
            self.cloth.modify_uvs(&mut |u: &mut Vec<Vec2>| {
                u.clear();
                u.extend(topology.uvs().iter().map(|&[a, b]| Vec2::new(a, b)));
            });
            self.cloth
                .modify_normals(&mut |v: &mut Vec<Vec3>| v.resize(n, Vec3::Y));
        }
        let positions = scene.cloth.positions();
        self.cloth.modify_vertices(&mut |v: &mut Vec<Vec3>| {
            v.clear();
            v.extend_from_slice(positions);
        });
        self.cloth.recompute_normals();
        self.cloth.set_color(cloth_color(&scene.cloth));
        for (node, o) in self.obstacles.iter_mut().zip(scene.current_obstacles()) {
            if let Some(node) = node {
                node.set_pose(o.pose);
            }
        }
    }

    /// Removes the nodes from the scene graph.
    pub fn remove(mut self) {
        self.group.remove();
    }
}

/// A node drawing an obstacle's shape (balls, cuboids, capsules); `None` for other shapes.
fn obstacle_node(group: &mut SceneNode3d, o: &Obstacle) -> Option<SceneNode3d> {
    let shape = &*o.shape;
    let node = if let Some(ball) = shape.as_ball() {
        group.add_sphere(ball.radius)
    } else if let Some(c) = shape.as_cuboid() {
        let h = c.half_extents;
        group.add_cube(2.0 * h.x, 2.0 * h.y, 2.0 * h.z)
    } else if let Some(c) = shape.as_capsule() {
        let axis = c.segment.b - c.segment.a;
        let mut wrapper = group.add_group();
        let mut node = wrapper.add_capsule(c.radius, axis.length());
        node.set_pose(Pose3::from_parts(
            (c.segment.a + c.segment.b) * 0.5,
            Quat::from_rotation_arc(Vec3::Y, axis.normalize_or(Vec3::Y)),
        ));
        node.set_color(OBSTACLE_COLOR);
        return Some(wrapper);
    } else if let Some(c) = shape.as_cylinder() {
        group.add_cylinder(c.radius, 2.0 * c.half_height)
    } else if let Some(c) = shape.as_cone() {
        group.add_cone(c.radius, 2.0 * c.half_height)
    } else if let Some(c) = shape.as_convex_polyhedron() {
        let (vertices, indices) = c.to_trimesh();
        let vertices = vertices
            .into_iter()
            .map(|v| Vec3::new(v.x, v.y, v.z))
            .collect();
        group.add_trimesh(vertices, indices, Vec3::ONE, true)
    } else if let Some(m) = shape.as_trimesh() {
        group.add_trimesh(
            m.vertices().to_vec(),
            m.indices().to_vec(),
            Vec3::ONE,
            false,
        )
    } else {
        return None;
    };
    let mut node = node;
    node.set_color(OBSTACLE_COLOR);
    Some(node)
}

/// A camera that frames each scene: a chosen view for the canonical ones,
/// and for a scene file a view over the cloth and its obstacles from the front right.
pub fn camera_for(scene: &Scene) -> OrbitCamera3d {
    let Some(kind) = scene.kind else {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        let boxes: Vec<_> = scene
            .current_obstacles()
            .iter()
            .map(|o| o.shape.compute_aabb(&o.pose))
            .filter(|b| (b.maxs - b.mins).max_element() < 100.0)
            .collect();
        let points = scene
            .cloth
            .positions()
            .iter()
            .copied()
            .chain(boxes.iter().flat_map(|b| [b.mins, b.maxs]));
        for p in points.filter(|p| p.is_finite()) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if !lo.is_finite() {
            return OrbitCamera3d::new(Vec3::new(0.7, 0.65, 0.95), Vec3::ZERO);
        }
        // The cloth falls: look below the middle of where it starts.
        let mut at = (lo + hi) * 0.5;
        at.y = lo.y + 0.35 * (hi.y - lo.y);
        let reach = (hi - lo).length().max(0.5);
        return OrbitCamera3d::new(at + Vec3::new(0.55, 0.45, 0.75) * reach * 1.1, at);
    };
    let (eye, at) = match kind {
        SceneKind::Drape | SceneKind::Box => {
            (Vec3::new(0.7, 0.65, 0.95), Vec3::new(0.0, 0.05, 0.0))
        }
        SceneKind::Flag => (Vec3::new(2.4, 1.6, 1.9), Vec3::new(0.6, 1.1, 0.2)),
        SceneKind::Pins => (Vec3::new(0.8, 0.9, 1.1), Vec3::new(0.0, 0.25, 0.0)),
        SceneKind::Curtain => (Vec3::new(1.5, 1.2, 1.3), Vec3::new(0.0, 1.0, 0.1)),
        SceneKind::Hammock => (Vec3::new(0.8, 0.7, 1.05), Vec3::new(0.0, 0.3, 0.0)),
        // Nearly along the bar, to see the layers' profile.
        SceneKind::Fold => (Vec3::new(0.55, 0.5, 1.45), Vec3::new(0.05, 0.2, 0.0)),
        // From the front and above, to look into the opening.
        SceneKind::Tear => (Vec3::new(0.45, 1.75, 1.55), Vec3::new(0.0, 0.85, 0.0)),
        SceneKind::Stack => (Vec3::new(0.75, 0.75, 1.0), Vec3::new(0.0, 0.1, 0.0)),
    };
    OrbitCamera3d::new(eye, at)
}

/// Draws the spring trace.
pub fn draw_trace(window: &mut Window, cloth: &Cloth, mode: TraceMode) {
    let x = cloth.positions();
    let springs = cloth.springs();
    match mode {
        TraceMode::Off => {}
        TraceMode::Kinds => {
            for kind in SpringKind::ALL {
                let color = kind_color(kind);
                for s in springs.range(kind) {
                    if let Some(sp) = springs.get(s) {
                        window.draw_line(x[sp.a as usize], x[sp.b as usize], color, 1.0, false);
                    }
                }
            }
        }
        TraceMode::Strain => {
            for s in springs.range(SpringKind::Stretch) {
                let (Some(sp), Some(strain)) = (springs.get(s), cloth.strain(s)) else {
                    continue;
                };
                window.draw_line(
                    x[sp.a as usize],
                    x[sp.b as usize],
                    strain_color(strain),
                    1.5,
                    false,
                );
            }
        }
    }
}

/// Blue when compressed, white at rest, red at 5% stretch or more.
pub fn strain_color(strain: f32) -> Color {
    let t = (strain / 0.05).clamp(-1.0, 1.0);
    if t >= 0.0 {
        Color::new(1.0, 1.0 - t, 1.0 - t, 1.0)
    } else {
        Color::new(1.0 + t, 1.0 + t, 1.0, 1.0)
    }
}

/// Highlights particle `i` and its neighbours, each line coloured by the kind
/// of spring that joins them.
pub fn draw_neighbours(window: &mut Window, cloth: &Cloth, i: usize) {
    let x = cloth.positions();
    let Some(&p) = x.get(i) else {
        return;
    };
    for sp in cloth.springs().iter() {
        let other = if sp.a as usize == i {
            sp.b as usize
        } else if sp.b as usize == i {
            sp.a as usize
        } else {
            continue;
        };
        let color = kind_color(sp.kind);
        window.draw_line(p, x[other], color, 4.0, false);
        window.draw_point(x[other], color, 10.0);
    }
    let marker = if cloth.is_pinned(i) {
        Color::new(1.0, 0.85, 0.1, 1.0)
    } else {
        WHITE
    };
    window.draw_point(p, marker, 16.0);
}

/// Draws every pinned particle as a yellow dot.
pub fn draw_pins(window: &mut Window, cloth: &Cloth) {
    for i in cloth.pinned() {
        window.draw_point(cloth.positions()[i], Color::new(1.0, 0.85, 0.1, 1.0), 8.0);
    }
}

/// The particle nearest to the ray `origin + t dir` (within `radius` metres of it), if any.
pub fn pick(cloth: &Cloth, origin: Vector, dir: Vector, radius: f32) -> Option<usize> {
    let dir = dir.try_normalize()?;
    let mut best: Option<(f32, usize)> = None;
    for (i, &p) in cloth.positions().iter().enumerate() {
        let t = (p - origin).dot(dir);
        if t <= 0.0 {
            continue;
        }
        let off = (p - origin - dir * t).length();
        if off <= radius && best.is_none_or(|(bt, _)| t < bt) {
            best = Some((t, i));
        }
    }
    best.map(|(_, i)| i)
}

/// Renders scenes off screen (no display needed) through one surface.
///
/// kiss3d keeps its GPU resources per process, so make one renderer and
/// render every picture with it.
pub struct OffscreenRenderer {
    surface: OffscreenSurface,
}

impl OffscreenRenderer {
    /// A renderer of `width × height` pixels.
    pub async fn new(width: u32, height: u32) -> Self {
        let mut surface = OffscreenSurface::new(width, height).await;
        surface.set_background_color(BACKGROUND);
        Self { surface }
    }

    /// A picture of the scene as it is now, with its camera and a caption.
    pub async fn render(&mut self, scene: &Scene) -> image::RgbImage {
        let mut camera = camera_for(scene);
        let mut root = SceneNode3d::empty();
        add_lights(&mut root);
        let view = SceneView::new(&mut root, scene);
        let label = format!(
            "{}  |  {}  |  {}  |  {} particles  |  frame {}",
            scene.name,
            scene.solver.integrator(),
            scene.cloth.material.name,
            scene.cloth.particle_count(),
            scene.frame
        );
        let width = self.surface.width();
        let text_scale = (width as f32 / 36.0).clamp(12.0, 40.0);
        self.surface.window_mut().draw_text(
            &label,
            Vec2::new(12.0, 12.0),
            text_scale,
            &Font::default(),
            WHITE,
        );
        self.surface.render_3d(&mut root, &mut camera).await;
        let snap = self.surface.snap_image();
        view.remove();
        image::RgbImage::from_raw(snap.width(), snap.height(), snap.into_raw()).unwrap_or_default()
    }
}

/// Runs a scene `frames` frames, renders the last one off screen (no
/// display needed) and writes it to `path` as a PNG.
pub async fn screenshot(
    mut scene: Scene,
    frames: u32,
    path: &std::path::Path,
    size: (u32, u32),
) -> Result<(), String> {
    for _ in 0..frames {
        scene.step_frame().map_err(|e| e.to_string())?;
    }
    let mut renderer = OffscreenRenderer::new(size.0, size.1).await;
    let image = renderer.render(&scene).await;
    image
        .save(path)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// A key light and a fill light.
pub fn add_lights(root: &mut SceneNode3d) {
    root.add_light(Light::point(100.0))
        .set_position(Vec3::new(2.0, 4.0, 3.0));
    root.add_light(Light::point(100.0))
        .set_position(Vec3::new(-3.0, 2.0, -2.0));
}
