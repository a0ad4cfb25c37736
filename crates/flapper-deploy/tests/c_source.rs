//! The C export computes flapper's own actions to the bit: compiled by the system C compiler as strict
//! ISO C99 (`-std=c99 -Wall -Werror -ffp-contract=off`), run on the observations of a real flight.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Arc;

use flapper_deploy::c_compiler::CCompiler;
use flapper_deploy::{DeployablePolicy, write_c_source};
use flapper_eval::tracking::{TrackingController, record_episode};
use flapper_ppo::InferenceScratch;
use flapper_sim::RobotModel;

fn shipped(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(path)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flapper-deploy-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Reads rows of float32 observations from argv[1] and writes the actions to argv[2].
const RUN_ON_FILE: &str = r#"#include <stdio.h>
#include "policy.h"

int main(int argc, char **argv) {
    float obs[FLAPPER_POLICY_OBSERVATION_SIZE], actions[FLAPPER_POLICY_ACTION_SIZE];
    FILE *in, *out;
    if (argc != 3) return 2;
    in = fopen(argv[1], "rb");
    out = fopen(argv[2], "wb");
    if (!in || !out) return 3;
    while (fread(obs, sizeof(float), FLAPPER_POLICY_OBSERVATION_SIZE, in) == FLAPPER_POLICY_OBSERVATION_SIZE) {
        flapper_policy_act(obs, actions);
        if (fwrite(actions, sizeof(float), FLAPPER_POLICY_ACTION_SIZE, out) != FLAPPER_POLICY_ACTION_SIZE) return 4;
    }
    return fclose(out) != 0;
}
"#;

#[test]
fn the_exported_c_gives_the_rust_actions_bit_for_bit_on_a_real_flight() {
    let compiler = CCompiler::find().expect("a C compiler (cc or $CC): the C export's test compiles it");
    let robot = RobotModel::flapper().unwrap();
    let deployable = DeployablePolicy::load(&shipped("policies/final/policy.safetensors"), &robot).unwrap();
    let policy = Arc::new(deployable.policy.clone());

    // A real flight: the shipped controller on the longitudinal reference, as `flapper eval` flies episode 0.
    let (file, task) = flapper_eval::load_flight_policy(&shipped("policies/final/policy.safetensors")).unwrap();
    assert_eq!(file, *policy);
    let period = task.control_period_s(robot.timestep_s());
    let reference =
        Arc::new(flapper_task::reference::resolve("longitudinal", period, task.observation.lookahead_steps).unwrap());
    let (result, trace) =
        record_episode(&robot, &TrackingController::Policy(policy.clone()), &task, reference, 11, 0).unwrap();
    assert!(result.completed() && trace.observations.len() > 1000, "{} steps", trace.observations.len());
    let observations: Vec<f32> = trace.observations.concat();

    let dir = scratch("c");
    write_c_source(&deployable, &dir.join("policy.c")).unwrap();
    std::fs::write(dir.join("run_on_file.c"), RUN_ON_FILE).unwrap();
    let program = dir.join("run_on_file");
    compiler.build(&[&dir.join("policy.c"), &dir.join("run_on_file.c")], &dir, &program).unwrap();
    let bytes: Vec<u8> = observations.iter().flat_map(|v| v.to_ne_bytes()).collect();
    std::fs::write(dir.join("observations.f32"), bytes).unwrap();
    let done = Command::new(&program).arg(dir.join("observations.f32")).arg(dir.join("actions.f32")).output().unwrap();
    assert!(done.status.success(), "{done:?}");
    let c_actions: Vec<f32> = std::fs::read(dir.join("actions.f32"))
        .unwrap()
        .chunks_exact(4)
        .map(|b| f32::from_ne_bytes(b.try_into().unwrap()))
        .collect();

    // Rust's actions, clipped as the environment clips them; flapper eval recorded the unclipped ones.
    let mut rust = Vec::new();
    policy.act_deterministic(&observations, &mut InferenceScratch::default(), &mut rust);
    assert_eq!(rust, trace.actions.concat(), "the recorded actions are the policy's");
    let clipped: Vec<f32> = rust.iter().map(|a| a.clamp(-1.0, 1.0)).collect();
    assert_eq!(c_actions.len(), clipped.len());
    let inside = rust.iter().filter(|a| a.abs() < 1.0).count();
    assert!(inside > rust.len() / 4, "most actions are not at the clip: {inside} of {}", rust.len());
    for (k, (c, r)) in c_actions.iter().zip(&clipped).enumerate() {
        assert_eq!(c.to_bits(), r.to_bits(), "step {} action {}: C {c} against Rust {r}", k / 5, k % 5);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_export_refuses_an_existing_file_and_a_name_without_c() {
    let robot = RobotModel::flapper().unwrap();
    let deployable = DeployablePolicy::load(&shipped("policies/history/stage1/policy.safetensors"), &robot).unwrap();
    let dir = scratch("refuse");
    std::fs::write(dir.join("policy.h"), "kept").unwrap();
    let error = write_c_source(&deployable, &dir.join("policy.c")).unwrap_err().to_string();
    assert!(error.contains("policy.h' exists"), "{error}");
    assert_eq!(std::fs::read_to_string(dir.join("policy.h")).unwrap(), "kept");
    assert!(!dir.join("policy.c").exists());
    let error = write_c_source(&deployable, &dir.join("policy.txt")).unwrap_err().to_string();
    assert!(error.contains("NAME.c"), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stage-1 policy saved as `file` in a scratch folder with `[task.SECTION] KEY = value` set in its
/// config (`appended_inputs` more zero-weighted inputs), and what `DeployablePolicy::load` makes of it
/// (with the C header it writes, when it exports).
fn export_of(
    file: &str,
    section: &str,
    key: &str,
    value: f64,
    appended_inputs: usize,
) -> Result<(DeployablePolicy, String), String> {
    use flapper_ppo::checkpoint;
    let robot = RobotModel::flapper().unwrap();
    let source = checkpoint::load(&shipped("policies/history/stage1/policy.safetensors")).unwrap();
    let mut config: toml::Table = source.info.config_toml.parse().unwrap();
    let task = config.entry("task").or_insert(toml::Value::Table(toml::Table::new())).as_table_mut().unwrap();
    let table = task.entry(section).or_insert(toml::Value::Table(toml::Table::new()));
    table.as_table_mut().unwrap().insert(key.into(), toml::Value::Float(value));
    let edited = source.with_inputs_appended(appended_inputs);
    let info = checkpoint::CheckpointInfo { config_toml: toml::to_string(&config).unwrap(), ..edited.info.clone() };
    let dir = scratch(key);
    let path = dir.join(file);
    checkpoint::save(&path, &info, &edited.policy, None, None).unwrap();
    let exported = DeployablePolicy::load(&path, &robot).map_err(|e| e.to_string()).map(|deployable| {
        let header = write_c_source(&deployable, &dir.join("policy.c")).unwrap();
        let text = std::fs::read_to_string(header).unwrap();
        (deployable, text)
    });
    let _ = std::fs::remove_dir_all(&dir);
    exported
}

#[test]
fn the_export_refuses_a_policy_that_reads_a_clock() {
    let error = export_of("clocked.safetensors", "observation", "clock_hz", 5.3, 2).expect_err("the export refuses it");
    assert!(error.contains("clocked.safetensors") && error.contains("5.3 Hz clock"), "{error}");
}

#[test]
fn passive_feathering_travels_as_a_fact_of_the_export() {
    let (feathered, header) = export_of("feathered.safetensors", "control", "passive_feathering_s", 0.03, 0).unwrap();
    assert_eq!(feathered.facts.passive_feathering_s, 0.03);
    assert!(feathered.facts.metadata().contains(&("passive_feathering_s".into(), "0.03".into())));
    assert!(header.contains("#define FLAPPER_POLICY_PASSIVE_FEATHERING_S 0.03"), "{header}");
    assert!(header.contains("Passive feathering: before the filter"), "{header}");

    // Without it the fact reads 0 and the header says nothing of a twist.
    let (plain, header) = export_of("plain.safetensors", "control", "passive_feathering_s", 0.0, 0).unwrap();
    assert_eq!(plain.facts.passive_feathering_s, 0.0);
    assert!(
        header.contains("#define FLAPPER_POLICY_PASSIVE_FEATHERING_S 0.0") && !header.contains("Passive feathering")
    );
}
