//! A recorded flight: one row per 50 Hz control step, its summary figures, and its CSV form.

use std::path::Path;

use flapper_sim::{ActuatedJoint, N_ACTUATED_JOINTS, SimFault, Vec3, quat_to_wxyz};
use flapper_task::ControlLoop;

use flapper_files::decimals::{each_fixed, fixed};
use flapper_files::write_csv_rows;

use crate::OutputError;
use crate::controller::FlightState;

/// One control step: the state the controller saw, what it commanded, and the result.
#[derive(Debug, Clone, Copy)]
pub struct FlightRow {
    pub state: FlightState,
    /// What the controller asked for (before the 7 Hz filter).
    pub commanded_rad: [f64; N_ACTUATED_JOINTS],
    /// The PD targets at the end of the step (after the filter).
    pub applied_rad: [f64; N_ACTUATED_JOINTS],
    pub torques_nm: [f64; N_ACTUATED_JOINTS],
    /// Net mechanical power into the joints over the step (W, integrated at 250 Hz).
    pub mechanical_power_w: f64,
    /// The same with each instant's power counted positive.
    pub absolute_power_w: f64,
}

impl FlightRow {
    /// The row for a control step that started from `state` and has just been applied.
    pub fn after_step(state: &FlightState, control: &ControlLoop) -> Self {
        let (sim, work, period) = (control.sim(), control.last_step_work(), control.control_period_s());
        Self {
            state: *state,
            commanded_rad: control.commanded_targets(),
            applied_rad: sim.joint_targets(),
            torques_nm: sim.actuator_torques(),
            mechanical_power_w: work.net_j / period,
            absolute_power_w: work.absolute_j / period,
        }
    }
}

/// The figures people ask about a flight.
#[derive(Debug, Clone, Copy)]
pub struct FlightSummary {
    pub duration_s: f64,
    pub completed: bool,
    /// Final minus initial altitude.
    pub altitude_change_m: f64,
    /// Largest distance from the starting altitude at any step.
    pub max_altitude_deviation_m: f64,
    pub horizontal_distance_m: f64,
    pub mean_speed_mps: f64,
    pub mean_airspeed_mps: f64,
    /// Net mechanical power into the joints (sum of torque times joint speed, averaged).
    pub mean_mechanical_power_w: f64,
    /// The same with every instant counted positive (the motors do work both ways).
    pub mean_absolute_power_w: f64,
}

#[derive(Debug, Clone, Default)]
pub struct FlightLog {
    rows: Vec<FlightRow>,
    fault: Option<SimFault>,
}

impl FlightLog {
    pub fn with_capacity(steps: usize) -> Self {
        Self { rows: Vec::with_capacity(steps), fault: None }
    }

    pub fn push(&mut self, row: FlightRow) {
        self.rows.push(row);
    }

    pub fn set_fault(&mut self, fault: SimFault) {
        self.fault = Some(fault);
    }

    pub fn rows(&self) -> &[FlightRow] {
        &self.rows
    }

    /// Why the flight stopped early, if it did.
    pub fn fault(&self) -> Option<&SimFault> {
        self.fault.as_ref()
    }

    pub fn summary(&self) -> FlightSummary {
        let n = self.rows.len().max(1) as f64;
        let first = self.rows.first().map(|r| r.state);
        let last = self.rows.last().map(|r| r.state);
        let (start, end) = match (first, last) {
            (Some(a), Some(b)) => (a, b),
            _ => {
                return FlightSummary {
                    duration_s: 0.0,
                    completed: self.fault.is_none(),
                    altitude_change_m: 0.0,
                    max_altitude_deviation_m: 0.0,
                    horizontal_distance_m: 0.0,
                    mean_speed_mps: 0.0,
                    mean_airspeed_mps: 0.0,
                    mean_mechanical_power_w: 0.0,
                    mean_absolute_power_w: 0.0,
                };
            }
        };
        let z0 = start.position_m.z;
        let mean = |f: &dyn Fn(&FlightRow) -> f64| self.rows.iter().map(f).sum::<f64>() / n;
        let (_, horizontal_distance_m) = self.glide_between(start.time_s, end.time_s);
        FlightSummary {
            duration_s: end.time_s - start.time_s,
            completed: self.fault.is_none(),
            altitude_change_m: end.position_m.z - z0,
            max_altitude_deviation_m: self.rows.iter().map(|r| (r.state.position_m.z - z0).abs()).fold(0.0, f64::max),
            horizontal_distance_m,
            mean_speed_mps: mean(&|r| r.state.velocity_mps.length()),
            mean_airspeed_mps: mean(&|r| r.state.airspeed_mps),
            mean_mechanical_power_w: mean(&|r| r.mechanical_power_w),
            mean_absolute_power_w: mean(&|r| r.absolute_power_w),
        }
    }

