//! The glide bar's measurement on the shipped policies: the flight-modes candidate holds its wings
//! through most of the longitudinal reference's glide segment, the final controller flaps through it.

use std::path::PathBuf;

use flapper_curriculum::glide::glide_fraction;
use flapper_sim::RobotModel;

fn shipped(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies").join(name).join("policy.safetensors")
}

#[test]
fn the_glide_bar_tells_the_gliding_candidate_from_the_flapping_final_controller() {
    let robot = RobotModel::flapper().unwrap();
    // `flapper modes` on both (policies/experiments/smooth/README.md and README.md): 0.74 and 0.00.
    let smooth = glide_fraction(&robot, &shipped("experiments/smooth")).unwrap();
    let final_controller = glide_fraction(&robot, &shipped("final")).unwrap();
    assert!(smooth >= 0.5, "policies/experiments/smooth glides {smooth:.2} of the glide segment");
    assert!(final_controller < 0.1, "the final controller glides {final_controller:.2} of it");
}
