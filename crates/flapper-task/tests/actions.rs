//! Actions: the paper's joint targets, and the flapping oscillator in which holding the wings is one
//! output (amplitude at or below 0), its frequency, its pitch swing a quarter cycle ahead of the flap,
//! and its phase carried through snapshots.

use std::f64::consts::TAU;

use flapper_sim::{ActuatedJoint, RobotModel};
use flapper_task::action::{ActionMap, OscillatorState, PITCH_SWING_PER_FLAP};
use flapper_task::config::{ActionMode, ControlConfig, TaskConfig};

const PERIOD_S: f64 = 0.02;

fn action_map(mode: ActionMode) -> ActionMap {
    map_for(ControlConfig { action_mode: mode, ..ControlConfig::default() })
}

/// The action map of `control` on the shipped robot.
fn map_for(control: ControlConfig) -> ActionMap {
    let sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    ActionMap::new(&sim, &control, PERIOD_S)
}

/// The targets of `steps` steps of one held action, and the phase after them.
fn hold(map: &ActionMap, action: [f32; 5], steps: usize) -> (Vec<[f64; 5]>, f64) {
    let mut oscillator = OscillatorState::default();
    let targets = (0..steps).map(|_| map.to_targets(&action, &mut oscillator)).collect();
    (targets, oscillator.phase_rad)
}

const FLAP: usize = ActuatedJoint::FlapLeft.index();
const FLAP_RIGHT: usize = ActuatedJoint::FlapRight.index();
const PITCH_LEFT: usize = ActuatedJoint::PitchLeft.index();
const PITCH_RIGHT: usize = ActuatedJoint::PitchRight.index();
const TAIL: usize = ActuatedJoint::TailPitch.index();

#[test]
fn joint_target_actions_scale_to_the_joint_limits_and_leave_the_phase_alone() {
    let map = action_map(ActionMode::JointTargets);
    let half = map.half_range_rad();
    let (targets, phase) = hold(&map, [0.5, -1.0, 2.0, f32::NAN, -0.25], 3);
    assert_eq!(phase, 0.0);
    assert_eq!(targets[2], [0.5 * half[0], -half[1], half[2], 0.0, -0.25 * half[4]]);
    assert_eq!(map.applied(&[0.5, -1.0, 2.0, f32::NAN, -0.25], &targets[2]), [0.5, -1.0, 1.0, 0.0, -0.25]);
}

#[test]
fn an_oscillator_amplitude_at_or_below_zero_holds_the_wings_at_their_biases() {
    let map = action_map(ActionMode::FlapOscillator);
    let half = map.half_range_rad();
    for amplitude in [0.0, -0.3, -1.0] {
        let (targets, phase) = hold(&map, [amplitude, 0.4, 0.2, 0.1, -0.4], 60);
        assert!(phase > 0.0, "the phase runs on while the wings are held");
        for t in &targets {
            assert!((t[FLAP] - 0.2 * half[FLAP]).abs() < 1e-6 && t[FLAP] == t[FLAP_RIGHT], "{t:?}");
            assert!((t[PITCH_LEFT] - 0.1 * half[PITCH_LEFT]).abs() < 1e-6, "{t:?}");
            assert!((t[PITCH_RIGHT] + 0.1 * half[PITCH_RIGHT]).abs() < 1e-6, "{t:?}");
            assert!((t[TAIL] + 0.4 * half[TAIL]).abs() < 1e-6);
        }
    }
}

/// Upward zero crossings of the left flap target.
fn cycles(targets: &[[f64; 5]]) -> usize {
    targets.windows(2).filter(|w| w[0][FLAP] < 0.0 && w[1][FLAP] >= 0.0).count()
}

