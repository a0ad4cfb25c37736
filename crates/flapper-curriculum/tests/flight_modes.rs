//! The flight-mode bars' measurement on the shipped policies: the flight-modes candidate holds its wings
//! through most of the longitudinal reference's glide segment on about 1.5 times the scripted gait's
//! energy per metre; the previous final controller flaps through it on about 5 times at 6.75 Hz; the five-
//! and six-stage controllers flap through it on about 1.4-1.6 times, at 5.2-5.7 Hz in the cruise; the final
//! controller, their seven-stage successor, and the gliding candidates hold their wings through more than
//! half of it at a bird's 4-6 Hz cruise flap.

use std::path::PathBuf;

use flapper_curriculum::config::CruiseFlapFlight;
use flapper_curriculum::flight_modes::flight_mode_figures;
use flapper_sim::RobotModel;

const SEGMENT: CruiseFlapFlight = CruiseFlapFlight::LongitudinalSegment;

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(name).join("policy.safetensors")
}

#[test]
fn the_flight_mode_figures_tell_gliding_cheap_and_costly_controllers_apart() {
    let robot = RobotModel::flapper().unwrap();
    // `flapper frontier --episodes 100 --seed 11` on each (policies/*/README.md): glide 0.74, 0.00, 0.00,
    // 0.02, 0.75; 1.5, 5.4, 1.59, 1.40 and 1.25 times the scripted gait's energy per metre; cruise flap 6.80,
    // 6.75, 5.22, 5.74 and 4.97 Hz. One exact start reads about 0.8 of the 100-start energy ratio (the
    // five-stage controller's: 1.26, the six-stage one's 1.11, the seven-stage final's 0.98).
    let smooth = flight_mode_figures(&robot, &shipped("experiments/smooth"), SEGMENT).unwrap();
    let previous = flight_mode_figures(&robot, &shipped("history/previous-final"), SEGMENT).unwrap();
    let five = flight_mode_figures(&robot, &shipped("history/five-stages"), SEGMENT).unwrap();
    let six = flight_mode_figures(&robot, &shipped("history/six-stages"), SEGMENT).unwrap();
    let last = flight_mode_figures(&robot, &shipped("final"), SEGMENT).unwrap();
    assert!(
        smooth.glide_fraction >= 0.5,
        "policies/experiments/smooth glides {:.2} of the glide segment",
        smooth.glide_fraction
    );
    for (name, f) in [("previous final", previous), ("five stages", five), ("six stages", six)] {
        assert!(f.glide_fraction < 0.1, "{name} glides {:.2} of it", f.glide_fraction);
    }
    assert!(smooth.energy_ratio < 2.0 && smooth.energy_ratio > 0.8, "smooth: {:.2} x", smooth.energy_ratio);
    assert!(previous.energy_ratio > 3.5, "previous final: {:.2} x", previous.energy_ratio);
    // Stage 5's gate asked 1.2 x and no checkpoint met it: the stage handed over its most efficient
    // checkpoint among those that track every reference (policies/history/five-stages/README.md); the sixth
    // stage's handed-over one flies cheaper still, and the seventh's glides, cheaper again.
    assert!(five.energy_ratio < 1.3, "five stages: {:.2} x, 1.26 when it was chosen", five.energy_ratio);
    assert!(six.energy_ratio < five.energy_ratio, "six stages: {:.2} x, 1.11 when it was chosen", six.energy_ratio);
    assert!(last.glide_fraction >= 0.5, "final: glides {:.2}, 0.75 when it was chosen", last.glide_fraction);
    assert!(last.energy_ratio < six.energy_ratio, "final: {:.2} x, 0.98 when it was chosen", last.energy_ratio);
    for (name, f) in [("smooth", smooth), ("previous final", previous)] {
        assert!((6.0..7.5).contains(&f.cruise_flap_hz), "{name}: {:.2} Hz", f.cruise_flap_hz);
    }
    // The five-stage controller's 6 s cruise segment reads the paper's 4-6 Hz; the six-stage one's reads 6.22
    // Hz where its 100 starts of the cruise reference read 5.74 (the segment reads up to 1.2 Hz off, which is
    // why the sixth stage's gate reads the cruise reference).
    assert!(
        (4.0..=6.0).contains(&five.cruise_flap_hz),
        "five stages: {:.2} Hz, the paper's 4-6 Hz",
        five.cruise_flap_hz
    );
}

#[test]
fn the_gliding_candidates_glide_cheaply_at_a_birds_flap() {
    let robot = RobotModel::flapper().unwrap();
    // policies/experiments/glide/README.md, `flapper frontier --episodes 100 --seed 11`: glide 0.58, 1.44 x,
    // 4.72 Hz; its stage's validation from the same exact start: glide 0.58, 1.19 x, 4.73 Hz.
    // policies/experiments/glide-slope/README.md: its stage's validation from the exact start: glide 0.53,
    // 1.07 x, 5.97 Hz.
    for name in ["glide", "glide-slope"] {
        let glide = flight_mode_figures(&robot, &shipped(&format!("experiments/{name}")), SEGMENT).unwrap();
        assert!(glide.glide_fraction >= 0.5, "policies/experiments/{name} glides {:.2} of it", glide.glide_fraction);
        assert!(glide.energy_ratio < 1.25, "{name}: {:.2} x from the exact start", glide.energy_ratio);
        assert!((4.0..=6.0).contains(&glide.cruise_flap_hz), "{name}: {:.2} Hz", glide.cruise_flap_hz);
    }
    // policies/experiments/glide-one-command/README.md: its stage's last validation from the exact start:
    // glide 0.56, 1.10 x (its cruise flap is measured on the cruise reference: 5.83 Hz on 100 starts).
    let one_command = flight_mode_figures(&robot, &shipped("experiments/glide-one-command"), SEGMENT).unwrap();
    assert!(one_command.glide_fraction >= 0.5, "glide-one-command glides {:.2} of it", one_command.glide_fraction);
    assert!(
        one_command.energy_ratio < 1.2,
        "glide-one-command: {:.2} x from the exact start",
        one_command.energy_ratio
    );
    // Its flap frequency as the bar reads it (the cruise reference's table, 100 starts): 5.83 Hz.
    // The cruise segment of longitudinal (6 s) reads 6.22 Hz, outside the paper's 4-6; the cruise
    // reference flown from its exact start (30 s) comes within 0.25 Hz of the 100 starts' mean.
    let reference = CruiseFlapFlight::CruiseReference;
    let on_cruise = flight_mode_figures(&robot, &shipped("experiments/glide-one-command"), reference).unwrap();
    let bar_reading = 5.83;
    assert!(
        (on_cruise.cruise_flap_hz - bar_reading).abs() < 0.25
            && (on_cruise.cruise_flap_hz - bar_reading).abs() < (one_command.cruise_flap_hz - bar_reading).abs(),
        "cruise reference {:.2} Hz, longitudinal's cruise segment {:.2} Hz, the bar's reading {bar_reading} Hz",
        on_cruise.cruise_flap_hz,
        one_command.cruise_flap_hz
    );
    assert_eq!(
        (on_cruise.glide_fraction, on_cruise.energy_ratio),
        (one_command.glide_fraction, one_command.energy_ratio),
        "the flap's flight changes only the frequency"
    );
}
