//! The task layer, between the simulator and whatever decides the joint targets (a learned policy or
//! the scripted baseline). So far it holds the paper's control loop (section III-A): a decision at
//! 50 Hz, smoothed by a 7 Hz first-order low-pass filter running at the 250 Hz simulation rate,
//! tracked by the joints' PD servos.

mod action_filter;
mod control_loop;

pub use action_filter::LowPassFilter;
pub use control_loop::{ControlLoop, ControlLoopConfig, JointWork};