#[test]
fn the_oscillator_flaps_both_wings_together_at_the_asked_frequency_and_amplitude() {
    let map = action_map(ActionMode::FlapOscillator);
    let half = map.half_range_rad();
    let [low_hz, high_hz] = ControlConfig::default().flap_frequency_hz;
    let steps = 200; // 4 s
    for (frequency_action, hz) in [(-1.0, low_hz), (1.0, high_hz), (0.0, 0.5 * (low_hz + high_hz))] {
        for amplitude in [1.0f32, 0.5] {
            let (targets, _) = hold(&map, [amplitude, frequency_action, 0.0, 0.0, 0.0], steps);
            let expected = hz * steps as f64 * PERIOD_S;
            assert!((cycles(&targets) as f64 - expected).abs() <= 1.0, "{hz} Hz: {} cycles", cycles(&targets));
            let peak = targets.iter().map(|t| t[FLAP].abs()).fold(0.0, f64::max);
            let asked = amplitude as f64 * half[FLAP];
            assert!(peak <= asked + 1e-12 && peak > 0.9 * asked, "{hz} Hz: peak {peak}, asked {asked}");
            assert!(targets.iter().all(|t| t[FLAP] == t[FLAP_RIGHT]));
        }
    }
}

#[test]
fn the_wing_pitch_swing_leads_the_flap_by_a_quarter_cycle() {
    let map = action_map(ActionMode::FlapOscillator);
    let amplitude = 0.5 * map.half_range_rad()[FLAP];
    let swing = PITCH_SWING_PER_FLAP * amplitude;
    let (targets, _) = hold(&map, [0.5, -0.3, 0.0, 0.0, 0.0], 150);
    // flap = A sin(phase), pitch = S cos(phase): every step lies on the ellipse, and the pitch reaches
    // its peak (leading edge down) as the flap crosses zero going up.
    for t in &targets {
        let on_ellipse = (t[FLAP] / amplitude).powi(2) + (t[PITCH_LEFT] / swing).powi(2);
        assert!((on_ellipse - 1.0).abs() < 1e-9, "{t:?}");
        assert_eq!(t[PITCH_LEFT], t[PITCH_RIGHT]);
    }
    let rising = targets.windows(2).find(|w| w[0][FLAP] < 0.0 && w[1][FLAP] >= 0.0).unwrap();
    assert!(rising[1][PITCH_LEFT] > 0.9 * swing, "{rising:?}");
    // The phase advances by 2 pi f per second: after one step at the middle of the range...
    let mut oscillator = OscillatorState::default();
    map.to_targets(&[0.5, 0.0, 0.0, 0.0, 0.0], &mut oscillator);
    let phase = oscillator.phase_rad;
    let [low_hz, high_hz] = ControlConfig::default().flap_frequency_hz;
    assert!((phase - TAU * 0.5 * (low_hz + high_hz) * PERIOD_S).abs() < 1e-12);
}

#[test]
fn oscillator_wing_pitch_stays_inside_its_joint_range() {
    let map = action_map(ActionMode::FlapOscillator);
    let half = map.half_range_rad();
    let (targets, _) = hold(&map, [1.0, 0.3, 1.0, 1.0, 1.0], 100);
    assert!(
        targets.iter().all(|t| t[PITCH_LEFT].abs() <= half[PITCH_LEFT] && t[PITCH_RIGHT].abs() <= half[PITCH_RIGHT])
    );
    // Full differential: the left wing at its limit, the right one flat apart from its swing.
    assert!(targets.iter().any(|t| t[PITCH_LEFT] == half[PITCH_LEFT]));
}

#[test]
fn the_flap_bias_moves_the_centre_of_the_stroke() {
    let map = action_map(ActionMode::FlapOscillator);
    let half = map.half_range_rad()[FLAP];
    // 3 Hz for 1 s: three whole cycles in 50 steps, so the mean is the centre.
    let (targets, _) = hold(&map, [0.3, -1.0, 0.5, 0.0, 0.0], 50);
    let mean = targets.iter().map(|t| t[FLAP]).sum::<f64>() / targets.len() as f64;
    assert!((mean - 0.5 * half).abs() < 1e-6 * half, "{mean}");
    let (low, high) = targets.iter().fold((f64::MAX, f64::MIN), |(l, h), t| (l.min(t[FLAP]), h.max(t[FLAP])));
    assert!(low > 0.19 * half && high <= 0.8 * half + 1e-12, "{low} {high}");
}

