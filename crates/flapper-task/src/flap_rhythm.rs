//! The flap's rhythm as the robot flies it: the frequency of the left flap joint, read online from the
//! times of its tops (the maxima of its angle), for the reward's price on a fast stroke
//! (`reward.flap_rate_weight`); and its swing, the peak-to-peak range over the last
//! [`FLAP_SWING_WINDOW_STEPS`], for the reward's pay for a held wing (`reward.glide_hold_weight`); and its
//! feathering, the wings' pitch against their flap rate over the same window ([`StrokeFeathering`]), for
//! the reward's pay for a pitch ahead of the flap (`reward.feathering_weight`).
//!
//! A top counts once the angle has fallen [`HELD_FLAP_RANGE_DEG`] below it after rising as much from the
//! bottom before it: a wing that moves less than that, peak to peak, is held (gliding) by the same
//! measure that `flapper modes` reads the glide with, and pays no price for its wobble. Its time is refined between control
//! steps by the parabola through the three samples around it (a 6.1 Hz stroke is 8.2 steps of 50 Hz; whole
//! steps would read it as 6.25 or 5.56 Hz). The frequency is one over the time between the last two tops
//! while the wing keeps turning (a top or a bottom within that time), else one over the time since the last
//! top: it falls towards 0 in a glide, and reads 0 until two tops have been seen.

use serde::{Deserialize, Serialize};

/// The flap's peak-to-peak range (deg) below which the wing counts as held, not flapping: the stroke
/// detector's reversal here, and the glide's measure in `flapper modes` (`flapper_analysis::modes`).
pub const HELD_FLAP_RANGE_DEG: f64 = 10.0;

/// How far (rad) the flap must turn back from a top or a bottom for it to count as a stroke.
const FLAP_REVERSAL_RAD: f64 = HELD_FLAP_RANGE_DEG * std::f64::consts::PI / 180.0;

/// The detector's state, carried across control steps (and in environment snapshots; it stays at its
/// default, which snapshots leave out, when the task does not weigh r_flap_rate).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FlapRhythm {
    /// The previous sample (rad); `started` once there is one.
    last_rad: f64,
    started: bool,
    /// Rising towards a top (true) or falling towards a bottom (false).
    rising: bool,
    /// The highest (rising) or lowest (falling) angle since the last turn, its time (s), and the samples
    /// just before and just after it (the one after, once taken), for the parabola.
    extreme_rad: f64,
    extreme_s: f64,
    before_extreme_rad: f64,
    after_extreme_rad: Option<f64>,
    /// The refined times of the last two tops (s), and how many have been seen (at most 2 counted).
    tops_s: [f64; 2],
    tops: u8,
    /// The refined time of the last top or bottom (s).
    turn_s: f64,
}

impl FlapRhythm {
    /// Nothing seen yet.
    pub fn is_unused(&self) -> bool {
        *self == Self::default()
    }

    /// Takes the angle `angle_rad` at time `time_s` (one call per control step, `period_s` apart).
    pub fn update(&mut self, angle_rad: f64, time_s: f64, period_s: f64) {
        let previous = std::mem::replace(&mut self.last_rad, angle_rad);
        if !self.started {
            self.started = true;
            self.rising = true;
            self.set_extreme(angle_rad, time_s, angle_rad);
            return;
        }
        let beyond = if self.rising { angle_rad > self.extreme_rad } else { angle_rad < self.extreme_rad };
        if beyond {
            self.set_extreme(angle_rad, time_s, previous);
            return;
        }
        self.after_extreme_rad.get_or_insert(angle_rad);
        if (angle_rad - self.extreme_rad).abs() < FLAP_REVERSAL_RAD {
            return;
        }
        self.turn_s = self.refined_extreme_s(period_s);
        if self.rising {
            self.tops_s = [self.tops_s[1], self.turn_s];
            self.tops = (self.tops + 1).min(2);
        }
        self.rising = !self.rising;
        self.set_extreme(angle_rad, time_s, previous);
    }

