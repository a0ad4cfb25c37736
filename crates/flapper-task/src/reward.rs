//! Reward (paper III-D): r = 0.5 r_pos + 0.1 r_rate + 0.2 r_level + 0.05 r_energy.
//!
//! The paper gives the weights, not the kernels. Ours are bounded in (0, 1], equal to 1 at the ideal,
//! so no term can dominate and staying alive is worth something:
//!
//! | term | kernel | scale (default) |
//! |---|---|---|
//! | r_pos | g exp(-e^2 / s^2), e = distance to the current target point, g = 1 but in steep dives | s = 1.0 m |
//! | r_rate | exp(-(p^2 + q^2 + r^2) / s^2) | s = 3.0 rad/s |
//! | r_level | exp(-(roll^2 + pitch^2) / s^2) | s = 0.5 rad |
//! | r_energy | exp(-P / s), P = mean of sum(abs(torque * joint velocity)) over the step | s = 20 W |
//! | r_action_rate | exp(-d^2 / s^2), d = norm of the change of the applied action since the last step | s = 1.0 |
//! | r_flap_rate | exp(-x^2 / s^2), x = how far the flap's frequency is above `flap_max_hz` (0 below) | s = 0.5 Hz |
//! | r_glide_hold | g exp(-a^2 / s^2), a = the flap's swing over 0.4 s, g = how much the path glides (0-1) | s = 10 deg |
//! | r_feathering | (1 - g)(1 + c) / 2, c = the correlation of the wings' pitch with their flap rate over 0.4 s | - |
//!
//! r_action_rate is not the paper's: its weight is 0 unless a config sets `action_rate_weight`. It
//! prices a quick change of what the policy asks (a dither) without pricing a steady flap. Nor is
//! r_flap_rate (weight 0 unless `flap_rate_weight` is set): it prices a stroke faster than a bird's, the
//! frequency read online from the left flap's tops ([`crate::flap_rhythm`]); a held wing reads 0 Hz.
//! Nor is r_glide_hold (weight 0 unless `glide_hold_weight` is set): it pays a held wing where the path
//! sinks at a slope the robot can glide (g, the glide share of [`crate::env::FlightEnv::glide_share`]),
//! by how little the flap swings ([`crate::flap_rhythm::FlapSwing`]), and nothing elsewhere: the
//! paper's "gliding instead of flapping when possible" asked for directly. Nor is r_pos's g: 1 + the
//! gain `position_dive_gain` where the path dives steeper than a glide slope (0 unless set), a dearer
//! miss where the robot must flap to brake and steer. Nor is r_feathering (weight 0 unless
//! `feathering_weight` is set): it pays a wing pitch that leads the flap by a quarter period
//! ([`crate::flap_rhythm::StrokeFeathering`], c = 1; a lag reads -1 and earns 0), the scripted gait's
//! feathering, off the glide slopes.

use crate::config::RewardConfig;

/// Each term's kernel value, in (0, 1]. Logged separately.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RewardTerms {
    pub position: f64,
    pub body_rate: f64,
    pub level: f64,
    pub energy: f64,
    /// Snapshots written before this term existed read it as 0.
    #[serde(default)]
    pub action_rate: f64,
    /// 0 unless weighed (`reward.flap_rate_weight`), and then left out of snapshots, so that the records
    /// of runs without it (checkpoints' environment states) stay byte for byte as before it.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub flap_rate: f64,
    /// 0 unless weighed (`reward.glide_hold_weight`) on a glide slope; left out of snapshots at 0, likewise.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub glide_hold: f64,
    /// 0 unless weighed (`reward.feathering_weight`); left out of snapshots at 0, likewise.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub feathering: f64,
}

/// A kernel's value `kernel` with its price paid by `share`: 1 - share (1 - kernel), and in full (1) the
/// kernel's own value, bit for bit (1 - (1 - k) need not be k).
fn priced_in_part(kernel: f64, share: f64) -> f64 {
    if share == 1.0 { kernel } else { 1.0 - share.max(0.0) * (1.0 - kernel) }
}

