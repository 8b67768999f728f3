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
    let default = cloth3d::solver::SolverSettings::default().integrator;
    for i in Integrator::ALL {
        let notes = [
            (i == default).then_some("default"),
            (!i.carries_dynamic_bodies()).then_some("refuses dynamic bodies"),
        ];
        let notes: Vec<&str> = notes.into_iter().flatten().collect();
        if notes.is_empty() {
            outln!(out, "  {}", i.name());
        } else {
            outln!(out, "  {:<18} ({})", i.name(), notes.join("; "));
        }
    }
    outln!(out, "materials:");
    for m in Material::presets() {
        let limit = m
            .stretch_limit
            .map_or(String::new(), |e| format!(", stretch limit {}%", 100.0 * e));
        outln!(
            out,
            "  {:<8} stretch {} N/m, shear {} N/m, bend {} N/m, {} kg/m²{limit}",
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
