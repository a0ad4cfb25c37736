//! The robot model a command flies: `--model FILE`, or the shipped one. Loaded only by the commands
//! that fly or simulate it.

use std::path::Path;

use anyhow::Result;
use flapper_sim::RobotModel;

pub fn load(model: Option<&Path>) -> Result<RobotModel> {
    Ok(match model {
        Some(path) => RobotModel::load(path)?,
        None => RobotModel::flapper()?,
    })
}
