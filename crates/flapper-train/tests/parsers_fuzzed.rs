//! Property-based tests over every parser of user files: run configs (TOML), reference CSVs and
//! policy/checkpoint files. Random bytes, random mutations of valid files and extreme numbers must
//! give a valid result or an error that names the file; never a panic. 2000 cases per property
//! (`PROPTEST_CASES=100000 cargo test -p flapper-train --test parsers_fuzzed` for more).

use std::path::{Path, PathBuf};

use flapper_eval::load_flight_policy;
use flapper_ppo::Start;
use flapper_ppo::checkpoint;
use flapper_sim::RobotModel;
use flapper_task::reference::csv_file::parse_reference_csv;
use flapper_train::TrainConfig;
use flapper_train::run::flight_trainer;
use proptest::prelude::*;
use proptest::sample::Index;

fn cases() -> ProptestConfig {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(2000);
    ProptestConfig { cases, failure_persistence: None, ..ProptestConfig::default() }
}

/// A mutation: overwrite, insert or delete one byte somewhere.
fn mutations() -> impl Strategy<Value = Vec<(Index, u8, u8)>> {
    proptest::collection::vec((any::<Index>(), any::<u8>(), 0..3u8), 1..10)
}

fn mutate(valid: &[u8], edits: &[(Index, u8, u8)]) -> Vec<u8> {
    let mut bytes = valid.to_vec();
    for (at, byte, op) in edits {
        let i = at.index(bytes.len().max(1));
        match op {
            0 if !bytes.is_empty() => bytes[i] = *byte,
            1 => bytes.insert(i.min(bytes.len()), *byte),
            _ if !bytes.is_empty() => {
                bytes.remove(i);
            }
            _ => {}
        }
    }
    bytes
}

/// Numbers a hostile or careless user writes: huge, tiny, negative, not numbers at all.
fn extreme_number() -> impl Strategy<Value = String> {
    prop_oneof![
        any::<f64>().prop_map(|v| format!("{v:e}")),
        any::<i64>().prop_map(|v| v.to_string()),
        Just("nan".to_owned()),
        Just("inf".to_owned()),
        Just("-inf".to_owned()),
        Just("1e308".to_owned()),
        Just("-0.0".to_owned()),
        Just("18446744073709551616".to_owned()),
        Just("\"text\"".to_owned()),
    ]
}

const STAGE3: &str = include_str!("../../../configs/experiments/stage3.toml");

fn config_result(text: &str) -> Result<TrainConfig, String> {
    TrainConfig::from_toml(text, "fuzz.toml", None).map_err(|e| e.to_string())
}

/// Keys of every table, numeric or interval-valued, as a config file writes them.
const KEYS: [(&str, &str, bool); 16] = [
    ("runner", "envs", false),
    ("runner", "iterations", false),
    ("runner", "seed", false),
    ("runner", "checkpoint_every", false),
    ("ppo", "learning_rate", false),
    ("ppo", "epochs", false),
    ("ppo", "steps_per_env", false),
    ("ppo", "init_noise_std", false),
    ("task.episode", "max_steps", false),
    ("task.episode", "max_position_error_m", false),
    ("task.control", "substeps", false),
    ("task.observation", "lookahead_steps", false),
    ("task.reference", "forward_speed_mps", true),
    ("task.reference", "loop_duration_s", false),
    ("task.initial_state", "speed_offset_mps", false),
    ("task.randomization", "wind_mps", true),
];

proptest! {
    #![proptest_config(cases())]

    #[test]
    fn config_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        if let Err(message) = config_result(&String::from_utf8_lossy(&bytes)) {
            prop_assert!(message.contains("fuzz.toml"), "{}", message);
        }
    }

    #[test]
    fn config_mutated(edits in mutations()) {
        if let Err(message) = config_result(&String::from_utf8_lossy(&mutate(STAGE3.as_bytes(), &edits))) {
            prop_assert!(message.contains("fuzz.toml"), "{}", message);
        }
    }

    #[test]
    fn config_extreme_numbers(key in 0..KEYS.len(), value in extreme_number(), other in extreme_number()) {
        let (table, name, interval) = KEYS[key];
        let value = if interval { format!("[{value}, {other}]") } else { value };
        match config_result(&format!("[{table}]\n{name} = {value}\n")) {
            Ok(config) => {
                // What is accepted is finite and within what the run can hold.
                prop_assert!(config.runner.envs <= 65_536 && config.task.episode.max_steps <= 1_000_000);
                prop_assert!(config.ppo.learning_rate.is_finite() && config.task.reference.loop_duration_s.is_finite());
            }
            Err(message) => prop_assert!(message.contains("fuzz.toml"), "{}", message),
        }
    }

    #[test]
    fn reference_csv_random_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        if let Err(e) = parse_reference_csv(&String::from_utf8_lossy(&bytes), "fuzz.csv", 0.02, 30) {
            prop_assert!(e.to_string().contains("fuzz.csv"), "{}", e);
        }
    }

    #[test]
    fn reference_csv_mutated(edits in mutations()) {
        let valid = "time_s,x_m,y_m,z_m\n0,0,0,10\n1,3.8,0,10\n2,7.6,0,10.5\n";
        let text = String::from_utf8_lossy(&mutate(valid.as_bytes(), &edits)).into_owned();
        match parse_reference_csv(&text, "fuzz.csv", 0.02, 30) {
            Ok(reference) => prop_assert!(reference.points().iter().all(|p| p.is_finite())),
            Err(e) => prop_assert!(e.to_string().contains("fuzz.csv"), "{}", e),
        }
    }

    #[test]
    fn reference_csv_extreme_numbers(rows in proptest::collection::vec(proptest::collection::vec(extreme_number(), 4), 1..6)) {
        let mut text = String::from("time_s,x_m,y_m,z_m\n");
        for row in &rows {
            text.push_str(&row.join(","));
            text.push('\n');
        }
        match parse_reference_csv(&text, "fuzz.csv", 0.02, 0) {
            Ok(reference) => prop_assert!(reference.points().iter().all(|p| p.is_finite() && p.abs().max_element() <= 1e6)),
            Err(e) => prop_assert!(e.to_string().contains("fuzz.csv"), "{}", e),
        }
    }
}

