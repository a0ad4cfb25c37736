//! The evaluation's success rule (the paper's: reach the end of the reference without ever being more
//! than 3 m from the target; attitude never ends an evaluation) and its manoeuvre figures.

use std::sync::Arc;

use flapper_eval::tracking::{EpisodeResult, TrackingStep, evaluation_task};
use flapper_eval::tracking_report::{ManoeuvreFigures, TrackingSummary};
use flapper_sim::{InitialState, RobotModel, Vec3, quat_from_euler};
use flapper_task::reference::named::{manoeuvre_window_s, named};
use flapper_task::termination::EpisodeEnd;
use flapper_task::{FlightEnv, ReferenceSource, TaskConfig};

/// One step of environment `env` started upside down on the reference's first point, flying along it.
fn step_inverted(config: TaskConfig, reference: Arc<flapper_task::reference::Reference>) -> Option<EpisodeEnd> {
    let robot = RobotModel::flapper().unwrap();
    let mut env = FlightEnv::new(&robot, Arc::new(config), ReferenceSource::Fixed(reference.clone()), 1, 0).unwrap();
    env.sim_mut().reset(&InitialState {
        position_m: reference.target(0),
        orientation: quat_from_euler(170f64.to_radians(), 0.0, 0.0),
        linear_velocity_mps: Vec3::new(3.8, 0.0, 0.0),
        ..InitialState::default()
    });
    env.step(&[0.0; 5]).end
}