    /// Altitude lost and horizontal distance covered between two times (m).
    pub fn glide_between(&self, t0_s: f64, t1_s: f64) -> (f64, f64) {
        let at =
            |t: f64| self.rows.iter().min_by(|a, b| (a.state.time_s - t).abs().total_cmp(&(b.state.time_s - t).abs()));
        match (at(t0_s), at(t1_s)) {
            (Some(a), Some(b)) => {
                let delta: Vec3 = b.state.position_m - a.state.position_m;
                (-delta.z, delta.truncate().length())
            }
            _ => (0.0, 0.0),
        }
    }

    /// Glide ratio (horizontal distance over altitude lost) between two times.
    pub fn glide_ratio_between(&self, t0_s: f64, t1_s: f64) -> f64 {
        let (lost, distance) = self.glide_between(t0_s, t1_s);
        distance / lost
    }

    /// Mean speed (m/s) between two times.
    pub fn mean_speed_between(&self, t0_s: f64, t1_s: f64) -> f64 {
        let speeds: Vec<f64> = self
            .rows
            .iter()
            .filter(|r| r.state.time_s >= t0_s && r.state.time_s <= t1_s)
            .map(|r| r.state.velocity_mps.length())
            .collect();
        speeds.iter().sum::<f64>() / speeds.len().max(1) as f64
    }

    /// Writes one row per control step: time, position, orientation (quaternion and roll/pitch/yaw),
    /// velocity, airspeed, body rates, and for each joint its angle, commanded and applied target
    /// and torque, then the mechanical power. SI units, angles in radians.
    pub fn write_csv(&self, path: &Path) -> Result<(), OutputError> {
        let rows = self.rows.iter().map(FlightCsvRow::of);
        write_csv_rows(path, &Self::csv_header(), rows)
            .map_err(|e| OutputError::Write { path: path.to_owned(), message: e.to_string() })
    }

    /// The column names of [`FlightCsvRow`].
    fn csv_header() -> Vec<String> {
        let mut header: Vec<String> = [
            "time_s",
            "x_m",
            "y_m",
            "z_m",
            "qw",
            "qx",
            "qy",
            "qz",
            "roll_rad",
            "pitch_rad",
            "yaw_rad",
            "vx_mps",
            "vy_mps",
            "vz_mps",
            "airspeed_mps",
            "p_radps",
            "q_radps",
            "r_radps",
        ]
        .map(String::from)
        .to_vec();
        for (suffix, unit) in [("", "rad"), ("_commanded", "rad"), ("_target", "rad"), ("_torque", "nm")] {
            header.extend(ActuatedJoint::ALL.map(|j| format!("{}{suffix}_{unit}", j.name())));
        }
        header.push("mechanical_power_w".into());
        header
    }
}

/// A row of `flight.csv`, every number at 6 decimals (columns in `FlightLog::csv_header`'s order).
#[derive(serde::Serialize)]
struct FlightCsvRow {
    #[serde(serialize_with = "fixed::<6, _>")]
    time_s: f64,
    #[serde(serialize_with = "each_fixed::<6, _>")]
    position_m: [f64; 3],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    quaternion_wxyz: [f64; 4],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    euler_rad: [f64; 3],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    velocity_mps: [f64; 3],
    #[serde(serialize_with = "fixed::<6, _>")]
    airspeed_mps: f64,
    #[serde(serialize_with = "each_fixed::<6, _>")]
    body_rates_radps: [f64; 3],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    joint_positions_rad: [f64; N_ACTUATED_JOINTS],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    commanded_rad: [f64; N_ACTUATED_JOINTS],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    applied_rad: [f64; N_ACTUATED_JOINTS],
    #[serde(serialize_with = "each_fixed::<6, _>")]
    torques_nm: [f64; N_ACTUATED_JOINTS],
    #[serde(serialize_with = "fixed::<6, _>")]
    mechanical_power_w: f64,
}

impl FlightCsvRow {
    fn of(row: &FlightRow) -> Self {
        let s = &row.state;
        Self {
            time_s: s.time_s,
            position_m: s.position_m.to_array(),
            quaternion_wxyz: quat_to_wxyz(s.orientation),
            euler_rad: s.euler_rad,
            velocity_mps: s.velocity_mps.to_array(),
            airspeed_mps: s.airspeed_mps,
            body_rates_radps: s.body_rates_radps.to_array(),
            joint_positions_rad: s.joint_positions_rad,
            commanded_rad: row.commanded_rad,
            applied_rad: row.applied_rad,
            torques_nm: row.torques_nm,
            mechanical_power_w: row.mechanical_power_w,
        }
    }
}