#[test]
fn the_oscillator_records_the_clipped_action_as_the_previous_action() {
    let map = action_map(ActionMode::FlapOscillator);
    let action = [1.5, -0.2, f32::INFINITY, 0.1, -3.0];
    let targets = map.to_targets(&action, &mut OscillatorState::default());
    assert_eq!(map.applied(&action, &targets), [1.0, -0.2, 0.0, 0.1, -1.0]);
    let half = map.half_range_rad();
    let at_rest = map.at_rest(&[0.3 * half[0], 0.1 * half[1], 0.1 * half[2], -0.1 * half[3], 0.05 * half[4]]);
    assert_eq!(at_rest[0..2], [0.0, 0.0], "an episode starts with the wings held");
    let expected = [0.2, 0.1, 0.05];
    assert!(at_rest[2..].iter().zip(expected).all(|(a, e)| (a - e).abs() < 1e-6), "{at_rest:?}");
    assert_eq!(TaskConfig::default().control.action_mode, ActionMode::JointTargets);
}

#[test]
fn a_roll_action_takes_lift_from_one_wing_by_its_pitch_and_with_differential_flap_by_its_amplitude() {
    let sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let control =
        |k| ControlConfig { action_mode: ActionMode::FlapOscillator, differential_flap: k, ..Default::default() };
    let peak = |targets: &[[f64; 5]], joint: usize| targets.iter().map(|t| t[joint].abs()).fold(0.0, f64::max);
    let rolling = [0.6, 0.0, 0.0, 0.5, 0.0];
    let (pitch_only, _) = hold(&ActionMap::new(&sim, &control(0.0), PERIOD_S), rolling, 100);
    assert_eq!(peak(&pitch_only, FLAP), peak(&pitch_only, FLAP_RIGHT), "k = 0: the wings flap alike");
    // Leading edge down on the left (less lift), up on the right, in the mean over the cycle.
    let mean =
        |targets: &[[f64; 5]], joint: usize| targets.iter().map(|t| t[joint]).sum::<f64>() / targets.len() as f64;
    assert!(mean(&pitch_only, PITCH_LEFT) > 0.0 && mean(&pitch_only, PITCH_RIGHT) < 0.0);
    let (both, _) = hold(&ActionMap::new(&sim, &control(0.5), PERIOD_S), rolling, 100);
    let ratio = peak(&both, FLAP) / peak(&both, FLAP_RIGHT);
    assert!((ratio - 0.75 / 1.25).abs() < 0.02, "left/right flap amplitude {ratio}");
    let flap_limit = ActionMap::new(&sim, &control(1.0), PERIOD_S).half_range_rad()[FLAP];
    let (saturated, _) = hold(&ActionMap::new(&sim, &control(1.0), PERIOD_S), [1.0, 0.0, 0.0, -1.0, 0.0], 100);
    assert!(peak(&saturated, FLAP) <= flap_limit && peak(&saturated, FLAP_RIGHT) == 0.0);
}

