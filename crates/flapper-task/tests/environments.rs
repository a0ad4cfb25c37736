//! Environments: observation layout and frame conventions, episode ends, randomization read back
//! from the model, seeded reproducibility across thread counts, and fault isolation.

use std::sync::Arc;

use flapper_sim::{BODY_NAMES, RobotModel, Vec3};
use flapper_task::config::TaskConfig;
use flapper_task::env::{FlightEnv, ReferenceSource};
use flapper_task::observation::{FRAME_SIZE, ObservationLayout};
use flapper_task::reference::Reference;
use flapper_task::reference::named::named;
use flapper_task::termination::EpisodeEnd;
use flapper_task::vec_env::FlightVecEnv;

fn robot() -> RobotModel {
    RobotModel::flapper().unwrap()
}

/// A straight, level reference along world +y: the robot must fly "north".
fn northbound() -> Arc<Reference> {
    let points = (0..2000).map(|k| Vec3::new(0.0, 3.8 * 0.02 * k as f64, 10.0)).collect();
    Arc::new(Reference::new("north", 0.02, points))
}

/// One environment flying `reference` under `config`.
fn env_on(config: TaskConfig, reference: Arc<Reference>) -> FlightEnv {
    FlightEnv::new(&robot(), Arc::new(config), ReferenceSource::Fixed(reference), 1, 0).unwrap()
}

fn exact_start(mut config: TaskConfig) -> TaskConfig {
    config.initial_state.position_offset_m = [0.0; 3];
    config.initial_state.speed_offset_mps = 0.0;
    config.initial_state.attitude_offset_deg = 0.0;
    config.initial_state.pitch_deg = 0.0;
    config
}

/// A straight path at 3.8 m/s forward sinking (or climbing) at `vertical` m/s, 2 s (dt 0.02 s).
fn sloped(vertical: f64) -> Arc<Reference> {
    let points = (0..=100).map(|k| Vec3::new(3.8 * 0.02 * k as f64, 0.0, 10.0 + vertical * 0.02 * k as f64)).collect();
    Arc::new(Reference::new(format!("slope {vertical}"), 0.02, points))
}

/// A path at 3.8 m/s turning left at `rate_degps` and sinking (or climbing) at `vertical` m/s, 2 s (dt 0.02 s).
fn turning(rate_degps: f64, vertical: f64) -> Arc<Reference> {
    let rate = rate_degps.to_radians();
    let radius = 3.8 / rate;
    let points = (0..=100)
        .map(|k| {
            let angle = rate * 0.02 * k as f64;
            Vec3::new(radius * angle.sin(), radius * (1.0 - angle.cos()), 10.0 + vertical * 0.02 * k as f64)
        })
        .collect();
    Arc::new(Reference::new(format!("turn {rate_degps} deg/s, vertical {vertical}"), 0.02, points))
}

/// The energy's price share at the start of `reference` under `config` (from the exact start), and the
/// fifth step of a full stroke, when the joints work and the energy kernel is well below its top.
fn stroke_priced(config: TaskConfig, reference: Arc<Reference>) -> (f64, flapper_task::env::StepResult) {
    let mut env =
        FlightEnv::new(&robot(), Arc::new(exact_start(config)), ReferenceSource::Fixed(reference), 1, 0).unwrap();
    let share = env.energy_price_share();
    let step = (0..5).map(|_| env.step(&[1.0, 0.0, 1.0, 0.0, 0.0])).last().unwrap();
    (share, step)
}

#[test]
fn observation_has_540_named_numbers() {
    let layout = ObservationLayout { history_frames: 25, lookahead_steps: 30, clock: false };
    assert_eq!(layout, ObservationLayout::paper());
    assert_eq!(FRAME_SIZE, 18);
    assert_eq!(layout.size(), 540);
    let names = layout.names();
    assert_eq!(names.len(), 540);
    let unique: std::collections::HashSet<_> = names.iter().collect();
    assert_eq!(unique.len(), 540);
    assert_eq!(names[0], "t-24.quat_w");
    assert_eq!(names[449], "t-0.action.tail_pitch");
    assert_eq!(names[450], "ahead+01.x_body_m");
    assert_eq!(names[539], "ahead+30.z_body_m");
}

#[test]
fn a_clock_closes_the_observation_turning_at_its_frequency_and_leaves_the_rest_as_it_was() {
    let run = |clock_hz: f64, steps: usize| {
        let mut config = exact_start(TaskConfig::default());
        config.observation.clock_hz = clock_hz;
        let mut env = FlightEnv::new(&robot(), Arc::new(config), ReferenceSource::Fixed(northbound()), 1, 0).unwrap();
        let mut seen = Vec::new();
        for _ in 0..steps {
            env.step(&[0.5, 0.0, 0.5, 0.0, -0.2]);
            let mut obs = vec![0.0f32; env.observation_layout().size()];
            env.observe(&mut obs);
            seen.push(obs);
        }
        (env.observation_layout(), seen)
    };
    let (plain_layout, plain) = run(0.0, 12);
    let (layout, clocked) = run(5.0, 12);
    assert_eq!((plain_layout.size(), layout.size()), (540, 542));
    assert_eq!(&layout.names()[540..], &["clock.sin", "clock.cos"]);
    for (k, (without, with)) in plain.iter().zip(&clocked).enumerate() {
        assert_eq!(&with[..540], &without[..], "step {k}: the clock changed the flight or the other numbers");
        // After k + 1 steps of 20 ms at 5 Hz the phase is 0.2 pi (k + 1): a turn every 10 steps.
        let phase = 0.2 * std::f64::consts::PI * (k + 1) as f64;
        let (sin, cos) = (with[540] as f64, with[541] as f64);
        assert!((sin - phase.sin()).abs() < 1e-6 && (cos - phase.cos()).abs() < 1e-6, "step {k}: {sin} {cos}");
    }
}

#[test]
fn a_robot_flying_straight_at_its_target_sees_it_straight_ahead() {
    let config = Arc::new(exact_start(TaskConfig::default()));
    let env = FlightEnv::new(&robot(), config, ReferenceSource::Fixed(northbound()), 1, 0).unwrap();
    let layout = env.observation_layout();
    let mut obs = vec![0.0f32; layout.size()];
    env.observe(&mut obs);
    let ahead = &obs[layout.lookahead_start()..];
    for (i, point) in ahead.chunks(3).enumerate() {
        let expected = 3.8 * 0.02 * (i + 1) as f32;
        assert!((point[0] - expected).abs() < 1e-4, "point {i}: x_body {} expected {expected}", point[0]);
        assert!(point[1].abs() < 1e-5 && point[2].abs() < 1e-5, "point {i}: off axis {point:?}");
    }
    // The newest frame holds the orientation (yawed 90 degrees), the airspeed and zero joints.
    let newest = &obs[(25 - 1) * FRAME_SIZE..25 * FRAME_SIZE];
    let half = std::f32::consts::FRAC_1_SQRT_2;
    assert!((newest[0] - half).abs() < 1e-6 && (newest[3] - half).abs() < 1e-6, "quaternion {:?}", &newest[0..4]);
    assert!((newest[12] - 3.8).abs() < 1e-5, "pitot airspeed {}", newest[12]);
    assert!(newest[7..12].iter().all(|q| q.abs() < 1e-9));
}

