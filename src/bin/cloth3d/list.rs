//! `cloth3d list`: the scenes, variants, integrators, materials and pin presets.

use cloth3d::cloth::{Material, PinPreset};
use cloth3d::scenes::SceneKind;
use cloth3d::solver::Integrator;

use crate::output::emit;
use crate::{outln, outp};

/// Prints every choice the command takes.
pub fn list() {
    let mut out = String::new();
    outln!(out, "scenes:");
    for s in SceneKind::ALL {
        let variants = s.variants().iter().map(|v| v.name()).collect::<Vec<_>>();
        let (c, r) = s.default_grid();
        outp!(
            out,
            "  {:<8} {c}×{r}, {} frames: {}",
            s.name(),
            s.default_frames(),
            s.description()
        );
        if !variants.is_empty() {
            outp!(out, " [variants: {}]", variants.join(", "));
        }
        outln!(out);
    }
    outln!(out, "integrators:");
    for i in Integrator::ALL {
        outln!(out, "  {}", i.name());
    }
    outln!(out, "materials:");
    for m in Material::presets() {
        outln!(
            out,
            "  {:<8} stretch {} N/m, shear {} N/m, bend {} N/m, {} kg/m²",
            m.name,
            m.stretch.stiffness,
            m.shear.stiffness,
            m.bend.stiffness,
            m.density
        );
    }
    outln!(out, "pin presets:");
    for p in PinPreset::ALL {
        outln!(out, "  {}", p.name());
    }
    emit(&out);
}
