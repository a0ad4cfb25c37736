//! The power curve's physics: the scripted gait holds its altitude, a lower trim flies faster for more
//! power, and a policy's level flight costs what its power and speed say.

use flapper_analysis::frontier::FrontierPolicy;
use flapper_analysis::power_curve::{fly_gait, fly_policy_level};
use flapper_eval::ScriptedGaitConfig;
use flapper_sim::RobotModel;

#[test]
fn the_scripted_gait_flies_level_and_a_lower_nose_flies_faster_for_more_power() {
    let robot = RobotModel::flapper().unwrap();
    let scripted = fly_gait(&robot, &ScriptedGaitConfig::default()).unwrap();
    assert!(scripted.level() && scripted.is_scripted_gait(), "{scripted:?}");
    assert!((3.3..4.0).contains(&scripted.speed_mps), "the scripted gait's own speed: {scripted:?}");
    let nose_down =
        fly_gait(&robot, &ScriptedGaitConfig { body_pitch_deg: 0.0, ..ScriptedGaitConfig::default() }).unwrap();
    assert!(nose_down.level() && !nose_down.is_scripted_gait(), "{nose_down:?}");
    assert!(nose_down.speed_mps > scripted.speed_mps + 0.4, "{nose_down:?} against {scripted:?}");
    assert!(nose_down.power_w > scripted.power_w, "faster than the minimum-power speed costs more: {nose_down:?}");
    assert!(nose_down.energy_per_metre_j > scripted.energy_per_metre_j, "{nose_down:?}");
}

#[test]
fn a_gait_that_cannot_hold_its_altitude_is_not_level() {
    let robot = RobotModel::flapper().unwrap();
    // A flap too slow to carry the robot: the altitude hold saturates and it sinks.
    let gait = ScriptedGaitConfig { frequency_hz: 1.0, max_flap_amplitude_deg: 5.0, ..ScriptedGaitConfig::default() };
    let sinking = fly_gait(&robot, &gait).unwrap();
    assert!(!sinking.level(), "{sinking:?}");
}

#[test]
fn a_policy_on_a_level_path_flies_the_path_s_speed() {
    let robot = RobotModel::flapper().unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../policies/final/policy.safetensors");
    let policy = FrontierPolicy::load("final", &path).unwrap();
    let level = fly_policy_level(&robot, &policy, 4.5, 2, 11).unwrap();
    assert_eq!((level.completed, level.episodes), (2, 2), "{level:?}");
    assert!((level.speed_mps - 4.5).abs() < 0.2, "it tracks the path: {level:?}");
    assert!(level.power_w > 0.0 && level.energy_per_metre_j > 0.0, "{level:?}");
}

#[test]
fn a_wing_pitch_behind_the_flap_steadies_the_body_and_costs_power() {
    let robot = RobotModel::flapper().unwrap();
    let gait = |pitch_lead_deg: f64| ScriptedGaitConfig {
        frequency_hz: 5.0,
        pitch_lead_deg,
        pitch_amplitude_deg: 20.0,
        body_pitch_deg: 15.0,
        tail_trim_deg: -10.0,
        ..ScriptedGaitConfig::default()
    };
    let (ahead, behind) = (fly_gait(&robot, &gait(0.0)).unwrap(), fly_gait(&robot, &gait(-75.0)).unwrap());
    assert!(ahead.completed && behind.completed, "{ahead:?} {behind:?}");
    assert!(behind.body_rate_rms_radps < 0.85 * ahead.body_rate_rms_radps, "{behind:?} against {ahead:?}");
    assert!(behind.power_w > 2.0 * ahead.power_w, "{behind:?} against {ahead:?}");
}