#[test]
fn history_shifts_by_one_frame_per_step() {
    let config = Arc::new(exact_start(TaskConfig::default()));
    let mut env = FlightEnv::new(&robot(), config, ReferenceSource::Fixed(northbound()), 1, 0).unwrap();
    let size = env.observation_layout().size();
    let (mut before, mut after) = (vec![0.0f32; size], vec![0.0f32; size]);
    env.step(&[0.5, 0.0, 0.5, 0.0, -0.2]);
    env.observe(&mut before);
    env.step(&[-0.5, 0.0, -0.5, 0.0, -0.2]);
    env.observe(&mut after);
    assert_eq!(&after[..24 * FRAME_SIZE], &before[FRAME_SIZE..25 * FRAME_SIZE]);
    // The newest frame carries the action just taken.
    assert_eq!(&after[24 * FRAME_SIZE + 13..25 * FRAME_SIZE], &[-0.5, 0.0, -0.5, 0.0, -0.2]);
}

#[test]
fn the_action_rate_term_reads_the_change_of_the_applied_action_and_joins_the_reward_only_when_weighted() {
    use flapper_task::config::ActionMode;
    let env = |mode: ActionMode, weight: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.control.action_mode = mode;
        config.reward.action_rate_weight = weight;
        env_on(config, northbound())
    };
    let (a, b) = ([0.3f32, 0.0, 0.3, 0.0, -0.2], [-0.3f32, 0.0, -0.3, 0.0, -0.2]);
    for mode in [ActionMode::JointTargets, ActionMode::FlapOscillator] {
        let (mut plain, mut weighted) = (env(mode, 0.0), env(mode, 0.5));
        for (step, action) in [a, a, b].into_iter().enumerate() {
            let (p, w) = (plain.step(&action), weighted.step(&action));
            // The same flight and kernels: the weight changes the reward, not the physics.
            assert_eq!((p.position_error_m, p.terms), (w.position_error_m, w.terms), "{mode:?}");
            assert!((w.reward - p.reward - 0.5 * w.terms.action_rate).abs() < 1e-12, "{mode:?}");
            match step {
                // Holding the action: no change, the kernel's top.
                1 => assert_eq!(w.terms.action_rate, 1.0, "{mode:?}"),
                // Two numbers jumping by 0.6 each: exp(-(0.6^2 + 0.6^2) / 1.0^2).
                2 => assert!((w.terms.action_rate - (-0.72f64).exp()).abs() < 1e-6, "{mode:?}: {:?}", w.terms),
                _ => {}
            }
        }
    }
}

#[test]
fn the_flap_rate_term_prices_the_flown_stroke_above_its_bar_and_joins_the_reward_only_when_weighted() {
    let env = |weight: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.flap_rate_weight = weight;
        config.reward.flap_max_hz = 5.5;
        env_on(config, northbound())
    };
    // Both flaps driven as a sine of `hz` for 0.6 s (before the unsteered robot tumbles); the last
    // step's kernel.
    let fly = |hz: f64| {
        let (mut plain, mut weighted) = (env(0.0), env(0.5));
        let mut last = None;
        for k in 0..30 {
            let flap = (0.8 * (std::f64::consts::TAU * hz * k as f64 * 0.02).sin()) as f32;
            let action = [flap, 0.0, flap, 0.0, -0.2];
            let (p, w) = (plain.step(&action), weighted.step(&action));
            assert!(p.end.is_none(), "{hz} Hz: ended at step {k}");
            // The same flight and the other kernels: the weight changes the reward, not the physics;
            // unweighed, the kernel reads 0.
            let unweighed = flapper_task::reward::RewardTerms { flap_rate: 0.0, ..w.terms };
            assert_eq!((p.position_error_m, p.terms), (w.position_error_m, unweighed), "{hz} Hz");
            assert!((w.reward - p.reward - 0.5 * w.terms.flap_rate).abs() < 1e-12, "{hz} Hz");
            last = Some(w.terms.flap_rate);
        }
        last.unwrap()
    };
    assert_eq!(fly(4.0), 1.0, "a 4 Hz stroke is within the bar");
    let fast = fly(7.0);
    // 1.5 Hz above the bar at a 0.5 Hz scale: exp(-9), read from the joint's own tops.
    assert!(fast < 1e-3, "a 7 Hz stroke reads {fast}");
    // Held wings: no stroke, the kernel's top.
    let mut held = env(0.5);
    for _ in 0..40 {
        assert_eq!(held.step(&[0.0, 0.0, 0.0, 0.0, -0.2]).terms.flap_rate, 1.0);
    }
}

#[test]
fn the_glide_hold_term_pays_held_wings_on_a_glide_slope_and_nothing_to_a_stroke_or_on_a_level_path() {
    let env = |weight: f64, reference: Arc<Reference>| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.glide_hold_weight = weight;
        env_on(config, reference)
    };
    // 0.8 s (40 steps) of held wings or of a 5 Hz stroke; every step's kernel.
    let fly = |weight: f64, reference: Arc<Reference>, stroke: bool| {
        let mut env = env(weight, reference);
        (0..40)
            .map(|k| {
                let flap =
                    if stroke { (0.8 * (std::f64::consts::TAU * 5.0 * k as f64 * 0.02).sin()) as f32 } else { 0.0 };
                env.step(&[flap, 0.0, flap, 0.0, -0.2])
            })
            .collect::<Vec<_>>()
    };
    let glide = sloped(-0.83);
    let held = fly(0.3, glide.clone(), false);
    let unweighed = fly(0.0, glide.clone(), false);
    for (w, p) in held.iter().zip(&unweighed) {
        // Held wings on a glide slope (their servos settling within 1 deg) earn nearly the kernel's top
        // times the slope's share (1 here), from the start.
        assert!(w.terms.glide_hold > 0.99, "{:?}", w.terms);
        // The weight changes the reward, not the flight; unweighed, the kernel reads 0.
        let without = flapper_task::reward::RewardTerms { glide_hold: 0.0, ..w.terms };
        assert_eq!((p.position_error_m, p.terms), (w.position_error_m, without));
        assert!((w.reward - p.reward - 0.3 * w.terms.glide_hold).abs() < 1e-12);
    }
    // A 5 Hz stroke earns nothing once its swing is seen (0.1 s, half a stroke: some 40 deg).
    let stroke = fly(0.3, glide, true);
    assert!(stroke[5..].iter().all(|s| s.terms.glide_hold < 1e-3), "{:?}", stroke[39].terms);
    // Nowhere but on a glide slope: held wings on a level path or a climb earn nothing.
    for reference in [sloped(0.0), sloped(0.8), northbound()] {
        assert!(fly(0.3, reference, false).iter().all(|s| s.terms.glide_hold == 0.0));
    }
}

#[test]
fn the_glide_share_rises_with_the_sink_to_a_glide_slope_and_is_zero_elsewhere() {
    let share = |reference: Arc<Reference>| env_on(exact_start(TaskConfig::default()), reference).glide_share();
    assert!((share(sloped(-0.83)) - 1.0).abs() < 1e-4, "a glide slope");
    assert!((share(sloped(-0.25)) - 0.5).abs() < 1e-4, "half the full sink: half");
    for (vertical, what) in [(0.0, "level"), (0.8, "a climb"), (-1.5, "longitudinal's dive")] {
        assert!(share(sloped(vertical)).abs() < 1e-6, "{what}");
    }
}