    fn set_extreme(&mut self, angle_rad: f64, time_s: f64, before_rad: f64) {
        (self.extreme_rad, self.extreme_s, self.before_extreme_rad) = (angle_rad, time_s, before_rad);
        self.after_extreme_rad = None;
    }

    /// The time of the extreme just confirmed: the vertex of the parabola through it and its two
    /// neighbouring samples, within half a step of its own sample.
    fn refined_extreme_s(&self, period_s: f64) -> f64 {
        let (before, extreme) = (self.before_extreme_rad, self.extreme_rad);
        let after = self.after_extreme_rad.unwrap_or(extreme);
        let bend = before - 2.0 * extreme + after;
        if bend.abs() < 1e-12 {
            return self.extreme_s;
        }
        self.extreme_s + (0.5 * (before - after) / bend).clamp(-0.5, 0.5) * period_s
    }

    /// The stroke's frequency (Hz) at time `time_s`; 0 until two tops have been seen.
    pub fn frequency_hz(&self, time_s: f64) -> f64 {
        if self.tops < 2 {
            return 0.0;
        }
        let period = self.tops_s[1] - self.tops_s[0];
        let period = if time_s - self.turn_s <= period { period } else { time_s - self.tops_s[1] };
        if period > 0.0 { 1.0 / period } else { 0.0 }
    }
}

/// How many control steps (0.4 s at 50 Hz, `flapper modes`' glide window) [`FlapSwing`] looks back over.
pub const FLAP_SWING_WINDOW_STEPS: usize = 20;

/// The left flap's last [`FLAP_SWING_WINDOW_STEPS`] angles, carried across control steps (and in
/// environment snapshots; it stays at its default, which snapshots leave out, when the task does not
/// weigh r_glide_hold). Unlike the rhythm's frequency it reads a wobble too: how far the wing is from
/// held, in degrees, rather than whether it strokes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct FlapSwing {
    angles_rad: [f64; FLAP_SWING_WINDOW_STEPS],
    /// Where the next angle goes, and how many have been seen (at most the window).
    next: usize,
    seen: usize,
}

impl FlapSwing {
    /// Nothing seen yet.
    pub fn is_unused(&self) -> bool {
        *self == Self::default()
    }

    /// Takes the angle of one control step.
    pub fn update(&mut self, angle_rad: f64) {
        self.angles_rad[self.next] = angle_rad;
        self.next = (self.next + 1) % FLAP_SWING_WINDOW_STEPS;
        self.seen = (self.seen + 1).min(FLAP_SWING_WINDOW_STEPS);
    }

    /// The peak-to-peak range (deg) of the angles in the window (fewer at the start; 0 before any).
    pub fn range_deg(&self) -> f64 {
        if self.seen == 0 { 0.0 } else { peak_to_peak(&self.angles_rad[..self.seen]).to_degrees() }
    }
}

/// The wings' common pitch against their common flap rate over the last [`FLAP_SWING_WINDOW_STEPS`]
/// (0.4 s), for the reward's pay for feathering (`reward.feathering_weight`): a stroke whose pitch
/// leads its flap by a quarter period (the scripted gait's, `pitch_lead_deg` 90) moves the pitch with
/// the flap's rate, and reads a correlation of 1; one lagging by a quarter period reads -1. Carried
/// across control steps and in environment snapshots (left out at its default, when not weighed).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StrokeFeathering {
    flap_rates_radps: [f64; FLAP_SWING_WINDOW_STEPS],
    pitches_rad: [f64; FLAP_SWING_WINDOW_STEPS],
    next: usize,
    seen: usize,
}

/// The flap rate's spread (rad/s, standard deviation over the window) under which the wing counts as
/// held and the correlation reads 0: a 10 deg peak-to-peak stroke at 4 Hz ([`HELD_FLAP_RANGE_DEG`]).
const HELD_FLAP_RATE_RADPS: f64 =
    0.5 * HELD_FLAP_RANGE_DEG * std::f64::consts::PI / 180.0 * std::f64::consts::TAU * 4.0 / std::f64::consts::SQRT_2;