fn is_zero(value: &f64) -> bool {
    *value == 0.0
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
    /// Norm of the change of the applied action (each number in [-1, 1]) since the last step.
    pub action_change: f64,
    /// The flap's frequency (Hz) as [`crate::flap_rhythm::FlapRhythm`] reads it (0 for a held wing).
    pub flap_hz: f64,
    /// The flap's peak-to-peak range (deg) over the last 0.4 s ([`crate::flap_rhythm::FlapSwing`]).
    pub flap_swing_deg: f64,
    /// How much the reference glides here: 0 on level paths, climbs and steeper dives, up to 1 on a glide
    /// slope ([`crate::env::FlightEnv::glide_share`]).
    pub glide_share: f64,
    /// The wings' pitch against their flap rate, in [-1, 1] ([`crate::flap_rhythm::StrokeFeathering`]).
    pub feathering: f64,
}

impl RewardTerms {
    pub fn evaluate(config: &RewardConfig, x: &RewardInputs) -> Self {
        let gaussian = |value: f64, scale: f64| (-(value * value) / (scale * scale)).exp();
        Self {
            position: gaussian(x.position_error_m, config.position_scale_m),
            body_rate: gaussian(x.body_rate_radps, config.body_rate_scale_radps),
            level: gaussian(x.roll_rad.hypot(x.pitch_rad), config.level_scale_rad),
            energy: (-x.absolute_power_w.max(0.0) / config.energy_scale_w).exp(),
            action_rate: gaussian(x.action_change, config.action_rate_scale),
            flap_rate: if config.flap_rate_weight > 0.0 {
                gaussian((x.flap_hz - config.flap_max_hz).max(0.0), config.flap_rate_scale_hz)
            } else {
                0.0
            },
            glide_hold: if config.glide_hold_weight > 0.0 {
                x.glide_share.clamp(0.0, 1.0) * gaussian(x.flap_swing_deg, config.glide_hold_scale_deg)
            } else {
                0.0
            },
            feathering: if config.feathering_weight > 0.0 {
                (1.0 - x.glide_share.clamp(0.0, 1.0)) * 0.5 * (1.0 + x.feathering.clamp(-1.0, 1.0))
            } else {
                0.0
            },
        }
    }

    /// The energy priced by `share`: r_energy = 1 - share (1 - e), e the kernel's value. `share` 1 leaves
    /// it as it is, below 1 moves it towards its top (1; 0 reads 1 whatever the power,
    /// `reward.energy_min_speed_mps`), above 1 prices the power more (`reward.energy_glide_gain`), down
    /// to 1 - share where the kernel reads 0.
    pub fn with_energy_priced(self, share: f64) -> Self {
        Self { energy: priced_in_part(self.energy, share), ..self }
    }

    /// r_pos weighed by `factor` (1 + `reward.position_dive_gain` in a steep dive,
    /// [`crate::env::FlightEnv::position_factor`]): 1 leaves it as it is, bit for bit.
    pub fn with_position_weighed(self, factor: f64) -> Self {
        Self { position: self.position * factor, ..self }
    }

    /// The flap's price paid in part: r_flap_rate = 1 - share (1 - k), k the kernel's value (`share` 1
    /// leaves it as it is, bit for bit; 0 reads its top, 1, whatever the frequency). Unweighed (0) stays 0.
    pub fn with_flap_rate_priced(self, share: f64) -> Self {
        if self.flap_rate == 0.0 { self } else { Self { flap_rate: priced_in_part(self.flap_rate, share), ..self } }
    }

    /// The weighted sum.
    pub fn total(&self, config: &RewardConfig) -> f64 {
        config.position_weight * self.position
            + config.body_rate_weight * self.body_rate
            + config.level_weight * self.level
            + config.energy_weight * self.energy
            + config.action_rate_weight * self.action_rate
            + config.flap_rate_weight * self.flap_rate
            + config.glide_hold_weight * self.glide_hold
            + config.feathering_weight * self.feathering
    }