#[test]
fn a_turn_ahead_takes_the_glide_share_only_where_its_turn_scale_is_set() {
    // The glide slope of the test above, flown on a helix turning at 60 deg/s (radius 3.63 m).
    let helix = turning(60.0, -0.83);
    let share = |scale: f64, reference: Arc<Reference>| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.glide_hold_turn_scale_degps = scale;
        env_on(config, reference).glide_share()
    };
    assert!((share(0.0, helix.clone()) - 1.0).abs() < 1e-3, "unset: a sinking turn glides in full");
    // At the turn's own rate the share falls to about 1/e (the path's direction turns at 60 deg/s
    // times the cosine of its 12 deg slope); a straight glide slope keeps it whole.
    let turn_degps = 60.0 * (0.83f64 / 3.8).atan().cos();
    let expected = (-(turn_degps / 60.0).powi(2)).exp();
    assert!((share(60.0, helix.clone()) - expected).abs() < 2e-3, "{} against {expected}", share(60.0, helix.clone()));
    assert!(share(20.0, helix) < 1e-3);
    assert!((share(20.0, sloped(-0.83)) - 1.0).abs() < 1e-4, "a straight glide slope");
}

#[test]
fn a_turn_ahead_lifts_the_energy_price_only_where_its_turn_scale_is_set() {
    // A level turn at 120 deg/s (a sharp turn's rate) and a straight level path, both at 3.8 m/s.
    let turn = turning(120.0, 0.0);
    let priced = |scale: f64, reference: Arc<Reference>| {
        let mut config = TaskConfig::default();
        config.reward.energy_turn_scale_degps = scale;
        stroke_priced(config, reference)
    };
    let (unset, unset_step) = priced(0.0, turn.clone());
    assert_eq!(unset, 1.0, "unset: a turn is priced as a straight path");
    let (at_rate, _) = priced(120.0, turn.clone());
    assert!((at_rate - (-1f64).exp()).abs() < 2e-3, "at the turn's own rate about 1/e, not {at_rate}");
    let (sharp, sharp_step) = priced(30.0, turn);
    assert!(sharp < 1e-6, "a turn at four times the scale is not priced: {sharp}");
    assert!(
        sharp_step.terms.energy > unset_step.terms.energy,
        "the same stroke earns more of r_energy where its price is lifted ({} against {})",
        sharp_step.terms.energy,
        unset_step.terms.energy
    );
    let (straight, _) = priced(30.0, sloped(0.0));
    assert_eq!(straight, 1.0, "a straight path keeps its whole price");
}

#[test]
fn an_unpowered_robot_ends_too_far_from_a_climbing_target() {
    // A reference climbing at 3 m/s: a glider falls behind and is terminated, not truncated.
    let points = (0..2000).map(|k| Vec3::new(3.8 * 0.02 * k as f64, 0.0, 10.0 + 3.0 * 0.02 * k as f64)).collect();
    let config = Arc::new(exact_start(TaskConfig::default()));
    let mut env =
        FlightEnv::new(&robot(), config, ReferenceSource::Fixed(Arc::new(Reference::new("up", 0.02, points))), 1, 0)
            .unwrap();
    let end = (0..500).find_map(|_| env.step(&[0.0; 5]).end).expect("episode should end");
    assert_eq!(end, EpisodeEnd::TooFarFromTarget);
    assert!(end.is_termination());
    assert!(env.step_count() < 200, "ended after {} steps", env.step_count());
}

#[test]
fn a_tumbling_robot_ends_on_attitude_in_stage_1_but_not_stage_3() {
    let tumble = |stage: i64| {
        let mut config = exact_start(TaskConfig::stage(stage).unwrap());
        config.episode.max_position_error_m = 1000.0;
        // Launched nose up past the vertical: upside down, heading back.
        config.initial_state.pitch_deg = 100.0;
        let mut env = env_on(config, northbound());
        (0..25).find_map(|_| env.step(&[0.0; 5]).end)
    };
    assert_eq!(tumble(1), Some(EpisodeEnd::AttitudeLimit));
    assert_ne!(tumble(3), Some(EpisodeEnd::AttitudeLimit));
}

#[test]
fn a_named_reference_is_truncated_when_it_runs_out() {
    let reference = Arc::new(named("sharp-turn", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.62).unwrap());
    let mut config = exact_start(TaskConfig::default());
    config.episode.max_position_error_m = 1000.0;
    let steps = reference.len();
    let mut env = env_on(config, reference);
    let end = (0..2000).find_map(|_| env.step(&[0.0; 5]).end);
    assert_eq!(end, Some(EpisodeEnd::ReferenceEnd));
    assert!(!EpisodeEnd::ReferenceEnd.is_termination());
    assert_eq!(env.step_count(), steps - 31);
}

#[test]
fn time_limit_truncates_after_max_steps() {
    let mut config = exact_start(TaskConfig::default());
    config.episode.max_steps = 20;
    let mut env = FlightEnv::new(&robot(), Arc::new(config), ReferenceSource::Procedural, 1, 0).unwrap();
    let end = (0..100).find_map(|_| env.step(&[0.0; 5]).end);
    assert_eq!(end, Some(EpisodeEnd::TimeLimit));
    assert_eq!(env.step_count(), 20);
}

#[test]
fn randomization_draws_within_table_iii_and_reads_back_from_the_model() {
    let robot = robot();
    let nominal = robot.instantiate().unwrap();
    let config = TaskConfig::stage(4).unwrap();
    let ranges = config.randomization.clone();
    let mut env = FlightEnv::new(&robot, Arc::new(config), ReferenceSource::Procedural, 42, 3).unwrap();
    let mut winds = Vec::new();
    for _ in 0..5 {
        let sim = env.control().sim();
        for body in BODY_NAMES {
            let ratio = sim.body_mass(body).unwrap() / nominal.body_mass(body).unwrap();
            assert!((0.9 - 1e-12..=1.1 + 1e-12).contains(&ratio), "{body} mass x{ratio}");
            let ratio = sim.body_inertia(body).unwrap()[0] / nominal.body_inertia(body).unwrap()[0];
            assert!((0.9 - 1e-12..=1.1 + 1e-12).contains(&ratio), "{body} inertia x{ratio}");
            let shift = sim.body_com(body).unwrap() - nominal.body_com(body).unwrap();
            assert!(shift.abs().max_element() <= ranges.link_com_offset_m + 1e-12);
        }
        for geom in ["wing_left", "wing_right", "tail"] {
            let (c, c0) = (
                sim.fluid_coefficients(geom).unwrap().to_array(),
                nominal.fluid_coefficients(geom).unwrap().to_array(),
            );
            for (value, base) in c.iter().zip(c0) {
                assert!((0.7 - 1e-12..=1.3 + 1e-12).contains(&(value / base)), "{geom} fluid x{}", value / base);
            }
            let m = sim.added_mass(geom).unwrap()[2] / nominal.added_mass(geom).unwrap()[2];
            assert!((0.9 - 1e-12..=1.1 + 1e-12).contains(&m));
        }
        for joint in ["flap_left", "tail_pitch"] {
            let d = sim.joint_damping(joint).unwrap() / nominal.joint_damping(joint).unwrap();
            assert!((0.9 - 1e-12..=1.1 + 1e-12).contains(&d));
        }
        let wind = sim.wind();
        assert!(wind.x.abs() <= 2.0 && wind.y.abs() <= 2.0 && wind.z.abs() <= 1.5);
        assert_eq!(wind, env.drawn_dynamics().wind_mps);
        winds.push(wind);
        env.reset().unwrap();
    }
    assert!(winds.windows(2).all(|w| w[0] != w[1]), "each episode draws anew");
    // Stage 3 leaves the model nominal.
    let plain =
        FlightEnv::new(&robot, Arc::new(TaskConfig::stage(3).unwrap()), ReferenceSource::Procedural, 42, 3).unwrap();
    assert_eq!(plain.control().sim().wind(), Vec3::ZERO);
    assert_eq!(plain.control().sim().body_mass("tail").unwrap(), nominal.body_mass("tail").unwrap());
}