#[test]
fn flying_upside_down_in_a_loop_ends_training_in_stage_1_but_never_an_evaluation() {
    let reference = Arc::new(named("loop", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap());
    let stage1 = TaskConfig::stage(1).unwrap();
    assert_eq!(step_inverted(stage1.clone(), reference.clone()), Some(EpisodeEnd::AttitudeLimit));
    let evaluation = evaluation_task(&stage1, &reference);
    assert!(!evaluation.episode.attitude_termination && !evaluation.randomization.enabled);
    assert_eq!(evaluation.episode.max_position_error_m, 3.0, "the paper's 3 m rule stays");
    assert_eq!(step_inverted(evaluation, reference), None);
}

fn step_at(time_s: f64, error_m: f64, roll_rad: f64) -> TrackingStep {
    TrackingStep {
        episode: 0,
        time_s,
        position_m: Vec3::new(3.8 * time_s, 0.0, 10.0 + error_m),
        target_m: Vec3::new(3.8 * time_s, 0.0, 10.0),
        error_m,
        airspeed_mps: 3.8,
        euler_rad: [roll_rad, 0.0, 0.0],
        joint_positions_rad: [0.0; 5],
        joint_velocities_radps: [0.0; 5],
        joint_targets_rad: [0.0; 5],
        mechanical_power_w: 5.0,
        absolute_power_w: 10.0,
    }
}

/// An episode on the `loop` reference (manoeuvre 3-6 s) whose error is `error(t)`.
fn episode(end: EpisodeEnd, until_s: f64, error: impl Fn(f64) -> f64) -> EpisodeResult {
    let steps = (1..=(until_s / 0.02).round() as usize)
        .map(|k| {
            let t = k as f64 * 0.02;
            let inverted = (4.0..5.0).contains(&t);
            step_at(t, error(t), if inverted { 3.0 } else { 0.0 })
        })
        .collect();
    EpisodeResult { end, steps, wind_mps: Vec3::ZERO }
}

#[test]
fn completion_counts_episodes_that_reach_the_end_and_manoeuvre_figures_follow_the_errors() {
    assert_eq!(manoeuvre_window_s("loop"), Some((3.0, 6.0)));
    assert_eq!(manoeuvre_window_s("sharp-turn"), Some((3.0, 4.2)));
    assert_eq!(manoeuvre_window_s("cruise"), None);
    assert_eq!(manoeuvre_window_s("longitudinal"), None, "it ends in its dive: nothing to rejoin after");
    // 2.5 m off during the loop, back within 0.5 m 1.5 s after it ends (at 7.5 s).
    let good = episode(EpisodeEnd::ReferenceEnd, 9.0, |t| if (3.0..7.5).contains(&t) { 2.5 } else { 0.2 });
    // 1.0 m off during the loop, back at once.
    let better = episode(EpisodeEnd::ReferenceEnd, 9.0, |t| if (3.0..6.0).contains(&t) { 1.0 } else { 0.1 });
    // Lost 3 m from the target in the loop.
    let lost = episode(EpisodeEnd::TooFarFromTarget, 4.5, |t| if t < 3.0 { 0.1 } else { 3.1 });
    let results = vec![good, better, lost];
    let summary = TrackingSummary::of(&results, 0.02, manoeuvre_window_s("loop"));
    assert_eq!((summary.completed, summary.episodes), (2, 3));
    assert_eq!(summary.failures, vec![("too_far".to_owned(), 1)]);
    assert_eq!(summary.inverted_episodes, 3);
    let m: &ManoeuvreFigures = summary.manoeuvre.as_ref().unwrap();
    assert_eq!(m.episodes, 2, "the lost episode never flew through the loop");
    assert!((m.mean_max_error_m - 1.75).abs() < 1e-9 && (m.worst_max_error_m - 2.5).abs() < 1e-9, "{m:?}");
    assert!(m.median_rejoin_s.abs() < 1e-6 || (m.median_rejoin_s - 1.5).abs() < 0.03, "{m:?}");
    assert!((m.worst_rejoin_s - 1.5).abs() < 0.03, "{m:?}");
    assert_eq!(m.never_rejoined, 0);
}

#[test]
fn the_scripted_gait_flies_the_same_beside_a_policy_trained_on_oscillator_actions() {
    use flapper_eval::ScriptedGaitConfig;
    use flapper_eval::tracking::{TrackingController, evaluate_tracking};
    let robot = RobotModel::flapper().unwrap();
    let reference = Arc::new(named("cruise", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap());
    let scripted = TrackingController::Scripted(ScriptedGaitConfig::default());
    let joint_targets = TaskConfig::stage(1).unwrap();
    let mut oscillator = joint_targets.clone();
    oscillator.control.action_mode = flapper_task::config::ActionMode::FlapOscillator;
    let fly = |task: &TaskConfig| evaluate_tracking(&robot, &scripted, task, reference.clone(), 2, 3).unwrap();
    let (a, b) = (fly(&joint_targets), fly(&oscillator));
    assert_eq!(a.len(), 2);
    for (a, b) in a.iter().zip(&b) {
        assert!(a.rms_error_m().is_finite() && a.energy_per_metre_j(0.02) > 0.0);
        assert_eq!(a.completed(), b.completed());
        assert_eq!(a.rms_error_m(), b.rms_error_m());
        assert_eq!(a.energy_per_metre_j(0.02), b.energy_per_metre_j(0.02));
    }
}

#[test]
fn the_scripted_gait_s_wing_pitch_reads_its_quarter_period_lead_and_a_lag_reads_negative() {
    use flapper_eval::ScriptedGaitConfig;
    use flapper_eval::tracking::{TrackingController, evaluate_tracking};
    let robot = RobotModel::flapper().unwrap();
    let reference = Arc::new(named("cruise", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.6).unwrap());
    let task = TaskConfig::stage(1).unwrap();
    let lead = |pitch_lead_deg: f64| {
        let gait = TrackingController::Scripted(ScriptedGaitConfig { pitch_lead_deg, ..ScriptedGaitConfig::default() });
        TrackingSummary::of(&evaluate_tracking(&robot, &gait, &task, reference.clone(), 2, 3).unwrap(), 0.02, None)
            .pitch_lead_deg
    };
    // The joints follow their targets through the same filter and servos: the lead survives within a few degrees.
    let (ahead, behind) = (lead(90.0), lead(-75.0));
    assert!((ahead - 90.0).abs() < 15.0, "{ahead}");
    assert!((behind + 75.0).abs() < 15.0, "{behind}");
}