#[test]
fn an_amplitude_above_the_flap_limit_flattens_the_stroke_at_the_limit() {
    let sim = RobotModel::flapper().unwrap().instantiate().unwrap();
    let map = |max| {
        let control =
            ControlConfig { action_mode: ActionMode::FlapOscillator, flap_amplitude_max: max, ..Default::default() };
        ActionMap::new(&sim, &control, PERIOD_S)
    };
    let limit = map(1.0).half_range_rad()[FLAP];
    let at_limit = |targets: &[[f64; 5]]| targets.iter().filter(|t| t[FLAP].abs() >= limit - 1e-12).count();
    let (sine, _) = hold(&map(1.0), [1.0, -0.3, 0.0, 0.0, 0.0], 200);
    let (flattened, _) = hold(&map(2.0), [1.0, -0.3, 0.0, 0.0, 0.0], 200);
    assert!(flattened.iter().all(|t| t[FLAP].abs() <= limit));
    // |sin(phase)| >= 1/2 for two thirds of the cycle: about 133 of 200 steps sit at the limit with twice it.
    assert!(
        at_limit(&sine) < 10 && (120..=145).contains(&at_limit(&flattened)),
        "{} {}",
        at_limit(&sine),
        at_limit(&flattened)
    );
    let (half, _) = hold(&map(2.0), [0.25, -0.3, 0.0, 0.0, 0.0], 200);
    let peak = half.iter().map(|t| t[FLAP].abs()).fold(0.0, f64::max);
    assert!(peak <= 0.5 * limit + 1e-12 && peak > 0.45 * limit, "a quarter of twice the limit: {peak}");
}

#[test]
fn the_shape_filter_smooths_amplitude_bias_and_roll_but_not_the_tail() {
    let map = map_for(ControlConfig {
        action_mode: ActionMode::FlapOscillator,
        flap_shape_filter_hz: 2.0,
        ..Default::default()
    });
    let half = map.half_range_rad();
    let mut oscillator = OscillatorState::default();
    // A bias and a roll dithered at 25 Hz (+1, -1, ...) stay near their mean of 0; the tail does not.
    let mut shapes = Vec::new();
    for k in 0..100 {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        let t = map.to_targets(&[-1.0, 0.0, sign, sign, -0.5 * sign], &mut oscillator);
        shapes.push((oscillator.bias, t[PITCH_LEFT] / half[PITCH_LEFT]));
        assert!((t[TAIL] + 0.5 * sign as f64 * half[TAIL]).abs() < 1e-6);
    }
    assert!(shapes[10..].iter().all(|(b, p)| b.abs() < 0.15 && p.abs() < 0.15), "{:?}", &shapes[..12]);
    // After a step to 1, one time constant (1 / (2 pi 2 Hz) = 80 ms, 4 steps) covers about 63%.
    let mut oscillator = OscillatorState::default();
    let bias_after = |steps: usize, oscillator: &mut OscillatorState| {
        (0..steps).for_each(|_| {
            map.to_targets(&[-1.0, 0.0, 1.0, 0.0, 0.0], oscillator);
        });
        oscillator.bias
    };
    let early = bias_after(4, &mut oscillator);
    assert!((0.55..0.75).contains(&early), "{early}");
    assert!(bias_after(60, &mut oscillator) > 0.99);
    // The amplitude too: a held wing asked to flap fully reaches the amplitude only gradually.
    let mut oscillator = OscillatorState::default();
    map.to_targets(&[1.0, 0.0, 0.0, 0.0, 0.0], &mut oscillator);
    assert!(oscillator.amplitude > 0.0 && oscillator.amplitude < 0.3, "{}", oscillator.amplitude);
}

#[test]
fn the_rate_limit_caps_how_fast_the_shape_moves_without_delaying_a_slow_change() {
    let map = map_for(ControlConfig {
        action_mode: ActionMode::FlapOscillator,
        flap_shape_rate_limit: 4.0,
        ..Default::default()
    });
    let max_step = 4.0 * PERIOD_S;
    // A bias and a roll dithered at 25 Hz (+1, -1, ...) move at most 0.08 per step: they stay within
    // one step of their start; the amplitude asked to go from 0 to 1 ramps at the rate.
    let mut oscillator = OscillatorState::default();
    for k in 0..50 {
        let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
        map.to_targets(&[1.0, 0.0, sign, sign, 0.0], &mut oscillator);
        assert!(oscillator.bias.abs() <= max_step + 1e-12 && oscillator.roll.abs() <= max_step + 1e-12);
        let expected = (max_step * (k + 1) as f64).min(1.0);
        assert!((oscillator.amplitude - expected).abs() < 1e-12, "step {k}: {}", oscillator.amplitude);
    }
    // A change slower than the limit passes undelayed: a ramp of 0.02 per step is followed exactly.
    let mut oscillator = OscillatorState::default();
    for k in 1..=40 {
        let asked = 0.02 * k as f64;
        map.to_targets(&[-1.0, 0.0, asked as f32, 0.0, 0.0], &mut oscillator);
        assert!((oscillator.bias - asked).abs() < 1e-6, "step {k}: {} for {asked}", oscillator.bias);
    }
}