#[test]
fn an_episode_fraction_leaves_the_other_episodes_nominal_in_still_air() {
    let robot = robot();
    let nominal = robot.instantiate().unwrap();
    let mut config = TaskConfig::stage(4).unwrap();
    config.randomization.episode_fraction = 0.5;
    let mut env = FlightEnv::new(&robot, Arc::new(config), ReferenceSource::Procedural, 7, 0).unwrap();
    let (mut randomized, episodes) = (0, 40);
    for _ in 0..episodes {
        let sim = env.control().sim();
        let still = sim.wind() == Vec3::ZERO;
        let nominal_mass = sim.body_mass("tail").unwrap() == nominal.body_mass("tail").unwrap();
        assert_eq!(still, nominal_mass, "an episode is randomized whole or not at all");
        assert_eq!(still, env.drawn_dynamics().joint_damping_scale.is_empty());
        randomized += usize::from(!still);
        env.reset().unwrap();
    }
    assert!((10..=30).contains(&randomized), "{randomized} of {episodes} randomized at fraction 0.5");
}

fn run(seed: u64, threads: usize, stage: i64) -> (Vec<f32>, Vec<f32>, usize) {
    let mut envs =
        FlightVecEnv::new(&robot(), TaskConfig::stage(stage).unwrap(), ReferenceSource::Procedural, 8, seed, threads)
            .unwrap();
    let mut rewards = Vec::new();
    let mut finished = 0;
    for k in 0..150 {
        let phase = k as f32 * 0.66;
        let actions: Vec<f32> = (0..8)
            .flat_map(|i| [phase.sin(), 0.3 * phase.cos(), phase.sin(), 0.3 * phase.cos(), -0.4 + 0.05 * i as f32])
            .collect();
        envs.step(&actions).unwrap();
        rewards.extend_from_slice(envs.rewards());
        finished += envs.take_finished_episodes().len();
    }
    (envs.observations().to_vec(), rewards, finished)
}

#[test]
fn same_seed_is_bit_identical_whatever_the_thread_count() {
    let one = run(11, 1, 4);
    let two = run(11, 2, 4);
    let three = run(11, 3, 4);
    assert_eq!(one, two);
    assert_eq!(one, three);
    assert_ne!(one.1, run(12, 2, 4).1, "another seed gives another run");
}

#[test]
fn finished_episodes_reset_automatically_and_report_why() {
    let mut envs = FlightVecEnv::new(&robot(), TaskConfig::default(), ReferenceSource::Procedural, 4, 5, 2).unwrap();
    let mut infos = Vec::new();
    for _ in 0..400 {
        envs.step(&[0.0; 20]).unwrap();
        for (i, (&terminated, &truncated)) in envs.terminated().iter().zip(envs.truncated()).enumerate() {
            assert!(!(terminated && truncated), "env {i} both terminated and truncated");
        }
        infos.extend(envs.take_finished_episodes());
    }
    assert!(!infos.is_empty(), "unpowered robots should fall away from the reference");
    for info in &infos {
        assert_eq!(info.end, EpisodeEnd::TooFarFromTarget);
        assert!(info.length > 0 && info.episode_return > 0.0);
        assert!(info.term_sums.position <= info.length as f64);
    }
    // After a reset the episode counter restarted.
    assert!(envs.envs().iter().all(|e| e.step_count() < 400));
}

#[test]
fn a_simulation_fault_ends_only_that_episode_and_is_counted() {
    let mut envs = FlightVecEnv::new(&robot(), TaskConfig::default(), ReferenceSource::Procedural, 4, 5, 2).unwrap();
    envs.step(&[0.0; 20]).unwrap();
    let size = envs.observation_size();
    let before_fault = envs.observations()[2 * size..3 * size].to_vec();
    envs.envs_mut()[2].sim_mut().set_wind(Vec3::new(1e12, 0.0, 0.0)).unwrap();
    envs.step(&[0.0; 20]).unwrap();
    let infos = envs.take_finished_episodes();
    assert_eq!(infos.len(), 1, "{infos:?}");
    assert_eq!((infos[0].env_index, infos[0].end), (2, EpisodeEnd::SimulationFault));
    assert_eq!(envs.simulation_faults(), 1);
    assert!(envs.truncated()[2] && !envs.terminated()[2]);
    assert_eq!(envs.rewards()[2], 0.0, "a broken state earns nothing");
    // The learner bootstraps a truncated episode from its final observation: after a fault that is
    // the last sound one (the observation the faulting action was chosen on), never the broken state.
    assert_eq!(&envs.final_observations()[2 * size..3 * size], before_fault.as_slice());
    assert!(envs.observations().iter().all(|x| x.is_finite()));
    // The faulted environment was reset with nominal wind and flies on.
    assert_eq!(envs.envs()[2].control().sim().wind(), Vec3::ZERO);
    envs.step(&[0.0; 20]).unwrap();
    assert!(envs.take_finished_episodes().is_empty());
}

#[test]
fn a_truncated_episode_keeps_its_final_observation_and_restart_replays_the_start() {
    let mut config = TaskConfig::default();
    config.episode.max_steps = 3;
    let mut envs = FlightVecEnv::new(&robot(), config.clone(), ReferenceSource::Procedural, 2, 11, 1).unwrap();
    // The same environment 1, stepped alone with the same actions, observed before any reset.
    let mut twin = FlightEnv::new(&robot(), Arc::new(config), ReferenceSource::Procedural, 11, 1).unwrap();
    let size = envs.observation_size();
    let first = envs.observations().to_vec();
    let action = [0.1f32, -0.2, 0.1, -0.2, -0.3];
    for step in 0..3 {
        envs.step(&[action, action].concat()).unwrap();
        twin.step(&action);
        assert_eq!(envs.truncated()[1], step == 2);
    }
    let mut expected = vec![0.0; size];
    twin.observe(&mut expected);
    assert_eq!(
        &envs.final_observations()[size..2 * size],
        expected.as_slice(),
        "the last observation before the reset"
    );
    assert_ne!(&envs.observations()[size..], expected.as_slice(), "the current observation is the new episode's");

    // Restarting from the construction seed gives the first episode's start again.
    envs.restart(11).unwrap();
    assert_eq!(envs.observations(), first.as_slice());
}

/// Steps `envs` with a flapping pattern for `steps` steps; returns every reward and finished episode.
fn fly(envs: &mut FlightVecEnv, steps: usize, from: usize) -> (Vec<f32>, Vec<(usize, usize, EpisodeEnd)>) {
    let n = envs.len();
    let (mut rewards, mut ends) = (Vec::new(), Vec::new());
    for k in from..from + steps {
        let phase = k as f32 * 0.66;
        let actions: Vec<f32> = (0..n)
            .flat_map(|i| [phase.sin(), 0.3 * phase.cos(), phase.sin(), 0.3 * phase.cos(), -0.4 + 0.05 * i as f32])
            .collect();
        envs.step(&actions).unwrap();
        rewards.extend_from_slice(envs.rewards());
        ends.extend(envs.take_finished_episodes().into_iter().map(|e| (e.env_index, e.length, e.end)));
    }
    (rewards, ends)
}

#[test]
fn a_snapshot_continues_every_episode_bit_for_bit() {
    // Stage 4: procedural references, randomized dynamics and wind, all redrawn from the snapshot.
    snapshot_continues(TaskConfig::stage(4).unwrap());
}

#[test]
fn a_snapshot_continues_the_flapping_oscillator_in_its_phase_and_filtered_shape() {
    let mut config = TaskConfig::stage(4).unwrap();
    config.control.action_mode = flapper_task::config::ActionMode::FlapOscillator;
    config.control.flap_shape_filter_hz = 2.0;
    snapshot_continues(config);
}

