//! A gate's flap bar read on the validation's own starts (`cruise_flap_flight = "validation_starts"`) reads
//! the figure `flapper eval` prints in its table's flap_left row for the same reference, starts and seed:
//! each start's fundamental after its first second, averaged over the starts.

use std::path::PathBuf;
use std::sync::Arc;

use flapper_curriculum::config::ValidationConfig;
use flapper_curriculum::validation::ValidationSet;
use flapper_eval::load_flight_policy;
use flapper_eval::tracking::{TrackingController, evaluate_tracking};
use flapper_eval::tracking_report::TrackingSummary;
use flapper_sim::RobotModel;
use flapper_task::reference::resolve;

fn shipped_final() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies/final/policy.safetensors")
}

#[test]
fn the_flap_read_on_the_validation_starts_is_flapper_evals_and_only_on_the_entry_asked() {
    let robot = RobotModel::flapper().unwrap();
    let (policy, task) = load_flight_policy(&shipped_final()).unwrap();
    let (episodes, seed) = (4, 11);
    let config: ValidationConfig =
        toml::from_str(&format!("references = [\"cruise\", \"lateral\"]\nepisodes = {episodes}")).unwrap();
    let set =
        ValidationSet::new(&config, &task, robot.timestep_s(), seed).unwrap().read_flap_on(Some("cruise")).unwrap();
    let score = set.judge(&robot, &shipped_final()).unwrap();

    // What `flapper eval --reference cruise --episodes 4 --seed 11` prints as flap_left's fundamental.
    let period_s = task.control_period_s(robot.timestep_s());
    let reference = Arc::new(resolve("cruise", period_s, task.observation.lookahead_steps).unwrap());
    let controller = TrackingController::Policy(Arc::new(policy));
    let results = evaluate_tracking(&robot, &controller, &task, reference, episodes, seed).unwrap();
    let printed = TrackingSummary::of(&results, period_s, None).frequency_hz[0];
    let read = score.reference("cruise").unwrap().flap_hz.expect("the flap is read on cruise");
    assert_eq!(read.to_bits(), printed.to_bits(), "the gate reads {read} Hz, the evaluation prints {printed} Hz");
    // 100 starts, seed 11: 4.97 Hz (policies/final/README.md); a flap, not a wing held or a harmonic.
    assert!((4.0..8.0).contains(&read), "the shipped controller's cruise flap at {read:.2} Hz");
    assert_eq!(score.reference("lateral").unwrap().flap_hz, None, "lateral's flap is not read");

    let unread = ValidationSet::new(&config, &task, robot.timestep_s(), seed).unwrap();
    assert_eq!(unread.judge(&robot, &shipped_final()).unwrap().reference("cruise").unwrap().flap_hz, None);
    let err = ValidationSet::new(&config, &task, robot.timestep_s(), seed)
        .unwrap()
        .read_flap_on(Some("loop"))
        .err()
        .expect("loop is not flown");
    assert!(err.to_string().contains("'loop'"), "{err}");
}
