//! Reward (paper III-D): r = 0.5 r_pos + 0.1 r_rate + 0.2 r_level + 0.05 r_energy.
//!
//! The paper gives the weights, not the kernels. Ours are bounded in (0, 1], equal to 1 at the ideal,
//! so no term can dominate and staying alive is worth something:
//!
//! | term | kernel | scale (default) |
//! |---|---|---|
//! | r_pos | exp(-e^2 / s^2), e = distance to the current target point | s = 1.0 m |
//! | r_rate | exp(-(p^2 + q^2 + r^2) / s^2) | s = 3.0 rad/s |
//! | r_level | exp(-(roll^2 + pitch^2) / s^2) | s = 0.5 rad |
//! | r_energy | exp(-P / s), P = mean of sum(abs(torque * joint velocity)) over the step | s = 20 W |

use crate::config::RewardConfig;

/// Each term's kernel value, in (0, 1]. Logged separately.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RewardTerms {
    pub position: f64,
    pub body_rate: f64,
    pub level: f64,
    pub energy: f64,
}

/// What the reward looks at after a control step.
#[derive(Debug, Clone, Copy)]
pub struct RewardInputs {
    pub position_error_m: f64,
    /// Norm of the body rates p, q, r.
    pub body_rate_radps: f64,
    pub roll_rad: f64,
    pub pitch_rad: f64,
    pub absolute_power_w: f64,
}

impl RewardTerms {
    pub fn evaluate(config: &RewardConfig, x: &RewardInputs) -> Self {
        let gaussian = |value: f64, scale: f64| (-(value * value) / (scale * scale)).exp();
        Self {
            position: gaussian(x.position_error_m, config.position_scale_m),
            body_rate: gaussian(x.body_rate_radps, config.body_rate_scale_radps),
            level: gaussian(x.roll_rad.hypot(x.pitch_rad), config.level_scale_rad),
            energy: (-x.absolute_power_w.max(0.0) / config.energy_scale_w).exp(),
        }
    }

    /// The weighted sum.
    pub fn total(&self, config: &RewardConfig) -> f64 {
        config.position_weight * self.position
            + config.body_rate_weight * self.body_rate
            + config.level_weight * self.level
            + config.energy_weight * self.energy
    }

    pub fn add(&mut self, other: &Self) {
        self.position += other.position;
        self.body_rate += other.body_rate;
        self.level += other.level;
        self.energy += other.energy;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ideal() -> RewardInputs {
        RewardInputs {
            position_error_m: 0.0,
            body_rate_radps: 0.0,
            roll_rad: 0.0,
            pitch_rad: 0.0,
            absolute_power_w: 0.0,
        }
    }

    #[test]
    fn ideal_flight_earns_the_sum_of_the_weights() {
        let c = RewardConfig::default();
        let terms = RewardTerms::evaluate(&c, &ideal());
        assert_eq!(terms, RewardTerms { position: 1.0, body_rate: 1.0, level: 1.0, energy: 1.0 });
        assert!((terms.total(&c) - 0.85).abs() < 1e-12);
    }

    #[test]
    fn each_term_falls_as_its_error_grows_and_stays_bounded() {
        let c = RewardConfig::default();
        /// A term's name, its input made worse by x, and the term read from the result.
        type Worsening = (&'static str, fn(f64) -> RewardInputs, fn(&RewardTerms) -> f64);
        let worse: [Worsening; 4] = [
            ("position", |x| RewardInputs { position_error_m: x, ..ideal() }, |t| t.position),
            ("body rate", |x| RewardInputs { body_rate_radps: x, ..ideal() }, |t| t.body_rate),
            ("level", |x| RewardInputs { roll_rad: x, pitch_rad: -x, ..ideal() }, |t| t.level),
            ("energy", |x| RewardInputs { absolute_power_w: 10.0 * x, ..ideal() }, |t| t.energy),
        ];
        for (name, input, term) in worse {
            let mut previous = 1.0;
            for x in [0.1, 0.5, 1.0, 3.0, 100.0] {
                let terms = RewardTerms::evaluate(&c, &input(x));
                let value = term(&terms);
                assert!(value < previous, "{name}: not decreasing at {x}");
                assert!((0.0..=1.0).contains(&value), "{name}: {value} out of bounds");
                let total = terms.total(&c);
                assert!((0.0..=0.85).contains(&total));
                previous = value;
            }
        }
        // At the scale, a term is 1/e.
        let at_scale = RewardTerms::evaluate(&c, &RewardInputs { position_error_m: 1.0, ..ideal() });
        assert!((at_scale.position - (-1f64).exp()).abs() < 1e-12);
    }
}
