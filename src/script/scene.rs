//! Rhai module `scene`: build the report's scene (or a variant) and run it. Types: `Scene`
//! (a built scene) and `Run` (one run's traces, report, ledger, crack traces, snapshots).

use crate::scene::{Scene, SceneSpec};
use crate::script::convert::{error, overlay, ScriptResult, WithPosition};
use crate::solve::RunOutput;
use rhai::plugin::*;
use rhai::{Engine, Map, Module, NativeCallContext};
use std::sync::Arc;

/// A built scene, shared by the runs and responders that use it.
pub type SceneRef = Arc<Scene>;
/// One run's output.
pub type RunRef = Arc<RunOutput>;

/// Registers the display names of the custom types.
pub fn register_types(engine: &mut Engine) {
    engine
        .register_type_with_name::<SceneRef>("Scene")
        .register_type_with_name::<RunRef>("Run");
}

/// The `scene` module.
pub fn module() -> Module {
    exported_module!(scene_api)
}

/// Builds a scene from an override map over `base`.
pub(crate) fn build(
    ctx: &NativeCallContext,
    overrides: Map,
    base: SceneSpec,
) -> ScriptResult<SceneRef> {
    refuse_unused_segment(ctx, &overrides)?;
    refuse_ignored_by_gmsh(ctx, &overrides)?;
    let mut spec: SceneSpec = overlay(ctx, overrides, &base, "scene")?;
    if let Some(g) = spec.gmsh.as_mut() {
        let bytes = crate::script::HostContext::of(ctx)?
            .read_input(&g.path)
            .map_err(|e| error(ctx, format!("scene.gmsh.path: {e}")))?;
        g.bytes = Some(Arc::new(bytes));
    }
    Ok(Arc::new(Scene::build(&spec).at(ctx)?))
}

/// `sources` replace the transmitter's segment: a segment or angle written next to them
/// would be ignored silently, so it is an error naming it.
fn refuse_unused_segment(ctx: &NativeCallContext, overrides: &Map) -> ScriptResult<()> {
    let Some(transmitter) = overrides
        .get("transmitter")
        .and_then(|t| t.read_lock::<Map>())
    else {
        return Ok(());
    };
    if !overrides.contains_key("sources") {
        return Ok(());
    }
    for field in ["depth_top_m", "depth_bottom_m", "angle_deg"] {
        if let Some(value) = transmitter.get(field) {
            return Err(error(
                ctx,
                format!(
                    "transmitter.{field} = {value} is not used when `sources` are given (they \
                     replace the transmitter's segment; only transmitter.peak_pa applies)"
                ),
            ));
        }
    }
    Ok(())
}

/// A Gmsh scene's mesh, materials and region are the file's: the layered rectangle's fields
/// written next to `gmsh` would be ignored silently, so each is an error naming it.
fn refuse_ignored_by_gmsh(ctx: &NativeCallContext, overrides: &Map) -> ScriptResult<()> {
    if overrides.get("gmsh").is_none_or(|g| g.is_unit()) {
        return Ok(());
    }
    for field in [
        "laminate",
        "width_m",
        "element_size_x_m",
        "element_size_y_m",
    ] {
        if let Some(value) = overrides.get(field) {
            return Err(error(
                ctx,
                format!(
                    "scene.{field} = {value} is not used with `gmsh` (the mesh, its materials \
                     and its size are the file's): leave it out"
                ),
            ));
        }
    }
    Ok(())
}

/// Contact options of a run act on the crack's faces: on a scene without open faces (no
/// crack, or faces tied) they cannot apply, so they are an error naming them.
fn refuse_contact_without_crack(
    ctx: &NativeCallContext,
    scene: &Scene,
    run_options: &Map,
) -> ScriptResult<()> {
    match run_options.get("contact") {
        Some(c) if !c.is_unit() && scene.crack().is_none() => Err(error(
            ctx,
            format!(
                "run.contact = {c} cannot apply: the scene has no crack faces to make contact \
                 (no crack, or tied faces)"
            ),
        )),
        _ => Ok(()),
    }
}

