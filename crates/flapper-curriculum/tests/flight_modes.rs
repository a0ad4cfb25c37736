//! The flight-mode bars' measurement on the shipped policies: the flight-modes candidate holds its wings
//! through most of the longitudinal reference's glide segment on about 1.5 times the scripted gait's
//! energy per metre, the final controller flaps through it on about 5 times; the scripted gait measured
//! against itself is exactly 1.

use std::path::PathBuf;

use flapper_curriculum::flight_modes::flight_mode_figures;
use flapper_sim::RobotModel;

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(name).join("policy.safetensors")
}

#[test]
fn the_flight_mode_figures_tell_the_gliding_candidate_from_the_flapping_final_controller() {
    let robot = RobotModel::flapper().unwrap();
    // `flapper modes` and `flapper eval` on both (policies/experiments/smooth/README.md and README.md):
    // glide 0.74 and 0.00; 1.50 and 5.4 times the scripted gait's energy per metre over 100 starts.
    let smooth = flight_mode_figures(&robot, &shipped("experiments/smooth")).unwrap();
    let final_controller = flight_mode_figures(&robot, &shipped("final")).unwrap();
    assert!(
        smooth.glide_fraction >= 0.5,
        "policies/experiments/smooth glides {:.2} of the glide segment",
        smooth.glide_fraction
    );
    assert!(
        final_controller.glide_fraction < 0.1,
        "the final controller glides {:.2} of it",
        final_controller.glide_fraction
    );
    assert!(smooth.energy_ratio < 2.5 && smooth.energy_ratio > 0.8, "smooth: {:.2} x", smooth.energy_ratio);
    assert!(final_controller.energy_ratio > 3.5, "final: {:.2} x", final_controller.energy_ratio);
    // Both flap in the cruise near 6.8 Hz (the eval table's flap_left row on cruise: 6.75 and 6.80 Hz).
    for (name, f) in [("smooth", smooth), ("final", final_controller)] {
        assert!((5.5..8.0).contains(&f.cruise_flap_hz), "{name}: {:.2} Hz", f.cruise_flap_hz);
    }
}
