//! The tables the page shows besides the experiments: the final controller's curriculum (steps, wall
//! time, selection and learning curves of every stage), the model's Table II and the randomization of Table III as used.

use std::path::Path;

use flapper_curriculum::selection::StageOutcome;
use flapper_sim::{FluidCoefficients, LIFTING_SURFACE_GEOMS, RobotModel};
use flapper_task::TaskConfig;
use flapper_task::config::RandomizationConfig;
use serde::{Deserialize, Serialize};

use crate::{ReportError, write_file, write_json};

/// `training/training.json`: the curriculum that trained the final controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainingTable {
    /// The curriculum folder read.
    pub curriculum: String,
    pub seed: u64,
    pub command: String,
    pub stages: Vec<TrainedStage>,
    pub total_env_steps: f64,
    pub total_wall_time_s: f64,
    /// Steps per second of wall time, validation included.
    pub steps_per_s: f64,
}

/// One stage of [`TrainingTable`]: its outcome as the curriculum's `summary.json` records it, and its
/// learning curves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainedStage {
    #[serde(flatten)]
    pub outcome: StageOutcome,
    /// The stage's learning curves copied beside `training.json` (None when the run had none).
    pub learning_curves: Option<String>,
}

/// Writes `training/training.json` and `training/stageK_learning_curves.svg`, from the folder a curriculum run
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
        let learning_curves = match std::fs::read(&curves) {
            Ok(svg) => {
                write_file(&dir.join(&copied), &svg)?;
                Some(copied)
            }
            Err(_) => None,
        };
        stages.push(TrainedStage { outcome: stage.clone(), learning_curves });
    }
    let (steps, time) = (summary.total_env_steps as f64, summary.total_wall_time_s);
    let training = TrainingTable {
        curriculum: curriculum.display().to_string(),
        seed: summary.seed,
        command: summary.command,
        stages,
        total_env_steps: steps,
        total_wall_time_s: time,
        steps_per_s: if time > 0.0 { steps / time } else { 0.0 },
    };
    write_json(&dir.join("training.json"), &training)
}

/// `tables/tables.json`: the robot's size and rates, Table II as the model has it, Table III as used.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelTables {
    pub robot: RobotFigures,
    pub table_ii: Vec<SurfaceCoefficients>,
    pub table_iii: RandomizationUsed,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotFigures {
    pub total_mass_kg: f64,
    pub wingspan_m: f64,
    pub mean_chord_m: f64,
    pub degrees_of_freedom: usize,
    pub actuators: usize,
    pub simulation_hz: f64,
    pub control_hz: f64,
    pub filter_cutoff_hz: f64,
}

/// Table II: one lifting surface's ellipsoid fluid coefficients.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SurfaceCoefficients {
    pub geom: String,
    pub blunt_drag: f64,
    pub slender_drag: f64,
    pub angular_drag: f64,
    pub kutta_lift: f64,
    pub magnus_lift: f64,
}

/// Table III: the randomization the final stage trains with, and where it was read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RandomizationUsed {
    pub source: String,
    pub randomization: RandomizationConfig,
}

/// `tables/tables.json`: Table II (the fluid coefficients of each lifting surface, read from the
/// model) with the robot's size and control rates, and Table III (the randomization the final stage
/// trains with: the policy's own when it trained randomized, else the stage-4 preset).
pub fn model_tables(robot: &RobotModel, task: &TaskConfig, dir: &Path) -> Result<(), ReportError> {
    let sim = robot.instantiate().map_err(|e| ReportError::step("model tables", e))?;
    let mut table_ii = Vec::new();
    for geom in LIFTING_SURFACE_GEOMS {
        let FluidCoefficients { blunt_drag, slender_drag, angular_drag, kutta_lift, magnus_lift } =
            sim.fluid_coefficients(geom).map_err(|e| ReportError::step("model tables", e))?;
        table_ii.push(SurfaceCoefficients {
            geom: geom.to_owned(),
            blunt_drag,
            slender_drag,
            angular_drag,
            kutta_lift,
            magnus_lift,
        });
    }
    let d = robot.dimensions();
    let (randomization, source) = if task.randomization.enabled {
        (task.randomization.clone(), "the final policy's training configuration")
    } else {
        let preset = TaskConfig::stage(4).map_err(|e| ReportError::step("stage-4 preset", e))?;
        (preset.randomization, "the stage-4 preset (the final policy trained without randomization)")
    };
    let tables = ModelTables {
        robot: RobotFigures {
            total_mass_kg: d.total_mass_kg,
            wingspan_m: d.wingspan_m,
            mean_chord_m: d.mean_chord_m,
            degrees_of_freedom: d.degrees_of_freedom,
            actuators: d.actuators,
            simulation_hz: 1.0 / robot.timestep_s(),
            control_hz: 1.0 / task.control_period_s(robot.timestep_s()),
            filter_cutoff_hz: task.control.filter_cutoff_hz,
        },
        table_ii,
        table_iii: RandomizationUsed { source: source.to_owned(), randomization },
    };
    write_json(&dir.join("tables.json"), &tables)
}
