//! The learner end to end: it solves the inverted pendulum, a resumed run equals an uninterrupted
//! one, the same seed gives the same run, and broken or mismatched checkpoints are refused.

use std::path::{Path, PathBuf};

use flapper_ppo::checkpoint::{self, CheckpointError, CheckpointKind};
use flapper_ppo::{PpoConfig, RunnerConfig, Start, TrainError, Trainer};
use flapper_sim::RobotModel;
use flapper_train::run::{flight_trainer, solve_inverted_pendulum};
use flapper_train::{InvertedPendulumEnvs, TrainConfig};

fn scratch_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flapper-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn ppo_solves_the_inverted_pendulum() {
    let dir = scratch_dir("pendulum");
    let outcome = solve_inverted_pendulum(1, 400, 5, &dir).unwrap();
    let steps = outcome
        .steps_to_solve
        .unwrap_or_else(|| panic!("not solved in {} iterations: {:?}", outcome.iterations, outcome.test_returns));
    assert!(steps <= 600_000, "solved only after {steps} steps");
    assert!(outcome.test_returns.iter().all(|&r| r == 1000.0));
    assert!(
        dir.join("policy.safetensors").exists()
            && dir.join("training.csv").exists()
            && dir.join("learning_curves.svg").exists()
    );
    std::fs::remove_dir_all(dir).ok();
}

/// A small flight-training config: few environments, short rollouts, small networks.
fn small_flight_config(iterations: usize, seed: u64) -> TrainConfig {
    let text = format!(
        "[runner]\nenvs = 6\niterations = {iterations}\nseed = {seed}\nthreads = 2\ncheckpoint_every = 2\n\
         [ppo]\nsteps_per_env = 8\nminibatches = 2\nepochs = 2\nactor_hidden = [16]\ncritic_hidden = [16]\n\
         [task.episode]\nmax_steps = 20\n"
    );
    TrainConfig::from_toml(&text, "test.toml", None).unwrap()
}

fn train(config: &TrainConfig, dir: &Path, start: Start) -> Trainer<flapper_train::FlightEnvs> {
    let robot = RobotModel::flapper().unwrap();
    let mut trainer = flight_trainer(&robot, config, dir, start).unwrap();
    trainer.run(&mut |_, _| true).unwrap();
    trainer
}

