//! A gate's energy bar on a validation entry (`gate.reference_max_energy_ratio`) reads the ratio `flapper
//! eval` prints for the same reference, starts and seed: the checkpoint's mean energy per metre over the
//! scripted gait's, flown from the same randomized starts.

use std::path::PathBuf;
use std::sync::Arc;

use flapper_curriculum::config::ValidationConfig;
use flapper_curriculum::validation::ValidationSet;
use flapper_eval::ScriptedGaitConfig;
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{TrackingController, evaluate_tracking};
use flapper_eval::tracking_report::TrackingSummary;
use flapper_sim::RobotModel;
use flapper_task::TaskConfig;
use flapper_task::reference::resolve;

fn shipped_final() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies/final/policy.safetensors")
}

#[test]
fn a_priced_entry_reads_the_energy_ratio_flapper_eval_prints_and_the_others_none() {
    let robot = RobotModel::flapper().unwrap();
    let (policy, task) = load_flight_policy(&shipped_final()).unwrap();
    let (episodes, seed) = (6, 11);
    let config: ValidationConfig =
        toml::from_str(&format!("references = [\"immelmann\", \"cruise\"]\nepisodes = {episodes}")).unwrap();
    let set = ValidationSet::new(&config, &task, robot.timestep_s(), seed)
        .unwrap()
        .price_energy(&robot, [&"immelmann".to_owned()])
        .unwrap();
    let score = set.judge(&robot, &shipped_final()).unwrap();

    // What `flapper eval --reference immelmann --episodes 6 --seed 11` flies and divides.
    let period_s = task.control_period_s(robot.timestep_s());
    let reference = Arc::new(resolve("immelmann", period_s, task.observation.lookahead_steps).unwrap());
    let mean_j_per_m = |controller: TrackingController, task: &TaskConfig| {
        let results = evaluate_tracking(&robot, &controller, task, reference.clone(), episodes, seed).unwrap();
        TrackingSummary::of(&results, period_s, None).energy_per_metre_j
    };
    let own = mean_j_per_m(TrackingController::Policy(Arc::new(policy)), &task);
    let scripted = mean_j_per_m(TrackingController::Scripted(ScriptedGaitConfig::default()), &TaskConfig::default());
    let ratio = score.reference("immelmann").unwrap().energy_ratio.expect("the Immelmann is priced");
    assert!((ratio - own / scripted).abs() < 1e-12, "the gate reads {ratio}, the evaluation {}", own / scripted);
    // 100 starts, seed 11: 2.47 x (policies/final/README.md).
    assert!(ratio > 2.0 && ratio < 4.5, "the shipped controller's Immelmann at {ratio:.2} x");
    assert_eq!(score.reference("cruise").unwrap().energy_ratio, None, "cruise is not priced");
}