/// A small flight policy (16 hidden units) from one training iteration, and a scratch folder named by `label`.
fn small_policy(label: &str) -> (Vec<u8>, PathBuf) {
    // A folder per test: tests run side by side in one process.
    let dir = std::env::temp_dir().join(format!("flapper-fuzz-{label}-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let config = TrainConfig::from_toml(
        "[runner]\nenvs = 2\niterations = 1\nthreads = 1\n[ppo]\nsteps_per_env = 4\nminibatches = 1\nepochs = 1\n\
         actor_hidden = [16]\ncritic_hidden = [16]\n",
        "small.toml",
        None,
    )
    .unwrap();
    let mut trainer = flight_trainer(&RobotModel::flapper().unwrap(), &config, &dir.join("run"), Start::Fresh).unwrap();
    trainer.run(&mut |_, _| true).unwrap();
    (std::fs::read(dir.join("run/policy.safetensors")).unwrap(), dir)
}

fn check_policy_file(path: &Path, bytes: &[u8]) -> Result<(), TestCaseError> {
    std::fs::write(path, bytes).unwrap();
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    if let Err(e) = checkpoint::load(path) {
        prop_assert!(e.to_string().contains(&name), "{}", e);
    }
    match load_flight_policy(path) {
        Ok((policy, _)) => prop_assert!(policy.actor.params().iter().all(|w| w.is_finite())),
        Err(e) => prop_assert!(e.to_string().contains(&name), "{}", e),
    }
    Ok(())
}

#[test]
fn policy_files_random_and_mutated() {
    let (valid, dir) = small_policy("mutated");
    let path = dir.join("fuzz-policy.safetensors");
    check_policy_file(&path, &valid).unwrap();
    assert!(load_flight_policy(&path).is_ok(), "the unmutated file loads");
    let mut runner = proptest::test_runner::TestRunner::new(cases());
    // Most mutations land in the tensors; half of them are aimed at the header (the JSON metadata).
    let header = u64::from_le_bytes(valid[..8].try_into().unwrap()) as usize + 8;
    let strategy = (mutations(), any::<bool>(), proptest::collection::vec(any::<u8>(), 0..400), 0..4u8);
    runner
        .run(&strategy, |(edits, in_header, random, kind)| {
            let bytes = match kind {
                0 => random,
                _ if in_header => {
                    let mut bytes = mutate(&valid[..header], &edits);
                    bytes.extend_from_slice(&valid[header..]);
                    bytes
                }
                _ => mutate(&valid, &edits),
            };
            check_policy_file(&path, &bytes)
        })
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
}

/// `valid` with its flapper description's `key` replaced by `value` (the safetensors header rewritten).
fn with_metadata(valid: &[u8], key: &str, value: serde_json::Value) -> Vec<u8> {
    let header_len = u64::from_le_bytes(valid[..8].try_into().unwrap()) as usize;
    let mut header: serde_json::Value = serde_json::from_slice(&valid[8..8 + header_len]).unwrap();
    let metadata = header["__metadata__"].as_object_mut().unwrap();
    let (name, text) = metadata.iter().next().map(|(k, v)| (k.clone(), v.as_str().unwrap().to_owned())).unwrap();
    let mut info: serde_json::Value = serde_json::from_str(&text).unwrap();
    info[key] = value;
    metadata.insert(name, serde_json::Value::String(info.to_string()));
    let mut json = serde_json::to_vec(&header).unwrap();
    json.resize(json.len().next_multiple_of(8), b' ');
    let mut bytes = (json.len() as u64).to_le_bytes().to_vec();
    bytes.extend(json);
    bytes.extend_from_slice(&valid[8 + header_len..]);
    bytes
}

#[test]
fn policy_metadata_declaring_enormous_networks_is_refused_without_allocating_them() {
    let (valid, dir) = small_policy("enormous");
    let path = dir.join("enormous.safetensors");
    let layers = |n: usize, width: usize| serde_json::json!([vec![540], vec![width; n], vec![5]].concat());
    for (key, value) in [
        ("actor_sizes", layers(100_000, 256)),
        ("actor_sizes", layers(3, 65_536)),
        ("critic_sizes", layers(2_000, 65_536)),
        ("observation_size", serde_json::json!(40_000_000_000u64)),
        ("action_size", serde_json::json!(u64::MAX)),
    ] {
        let bytes = with_metadata(&valid, key, value);
        std::fs::write(&path, &bytes).unwrap();
        let error = load_flight_policy(&path).err().unwrap_or_else(|| panic!("{key}: loaded")).to_string();
        assert!(error.contains("enormous.safetensors"), "{key}: {error}");
    }
    let mut runner = proptest::test_runner::TestRunner::new(cases());
    let sizes = proptest::collection::vec(1usize..100_000, 0..3_000);
    runner
        .run(&(sizes, any::<bool>()), |(sizes, actor)| {
            let key = if actor { "actor_sizes" } else { "critic_sizes" };
            check_policy_file(&path, &with_metadata(&valid, key, serde_json::json!(sizes)))
        })
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
}