    pub fn add(&mut self, other: &Self) {
        self.position += other.position;
        self.body_rate += other.body_rate;
        self.level += other.level;
        self.energy += other.energy;
        self.action_rate += other.action_rate;
        self.flap_rate += other.flap_rate;
        self.glide_hold += other.glide_hold;
        self.feathering += other.feathering;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_energy_priced_in_part_moves_its_kernel_towards_the_top_and_leaves_the_other_terms() {
        let terms = RewardTerms {
            position: 0.9,
            body_rate: 0.8,
            level: 0.7,
            energy: 0.2,
            action_rate: 0.6,
            flap_rate: 0.5,
            glide_hold: 0.4,
            feathering: 0.3,
        };
        assert_eq!(terms.with_energy_priced(1.0), terms, "in full: unchanged, bit for bit");
        assert_eq!(terms.with_energy_priced(0.0), RewardTerms { energy: 1.0, ..terms }, "waived: the top");
        assert!((terms.with_energy_priced(0.5).energy - 0.6).abs() < 1e-12, "half the price: halfway up");
        assert_eq!(terms.with_energy_priced(0.5).position, terms.position);
    }

    fn ideal() -> RewardInputs {
        RewardInputs {
            position_error_m: 0.0,
            body_rate_radps: 0.0,
            roll_rad: 0.0,
            pitch_rad: 0.0,
            absolute_power_w: 0.0,
            action_change: 0.0,
            flap_hz: 5.0,
            flap_swing_deg: 0.0,
            glide_share: 0.0,
            feathering: 0.0,
        }
    }

    #[test]
    fn ideal_flight_earns_the_sum_of_the_weights() {
        let c = RewardConfig::default();
        let terms = RewardTerms::evaluate(&c, &ideal());
        let ones = RewardTerms {
            position: 1.0,
            body_rate: 1.0,
            level: 1.0,
            energy: 1.0,
            action_rate: 1.0,
            ..Default::default()
        };
        assert_eq!(terms, ones, "r_flap_rate, r_glide_hold and r_feathering read 0 unless weighed");
        assert!((terms.total(&c) - 0.85).abs() < 1e-12);
    }

    #[test]
    fn the_action_rate_term_counts_only_with_its_weight_and_prices_a_dither_above_a_steady_change() {
        let mut c = RewardConfig::default();
        let dither = RewardInputs { action_change: 0.6, ..ideal() };
        // Off by default: the paper's reward, whatever the action does.
        assert_eq!(RewardTerms::evaluate(&c, &dither).total(&c), RewardTerms::evaluate(&c, &ideal()).total(&c));
        c.action_rate_weight = 0.2;
        let total =
            |change: f64| RewardTerms::evaluate(&c, &RewardInputs { action_change: change, ..ideal() }).total(&c);
        assert!((total(0.0) - 1.05).abs() < 1e-12);
        // A jump of 0.6 every step (a dither at 25 Hz) costs more than the same change spread over 5 steps.
        let dither_cost = 5.0 * (total(0.0) - total(0.6));
        let steady_cost = 5.0 * (total(0.0) - total(0.12));
        assert!(dither_cost > 10.0 * steady_cost, "dither {dither_cost}, steady {steady_cost}");
        // At the scale the kernel is 1/e.
        let at_scale = RewardTerms::evaluate(&c, &RewardInputs { action_change: c.action_rate_scale, ..ideal() });
        assert!((at_scale.action_rate - (-1f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn the_flap_rate_term_prices_only_a_stroke_faster_than_its_bar_and_only_with_its_weight() {
        let mut c = RewardConfig::default();
        let at = |c: &RewardConfig, hz: f64| RewardTerms::evaluate(c, &RewardInputs { flap_hz: hz, ..ideal() });
        // Off by default: the paper's reward at any frequency, and no kernel.
        assert_eq!(at(&c, 7.0).total(&c), at(&c, 5.0).total(&c));
        assert_eq!(at(&c, 7.0).flap_rate, 0.0);
        c.flap_rate_weight = 0.1;
        c.flap_max_hz = 5.5;
        for hz in [0.0, 4.0, 5.5] {
            assert_eq!(at(&c, hz).flap_rate, 1.0, "{hz} Hz is within the bar");
        }
        let above = |hz: f64| at(&c, hz).flap_rate;
        assert!((above(5.5 + c.flap_rate_scale_hz) - (-1f64).exp()).abs() < 1e-12);
        assert!(above(6.0) > above(6.25) && above(6.25) > above(6.5), "falls with the excess");
        assert!((at(&c, 5.0).total(&c) - at(&c, 6.0).total(&c) - 0.1 * (1.0 - above(6.0))).abs() < 1e-12);
    }

    #[test]
    fn the_glide_hold_term_pays_a_held_wing_only_where_the_path_glides_and_only_with_its_weight() {
        let mut c = RewardConfig::default();
        let at = |c: &RewardConfig, swing: f64, glide: f64| {
            RewardTerms::evaluate(c, &RewardInputs { flap_swing_deg: swing, glide_share: glide, ..ideal() })
        };
        // Off by default: nothing, gliding or not.
        assert_eq!(at(&c, 0.0, 1.0).glide_hold, 0.0);
        assert_eq!(at(&c, 0.0, 1.0).total(&c), at(&c, 60.0, 1.0).total(&c));
        c.glide_hold_weight = 0.2;
        // Where the path glides in full: the held wing earns the whole weight, a stroke nothing.
        assert_eq!(at(&c, 0.0, 1.0).glide_hold, 1.0);
        assert!((at(&c, c.glide_hold_scale_deg, 1.0).glide_hold - (-1f64).exp()).abs() < 1e-12);
        assert!(at(&c, 60.0, 1.0).glide_hold < 1e-12, "a 60 deg stroke is not a glide");
        assert!(at(&c, 5.0, 1.0).glide_hold > at(&c, 8.0, 1.0).glide_hold, "the smaller the swing, the more");
        // In part on a shallower sink, nothing on a level path, a climb or a dive.
        assert!((at(&c, 0.0, 0.25).glide_hold - 0.25).abs() < 1e-12);
        assert_eq!(at(&c, 0.0, 0.0).glide_hold, 0.0);
        assert!(
            (at(&c, 0.0, 1.0).total(&c) - at(&c, 5.0, 1.0).total(&c) - 0.2 * (1.0 - at(&c, 5.0, 1.0).glide_hold)).abs()
                < 1e-12
        );
    }

    #[test]
    fn each_term_falls_as_its_error_grows_and_stays_bounded() {
        let c = RewardConfig { action_rate_weight: 0.2, ..RewardConfig::default() };
        /// A term's name, its input made worse by x, and the term read from the result.
        type Worsening = (&'static str, fn(f64) -> RewardInputs, fn(&RewardTerms) -> f64);
        let worse: [Worsening; 5] = [
            ("position", |x| RewardInputs { position_error_m: x, ..ideal() }, |t| t.position),
            ("body rate", |x| RewardInputs { body_rate_radps: x, ..ideal() }, |t| t.body_rate),
            ("level", |x| RewardInputs { roll_rad: x, pitch_rad: -x, ..ideal() }, |t| t.level),
            ("energy", |x| RewardInputs { absolute_power_w: 10.0 * x, ..ideal() }, |t| t.energy),
            ("action rate", |x| RewardInputs { action_change: x, ..ideal() }, |t| t.action_rate),
        ];
        for (name, input, term) in worse {
            let mut previous = 1.0;
            for x in [0.1, 0.5, 1.0, 3.0, 100.0] {
                let terms = RewardTerms::evaluate(&c, &input(x));
                let value = term(&terms);
                assert!(value < previous, "{name}: not decreasing at {x}");
                assert!((0.0..=1.0).contains(&value), "{name}: {value} out of bounds");
                let total = terms.total(&c);
                assert!((0.0..1.05).contains(&total), "{name}: total {total} at {x}");
                previous = value;
            }
        }
        // At the scale, a term is 1/e.
        let at_scale = RewardTerms::evaluate(&c, &RewardInputs { position_error_m: 1.0, ..ideal() });
        assert!((at_scale.position - (-1f64).exp()).abs() < 1e-12);
    }

    #[test]
    fn feathering_pays_a_pitch_ahead_of_the_flap_only_when_weighed_and_nothing_on_a_glide_slope() {
        let mut c = RewardConfig::default();
        let ahead = RewardInputs { feathering: 1.0, ..ideal() };
        let behind = RewardInputs { feathering: -1.0, ..ideal() };
        assert_eq!(RewardTerms::evaluate(&c, &ahead).total(&c), RewardTerms::evaluate(&c, &behind).total(&c));
        c.feathering_weight = 0.05;
        let (pay_ahead, pay_behind) = (RewardTerms::evaluate(&c, &ahead), RewardTerms::evaluate(&c, &behind));
        assert_eq!((pay_ahead.feathering, pay_behind.feathering), (1.0, 0.0));
        assert!((pay_ahead.total(&c) - pay_behind.total(&c) - 0.05).abs() < 1e-12);
        let gliding = RewardInputs { glide_share: 1.0, ..ahead };
        assert_eq!(RewardTerms::evaluate(&c, &gliding).feathering, 0.0, "the glide slopes pay the held wing");
    }
}