impl StrokeFeathering {
    /// Nothing seen yet.
    pub fn is_unused(&self) -> bool {
        *self == Self::default()
    }

    /// Takes one control step's common flap rate (rad/s, mean of the two wings) and common wing pitch
    /// (rad, likewise; their difference rolls the robot and is left out).
    pub fn update(&mut self, flap_rate_radps: f64, pitch_rad: f64) {
        self.flap_rates_radps[self.next] = flap_rate_radps;
        self.pitches_rad[self.next] = pitch_rad;
        self.next = (self.next + 1) % FLAP_SWING_WINDOW_STEPS;
        self.seen = (self.seen + 1).min(FLAP_SWING_WINDOW_STEPS);
    }

    /// The correlation of pitch with flap rate over the window, in [-1, 1]; 0 before two steps, for a
    /// held wing (its flap rate's spread under a 10 deg, 4 Hz stroke's) or a pitch that does not move
    /// (its spread under 0.1 deg).
    pub fn correlation(&self) -> f64 {
        let n = self.seen;
        if n < 2 {
            return 0.0;
        }
        let (rates, pitches) = (&self.flap_rates_radps[..n], &self.pitches_rad[..n]);
        let mean = |v: &[f64]| v.iter().sum::<f64>() / n as f64;
        let (rate_mean, pitch_mean) = (mean(rates), mean(pitches));
        let (mut cross, mut rate_var, mut pitch_var) = (0.0, 0.0, 0.0);
        for (r, p) in rates.iter().zip(pitches) {
            let (dr, dp) = (r - rate_mean, p - pitch_mean);
            cross += dr * dp;
            rate_var += dr * dr;
            pitch_var += dp * dp;
        }
        let still_pitch_rad = 0.1f64.to_radians();
        if rate_var / (n as f64) < HELD_FLAP_RATE_RADPS * HELD_FLAP_RATE_RADPS
            || pitch_var / (n as f64) < still_pitch_rad * still_pitch_rad
        {
            return 0.0;
        }
        (cross / (rate_var * pitch_var).sqrt()).clamp(-1.0, 1.0)
    }
}