#[test]
fn a_snapshot_continues_the_flap_rhythm_that_the_flap_price_reads() {
    // `fly` flaps at 5.25 Hz: above a 4 Hz bar the price bites from the second top on, and a rhythm not
    // carried over would read 0 Hz (no price) for the first strokes after the restore.
    let mut config = TaskConfig::stage(4).unwrap();
    config.reward.flap_rate_weight = 0.2;
    config.reward.flap_max_hz = 4.0;
    config.reward.flap_rate_glide_share = 0.5;
    snapshot_continues(config);
}

#[test]
fn a_snapshot_continues_the_flap_swing_that_the_glide_hold_reads() {
    // A 5 Hz stroke on a glide slope reads nothing of the kernel's top; a swing not carried over would
    // see only the other environment's first steps' small swing, or none, after the restore.
    let mut config = exact_start(TaskConfig::default());
    config.reward.glide_hold_weight = 0.3;
    let stroke = |k: usize| {
        let flap = (0.8 * (std::f64::consts::TAU * 5.0 * k as f64 * 0.02).sin()) as f32;
        [flap, 0.0, flap, 0.0, -0.2]
    };
    let mut original = env_on(config.clone(), sloped(-0.83));
    (0..30).for_each(|k| _ = original.step(&stroke(k)));
    let snapshot = original.snapshot();
    let mut resumed = env_on(config, sloped(-0.83));
    (0..3).for_each(|_| _ = resumed.step(&[0.0, 0.0, 0.0, 0.0, -0.2]));
    resumed.restore(&snapshot).unwrap();
    for k in 30..45 {
        let (a, b) = (original.step(&stroke(k)), resumed.step(&stroke(k)));
        assert!(a.terms.glide_hold < 1e-3, "step {k}: {:?}", a.terms);
        assert_eq!((a.reward, a.terms), (b.reward, b.terms), "step {k}");
    }
}

fn snapshot_continues(config: TaskConfig) {
    let mut original = FlightVecEnv::new(&robot(), config.clone(), ReferenceSource::Procedural, 5, 21, 2).unwrap();
    original.spread_first_time_limits(3);
    fly(&mut original, 37, 0);
    let snapshot = original.snapshot();
    // Another batch of the same seed, elsewhere in its own episodes, takes over from the snapshot.
    let mut resumed = FlightVecEnv::new(&robot(), config, ReferenceSource::Procedural, 5, 21, 1).unwrap();
    fly(&mut resumed, 11, 0);
    resumed.restore(&snapshot).unwrap();
    assert_eq!(resumed.observations(), original.observations());
    let a = fly(&mut original, 400, 37);
    let b = fly(&mut resumed, 400, 37);
    assert!(!a.1.is_empty(), "episodes end and restart within the comparison");
    assert_eq!(a, b);
    assert_eq!(resumed.observations(), original.observations());
    // A snapshot of another batch size is refused.
    let mut other =
        FlightVecEnv::new(&robot(), TaskConfig::stage(4).unwrap(), ReferenceSource::Procedural, 4, 21, 1).unwrap();
    assert!(other.restore(&snapshot).is_err());
}

#[test]
fn first_episodes_end_at_spread_out_times_and_later_ones_run_full_length() {
    let mut config = exact_start(TaskConfig::default());
    config.episode.max_steps = 40;
    let north = ReferenceSource::Fixed(northbound());
    let mut envs = FlightVecEnv::new(&robot(), config, north, 16, 9, 2).unwrap();
    envs.spread_first_time_limits(4);
    let mut first_lengths = vec![None; 16];
    let mut later_lengths = Vec::new();
    for _ in 0..120 {
        envs.step(&[0.0; 80]).unwrap();
        for e in envs.take_finished_episodes() {
            assert_eq!(e.end, EpisodeEnd::TimeLimit, "a gliding robot stays within 3 m for 40 steps");
            match first_lengths[e.env_index] {
                None => first_lengths[e.env_index] = Some(e.length),
                Some(_) => later_lengths.push(e.length),
            }
        }
    }
    let first: Vec<usize> = first_lengths.into_iter().map(|l| l.expect("every first episode ended")).collect();
    let distinct: std::collections::HashSet<_> = first.iter().collect();
    assert!(distinct.len() >= 8, "first episodes end at many different steps: {first:?}");
    assert!(first.iter().all(|&l| (1..=40).contains(&l)));
    assert!(!later_lengths.is_empty() && later_lengths.iter().all(|&l| l == 40), "{later_lengths:?}");
}

#[test]
fn a_reference_sampled_at_another_step_than_the_control_period_is_refused() {
    let robot = robot();
    let config = Arc::new(TaskConfig::stage(3).unwrap());
    let period = config.control_period_s(robot.timestep_s());
    let at =
        |dt_s: f64| ReferenceSource::Fixed(Arc::new(named("cruise", Vec3::new(0.0, 0.0, 10.0), dt_s, 1.0).unwrap()));
    let error =
        FlightEnv::new(&robot, config.clone(), at(period / 2.0), 1, 0).err().expect("half the period is refused");
    assert!(error.to_string().contains("control period"), "{error}");
    let mut env = FlightEnv::new(&robot, config.clone(), at(period), 1, 0).unwrap();
    assert!(env.set_reference_source(at(2.0 * period)).is_err());
    assert!(env.set_reference_source(at(period)).is_ok());
}

#[test]
fn the_smoothness_weight_is_one_without_its_scale_and_falls_where_the_reference_turns() {
    let reference = Arc::new(named("loop", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.62).unwrap());
    let weights = |scale: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.episode.max_position_error_m = 1000.0;
        config.reward.smoothness_turn_scale_degps = scale;
        let mut env = env_on(config, reference.clone());
        let mut weights = vec![env.smoothness_weight()];
        while env.step(&[0.0; 5]).end.is_none() {
            weights.push(env.smoothness_weight());
        }
        weights
    };
    assert!(weights(0.0).iter().all(|&w| w == 1.0));
    let weighted = weights(30.0);
    // 3 s of cruise (150 steps), the loop from 3 to 6 s: weight 1 until the 0.6 s lookahead reaches it.
    assert!(weighted[..115].iter().all(|&w| (w - 1.0).abs() < 1e-6), "{:?}", &weighted[..120]);
    assert!(weighted[160..290].iter().all(|&w| w < 1e-3), "{:?}", &weighted[160..290]);
    assert!(weighted.iter().all(|w| (0.0..=1.0).contains(w)));
}

#[test]
fn the_smoothness_weight_falls_below_its_speed_and_multiplies_the_turns_weight() {
    // Straight level paths at 2.9, 3.25 and 3.8 m/s, 2 s each (dt 0.02 s).
    let level = |speed: f64| {
        let points = (0..=100).map(|k| Vec3::new(speed * 0.02 * k as f64, 0.0, 10.0)).collect();
        Arc::new(Reference::new(format!("level {speed}"), 0.02, points))
    };
    let first_weight = |reference: Arc<Reference>, min_speed: f64, turn_scale: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.smoothness_min_speed_mps = min_speed;
        config.reward.smoothness_turn_scale_degps = turn_scale;
        let env = env_on(config, reference);
        env.smoothness_weight()
    };
    assert_eq!(first_weight(level(2.9), 0.0, 0.0), 1.0, "off: every speed weighs 1");
    assert_eq!(first_weight(level(2.9), 3.5, 0.0), 0.0, "0.6 m/s below: past the 0.5 m/s ramp");
    assert!((first_weight(level(3.25), 3.5, 0.0) - 0.5).abs() < 1e-4, "halfway down the ramp");
    assert_eq!(first_weight(level(3.8), 3.5, 0.0), 1.0, "above the speed");
    // With the turn weight too: on the loop's approach (3.8 m/s, straight) both are 1; where the loop
    // turns the product is as small as the turn weight alone.
    let looping = Arc::new(named("loop", Vec3::new(0.0, 0.0, 10.0), 0.02, 0.62).unwrap());
    assert_eq!(first_weight(looping.clone(), 3.5, 30.0), 1.0);
    assert!(first_weight(level(3.25), 3.5, 30.0) > 0.49, "a straight path: only the speed ramp weighs");
}

