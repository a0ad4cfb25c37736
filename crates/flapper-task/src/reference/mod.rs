//! Reference trajectories (paper III-B, IV-C): 3-D positions sampled at the control rate (50 Hz).
//! The robot is rewarded for its distance to the current point and sees the next points ahead.
//!
//! - [`generator`] holds the pieces (commands of forward speed, vertical speed and yaw rate; vertical loops)
//!   joined into a path, and the seeded procedural generator of the curriculum;
//! - [`named`] holds the references of the paper's results, by name;
//! - [`csv_file`] reads a user's own reference from a CSV of time, x, y, z, validated.

pub mod csv_file;
pub mod generator;
pub mod named;

use std::path::Path;

use flapper_sim::Vec3;

use csv_file::{ReferenceFileError, load_reference_csv};
use named::{named, reference_names};

/// Where every named reference starts: 10 m above the ground, heading along +x.
pub const NAMED_START_M: Vec3 = Vec3::new(0.0, 0.0, 10.0);

#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error(transparent)]
    File(#[from] ReferenceFileError),
    #[error("unknown reference '{name}' (named: {known}; or a .csv file)")]
    UnknownName { name: String, known: String },
}

/// A reference by name (see [`named`]) or CSV file (a path ending in `.csv` or one that exists),
/// sampled every `dt_s`, with `lookahead_steps` of path beyond its end for the observation. A CSV
/// must cover at least the default lookahead too, so that any policy can fly it.
pub fn resolve(reference: &str, dt_s: f64, lookahead_steps: usize) -> Result<Reference, ReferenceError> {
    let path = Path::new(reference);
    if reference.ends_with(".csv") || path.exists() {
        let lookahead = lookahead_steps.max(crate::config::ObservationConfig::default().lookahead_steps);
        Ok(load_reference_csv(path, dt_s, lookahead)?)
    } else {
        named(reference, NAMED_START_M, dt_s, lookahead_steps as f64 * dt_s).ok_or_else(|| {
            ReferenceError::UnknownName { name: reference.to_owned(), known: reference_names().join(", ") }
        })
    }
}

/// A path sampled every `dt_s` seconds; point k is the target at control step k.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    name: String,
    dt_s: f64,
    points: Vec<Vec3>,
}

impl Reference {
    pub fn new(name: impl Into<String>, dt_s: f64, points: Vec<Vec3>) -> Self {
        assert!(!points.is_empty(), "a reference needs at least one point");
        Self { name: name.into(), dt_s, points }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    pub fn duration_s(&self) -> f64 {
        (self.points.len() - 1) as f64 * self.dt_s
    }

    /// The target at control step `step` (the last point once the path has run out).
    pub fn target(&self, step: usize) -> Vec3 {
        self.points[step.min(self.points.len() - 1)]
    }

    /// Direction of travel at `step` (unit vector; +x if the path stands still).
    pub fn direction(&self, step: usize) -> Vec3 {
        let a = self.target(step);
        let b = self.target(step + 1);
        let d = if b != a { b - a } else { a - self.target(step.saturating_sub(1)) };
        d.try_normalize().unwrap_or(Vec3::X)
    }

    /// Speed along the path at `step` (m/s).
    pub fn speed(&self, step: usize) -> f64 {
        let (a, b) = (self.target(step), self.target(step + 1));
        (b - a).length() / self.dt_s
    }

    /// Velocity along the path at `step` (m/s; z up): its length is [`Reference::speed`].
    pub fn velocity(&self, step: usize) -> Vec3 {
        (self.target(step + 1) - self.target(step)) / self.dt_s
    }

    /// The fastest turn of the direction of travel (deg/s) between consecutive steps over the `steps`
    /// steps from `step` on (0 for a straight path, whatever its slope or speed).
    pub fn fastest_turn_degps(&self, step: usize, steps: usize) -> f64 {
        // Each direction once: every step's training environments ask this over the whole lookahead.
        let mut before = self.direction(step);
        (step + 1..=step + steps)
            .map(|k| {
                let after = self.direction(k);
                let turn = before.cross(after).length().atan2(before.dot(after));
                before = after;
                turn.to_degrees() / self.dt_s
            })
            .fold(0.0, f64::max)
    }

    /// The slowest and the fastest speed along the path (m/s).
    pub fn speed_range_mps(&self) -> [f64; 2] {
        (0..self.points.len().saturating_sub(1))
            .map(|step| self.speed(step))
            .fold([f64::INFINITY, 0.0], |[lo, hi], v| [lo.min(v), hi.max(v)])
    }

    /// Steps at which the whole lookahead window still lies on the path.
    pub fn steps_with_full_lookahead(&self, lookahead_steps: usize) -> usize {
        self.points.len().saturating_sub(lookahead_steps)
    }
}
