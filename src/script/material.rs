//! Rhai module `material`: material presets and custom orthotropic materials, reduced to
//! 2D, returned as maps of constants, plane stiffness and wave speeds.

use crate::material::{Orthotropic, Plane};
use crate::script::convert::{named, to_dynamic, ScriptResult, WithPosition};
use rhai::plugin::*;
use rhai::{Dynamic, Module, NativeCallContext};

/// The `material` module.
pub fn module() -> Module {
    exported_module!(material_api)
}

/// The summary map of `m` reduced to `plane`: its constants, `plane`, `stiffness_pa`
/// (3x3, Voigt xx, yy, xy), wave speeds along the axes and the P impedance along y.
fn summary(ctx: &NativeCallContext, m: &Orthotropic, plane: &str) -> ScriptResult<Dynamic> {
    let plane_kind: Plane = named(ctx, plane, "plane")?;
    let reduced = m.reduce(plane_kind).at(ctx)?;
    let mut map = to_dynamic(ctx, m)?.cast::<rhai::Map>();
    let speeds = to_dynamic(ctx, &reduced.wave_speeds())?.cast::<rhai::Map>();
    map.extend(speeds);
    map.insert("plane".into(), plane.into());
    map.insert(
        "stiffness_pa".into(),
        to_dynamic(ctx, &reduced.stiffness_pa)?,
    );
    map.insert("max_wave_speed_m_s".into(), reduced.max_wave_speed().into());
    map.insert("impedance_p_y".into(), reduced.impedance_p_y().into());
    Ok(map.into())
}

#[export_module]
mod material_api {
    use super::summary;
    use crate::material::Orthotropic;
    use crate::script::convert::{options, WithPosition};
    use rhai::{Dynamic, Map, NativeCallContext, FLOAT};

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// A preset ("epoxy", "fabric_0_90", "fabric_45_45") in plane strain: constants, stiffness_pa, p_x_m_s, p_y_m_s, s_m_s, impedance_p_y.
    #[rhai_fn(return_raw)]
    pub fn preset(ctx: NativeCallContext, name: &str) -> Res<Dynamic> {
        preset_in(ctx, name, "strain")
    }

    /// A preset reduced to plane "strain" or "stress".
    #[rhai_fn(name = "preset", return_raw)]
    pub fn preset_in(ctx: NativeCallContext, name: &str, plane: &str) -> Res<Dynamic> {
        summary(&ctx, &Orthotropic::preset(name).at(&ctx)?, plane)
    }

    /// A custom orthotropic material from #{name, e1_pa, e2_pa, e3_pa, g12_pa, nu12, nu13, nu23, density_kg_m3} reduced to plane "strain" or "stress"; rejected unless its stiffness is positive definite.
    #[rhai_fn(return_raw)]
    pub fn orthotropic(ctx: NativeCallContext, constants: Map, plane: &str) -> Res<Dynamic> {
        let m: Orthotropic = options(&ctx, constants, &Orthotropic::epoxy(), "material")?;
        summary(&ctx, &m, plane)
    }

    /// The losses of the report's materials from the literature (the scene field `attenuation` that `--set losses=true` gives the experiments): #{band_hz, mechanisms, reference_hz, quality: #{epoxy: #{q_p, q_s}, fabric_0_90, fabric_45_45}}.
    #[rhai_fn(return_raw)]
    pub fn losses(ctx: NativeCallContext) -> Res<Dynamic> {
        crate::script::convert::to_dynamic(
            &ctx,
            &crate::attenuation::AttenuationSpec::report_materials(),
        )
    }

    /// Plane waves along the axes of preset `name` (plane strain) with the losses `attenuation` (a scene's `attenuation` map) at `frequency_hz`: #{material, frequency_hz, p_x, p_y, s}, each wave #{quality, attenuation_db_per_mm, phase_velocity_m_s}. A material `attenuation` does not list stays elastic (infinite Q, no loss).
    #[rhai_fn(return_raw)]
    pub fn dispersion(
        ctx: NativeCallContext,
        name: &str,
        attenuation: Map,
        frequency_hz: rhai::Array,
    ) -> Res<Dynamic> {
        use crate::attenuation::{attenuate, AttenuationSpec, Dispersion};
        use crate::material::Plane;
        let spec: AttenuationSpec = options(
            &ctx,
            attenuation,
            &AttenuationSpec::report_materials(),
            "attenuation",
        )?;
        let mut materials = ["epoxy", "fabric_0_90", "fabric_45_45"]
            .iter()
            .map(|n| Orthotropic::preset(n).and_then(|m| m.reduce(Plane::Strain)))
            .collect::<crate::Result<Vec<_>>>()
            .at(&ctx)?;
        if !materials.iter().any(|m| m.name == name) {
            Orthotropic::preset(name).at(&ctx)?;
        }
        attenuate(&mut materials, &spec).at(&ctx)?;
        let material = materials.iter().find(|m| m.name == name).expect("a preset");
        let frequencies =
            crate::script::convert::floats(&ctx, &frequency_hz.into(), "frequency_hz")?;
        let d = Dispersion::of(material, &frequencies).at(&ctx)?;
        crate::script::convert::to_dynamic(&ctx, &d)
    }

    /// An isotropic material (E in Pa, Poisson ratio nu, density in kg/m^3) in plane strain.
    #[rhai_fn(return_raw)]
    pub fn isotropic(
        ctx: NativeCallContext,
        name: &str,
        e_pa: FLOAT,
        nu: FLOAT,
        density_kg_m3: FLOAT,
    ) -> Res<Dynamic> {
        summary(
            &ctx,
            &Orthotropic::isotropic(name, e_pa, nu, density_kg_m3),
            "strain",
        )
    }
}