#[test]
fn the_energy_is_priced_in_full_above_its_speed_and_not_at_all_below_its_ramp() {
    // Straight level paths at 2.9, 3.25 and 3.8 m/s, 2 s each (dt 0.02 s).
    let level = |speed: f64| {
        let points = (0..=100).map(|k| Vec3::new(speed * 0.02 * k as f64, 0.0, 10.0)).collect();
        Arc::new(Reference::new(format!("level {speed}"), 0.02, points))
    };
    let flown = |reference: Arc<Reference>, min_speed: f64| {
        let mut config = TaskConfig::default();
        config.reward.energy_min_speed_mps = min_speed;
        stroke_priced(config, reference)
    };
    let (share, priced) = flown(level(2.9), 0.0);
    assert_eq!(share, 1.0, "off: priced at every speed");
    assert!(priced.terms.energy < 0.99, "the stroke costs: {:?}", priced.terms);
    let (share, free) = flown(level(2.9), 3.5);
    assert_eq!(share, 0.0, "0.6 m/s below: past the 0.5 m/s ramp");
    assert_eq!(free.terms.energy, 1.0, "not priced: the kernel's top whatever the power");
    // The same flight: only the energy kernel and the reward move.
    assert_eq!((free.position_error_m, free.terms.position), (priced.position_error_m, priced.terms.position));
    let weight = TaskConfig::default().reward.energy_weight;
    assert!((free.reward - priced.reward - weight * (1.0 - priced.terms.energy)).abs() < 1e-9);
    assert!((flown(level(3.25), 3.5).0 - 0.5).abs() < 1e-4, "halfway down the ramp");
    let (share, fast) = flown(level(3.8), 3.5);
    assert_eq!(share, 1.0, "above the speed: in full");
    assert_eq!(fast.terms, flown(level(3.8), 0.0).1.terms, "in full is the kernel itself, bit for bit");
}

#[test]
fn the_smoothness_weight_rises_on_glide_slopes_up_to_its_gain_and_never_on_climbs_or_dives() {
    let first_weight = |reference: Arc<Reference>, gain: f64, min_speed: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.smoothness_glide_gain = gain;
        config.reward.smoothness_min_speed_mps = min_speed;
        assert_eq!(config.reward.weighs_smoothness(), gain > 0.0 || min_speed > 0.0);
        let env = env_on(config, reference);
        env.smoothness_weight()
    };
    assert_eq!(first_weight(sloped(-0.83), 0.0, 0.0), 1.0, "off: every slope weighs 1");
    assert!((first_weight(sloped(-0.83), 4.0, 0.0) - 5.0).abs() < 1e-4, "a glide slope: 1 + the gain");
    assert!((first_weight(sloped(-1.05), 4.0, 0.0) - 5.0).abs() < 1e-4, "3.6 : 1, steeper: no more than 1 + the gain");
    assert!((first_weight(sloped(-1.5), 4.0, 0.0) - 1.0).abs() < 1e-6, "longitudinal's dive, 2.5 : 1, is no glide");
    assert!((first_weight(sloped(-0.25), 4.0, 0.0) - 3.0).abs() < 1e-4, "half the full sink: half the gain");
    assert!((first_weight(sloped(0.0), 4.0, 0.0) - 1.0).abs() < 1e-6, "level");
    assert!((first_weight(sloped(0.8), 4.0, 0.0) - 1.0).abs() < 1e-6, "a climb");
    // It multiplies the other weights: below the speed ramp a descent weighs nothing either.
    assert_eq!(first_weight(sloped(-0.83), 4.0, 4.5), 0.0);
}

#[test]
fn the_flap_price_on_glide_slopes_is_its_share_and_full_on_level_paths_climbs_and_dives() {
    let first_share = |reference: Arc<Reference>, share: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.flap_rate_weight = 0.1;
        config.reward.flap_rate_glide_share = share;
        let env = env_on(config, reference);
        env.flap_rate_price_share()
    };
    assert_eq!(first_share(sloped(-0.83), 1.0), 1.0, "by default: in full on every slope");
    assert!(first_share(sloped(-0.83), 0.0).abs() < 1e-4, "a glide slope: free");
    assert!((first_share(sloped(-0.83), 0.3) - 0.3).abs() < 1e-4, "a glide slope: the share");
    assert!((first_share(sloped(-0.25), 0.0) - 0.5).abs() < 1e-4, "half the full sink: halfway");
    for (vertical, what) in [(0.0, "level"), (0.8, "a climb"), (-1.5, "longitudinal's dive")] {
        assert!((first_share(sloped(vertical), 0.0) - 1.0).abs() < 1e-6, "{what}: in full");
    }
    // The kernel priced in part: 1 - share (1 - k), bit for bit at 1, and an unweighed 0 stays 0.
    let terms = flapper_task::reward::RewardTerms { flap_rate: 0.2, ..Default::default() };
    assert_eq!(terms.with_flap_rate_priced(1.0), terms);
    assert!((terms.with_flap_rate_priced(0.5).flap_rate - 0.6).abs() < 1e-12);
    assert_eq!(terms.with_flap_rate_priced(0.0).flap_rate, 1.0);
    let unweighed = flapper_task::reward::RewardTerms::default();
    assert_eq!(unweighed.with_flap_rate_priced(0.0).flap_rate, 0.0);
}

#[test]
fn the_smoothness_weight_in_steep_dives_is_its_share_and_glide_slopes_are_not_dives() {
    let first_weight = |reference: Arc<Reference>, dive_share: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.smoothness_glide_gain = 9.0;
        config.reward.smoothness_dive_share = dive_share;
        assert!(config.reward.weighs_smoothness());
        let env = env_on(config, reference);
        env.smoothness_weight()
    };
    assert_eq!(first_weight(sloped(-1.5), 0.0), 0.0, "longitudinal's dive, 2.5 : 1: no steady stroke asked");
    assert!((first_weight(sloped(-1.5), 0.25) - 0.25).abs() < 1e-6, "a dive: its share of level flight's 1");
    assert_eq!(first_weight(sloped(-1.5), 1.0), 1.0, "1: a dive weighs as level flight");
    for (vertical, weight, what) in [(-0.83, 10.0, "a glide slope"), (0.0, 1.0, "level"), (0.8, 1.0, "a climb")] {
        let shared = first_weight(sloped(vertical), 0.0);
        assert!((shared - weight).abs() < 1e-4, "{what}: no dive, weighed as without the share: {shared}");
        assert_eq!(shared, first_weight(sloped(vertical), 1.0), "{what}: bit for bit");
    }
    let mut off = TaskConfig::default();
    off.reward.smoothness_dive_share = 0.5;
    assert!(off.reward.weighs_smoothness(), "a share below 1 alone weighs the term per step");
}

