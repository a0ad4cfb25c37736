//! The tables the page shows besides the experiments: training of every stage (steps, wall time,
//! learning curves), the model's Table II and the randomization of Table III as used.

use std::path::{Path, PathBuf};

use flapper_sim::{FluidCoefficients, LIFTING_SURFACE_GEOMS, RobotModel};
use flapper_task::TaskConfig;
use serde_json::json;

use crate::{ReportError, write_file};

/// `training/training.json` (per stage: iterations, environment steps, wall time, from each policy's
/// sidecar) and `training/stageK_learning_curves.svg` copied from each policy's folder.
pub fn training(stage_policies: &[PathBuf], dir: &Path) -> Result<(), ReportError> {
    let mut stages = Vec::new();
    for (k, policy) in stage_policies.iter().enumerate() {
        let sidecar = policy.with_file_name(format!(
            "{}.json",
            policy.file_name().map_or("".into(), |n| n.to_string_lossy().into_owned())
        ));
        if !sidecar.exists() {
            continue;
        }
        // A stage trained in several runs keeps the earlier runs' sidecars beside the policy
        // (`earlier_run*.safetensors.json`): their iterations, steps and time count too.
        let folder = policy.parent().unwrap_or(Path::new("."));
        let mut sidecars: Vec<PathBuf> =
            std::fs::read_dir(folder).map(|d| d.flatten().map(|e| e.path()).collect()).unwrap_or_default();
        sidecars.retain(|p| {
            p.file_name().is_some_and(|n| {
                n.to_string_lossy().starts_with("earlier_run") && n.to_string_lossy().ends_with(".json")
            })
        });
        sidecars.sort();
        sidecars.insert(0, sidecar);
        let runs = sidecars.len();
        let (mut iterations, mut env_steps, mut wall_time_s) = (0.0, 0.0, 0.0);
        for path in &sidecars {
            let read = |e: &dyn std::fmt::Display| ReportError::step(format!("reading '{}'", path.display()), e);
            let text = std::fs::read_to_string(path).map_err(|e| read(&e))?;
            let run: serde_json::Value = serde_json::from_str(&text).map_err(|e| read(&e))?;
            iterations += run["iteration"].as_f64().unwrap_or(0.0);
            env_steps += run["env_steps"].as_f64().unwrap_or(0.0);
            wall_time_s += run["wall_time_s"].as_f64().unwrap_or(0.0);
        }
        let curves = policy.with_file_name("learning_curves.svg");
        let copied = format!("stage{}_learning_curves.svg", k + 1);
        if let Ok(svg) = std::fs::read(&curves) {
            write_file(&dir.join(&copied), &svg)?;
        }
        stages.push(json!({
            "stage": k + 1,
            "policy": policy.display().to_string(),
            "runs": runs,
            "iterations": iterations,
            "env_steps": env_steps,
            "wall_time_s": wall_time_s,
            "learning_curves": if curves.exists() { json!(copied) } else { json!(null) },
        }));
    }
    let total_steps: f64 = stages.iter().filter_map(|s| s["env_steps"].as_f64()).sum();
    let total_time: f64 = stages.iter().filter_map(|s| s["wall_time_s"].as_f64()).sum();
    let summary = json!({ "stages": stages, "total_env_steps": total_steps, "total_wall_time_s": total_time,
        "steps_per_s": if total_time > 0.0 { total_steps / total_time } else { 0.0 } });
    write_file(&dir.join("training.json"), serde_json::to_string_pretty(&summary).expect("plain data").as_bytes())
}

/// `tables/tables.json`: Table II (the fluid coefficients of each lifting surface, read from the
/// model) with the robot's size and control rates, and Table III (the randomization the final stage
/// trains with: the policy's own when it trained randomized, else the stage-4 preset).
pub fn model_tables(robot: &RobotModel, task: &TaskConfig, dir: &Path) -> Result<(), ReportError> {
    let sim = robot.instantiate().map_err(|e| ReportError::step("model tables", e))?;
    let mut surfaces = Vec::new();
    for geom in LIFTING_SURFACE_GEOMS {
        let FluidCoefficients { blunt_drag, slender_drag, angular_drag, kutta_lift, magnus_lift } =
            sim.fluid_coefficients(geom).map_err(|e| ReportError::step("model tables", e))?;
        surfaces.push(
            json!({ "geom": geom, "blunt_drag": blunt_drag, "slender_drag": slender_drag, "angular_drag": angular_drag,
            "kutta_lift": kutta_lift, "magnus_lift": magnus_lift }),
        );
    }
    let d = robot.dimensions();
    let randomization = if task.randomization.enabled {
        (task.randomization.clone(), "the final policy's training configuration")
    } else {
        let preset = TaskConfig::stage(4).map_err(|e| ReportError::step("stage-4 preset", e))?;
        (preset.randomization, "the stage-4 preset (the final policy trained without randomization)")
    };
    let tables = json!({
        "robot": { "total_mass_kg": d.total_mass_kg, "wingspan_m": d.wingspan_m, "mean_chord_m": d.mean_chord_m,
            "degrees_of_freedom": d.degrees_of_freedom, "actuators": d.actuators,
            "simulation_hz": 1.0 / robot.timestep_s(), "control_hz": 1.0 / task.control_period_s(robot.timestep_s()),
            "filter_cutoff_hz": task.control.filter_cutoff_hz },
        "table_ii": surfaces,
        "table_iii": { "source": randomization.1, "randomization": randomization.0 },
    });
    write_file(&dir.join("tables.json"), serde_json::to_string_pretty(&tables).expect("plain data").as_bytes())
}
