//! Any text given to the scene-file reader gives a scene or an error with a
//! line, never a panic; a scene that builds steps without a panic.
#![no_main]

use cloth3d::scenes::{file, Scene};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match file::from_ron(text) {
        Err(e) => assert!(e.to_string().starts_with("line "), "{e}"),
        Ok(desc) => {
            // Keep each run small: the fuzzer looks for panics, not for big grids.
            if desc.cloth.cols.saturating_mul(desc.cloth.rows) > 4096 || desc.bodies.len() > 16 {
                return;
            }
            if let Ok(mut scene) = Scene::from_desc(desc) {
                let _ = scene.step_frame();
                assert!(scene.cloth.is_finite());
            }
        }
    }
});
