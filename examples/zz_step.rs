//! Scratch: steps a scene, prints mean ms a frame and a bit checksum.
use cloth3d::scenes::{Scene, SceneKind, SceneOptions};
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let kind = SceneKind::from_name(&args[1])?;
    let frames: u32 = args[2].parse()?;
    let mut opts = SceneOptions::default();
    if let Some(n) = args.get(3) {
        opts.n = Some(n.parse()?);
    }
    let mut scene = Scene::build(kind, &opts)?;
    let warm: u32 = std::env::var("ZZW")
        .ok()
        .and_then(|w| w.parse().ok())
        .unwrap_or(0);
    for _ in 0..warm {
        scene.step_frame()?;
    }
    if warm > 0 {
        eprintln!("warm done");
        std::thread::sleep(std::time::Duration::from_millis(1500));
    }
    let mut total = 0.0;
    let (mut looks, mut touch, mut subs) = (0u64, 0u64, 0u64);
    let verbose = std::env::var("ZZV").is_ok();
    for _ in 0..frames {
        let t = Instant::now();
        let r = scene.step_frame()?;
        looks += r.self_looks as u64;
        touch += r.self_contacts as u64;
        subs += r.substeps as u64;
        if verbose {
            println!(
                "looks {} touching {} subs {} ms {:.2}",
                r.self_looks,
                r.self_contacts,
                r.substeps,
                t.elapsed().as_secs_f64() * 1e3
            );
            println!(
                "   integ {:.2} self {:.2} looks {:.2} constr {:.2} contacts {:.2} total {:.2}",
                r.times.integrate * 1e3,
                r.times.self_collision * 1e3,
                r.times.self_looks * 1e3,
                r.times.constraints * 1e3,
                r.times.contacts * 1e3,
                r.times.total * 1e3
            );
        }
        total += t.elapsed().as_secs_f64();
    }
    let mut h: u64 = 0xcbf29ce484222325;
    for p in scene.cloth.positions() {
        for c in p.to_array() {
            h = (h ^ c.to_bits() as u64).wrapping_mul(0x100000001b3);
        }
    }
    println!(
        "{} {:.3} ms/frame hash {:016x} looks/frame {:.2} touching/substep {:.1}",
        args[1],
        total * 1000.0 / frames as f64,
        h,
        looks as f64 / frames as f64,
        touch as f64 / subs.max(1) as f64
    );

    Ok(())
}