#[test]
fn the_glide_slopes_smoothness_gain_is_lifted_before_a_dive_and_only_within_its_time() {
    // Glides (0.83 m/s down at 3.8 m/s) for 0.5 s (steps 0-24), then dives (1.5 m/s down) for 1 s.
    let glide_then_dive = {
        let mut point = Vec3::new(0.0, 0.0, 10.0);
        let mut points = vec![point];
        for k in 0..75 {
            point += Vec3::new(3.8, 0.0, if k < 25 { -0.83 } else { -1.5 }) * 0.02;
            points.push(point);
        }
        Arc::new(Reference::new("glide then dive", 0.02, points))
    };
    let first_weight = |reference: Arc<Reference>, stop_s: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.smoothness_glide_gain = 9.0;
        config.reward.smoothness_glide_stop_before_dive_s = stop_s;
        env_on(config, reference).smoothness_weight()
    };
    assert!((first_weight(glide_then_dive.clone(), 0.0) - 10.0).abs() < 1e-4, "off: the glide slope's 1 + gain");
    assert!((first_weight(glide_then_dive.clone(), 0.4) - 10.0).abs() < 1e-4, "the dive 0.5 s ahead: not within 0.4 s");
    assert!((first_weight(glide_then_dive.clone(), 0.6) - 1.0).abs() < 1e-6, "within 0.6 s: weighed as level flight");
    assert!((first_weight(sloped(-0.83), 5.0) - 10.0).abs() < 1e-4, "no dive ahead, however far: the gain holds");
    assert!((first_weight(sloped(-1.5), 5.0) - 1.0).abs() < 1e-6, "the dive itself: its share, as without the key");
}

#[test]
fn the_energy_is_priced_more_on_glide_slopes_by_its_gain_and_nowhere_else() {
    let flown = |reference: Arc<Reference>, gain: f64| {
        let mut config = TaskConfig::default();
        config.reward.energy_glide_gain = gain;
        stroke_priced(config, reference)
    };
    let (share, plain) = flown(sloped(-0.83), 0.0);
    assert_eq!(share, 1.0, "off: priced alike on every slope");
    let (share, glide) = flown(sloped(-0.83), 9.0);
    assert!((share - 10.0).abs() < 1e-9, "a glide slope: 1 + the gain, got {share}");
    // The same flight, the energy priced ten times: 1 - 10 (1 - e).
    assert_eq!(glide.position_error_m, plain.position_error_m);
    assert!(plain.terms.energy < 0.99, "the stroke costs: {:?}", plain.terms);
    assert!((glide.terms.energy - (1.0 - 10.0 * (1.0 - plain.terms.energy))).abs() < 1e-12);
    let weight = TaskConfig::default().reward.energy_weight;
    assert!((plain.reward - glide.reward - weight * 9.0 * (1.0 - plain.terms.energy)).abs() < 1e-9);
    assert!((flown(sloped(-0.25), 9.0).0 - 5.5).abs() < 1e-9, "half the full sink: half the gain");
    for (vertical, what) in [(-1.5, "longitudinal's dive, 2.5 : 1"), (0.0, "level"), (0.8, "a climb")] {
        let (share, step) = flown(sloped(vertical), 9.0);
        assert_eq!(share, 1.0, "{what}: no glide, priced as everywhere");
        assert_eq!(step.terms, flown(sloped(vertical), 0.0).1.terms, "{what}: the kernel itself, bit for bit");
    }
}

#[test]
fn the_energy_in_steep_dives_is_priced_by_its_share_and_glide_slopes_are_not_dives() {
    let flown = |reference: Arc<Reference>, dive_share: f64| {
        let mut config = TaskConfig::default();
        config.reward.energy_dive_share = dive_share;
        stroke_priced(config, reference)
    };
    let (share, free) = flown(sloped(-1.5), 0.0);
    assert_eq!(share, 0.0, "longitudinal's dive, 2.5 : 1: not priced");
    assert_eq!(free.terms.energy, 1.0, "the kernel's top whatever the power");
    let (share, priced) = flown(sloped(-1.5), 0.25);
    assert_eq!(share, 0.25);
    assert!(priced.terms.energy < 1.0 && priced.terms.energy > flown(sloped(-1.5), 1.0).1.terms.energy);
    for (vertical, what) in [(-0.83, "a glide slope"), (0.0, "level"), (0.8, "a climb")] {
        let (share, step) = flown(sloped(vertical), 0.0);
        assert_eq!(share, 1.0, "{what}: no dive, priced in full");
        assert_eq!(step.terms, flown(sloped(vertical), 1.0).1.terms, "{what}: the kernel itself, bit for bit");
    }
}

#[test]
fn the_position_term_in_steep_dives_weighs_one_plus_its_gain_and_nowhere_else() {
    let flown = |reference: Arc<Reference>, gain: f64| {
        let mut config = TaskConfig::default();
        config.reward.position_dive_gain = gain;
        let factor = FlightEnv::new(
            &robot(),
            Arc::new(exact_start(config.clone())),
            ReferenceSource::Fixed(reference.clone()),
            1,
            0,
        )
        .unwrap()
        .position_factor();
        (factor, stroke_priced(config, reference).1)
    };
    let (factor, plain) = flown(sloped(-1.5), 0.0);
    assert_eq!(factor, 1.0, "off: every slope alike");
    let (factor, dearer) = flown(sloped(-1.5), 2.0);
    assert_eq!(factor, 3.0, "longitudinal's dive, 2.5 : 1: 1 + the gain");
    // The same flight, r_pos three times its kernel, and the reward richer by the weight of two kernels.
    assert_eq!(dearer.position_error_m, plain.position_error_m);
    assert!(plain.terms.position > 0.5, "near the path from the exact start: {:?}", plain.terms);
    assert!((dearer.terms.position - 3.0 * plain.terms.position).abs() < 1e-12);
    let weight = TaskConfig::default().reward.position_weight;
    assert!((dearer.reward - plain.reward - weight * 2.0 * plain.terms.position).abs() < 1e-9);
    for (vertical, what) in [(-0.83, "a glide slope"), (0.0, "level"), (0.8, "a climb")] {
        let (factor, step) = flown(sloped(vertical), 2.0);
        assert_eq!(factor, 1.0, "{what}: no dive, weighed as everywhere");
        assert_eq!(step.terms, flown(sloped(vertical), 0.0).1.terms, "{what}: the kernel itself, bit for bit");
    }
    let refused = TaskConfig::from_toml("[reward]\nposition_dive_gain = -1\n", "test.toml").unwrap_err().to_string();
    assert!(refused.contains("reward.position_dive_gain") && refused.contains("-1"), "{refused}");
}

/// A circle of radius `radius_m` flown at `speed_mps`, starting at `start_rad` of its way round, in the
/// vertical x-z plane (a back-flip: climbing first) or, `level`, in the horizontal plane (turning left).
fn circle(radius_m: f64, speed_mps: f64, start_rad: f64, level: bool) -> Reference {
    let rate = speed_mps / radius_m;
    let points = (0..200)
        .map(|k| {
            let angle = start_rad + rate * 0.02 * k as f64;
            if level {
                Vec3::new(radius_m * angle.sin(), radius_m * (1.0 - angle.cos()), 10.0)
            } else {
                Vec3::new(radius_m * angle.sin(), 0.0, 10.0 + radius_m * (1.0 - angle.cos()))
            }
        })
        .collect();
    Reference::new("circle", 0.02, points)
}