/// A 1-based index into `len` items, named `what` in errors.
pub fn index(ctx: &NativeCallContext, k: rhai::INT, len: usize, what: &str) -> ScriptResult<usize> {
    usize::try_from(k)
        .ok()
        .filter(|&k| k >= 1 && k <= len)
        .map(|k| k - 1)
        .ok_or_else(|| error(ctx, format!("{what} {k} does not exist (1..={len})")))
}

/// `scene` refined for a requested relative error `tolerance` of the first-pass responses to
/// the chirp of `tr` ([`crate::study::resolution_for_tolerance`]), saying what was chosen.
pub(crate) fn refined_for(
    ctx: &NativeCallContext,
    scene: &SceneRef,
    tolerance: f64,
    tr: &crate::trnews::TrNewsSpec,
) -> ScriptResult<SceneRef> {
    let (spec, c) = crate::study::resolution_for_tolerance(&scene.spec, tolerance, tr).at(ctx)?;
    crate::script::HostContext::of(ctx)?.print(&format!(
        "tolerance {tolerance}: element sizes {:.3e} x {:.3e} m ({}x the scene's), \
         predicted error {:.2e} (pilot differences {:.2e} and {:.2e}, order {:.2}), \
         predicted run time {:.3e} s per transmission",
        c.element_size_x_m,
        c.element_size_y_m,
        c.size_factor,
        c.predicted_error,
        c.pilot_differences[0],
        c.pilot_differences[1],
        c.order,
        c.predicted_run_time_s,
    ));
    Ok(Arc::new(Scene::build(&spec).at(ctx)?))
}

#[export_module]
mod scene_api {
    use super::{index, RunRef, SceneRef};
    use crate::scene::SceneSpec;
    use crate::script::convert::{overlay, to_dynamic, WithPosition};
    use crate::signal::Signal;
    use crate::solve::RunConfig;
    use rhai::{Array, Dynamic, Map, NativeCallContext, FLOAT, INT};
    use std::sync::Arc;

    type Res<T> = Result<T, Box<rhai::EvalAltResult>>;

    /// The default scene (the report's configuration on its linear triangles, 60 x 40 um) as a map of every field.
    #[rhai_fn(return_raw)]
    pub fn default_spec(ctx: NativeCallContext) -> Res<Dynamic> {
        to_dynamic(&ctx, &SceneSpec::default())
    }

    /// Builds the default scene (the report's configuration on its linear triangles, 60 x 40 um; `preset("quick", overrides)` is the same scene on the experiments' spectral elements) with the fields of `overrides` replaced (unknown fields are errors); `crack: ()` removes the crack.
    #[rhai_fn(return_raw)]
    pub fn build(ctx: NativeCallContext, overrides: Map) -> Res<SceneRef> {
        super::build(&ctx, overrides, SceneSpec::default())
    }

    /// Builds a preset scene, "quick" (the default), "paper" or "smoke" (a small fast scene for tests), with `overrides`, on its default discretisation: spectral elements (quick and smoke: order 7 along x on 0.5 mm elements, orders 2-4 across; paper: order 6 on 0.25 mm, orders 3-6 across; docs/src/validation/spectral-elements.md). `preset(name, "t3", overrides)` gives the report's triangles.
    #[rhai_fn(return_raw)]
    pub fn preset(ctx: NativeCallContext, name: &str, overrides: Map) -> Res<SceneRef> {
        let base = SceneSpec::preset(name.parse().at(&ctx)?);
        super::build(&ctx, overrides, base)
    }

    /// Builds a preset scene (as `preset(name, overrides)`) on the discretisation `kind`: "sem" (the default: spectral elements of the sizes and orders that go with the resolution; docs/src/validation/spectral-elements.md) or "t3" (the report's linear triangles: 60 x 40 um for quick, 20 x 10 um for paper, 80 x 40 um for smoke).
    #[rhai_fn(name = "preset", return_raw)]
    pub fn preset_on(
        ctx: NativeCallContext,
        name: &str,
        kind: &str,
        overrides: Map,
    ) -> Res<SceneRef> {
        let base = SceneSpec::preset_on(name.parse().at(&ctx)?, kind.parse().at(&ctx)?);
        super::build(&ctx, overrides, base)
    }

