//! Headless rendering (feature `viewer`): every scene renders off screen with
//! no display, and each picture really shows cloth.
#![cfg(feature = "viewer")]

use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use cloth3d::viewer;

/// Pixels in the cloth's colour: cotton is warm (red well above blue), while
/// the background is blue-grey and obstacles are neutral grey.
fn cloth_pixels(img: &image::RgbImage) -> usize {
    img.pixels()
        .filter(|p| {
            let [r, g, b] = p.0.map(i32::from);
            r > b + 25 && g > b + 10 && r > 90
        })
        .count()
}

fn mean_difference(a: &image::RgbImage, b: &image::RgbImage) -> f64 {
    let total: u64 = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| {
            (0..3)
                .map(|c| (p.0[c] as i32 - q.0[c] as i32).unsigned_abs() as u64)
                .sum::<u64>()
        })
        .sum();
    total as f64 / (a.width() * a.height() * 3) as f64
}

#[test]
fn every_scene_renders_off_screen_and_shows_cloth() {
    let dir = std::env::temp_dir().join(format!("cloth3d-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (480u32, 270u32);
    let mut images = Vec::new();
    let mut renderer = kiss3d::pollster::block_on(viewer::OffscreenRenderer::new(w, h));
    for kind in SceneKind::ALL {
        let path = dir.join(format!("{}.png", kind.name()));
        let options = SceneOptions {
            n: Some(24).filter(|_| matches!(kind, SceneKind::Drape | SceneKind::Box)),
            ..Default::default()
        };
        let mut scene = Scene::build(kind, &options).unwrap();
        for _ in 0..45 {
            scene.step_frame().unwrap();
        }
        kiss3d::pollster::block_on(renderer.render(&scene))
            .save(&path)
            .unwrap();
        // Read back from the file, as a user would.
        let img = image::open(&path).unwrap().to_rgb8();
        assert_eq!((img.width(), img.height()), (w, h));
        let cloth = cloth_pixels(&img);
        let share = cloth as f64 / (w * h) as f64;
        assert!(
            share > 0.01,
            "{}: only {:.2}% of the picture is cloth-coloured",
            kind.name(),
            100.0 * share
        );
        images.push((kind, img));
    }
    // Different scenes give different pictures.
    for i in 0..images.len() {
        for j in i + 1..images.len() {
            let d = mean_difference(&images[i].1, &images[j].1);
            assert!(
                d > 2.0,
                "{} and {} look the same ({d})",
                images[i].0.name(),
                images[j].0.name()
            );
        }
    }
    // A scene file written by hand opens in the viewer too: the red silk
    // scarf over the capsule fills part of the picture.
    let path = format!(
        "{}/examples/scenes/capsule_drape.ron",
        env!("CARGO_MANIFEST_DIR")
    );
    let mut scene = Scene::open(&path, &SceneOptions::default()).unwrap();
    for _ in 0..45 {
        scene.step_frame().unwrap();
    }
    let img = kiss3d::pollster::block_on(renderer.render(&scene));
    let red = img
        .pixels()
        .filter(|p| {
            let [r, g, b] = p.0.map(i32::from);
            r > g + 40 && r > b + 40
        })
        .count();
    assert!(
        red as f64 / (w * h) as f64 > 0.01,
        "the scene file's scarf covers only {red} pixels"
    );
    // And an empty scene has no cloth colour at all: the check can fail.
    let blank = image::RgbImage::from_pixel(w, h, image::Rgb([40, 44, 55]));
    assert_eq!(cloth_pixels(&blank), 0);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn picking_finds_the_nearest_particle_along_the_mouse_ray() {
    let cloth = cloth3d::cloth::ClothBuilder::new(5, 5).build().unwrap();
    // Looking straight down at the particle at (row 1, column 3): x = 0.25, z = -0.25.
    let origin = cloth3d::math::Vector::new(0.25, 2.0, -0.25);
    let down = cloth3d::math::Vector::new(0.0, -1.0, 0.0);
    assert_eq!(
        viewer::pick(&cloth, origin, down, 0.02),
        Some(cloth.index(1, 3).unwrap())
    );
    // A ray between particles, or looking away, picks nothing.
    let between = cloth3d::math::Vector::new(0.125, 2.0, -0.125);
    assert_eq!(viewer::pick(&cloth, between, down, 0.02), None);
    assert_eq!(viewer::pick(&cloth, origin, -down, 0.02), None);
}
