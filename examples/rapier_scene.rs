//! A typical rapier world with a cloth in it: ground, dynamic boxes, a
//! spinning kinematic paddle, and a tablecloth that hits them all and pushes
//! the boxes around.
//!
//! `cargo run --release --example rapier_scene`

use cloth3d::prelude::*;
use cloth3d::rapier::RapierCoupling;
use rapier3d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder};

fn main() -> Result<(), ClothError> {
    // The user's world, built as usual.
    let mut world = PhysicsWorld::new();
    world.insert(
        RigidBodyBuilder::fixed().translation(Vector::new(0.0, -0.1, 0.0)),
        ColliderBuilder::cuboid(3.0, 0.1, 3.0),
    );
    for (i, x) in [-0.3f32, 0.0, 0.3].into_iter().enumerate() {
        world.insert(
            RigidBodyBuilder::dynamic().translation(Vector::new(x, 0.1 + 0.2 * i as f32, 0.0)),
            ColliderBuilder::cuboid(0.1, 0.1, 0.1).density(200.0),
        );
    }
    let (paddle, _) = world.insert(
        RigidBodyBuilder::kinematic_velocity_based()
            .translation(Vector::new(0.0, 0.6, 0.0))
            .angvel(Vector::new(0.0, 2.0, 0.0)),
        ColliderBuilder::cuboid(0.6, 0.03, 0.08),
    );

    // The cloth, and the coupling that puts it in that world.
    let mut cloth = Simulation::new(
        ClothBuilder::new(40, 40)
            .size(1.2, 1.2)
            .horizontal(Vector::new(0.0, 1.0, 0.0))
            .build()?,
    )
    .with_integrator(Integrator::SymplecticEuler);
    let mut coupling = RapierCoupling::new();

    for frame in 1..=180 {
        coupling.step_world(&mut cloth, &mut world)?; // cloth first ...
        world.step(); // ... then rapier integrates what the cloth did to its bodies,
        coupling.push_out_of_world(&mut cloth, &world); // and the cloth leaves any body rapier moved into it
        if frame % 45 == 0 {
            println!(
                "t = {:.2} s  cloth centroid y = {:.3} m  paddle angle {:.2} rad  colliders near the cloth: {}",
                cloth.time(),
                cloth.centroid().y,
                world.bodies[paddle].rotation().to_scaled_axis().length(),
                coupling.last_obstacles().count()
            );
        }
    }
    Ok(())
}
