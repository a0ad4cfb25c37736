//! The paper's numbers (Cai et al., arXiv 2411.15130), written once: the page and the paper-vs-flapper
//! table both read them here. Each carries the place in the paper it comes from.

/// IV-A: "a fundamental frequency of 5.3Hz" of the flap, wing pitch and tail in cruise at 3.8 m/s.
pub const FLAP_FREQUENCY_HZ: f64 = 5.3;

/// IV-A: the energy in that fundamental, "38.65%, 36.81%, and 38.24%" (flap, wing pitch, tail): the
/// lowest and the highest, as printed (percent).
pub const FUNDAMENTAL_ENERGY_PERCENT: (&str, &str) = ("36.8", "38.7");

/// IV-A, eq. 9: the identified closed loop "predicted result with a Mean Squared Error (MSE) as low as
/// 5.629e-5" (m^2), as printed on the page.
pub const IDENTIFICATION_MSE_M2: f64 = 5.6e-5;

/// III-D: "a full controller trained in about 30 million steps" ... "around 5 hours" on an Intel Core
/// i7-11800H (8 cores).
pub const TRAINING_ENV_STEPS_MILLIONS: f64 = 30.0;
pub const TRAINING_HOURS: f64 = 5.0;
pub const TRAINING_CORES: usize = 8;

/// The training cost as the page and the table state it.
pub fn training_cost() -> String {
    format!("{TRAINING_ENV_STEPS_MILLIONS} M steps in about {TRAINING_HOURS} h on {TRAINING_CORES} cores")
}

/// The paper's environment steps per second (thousands) of [`training_cost`].
pub fn training_thousand_steps_per_s() -> f64 {
    TRAINING_ENV_STEPS_MILLIONS * 1e3 / (TRAINING_HOURS * 3600.0)
}

/// Table II: blunt drag, slender drag, angular drag, Kutta lift and Magnus lift coefficients (the
/// Kutta lift as printed, 3.14, not pi).
#[allow(clippy::approx_constant)]
pub const TABLE_II: [f64; 5] = [0.2, 0.12, 1.5, 3.14, 1.0];

/// Table III as the paper gives each range, in the order the page lists the parameters: joint damping,
/// link mass, link inertia, centre of mass, fluid coefficients, added mass, added inertia, wind, and
/// the share of episodes randomized (all of them).
pub const TABLE_III: [&str; 9] = [
    "x[0.9, 1.1]",
    "x[0.9, 1.1]",
    "x[0.9, 1.1]",
    "+-50 mm (ours: README, Randomization)",
    "x[0.7, 1.3]",
    "x[0.9, 1.1]",
    "x[0.9, 1.1]",
    "+-2, +-2, +-1.5 m/s",
    "1",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_training_cost_reads_as_the_paper_says_it() {
        assert_eq!(training_cost(), "30 M steps in about 5 h on 8 cores");
        assert_eq!(format!("{:.1}", training_thousand_steps_per_s()), "1.7");
        assert_eq!(TABLE_II.map(|c| c.to_string()), ["0.2", "0.12", "1.5", "3.14", "1"]);
    }
}