/// The CSV without its timing columns (wall time, steps/s, time split differ between runs).
fn csv_numbers(dir: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("training.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let timing = |h: &str| h.contains("time") || h == "steps_per_s";
    text.lines()
        .map(|line| {
            line.split(',').zip(&header).filter(|(_, h)| !timing(h)).map(|(v, _)| v).collect::<Vec<_>>().join(",")
        })
        .collect()
}

#[test]
fn a_resumed_flight_run_equals_the_uninterrupted_one() {
    let whole = scratch_dir("whole");
    let uninterrupted = train(&small_flight_config(6, 5), &whole, Start::Fresh);

    // The same run killed after iteration 4 with only the iteration-2 checkpoint on disk.
    let parts = scratch_dir("parts");
    train(&small_flight_config(4, 5), &parts, Start::Fresh);
    for name in ["iter_000004.safetensors", "iter_000004.safetensors.json"] {
        std::fs::remove_file(parts.join("checkpoints").join(name)).unwrap();
    }
    std::fs::remove_file(parts.join("policy.safetensors")).unwrap();
    // The checkpoint holds every environment mid-episode (20-step episodes, checkpoints every 16 steps).
    let saved = checkpoint::load(&parts.join("checkpoints").join("iter_000002.safetensors")).unwrap();
    assert!(saved.environments.as_ref().is_some_and(|bytes| bytes.len() > 1000));
    let resumed = train(&small_flight_config(6, 5), &parts, Start::Resume);

    assert_eq!(resumed.iteration(), 6);
    assert_eq!(resumed.env_steps(), uninterrupted.env_steps());
    assert_eq!(resumed.ppo().policy, uninterrupted.ppo().policy, "weights, log-std and normalizer");
    assert_eq!(resumed.ppo().optimizer, uninterrupted.ppo().optimizer);
    assert_eq!(resumed.ppo().learning_rate, uninterrupted.ppo().learning_rate);
    assert_eq!(csv_numbers(&parts), csv_numbers(&whole), "every logged number except timings");
    assert_eq!(csv_numbers(&whole).len(), 7, "header and six iterations");

    let a = checkpoint::load(&whole.join("policy.safetensors")).unwrap();
    let b = checkpoint::load(&parts.join("policy.safetensors")).unwrap();
    assert_eq!(a.policy, b.policy);
    assert!(a.optimizer.is_none(), "policy files hold no optimizer");
    for dir in [whole, parts] {
        std::fs::remove_dir_all(dir).ok();
    }
}

#[test]
fn a_restart_from_an_earlier_checkpoint_takes_its_learner_and_goes_on_from_the_latest() {
    let dir = scratch_dir("restart-earlier");
    train(&small_flight_config(4, 5), &dir, Start::Fresh);
    let checkpoints = dir.join("checkpoints");
    let earlier = checkpoint::load(&checkpoints.join("iter_000002.safetensors")).unwrap();
    let latest = checkpoint::load(&checkpoints.join("iter_000004.safetensors")).unwrap();
    assert_ne!(earlier.policy, latest.policy, "two iterations of learning changed the weights");

    let robot = RobotModel::flapper().unwrap();
    let start = |learner_from| Start::Restart { noise_std: 0.7, learner_from };
    let from_earlier = checkpoints.join("iter_000002.safetensors");
    let restarted = flight_trainer(&robot, &small_flight_config(6, 5), &dir, start(Some(from_earlier))).unwrap();
    assert_eq!(
        (restarted.iteration(), restarted.env_steps()),
        (4, latest.info.env_steps),
        "the run's clock goes on from the latest checkpoint"
    );
    assert_eq!(restarted.ppo().optimizer, earlier.optimizer.clone().unwrap(), "the earlier checkpoint's optimizer");
    assert_eq!(restarted.ppo().learning_rate, earlier.info.learning_rate);
    let mut expected = earlier.policy.clone();
    expected.set_noise_std(0.7);
    assert_eq!(restarted.ppo().policy, expected, "the earlier weights and normalizer, the noise reset");
    drop(restarted);

    // Without it, the restart keeps the latest learner (as before): only the noise differs.
    let continued = flight_trainer(&robot, &small_flight_config(6, 5), &dir, start(None)).unwrap();
    let mut expected = latest.policy.clone();
    expected.set_noise_std(0.7);
    assert_eq!(continued.ppo().policy, expected);
    drop(continued);

    // An earlier checkpoint that is not there is refused, naming it.
    let missing = checkpoints.join("iter_000003.safetensors");
    let err = flight_trainer(&robot, &small_flight_config(6, 5), &dir, start(Some(missing))).err().unwrap();
    assert!(err.to_string().contains("iter_000003.safetensors"), "{err}");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn the_action_rate_kernel_and_the_smoothness_are_logged_when_weighted_and_older_logs_keep_their_columns() {
    // Weighted: the action-rate, flap-rate and glide-hold kernels, the smoothness and the curvature together.
    let columns = |weight: Option<f64>, smoothness: f32, name: &str| {
        let mut config = small_flight_config(2, 5);
        if let Some(w) = weight {
            config.task.reward.action_rate_weight = w;
            config.task.reward.flap_rate_weight = w;
            config.task.reward.glide_hold_weight = w;
            config.ppo.curvature_coef = smoothness;
        }
        config.ppo.smoothness_coef = smoothness;
        let dir = scratch_dir(name);
        train(&config, &dir, Start::Fresh);
        let text = std::fs::read_to_string(dir.join("training.csv")).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        let mut lines = text.lines().map(|l| l.split(',').map(str::to_string).collect::<Vec<_>>());
        let header = lines.next().unwrap();
        (header, lines.collect::<Vec<_>>())
    };
    let (header, _) = columns(None, 0.0, "no-action-rate");
    assert!(header.contains(&"r_energy".to_string()) && !header.contains(&"r_action_rate".to_string()));
    for absent in ["smoothness", "r_flap_rate", "r_glide_hold", "curvature"] {
        assert!(!header.contains(&absent.to_string()), "{absent} logged unweighed");
    }
    let (header, rows) = columns(Some(0.2), 0.5, "action-rate");
    let column = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("{name} logged"));
    let (rate, smoothness) = (column("r_action_rate"), column("smoothness"));
    let (flap_rate, curvature) = (column("r_flap_rate"), column("curvature"));
    assert_eq!(flap_rate, rate + 1, "the flap's kernel after the action rate's");
    let glide_hold = column("r_glide_hold");
    assert_eq!(glide_hold, flap_rate + 1, "the glide's kernel after the flap's");
    assert_eq!(curvature, smoothness + 1);
    for row in rows {
        assert_eq!(row.len(), header.len());
        let value: f64 = row[flap_rate].parse().unwrap();
        assert!(value > 0.0 && value <= 1.0, "r_flap_rate {value}");
        let value: f64 = row[glide_hold].parse().unwrap();
        assert!((0.0..=1.0).contains(&value), "r_glide_hold {value}");
        let value: f64 = row[curvature].parse().unwrap();
        assert!(value > 0.0, "curvature {value}: a fresh policy's mean bends between steps");
        let value: f64 = row[rate].parse().unwrap();
        assert!(value > 0.0 && value < 1.0, "r_action_rate {value}: exploration noise moves the action every step");
        let value: f64 = row[smoothness].parse().unwrap();
        assert!(value > 0.0, "smoothness {value}: a fresh policy's mean moves between steps");
    }
}

#[test]
fn environments_saved_in_a_checkpoint_read_back_to_the_last_bit() {
    // A checkpoint holds every environment as JSON. serde_json's default float parser may miss the
    // last bit of an f64; a run resumed from such a state drifted from the uninterrupted one from its
    // first step (`flapper train --resume` at 256 environments: 152 of them differed after one
    // iteration). Saved, restored into fresh environments and saved again, the state must not change.
    use flapper_ppo::VecEnv;
    let robot = RobotModel::flapper().unwrap();
    let task = flapper_task::TaskConfig::stage(4).unwrap();
    let mut flown = flapper_train::FlightEnvs::new(&robot, task.clone(), 64, 9, 1).unwrap();
    let mut actions = vec![0.0f32; 64 * flown.action_size()];
    for k in 0..30 {
        actions.iter_mut().enumerate().for_each(|(i, a)| *a = ((k * 7 + i) as f32 * 0.37).sin());
        flown.step(&actions).unwrap();
    }
    let saved = flown.save_state().unwrap();
    let mut fresh = flapper_train::FlightEnvs::new(&robot, task, 64, 9, 1).unwrap();
    fresh.restore_state(&saved).unwrap();
    assert!(fresh.save_state().unwrap() == saved, "the restored state differs from the saved one");
    assert_eq!(fresh.observations(), flown.observations());
}

#[test]
fn the_same_seed_gives_the_same_run_and_another_seed_does_not() {
    let (a, b, c) = (scratch_dir("seed-a"), scratch_dir("seed-b"), scratch_dir("seed-c"));
    let first = train(&small_flight_config(2, 9), &a, Start::Fresh);
    let second = train(&small_flight_config(2, 9), &b, Start::Fresh);
    let other = train(&small_flight_config(2, 10), &c, Start::Fresh);
    assert_eq!(first.ppo().policy, second.ppo().policy);
    assert_eq!(csv_numbers(&a), csv_numbers(&b));
    assert_ne!(first.ppo().policy, other.ppo().policy);
    for dir in [a, b, c] {
        std::fs::remove_dir_all(dir).ok();
    }
}

#[test]
fn runs_refuse_to_overwrite_and_checkpoints_are_checked() {
    let dir = scratch_dir("refuse");
    train(&small_flight_config(2, 1), &dir, Start::Fresh);
    let robot = RobotModel::flapper().unwrap();
    let before = std::fs::read(dir.join("policy.safetensors")).unwrap();

    // A second fresh run into the same folder is refused and writes nothing.
    let again = flight_trainer(&robot, &small_flight_config(2, 1), &dir, Start::Fresh).err().unwrap();
    assert!(again.to_string().contains("already holds a training run"), "{again}");
    // Resuming a finished run asks for more iterations.
    let done = flight_trainer(&robot, &small_flight_config(2, 1), &dir, Start::Resume).err().unwrap();
    assert!(done.to_string().contains("raise the iteration count"), "{done}");
    assert_eq!(std::fs::read(dir.join("policy.safetensors")).unwrap(), before);

    // A truncated file: one clear error naming it.
    let truncated = dir.join("truncated.safetensors");
    std::fs::write(&truncated, &before[..before.len() / 2]).unwrap();
    let err = checkpoint::load(&truncated).unwrap_err();
    assert!(
        matches!(err, CheckpointError::Format { .. }) && err.to_string().contains("truncated.safetensors"),
        "{err}"
    );

    // A policy of another layout (the pendulum's 4 observations) cannot start a flight run.
    let pendulum_dir = scratch_dir("pendulum-layout");
    let envs = InvertedPendulumEnvs::new(4, 1).unwrap();
    let runner = RunnerConfig { envs: 4, iterations: 1, threads: 1, ..RunnerConfig::default() };
    let ppo = PpoConfig { steps_per_env: 4, actor_hidden: vec![8], critic_hidden: vec![8], ..PpoConfig::default() };
    Trainer::new(envs, ppo, runner, String::new(), &pendulum_dir, Start::Fresh).unwrap().run(&mut |_, _| true).unwrap();
    let other = scratch_dir("other-layout");
    let err = flight_trainer(
        &robot,
        &small_flight_config(2, 1),
        &other,
        Start::InitFrom(pendulum_dir.join("policy.safetensors")),
    )
    .err()
    .unwrap();
    assert!(
        matches!(err, flapper_train::run::RunError::Train(TrainError::Checkpoint(CheckpointError::Layout { .. }))),
        "{err}"
    );
    assert!(
        err.to_string().contains("4 observations and 1 actions") && err.to_string().contains("540 observations"),
        "{err}"
    );
    assert!(!other.join("training.csv").exists(), "a refused run writes nothing");

    // --init-from a policy of the same layout starts a new run from its weights.
    let chained = scratch_dir("chained");
    let source = checkpoint::load(&dir.join("policy.safetensors")).unwrap();
    let trainer =
        flight_trainer(&robot, &small_flight_config(2, 1), &chained, Start::InitFrom(dir.join("policy.safetensors")))
            .unwrap();
    assert_eq!(trainer.ppo().policy, source.policy);
    assert_eq!(trainer.iteration(), 0);
    // ... and with `init_from_noise_std`, from that action noise instead of the source's.
    let renoised = scratch_dir("renoised");
    let mut config = small_flight_config(2, 1);
    config.runner.init_from_noise_std = Some(0.25);
    let trainer = flight_trainer(&robot, &config, &renoised, Start::InitFrom(dir.join("policy.safetensors"))).unwrap();
    assert!(
        trainer.ppo().policy.log_std.iter().all(|s| (s.exp() - 0.25).abs() < 1e-6),
        "{:?}",
        trainer.ppo().policy.log_std
    );
    assert!(source.policy.log_std.iter().all(|s| (s.exp() - 0.25).abs() > 1e-3), "the source's noise differs");
    assert_eq!(trainer.ppo().policy.actor, source.policy.actor, "the weights are the source's");
    // ... and with a clock in the observation (`[task.observation] clock_hz`), from the source given the
    // clock's two numbers with zero weights: the same networks on its 540, Adam's moments for the new 0.
    let mut checkpoints: Vec<PathBuf> = std::fs::read_dir(dir.join("checkpoints"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "safetensors"))
        .collect();
    checkpoints.sort();
    let newest = checkpoint::load(checkpoints.last().unwrap()).unwrap();
    let mut clocked_config = small_flight_config(2, 1);
    clocked_config.task.observation.clock_hz = 5.3;
    let clocked = scratch_dir("clocked");
    let trainer =
        flight_trainer(&robot, &clocked_config, &clocked, Start::InitFrom(checkpoints.last().unwrap().clone()))
            .unwrap();
    let (policy, optimizer) = (&trainer.ppo().policy, &trainer.ppo().optimizer);
    assert_eq!((policy.observation_size(), policy.actor.sizes()), (542, &[542, 16, 5][..]));
    let source_optimizer = newest.optimizer.as_ref().unwrap();
    for (new, old, new_adam, old_adam) in [
        (&policy.actor, &newest.policy.actor, &optimizer.actor, &source_optimizer.actor),
        (&policy.critic, &newest.policy.critic, &optimizer.critic, &source_optimizer.critic),
    ] {
        for (j, (new_row, old_row)) in new.params()[..542 * 16].chunks(542).zip(old.params().chunks(540)).enumerate() {
            assert_eq!(&new_row[..540], old_row, "row {j} of the first weight");
            assert_eq!(&new_row[540..], &[0.0, 0.0], "row {j}: the clock's weights");
        }
        assert_eq!(&new.params()[542 * 16..], &old.params()[540 * 16..]);
        let moments =
            [(&new_adam.first_moment, &old_adam.first_moment), (&new_adam.second_moment, &old_adam.second_moment)];
        for (new_moment, old_moment) in moments {
            assert_eq!(new_moment.len(), new.params().len());
            assert!(new_moment[..542 * 16].chunks(542).all(|row| row[540..] == [0.0, 0.0]));
            assert_eq!(&new_moment[542 * 16..], &old_moment[540 * 16..]);
        }
    }
    assert_eq!(&policy.normalizer.mean[..540], &newest.policy.normalizer.mean[..]);
    assert_eq!(
        (&policy.normalizer.mean[540..], &policy.normalizer.variance[540..]),
        (&[0.0, 0.0][..], &[1.0, 1.0][..])
    );
    // A source of another size is still refused: only the clock's two numbers may be added.
    let mut longer_config = clocked_config.clone();
    longer_config.task.observation.lookahead_steps = 31;
    let longer = scratch_dir("longer");
    let err =
        flight_trainer(&robot, &longer_config, &longer, Start::InitFrom(dir.join("policy.safetensors"))).err().unwrap();
    assert!(err.to_string().contains("540 observations") && err.to_string().contains("545 observations"), "{err}");
    config.runner.init_from_noise_std = Some(f32::NAN);
    assert!(config.runner.validate(&config.ppo).unwrap_err().to_string().contains("runner.init_from_noise_std"));
    // A second trainer on a live run's folder is refused while the first holds it.
    let first = flight_trainer(&robot, &small_flight_config(4, 1), &dir, Start::Resume).unwrap();
    let err = flight_trainer(&robot, &small_flight_config(4, 1), &dir, Start::Resume).err().unwrap();
    assert!(matches!(err, flapper_train::run::RunError::Train(TrainError::Busy(_))), "{err}");
    drop(first);
    assert!(
        flight_trainer(&robot, &small_flight_config(4, 1), &dir, Start::Resume).is_ok(),
        "released with its trainer"
    );

    // Values no trained policy holds are refused by name, not flown.
    let bad_file = renoised.join("bad.safetensors");
    let mut nan_weight = source.policy.clone();
    nan_weight.actor.params_mut()[3] = f32::NAN;
    let mut negative_variance = source.policy.clone();
    negative_variance.normalizer.variance[7] = -1.0;
    let mut nan_mean = source.policy.clone();
    nan_mean.normalizer.mean[0] = f64::NAN;
    for (info, policy, needle) in [
        (&source.info, &nan_weight, "'actor' holds a non-finite value"),
        (&source.info, &negative_variance, "negative variance"),
        (&source.info, &nan_mean, "'normalizer.mean' holds a non-finite value"),
    ] {
        checkpoint::save(&bad_file, info, policy, None, None).unwrap();
        let err = checkpoint::load(&bad_file).unwrap_err();
        assert!(err.to_string().contains(needle) && err.to_string().contains("bad.safetensors"), "{err}");
    }
    // A weight stored transposed (same element count, other shape) is refused too.
    let mut bytes = std::fs::read(dir.join("policy.safetensors")).unwrap();
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header = String::from_utf8(bytes[8..8 + header_len].to_vec()).unwrap();
    let swapped = header.replacen("\"shape\":[16,540]", "\"shape\":[540,16]", 1);
    assert_ne!(swapped, header, "the test network's first weight is [16, 540]");
    bytes[8..8 + header_len].copy_from_slice(swapped.as_bytes());
    std::fs::write(&bad_file, &bytes).unwrap();
    let err = checkpoint::load(&bad_file).unwrap_err();
    assert!(err.to_string().contains("has shape [540, 16], expected [16, 540]"), "{err}");
    // So is a kind other than policy or checkpoint (the description is JSON inside the header).
    let mut bytes = std::fs::read(dir.join("policy.safetensors")).unwrap();
    let header = String::from_utf8(bytes[8..8 + header_len].to_vec()).unwrap();
    let renamed = header.replacen(r#"\"kind\": \"policy\""#, r#"\"kind\": \"weight\""#, 1);
    assert_ne!(renamed, header, "the description names its kind");
    bytes[8..8 + header_len].copy_from_slice(renamed.as_bytes());
    std::fs::write(&bad_file, &bytes).unwrap();
    let err = checkpoint::load(&bad_file).unwrap_err();
    assert!(
        err.to_string().contains("unknown variant `weight`") && err.to_string().contains("bad.safetensors"),
        "{err}"
    );
    // Exporting a policy never overwrites: an existing target is refused and kept.
    let err = checkpoint::export_policy(&dir.join("policy.safetensors"), &bad_file).unwrap_err();
    assert!(err.to_string().contains("exists") && err.to_string().contains("bad.safetensors"), "{err}");
    assert_eq!(std::fs::read(&bad_file).unwrap(), bytes);
    // Exported from a checkpoint: the same networks, as a policy (no optimizer, no random state).
    let from = flapper_ppo::run_folder::latest_checkpoint(&dir).expect("the run saved checkpoints");
    let exported = renoised.join("exported.safetensors");
    let info = checkpoint::export_policy(&from, &exported).unwrap();
    let (saved, loaded) = (checkpoint::load(&from).unwrap(), checkpoint::load(&exported).unwrap());
    assert_eq!(
        (saved.info.kind, info.kind, loaded.info.kind),
        (CheckpointKind::Checkpoint, CheckpointKind::Policy, CheckpointKind::Policy)
    );
    assert!(loaded.optimizer.is_none() && loaded.info.rng.is_none() && loaded.environments.is_none());
    assert_eq!((loaded.policy.actor, loaded.info.iteration), (saved.policy.actor, saved.info.iteration));
    for d in [dir, pendulum_dir, other, chained, renoised, clocked, longer] {
        std::fs::remove_dir_all(d).ok();
    }
}

#[test]
fn nothing_saved_is_lost_user_files_damaged_logs_and_failed_writes() {
    let robot = RobotModel::flapper().unwrap();
    // A folder with the user's own config.toml is not a run: a new run there is refused, the file kept.
    let users = scratch_dir("users-folder");
    std::fs::create_dir_all(&users).unwrap();
    std::fs::write(users.join("config.toml"), "# my notes\n").unwrap();
    let err = flight_trainer(&robot, &small_flight_config(2, 1), &users, Start::Fresh).err().unwrap();
    assert!(
        err.to_string().contains("already holds config.toml") && err.to_string().contains("new or empty folder"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(users.join("config.toml")).unwrap(), "# my notes\n");

    // A damaged training log stops a resume and stays as it was.
    let dir = scratch_dir("damaged-log");
    train(&small_flight_config(2, 1), &dir, Start::Fresh);
    let log = dir.join("training.csv");
    let good = std::fs::read(&log).unwrap();
    let mut invalid_utf8 = good.clone();
    invalid_utf8[good.len() - 5] = 0xff;
    let mut bad_line = good.clone();
    bad_line.extend_from_slice(b"garbage,row\n");
    // Iteration 1's row without its last field.
    let text = String::from_utf8(good.clone()).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let fields = lines[0].split(',').count();
    let cut = lines[1].rfind(',').unwrap();
    lines[1].truncate(cut);
    let short_row = (lines.join("\n") + "\n").into_bytes();
    let short_needle = format!("line 2 has {} fields, the header {fields}", fields - 1);
    for (damaged, needle) in [
        (invalid_utf8, "invalid UTF-8"),
        (bad_line, "line 4 does not start with an iteration number"),
        (short_row, short_needle.as_str()),
    ] {
        std::fs::write(&log, &damaged).unwrap();
        let err = flight_trainer(&robot, &small_flight_config(4, 1), &dir, Start::Resume).err().unwrap();
        assert!(err.to_string().contains(needle) && err.to_string().contains("training.csv"), "{err}");
        assert_eq!(std::fs::read(&log).unwrap(), damaged, "the log is left as it was");
    }
    // Moved away, the run resumes from its checkpoint with a new log.
    std::fs::remove_file(&log).unwrap();
    assert!(flight_trainer(&robot, &small_flight_config(4, 1), &dir, Start::Resume).is_ok());

    // A write that fails leaves the old file and no temporary file behind.
    let target = dir.join("occupied");
    std::fs::create_dir_all(target.join("inside")).unwrap();
    assert!(checkpoint::write_atomically(&target, b"new").is_err());
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    assert!(target.join("inside").is_dir());
}

#[test]
fn evaluation_reads_the_same_task_from_a_policy_as_training_saved() {
    // flapper_eval::load_flight_policy reads only the saved config's [task]; it must be the task the
    // run trained on, for every shipped policy.
    for stage in 1..=4 {
        let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../../policies/history/stage{stage}/policy.safetensors"));
        let saved = checkpoint::load(&path).unwrap().info.config_toml;
        let trained = TrainConfig::from_toml(&saved, "saved", None).unwrap().task;
        let (_, evaluated) = flapper_eval::load_flight_policy(&path).unwrap();
        assert_eq!(evaluated, trained, "stage {stage}");
    }
}

#[test]
fn flight_environments_weigh_the_smoothness_only_when_asked_and_by_the_turns_ahead() {
    use flapper_ppo::VecEnv;
    let robot = RobotModel::flapper().unwrap();
    let mut task = flapper_task::TaskConfig::stage(3).unwrap();
    let unweighted = flapper_train::FlightEnvs::new(&robot, task.clone(), 4, 5, 1).unwrap();
    assert!(unweighted.smoothness_weights().is_none(), "without the scale every weight is 1");
    task.reward.smoothness_turn_scale_degps = 30.0;
    task.episode.max_position_error_m = 1e3; // the unpowered robot falls; its references run on
    let mut envs = flapper_train::FlightEnvs::new(&robot, task, 16, 5, 1).unwrap();
    let actions = vec![0.0f32; 16 * envs.action_size()];
    let mut weights = Vec::new();
    for _ in 0..500 {
        weights.extend_from_slice(envs.smoothness_weights().unwrap());
        envs.step(&actions).unwrap();
    }
    assert!(weights.iter().all(|w| (0.0..=1.0).contains(w)));
    // Stage 3's references hold straight commands and turn, loop and sharply turn between them.
    let straight = weights.iter().filter(|&&w| w > 0.999).count();
    let turning = weights.iter().filter(|&&w| w < 0.5).count();
    assert!(straight > weights.len() / 10 && turning > weights.len() / 50, "{straight} straight, {turning} turning");
}