#[test]
fn a_wing_pitch_second_action_pitches_both_wings_alike_at_a_fixed_frequency_and_starts_where_they_are() {
    use flapper_task::config::OscillatorA2;
    let control = ControlConfig {
        action_mode: ActionMode::FlapOscillator,
        oscillator_a2: OscillatorA2::WingPitch,
        flap_frequency_hz: [5.0, 6.0],
        ..Default::default()
    };
    let map = map_for(control);
    let half = map.half_range_rad();
    // Held wings: a2 adds to both pitches on top of the roll's differential.
    let (targets, _) = hold(&map, [-1.0, 0.3, 0.0, 0.1, 0.0], 5);
    let t = targets[4];
    assert!((t[PITCH_LEFT] - 0.4 * half[PITCH_LEFT]).abs() < 1e-6, "{t:?}");
    assert!((t[PITCH_RIGHT] - 0.2 * half[PITCH_RIGHT]).abs() < 1e-6, "{t:?}");
    // Flapping: 5.5 Hz whatever a2 asks (22 cycles in 4 s).
    for second in [-1.0f32, 1.0] {
        let (targets, _) = hold(&map, [1.0, second, 0.0, 0.0, 0.0], 200);
        assert!((cycles(&targets) as f64 - 22.0).abs() <= 1.0, "a2 {second}: {} cycles", cycles(&targets));
    }
    // A robot at rest with both wings pitched +0.2 and +0.1 starts with a2 = 0.15 and its roll at 0.05,
    // and its first held-wing targets are where the wings are.
    let pose = [0.0, 0.2 * half[PITCH_LEFT], 0.0, 0.1 * half[PITCH_RIGHT], 0.0];
    let at_rest = map.at_rest(&pose);
    assert!((at_rest[1] - 0.15).abs() < 1e-6 && (at_rest[3] - 0.05).abs() < 1e-6, "{at_rest:?}");
    let mut oscillator = map.oscillator_at_rest(&at_rest);
    let first = map.to_targets(&at_rest, &mut oscillator);
    assert!(first.iter().zip(pose).all(|(t, p)| (t - p).abs() < 1e-6), "{first:?} from {pose:?}");
}

#[test]
fn passive_feathering_adds_each_wing_s_own_flap_rate_to_its_pitch_within_the_limit() {
    let map = action_map(ActionMode::JointTargets);
    let half = map.half_range_rad();
    let mut oscillator = OscillatorState::default();
    let asked = map.to_targets(&[0.3, 0.1, -0.3, -0.1, 0.2], &mut oscillator);
    // The left wing flapping up at 8 rad/s, the right one down at 2 rad/s.
    let rates = [8.0, 0.0, -2.0, 0.0, 0.0];
    let mut feathered = asked;
    map.feather(&mut feathered, &rates, 0.02);
    assert!((feathered[PITCH_LEFT] - (asked[PITCH_LEFT] + 0.16)).abs() < 1e-12);
    assert!((feathered[PITCH_RIGHT] - (asked[PITCH_RIGHT] - 0.04)).abs() < 1e-12);
    for joint in [FLAP, FLAP_RIGHT, TAIL] {
        assert_eq!(feathered[joint], asked[joint], "only the wing pitch twists");
    }
    let mut fast = asked;
    map.feather(&mut fast, &[1e3, 0.0, -1e3, 0.0, 0.0], 0.2);
    assert_eq!((fast[PITCH_LEFT], fast[PITCH_RIGHT]), (half[PITCH_LEFT], -half[PITCH_RIGHT]), "clipped to the limit");
}