    /// The uncracked companion: the same scene with the crack's faces tied, on the same mesh and with the same time step (the cracked scene's dt_crit).
    #[rhai_fn(global, pure, return_raw)]
    pub fn uncracked(ctx: NativeCallContext, scene: &mut SceneRef) -> Res<SceneRef> {
        Ok(Arc::new(
            crate::scene::Scene::build(&scene.spec.uncracked()).at(&ctx)?,
        ))
    }

    /// The companions of an error estimate (same laminate draw): on linear triangles the scene at 2x and 4x the element sizes; on spectral elements the same elements at orders order_x - 1 and order_x - 2 along x (every row's order across and the time step as the scene has them), then the same elements one order higher across every row (at its own step); on a Gmsh mesh of quadrilaterals (gmsh.order p) the same mesh at orders p - 1 and p - 2 at the scene's step. Estimate a quantity from its values on the scene and on them, in this order, with `accuracy::scalar([value, ...], scene)`.
    #[rhai_fn(global, pure, return_raw)]
    pub fn companions(ctx: NativeCallContext, scene: &mut SceneRef) -> Res<Array> {
        scene
            .spec
            .companions(scene.default_dt_s())
            .at(&ctx)?
            .iter()
            .map(|spec| {
                let built = crate::scene::Scene::build(spec).at(&ctx)?;
                Ok(Dynamic::from(Arc::new(built)))
            })
            .collect()
    }

    /// Degrees of freedom of the scene's model.
    #[rhai_fn(global, get = "dofs", pure)]
    pub fn dofs(scene: &mut SceneRef) -> INT {
        scene.dofs() as INT
    }

    /// Default time step of its runs, 0.9 dt_crit (s).
    #[rhai_fn(global, get = "dt", pure)]
    pub fn dt(scene: &mut SceneRef) -> FLOAT {
        scene.default_dt_s()
    }

    /// Critical explicit step estimated by Lanczos on M^-1 K (s).
    #[rhai_fn(global, get = "dt_crit", pure)]
    pub fn dt_crit(scene: &mut SceneRef) -> FLOAT {
        scene.stability.dt_crit_s
    }

    /// True without a contacting crack: responses are then convolutions of one impulse response.
    #[rhai_fn(global, get = "linear", pure)]
    pub fn linear(scene: &mut SceneRef) -> bool {
        scene.is_linear()
    }

    /// Summary map: spec, DOFs, nodes, elements (triangles or spectral elements), layers, size, dt_crit and its element bound, clamped epoxy fraction, crack pairs, and crack: #{depth_requested_m, depth_used_m, x0_requested_m, x0_used_m, x1_requested_m, x1_used_m, tied} (where the crack snapped to the mesh lines; () without a crack).
    #[rhai_fn(global, pure, return_raw)]
    pub fn summary(ctx: NativeCallContext, scene: &mut SceneRef) -> Res<Dynamic> {
        let (x0, x1, y0, y1) = scene.mesh().bounds();
        let mut m = Map::new();
        m.insert("spec".into(), to_dynamic(&ctx, &scene.spec)?);
        m.insert("dofs".into(), (scene.dofs() as INT).into());
        m.insert("nodes".into(), (scene.mesh().nodes.len() as INT).into());
        m.insert("elements".into(), (scene.elements() as INT).into());
        m.insert("layers".into(), (scene.laminate.layers.len() as INT).into());
        m.insert("width_m".into(), (x1 - x0).into());
        m.insert("height_m".into(), (y1 - y0).into());
        m.insert("stability".into(), to_dynamic(&ctx, &scene.stability)?);
        m.insert(
            "band".into(),
            crate::transducer::band_label(scene.spec.transducer.as_ref()).into(),
        );
        m.insert(
            "clamped_epoxy_fraction".into(),
            scene.laminate.clamped_fraction().into(),
        );
        m.insert(
            "crack_pairs".into(),
            (scene.crack().map_or(0, |c| c.pairs.len()) as INT).into(),
        );
        m.insert("crack".into(), to_dynamic(&ctx, &scene.crack_placement)?);
        Ok(m.into())
    }