#[test]
fn the_attitude_a_path_asks_is_level_on_a_straight_path_banked_in_a_turn_and_inverted_atop_a_tight_loop() {
    use flapper_sim::quat_to_euler;
    use flapper_task::env::path_frame;
    // Straight and level, heading north: no roll, no pitch, yaw 90 deg.
    let [roll, pitch, yaw] = quat_to_euler(path_frame(&northbound()));
    assert!(roll.abs() < 1e-9 && pitch.abs() < 1e-9 && (yaw - std::f64::consts::FRAC_PI_2).abs() < 1e-9);
    // A straight climb: the nose along the path, no roll.
    let [roll, pitch, _] = quat_to_euler(path_frame(&sloped(1.0)));
    assert!(roll.abs() < 1e-9 && (pitch - (1.0f64 / 3.8).atan()).abs() < 1e-9, "{roll} {pitch}");
    // A level left turn at 4 m/s on a 5 m radius: the coordinated bank, left wing down (roll < 0).
    let [roll, pitch, _] = quat_to_euler(path_frame(&circle(5.0, 4.0, 0.3, true)));
    let bank = (4.0f64 * 4.0 / 5.0 / 9.81).atan();
    assert!((roll + bank).abs() < 0.01 && pitch.abs() < 0.01, "roll {roll}, expected {}", -bank);
    // The top of a 1.2 m loop at 4 m/s (13.3 m/s^2 towards its centre, more than gravity): flying
    // backwards, inverted, the lift's side down; the bottom of the same loop: upright.
    let top = path_frame(&circle(1.2, 4.0, std::f64::consts::PI, false));
    assert!((top * Vec3::X).x < -0.99 && (top * Vec3::Z).z < -0.99, "top: {:?}", top * Vec3::Z);
    let bottom = path_frame(&circle(1.2, 4.0, 0.0, false));
    assert!((bottom * Vec3::X).x > 0.99 && (bottom * Vec3::Z).z > 0.99);
    // A vertical climb in the loop: the lift's side points to the loop's centre (behind).
    let side = path_frame(&circle(1.2, 4.0, std::f64::consts::FRAC_PI_2, false));
    assert!((side * Vec3::X).z > 0.99 && (side * Vec3::Z).x < -0.99);
    // Every frame is a rotation.
    for q in [top, bottom, side] {
        assert!((q.length() - 1.0).abs() < 1e-12);
    }
}

#[test]
fn training_episodes_start_along_the_path_where_asked_and_fixed_references_never_do() {
    let full = |config: &TaskConfig| config.episode.max_steps + config.observation.lookahead_steps + 2;
    let mut config = exact_start(TaskConfig::stage(3).unwrap());
    config.initial_state.path_start_probability = 1.0;
    let config = Arc::new(config);
    let mut shortened = 0;
    for index in 0..8 {
        let env = FlightEnv::new(&robot(), config.clone(), ReferenceSource::Procedural, 7, index).unwrap();
        let (reference, sim) = (env.reference(), env.control().sim());
        shortened += usize::from(reference.len() + 10 < full(&config));
        // At least 6 s of path left to fly, on it, along it, at its speed.
        assert!(reference.duration_s() >= flapper_task::env::PATH_START_MIN_REMAINING_S);
        assert!((sim.base_position_m() - reference.target(0)).length() < 1e-9);
        let velocity = sim.linear_velocity_mps();
        assert!((velocity - reference.velocity(0)).length() < 1e-6 * reference.speed(0).max(1.0), "{velocity:?}");
        assert_eq!(sim.orientation(), flapper_task::env::path_frame(reference));
    }
    assert!(shortened >= 7, "only {shortened} of 8 episodes started along the path");

    // Without it every training path is flown whole; a fixed reference is flown whole either way.
    let whole = Arc::new(exact_start(TaskConfig::stage(3).unwrap()));
    for index in 0..4 {
        let env = FlightEnv::new(&robot(), whole.clone(), ReferenceSource::Procedural, 7, index).unwrap();
        assert!(env.reference().len() + 10 >= full(&whole), "{} of {}", env.reference().len(), full(&whole));
    }
    let env = FlightEnv::new(&robot(), config, ReferenceSource::Fixed(northbound()), 7, 0).unwrap();
    assert_eq!(env.reference().len(), northbound().len());
    assert!((env.control().sim().base_position_m() - northbound().target(0)).length() < 1e-9);
}

/// A 5 Hz stroke whose wing pitch leads the flap by `lead_deg`, as actions.
fn feathered_stroke(k: usize, lead_deg: f64) -> [f32; 5] {
    let phase = std::f64::consts::TAU * 5.0 * k as f64 * 0.02;
    let flap = (0.8 * phase.sin()) as f32;
    let pitch = (0.5 * (phase + lead_deg.to_radians()).sin()) as f32;
    [flap, pitch, flap, pitch, -0.2]
}

#[test]
fn the_feathering_term_pays_a_pitch_ahead_of_the_flap_and_joins_the_reward_only_when_weighted() {
    let fly = |weight: f64, lead_deg: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.feathering_weight = weight;
        let mut env = env_on(config, sloped(0.0));
        (0..40).map(|k| env.step(&feathered_stroke(k, lead_deg))).collect::<Vec<_>>()
    };
    let (ahead, behind) = (fly(0.2, 90.0), fly(0.2, -90.0));
    let last =
        |steps: &[flapper_task::env::StepResult]| steps[30..].iter().map(|s| s.terms.feathering).sum::<f64>() / 10.0;
    assert!(last(&ahead) > 0.8, "{:?}", ahead[39].terms);
    assert!(last(&behind) < 0.2, "{:?}", behind[39].terms);
    let unweighed = fly(0.0, 90.0);
    for (w, u) in ahead.iter().zip(&unweighed) {
        assert_eq!(u.terms.feathering, 0.0);
        assert!((w.reward - u.reward - 0.2 * w.terms.feathering).abs() < 1e-12);
    }
}

#[test]
fn a_snapshot_continues_the_feathering_it_reads() {
    let mut config = exact_start(TaskConfig::default());
    config.reward.feathering_weight = 0.2;
    let mut original = env_on(config.clone(), sloped(0.0));
    (0..30).for_each(|k| _ = original.step(&feathered_stroke(k, 90.0)));
    let snapshot = original.snapshot();
    let mut resumed = env_on(config, sloped(0.0));
    (0..7).for_each(|k| _ = resumed.step(&feathered_stroke(k, -90.0)));
    resumed.restore(&snapshot).unwrap();
    for k in 30..45 {
        let (a, b) = (original.step(&feathered_stroke(k, 90.0)), resumed.step(&feathered_stroke(k, 90.0)));
        assert_eq!((a.reward, a.terms), (b.reward, b.terms), "step {k}");
    }
}

#[test]
fn passive_feathering_leads_a_stroke_that_asks_for_no_pitch() {
    let stroke_only = |k: usize| {
        let flap = (0.8 * (std::f64::consts::TAU * 5.0 * k as f64 * 0.02).sin()) as f32;
        [flap, 0.0, flap, 0.0, -0.2]
    };
    let feathering = |feathering_s: f64| {
        let mut config = exact_start(TaskConfig::default());
        config.reward.feathering_weight = 0.2;
        config.control.passive_feathering_s = feathering_s;
        let mut env = env_on(config, sloped(0.0));
        let steps: Vec<_> = (0..40).map(|k| env.step(&stroke_only(k))).collect();
        steps[30..].iter().map(|s| s.terms.feathering).sum::<f64>() / 10.0
    };
    // Without it the pitch moves only as the airflow and the flap's motion push it (measured: r_feathering
    // 0.40); with it the pitch swings with the flap's rate, behind it by the filter's and the servo's lag,
    // and leads the stroke (0.67).
    let (still, twisted) = (feathering(0.0), feathering(0.03));
    assert!(twisted > 0.6, "{still} -> {twisted}");
    assert!(twisted > still + 0.2, "{still} -> {twisted}");
}
