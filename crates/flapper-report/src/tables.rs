//! The tables the page shows besides the experiments: the final controller's curriculum (steps, wall
//! time, selection and learning curves of every stage), the model's Table II and the randomization of Table III as used.

use std::path::Path;

use flapper_sim::{FluidCoefficients, LIFTING_SURFACE_GEOMS, RobotModel};
use flapper_task::TaskConfig;
use serde_json::json;

use crate::{ReportError, write_file, write_json};

/// `training/training.json` and `training/stageK_learning_curves.svg`, from the folder a curriculum run
/// left (`flapper curriculum --out DIR`; shipped as `policies/final/`): per stage its name, iterations,
/// environment steps, wall time (training and validation), the iteration it handed over and that
/// checkpoint's validation score, read from `DIR/summary.json`, and the stage's learning curves.
pub fn training(curriculum: &Path, dir: &Path) -> Result<(), ReportError> {
    let summary = flapper_curriculum::summary::Summary::read(curriculum)
        .map_err(|e| ReportError::step("the final controller's curriculum", e))?;
    let mut stages = Vec::new();
    for stage in &summary.stages {
        let curves = curriculum.join(format!("stage{}", stage.stage)).join("learning_curves.svg");
        let copied = format!("stage{}_learning_curves.svg", stage.stage);
        let drawn = match std::fs::read(&curves) {
            Ok(svg) => {
                write_file(&dir.join(&copied), &svg)?;
                json!(copied)
            }
            Err(_) => json!(null),
        };
        stages.push(json!({
            "stage": stage.stage,
            "name": stage.name,
            "iterations": stage.iterations,
            "env_steps": stage.env_steps,
            "wall_time_s": stage.wall_time_s,
            "selected_iteration": stage.selected_iteration,
            "validation_score": stage.validation_score,
            "learning_curves": drawn,
        }));
    }
    let (steps, time) = (summary.total_env_steps as f64, summary.total_wall_time_s);
    let training = json!({
        "curriculum": curriculum.display().to_string(),
        "seed": summary.seed,
        "command": summary.command,
        "stages": stages,
        "total_env_steps": steps,
        "total_wall_time_s": time,
        "steps_per_s": if time > 0.0 { steps / time } else { 0.0 },
    });
    write_json(&dir.join("training.json"), &training)
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
    write_json(&dir.join("tables.json"), &tables)
}