    /// Transmits `traction` (Pa) from the transmitter with run options #{duration_s, dt_s, step_fraction, integrator, force, ledger_every, snapshot_every, snapshot_dir (under the output directory), record_crack, contact (laid over the scene's; () opens the crack), progress}; returns the Run.
    #[rhai_fn(global, pure, return_raw)]
    pub fn transmit(
        ctx: NativeCallContext,
        scene: &mut SceneRef,
        traction: Signal,
        run_options: Map,
    ) -> Res<RunRef> {
        super::refuse_contact_without_crack(&ctx, scene, &run_options)?;
        let base = scene.run_config(RunConfig::default().duration_s);
        let mut o: RunConfig = overlay(&ctx, run_options, &base, "run")?;
        o.check_snapshots().at(&ctx)?;
        if let Some(dir) = &o.snapshot_dir {
            // resolve a file inside the directory: checks the sandbox and creates it
            let host = crate::script::HostContext::of(&ctx)?;
            let resolved = host
                .resolve_output(&dir.join("x").to_string_lossy())
                .map_err(|e| super::error(&ctx, e))?;
            o.snapshot_dir = resolved.parent().map(|p| p.to_path_buf());
        }
        Ok(Arc::new(scene.transmit(&traction, &o).at(&ctx)?))
    }

    /// Traces of every receiver, in order (array of Signal).
    #[rhai_fn(global, get = "traces", pure)]
    pub fn traces(run: &mut RunRef) -> Array {
        run.traces.iter().cloned().map(Dynamic::from).collect()
    }

    /// Trace of receiver `k` (1-based).
    #[rhai_fn(global, pure, return_raw)]
    pub fn trace(ctx: NativeCallContext, run: &mut RunRef, k: INT) -> Res<Signal> {
        Ok(run.traces[index(&ctx, k, run.traces.len(), "receiver")?].clone())
    }

    /// The run report (scalars): wall time, steps, DOFs, dt, dt_crit, dt/dt_crit, energy residuals, source work, contact diagnostics (iterations, penetration, steps in contact or slipping, max and mean pairs in contact and slipping) or ().
    #[rhai_fn(global, get = "report", pure, return_raw)]
    pub fn report(ctx: NativeCallContext, run: &mut RunRef) -> Res<Dynamic> {
        to_dynamic(&ctx, &run.report)
    }

    /// Pairs in contact, sticking and slipping at every step as #{in_contact, sticking, slipping} of Signal (sample n: after step n, t = (n + 1) dt), or () when the run had no contact.
    #[rhai_fn(global, get = "contact_series", pure)]
    pub fn contact_series(run: &mut RunRef) -> Dynamic {
        let Some(c) = &run.contact_series else {
            return Dynamic::UNIT;
        };
        let mut m = Map::new();
        for (name, s) in [
            ("in_contact", &c.in_contact),
            ("sticking", &c.sticking),
            ("slipping", &c.slipping),
        ] {
            m.insert(name.into(), Dynamic::from(s.clone()));
        }
        m.into()
    }

    /// The energy ledger: #{time_s, kinetic_j, strain_j, source_work_j, dashpot_loss_j, contact_loss_j, friction_loss_j, residual, initial_j}.
    #[rhai_fn(global, get = "ledger", pure, return_raw)]
    pub fn ledger(ctx: NativeCallContext, run: &mut RunRef) -> Res<Dynamic> {
        to_dynamic(&ctx, &run.ledger)
    }

    /// Number of crack pairs recorded (0 unless the run had record_crack and a crack).
    #[rhai_fn(global, get = "crack_pairs", pure)]
    pub fn crack_pairs(run: &mut RunRef) -> INT {
        run.crack.as_ref().map_or(0, |c| c.x_m.len() as INT)
    }

    /// Normal gap g_N of crack pair `k` (1-based, ordered by x): > 0 is penetration (m).
    #[rhai_fn(global, pure, return_raw)]
    pub fn crack_gap(ctx: NativeCallContext, run: &mut RunRef, k: INT) -> Res<Signal> {
        let c = run.crack.as_ref().ok_or_else(|| {
            super::error(
                &ctx,
                "the run recorded no crack (set record_crack: true on a cracked scene)",
            )
        })?;
        Ok(c.normal_gap[index(&ctx, k, c.normal_gap.len(), "crack pair")?].clone())
    }