/// Largest minus smallest value (negative infinity for none): the swing's range here, and each window's
/// in `flapper modes`.
pub fn peak_to_peak(values: &[f64]) -> f64 {
    let (lo, hi) = values.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &a| (lo.min(a), hi.max(a)));
    hi - lo
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `seconds` of a 5 Hz stroke, 20 deg of flap, its pitch leading by `lead_deg` (`pitch_deg` amplitude).
    fn feathering_of(lead_deg: f64, flap_deg: f64, pitch_deg: f64, seconds: f64) -> StrokeFeathering {
        let (omega, dt) = (std::f64::consts::TAU * 5.0, 0.02);
        let mut feathering = StrokeFeathering::default();
        for k in 0..(seconds / dt) as usize {
            let t = k as f64 * dt;
            let flap_rate = flap_deg.to_radians() * omega * (omega * t).cos();
            feathering.update(flap_rate, pitch_deg.to_radians() * (omega * t + lead_deg.to_radians()).sin() + 0.1);
        }
        feathering
    }

    #[test]
    fn feathering_reads_the_pitch_s_lead_on_the_flap_and_nothing_for_a_held_wing() {
        assert!(feathering_of(90.0, 20.0, 10.0, 1.0).correlation() > 0.99, "a quarter period ahead: 1");
        assert!(feathering_of(-90.0, 20.0, 10.0, 1.0).correlation() < -0.99, "a quarter period behind: -1");
        let half_way = feathering_of(45.0, 20.0, 10.0, 1.0).correlation();
        assert!((half_way - 45f64.to_radians().cos()).abs() < 0.05, "{half_way}");
        assert_eq!(feathering_of(90.0, 2.0, 10.0, 1.0).correlation(), 0.0, "a held wing reads 0");
        assert_eq!(feathering_of(90.0, 20.0, 0.0, 1.0).correlation(), 0.0, "a still pitch reads 0");
        assert_eq!(StrokeFeathering::default().correlation(), 0.0);
        assert!(StrokeFeathering::default().is_unused() && !feathering_of(90.0, 20.0, 10.0, 0.1).is_unused());
    }

    const PERIOD_S: f64 = 0.02;

    /// Feeds `angle(t)` for `steps` control steps and returns the detector and the last time.
    fn fed(steps: usize, angle: impl Fn(f64) -> f64) -> (FlapRhythm, f64) {
        let mut rhythm = FlapRhythm::default();
        let mut time = 0.0;
        for k in 0..steps {
            time = k as f64 * PERIOD_S;
            rhythm.update(angle(time), time, PERIOD_S);
        }
        (rhythm, time)
    }

    #[test]
    fn a_steady_stroke_reads_its_frequency_between_whole_steps() {
        for hz in [4.0, 5.3, 6.1, 6.5, 8.0] {
            // At every step from the third stroke on, not only at the end.
            for steps in 50..200 {
                let (rhythm, time) = fed(steps, |t| 0.5 * (std::f64::consts::TAU * hz * t + 0.3).sin() + 0.1);
                let read = rhythm.frequency_hz(time);
                assert!((read - hz).abs() < 0.06, "{hz} Hz read as {read} after {steps} steps");
            }
        }
    }

    #[test]
    fn a_held_wing_and_a_tremor_read_no_stroke_and_a_stop_decays_the_frequency() {
        let (held, time) = fed(100, |_| 0.2);
        assert_eq!(held.frequency_hz(time), 0.0);
        // 9 deg peak to peak at 10 Hz: a held wing's wobble, under the reversal that counts.
        let wobble = 0.5 * (HELD_FLAP_RANGE_DEG - 1.0).to_radians();
        let (tremor, time) = fed(100, |t| wobble * (std::f64::consts::TAU * 10.0 * t).sin());
        assert_eq!(tremor.frequency_hz(time), 0.0);
        // A 6 Hz stroke for 1 s, then the wing held: after the last top the reading falls as 1 / time.
        let stroke = |t: f64| if t < 1.0 { 0.5 * (std::f64::consts::TAU * 6.0 * t).sin() } else { 0.0 };
        let (stopped, _) = fed(100, stroke);
        let at_stop = stopped.frequency_hz(1.0);
        assert!((at_stop - 6.0).abs() < 0.1, "{at_stop}");
        let later = stopped.frequency_hz(2.0);
        assert!(later < 1.2 && later > 0.5, "1 s after the stop: {later}");
    }

    #[test]
    fn the_swing_is_the_range_of_the_last_window_and_forgets_a_stroke_once_the_wing_is_held() {
        let mut swing = FlapSwing::default();
        assert_eq!(swing.range_deg(), 0.0);
        // A 5 Hz stroke of +-40 deg for 1 s: its whole range within a window of two strokes.
        let stroke = |k: usize| 40f64.to_radians() * (std::f64::consts::TAU * 5.0 * k as f64 * PERIOD_S).sin();
        (0..50).for_each(|k| swing.update(stroke(k)));
        assert!((swing.range_deg() - 80.0).abs() < 5.0, "sampled at 50 Hz: {}", swing.range_deg());
        // Held at 3 deg with a 1 deg wobble: the stroke is still in the window for its length, then gone.
        let held = |k: usize| (3.0 + 0.5 * (k as f64).sin()).to_radians();
        (50..50 + FLAP_SWING_WINDOW_STEPS - 1).for_each(|k| swing.update(held(k)));
        assert!(swing.range_deg() > 10.0, "the last stroke still seen: {}", swing.range_deg());
        swing.update(held(69));
        assert!(swing.range_deg() <= 1.0 + 1e-9, "{}", swing.range_deg());
    }
}