    /// Vertical displacement of the upper crack face at pair `k` (1-based) (m).
    #[rhai_fn(global, pure, return_raw)]
    pub fn crack_upper(ctx: NativeCallContext, run: &mut RunRef, k: INT) -> Res<Signal> {
        let c = run.crack.as_ref().ok_or_else(|| {
            super::error(
                &ctx,
                "the run recorded no crack (set record_crack: true on a cracked scene)",
            )
        })?;
        Ok(c.master_uy[index(&ctx, k, c.master_uy.len(), "crack pair")?].clone())
    }

    /// Number of snapshots kept.
    #[rhai_fn(global, get = "snapshots", pure)]
    pub fn snapshots(run: &mut RunRef) -> INT {
        run.snapshots.len() as INT
    }

    /// Time of snapshot `k` (1-based) (s).
    #[rhai_fn(global, pure, return_raw)]
    pub fn snapshot_time(ctx: NativeCallContext, run: &mut RunRef, k: INT) -> Res<FLOAT> {
        Ok(run.snapshots[index(&ctx, k, run.snapshots.len(), "snapshot")?].time_s)
    }

    /// Writes snapshot `k` (1-based) of a run of `scene` as a binary VTU file for ParaView: the displacement vector on the points, the material and layer index of every triangle.
    #[rhai_fn(global, return_raw)]
    pub fn write_vtu(
        ctx: NativeCallContext,
        path: &str,
        scene: SceneRef,
        run: RunRef,
        k: INT,
    ) -> Res<()> {
        let snap = &run.snapshots[index(&ctx, k, run.snapshots.len(), "snapshot")?];
        let file = crate::script::HostContext::of(&ctx)?
            .resolve_output(path)
            .at(&ctx)?;
        snapshot_vtu(&file, &scene, snap).at(&ctx)
    }

    /// Writes every snapshot of a run of `scene` as a binary VTU file beside the ParaView collection `path` (`.pvd`), named after it with the snapshot number (`field.pvd` -> `field_001.vtu`, ...), and the collection listing them with their times: ParaView opens it as an animation.
    #[rhai_fn(global, return_raw)]
    pub fn write_pvd(ctx: NativeCallContext, path: &str, scene: SceneRef, run: RunRef) -> Res<()> {
        let collection = crate::script::HostContext::of(&ctx)?
            .resolve_output(path)
            .at(&ctx)?;
        let files = series_files(&collection, run.snapshots.len());
        for (file, snap) in files.iter().zip(&run.snapshots) {
            snapshot_vtu(file, &scene, snap).at(&ctx)?;
        }
        let frames: Vec<(f64, &std::path::Path)> = run
            .snapshots
            .iter()
            .zip(&files)
            .map(|(snap, file)| (snap.time_s, file.as_path()))
            .collect();
        crate::io::write_pvd(&collection, &frames).at(&ctx)
    }
}

/// Writes one snapshot of a run of `scene` as a VTU file (displacement on the points).
fn snapshot_vtu(
    file: &std::path::Path,
    scene: &Scene,
    snap: &crate::solve::Snapshot,
) -> Result<(), crate::io::OutputError> {
    let displacement = crate::io::vtu::Field {
        name: "displacement",
        components: 2,
        values: &snap.displacement,
    };
    crate::io::write_vtu(file, scene.mesh(), &[displacement], &[])
}

/// The VTU files of a series of `count` snapshots beside the collection `pvd`:
/// `<stem>_<k>.vtu`, k from 1, zero-padded to at least three digits.
fn series_files(pvd: &std::path::Path, count: usize) -> Vec<std::path::PathBuf> {
    let stem = pvd.file_stem().unwrap_or_default().to_string_lossy();
    let width = count.to_string().len().max(3);
    (1..=count)
        .map(|k| pvd.with_file_name(format!("{stem}_{k:0width$}.vtu")))
        .collect()
}
