//! The `flapper` command end to end: it writes what it says, and bad input gets one clear line on
//! stderr, a non-zero exit code, no panic, and leaves existing output alone.

use std::path::PathBuf;
use std::process::{Command, Output};

fn flapper(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_flapper")).args(args).output().expect("run flapper")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flapper-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Fails unless the command failed with exactly one line on stderr mentioning `needle`.
fn assert_one_line_error(output: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success(), "expected failure, stderr: {stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "expected one line, got: {stderr}");
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for clause in stderr.trim_end().split(": ").filter(|clause| clause.len() >= 30) {
        assert_eq!(stderr.matches(clause).count(), 1, "'{clause}' said twice: {stderr}");
    }
}

/// An argument error as clap reports it: exit code 2, what is wrong, and the subcommand's usage.
fn assert_usage_error(output: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(stderr.starts_with("error: ") && stderr.contains("Usage: flapper"), "{stderr}");
    assert!(stderr.contains(needle), "'{needle}' not in: {stderr}");
}

#[test]
fn fly_writes_csv_and_plots() {
    let out = scratch("fly");
    let output = flapper(&["fly", "--controller", "scripted", "--seconds", "2", "--out", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("altitude change") && stdout.contains("mechanical power"), "{stdout}");
    for file in ["flight.csv", "altitude_speed.svg", "joints.svg", "path.svg"] {
        assert!(out.join(file).metadata().unwrap().len() > 100, "{file} missing or empty");
    }
}

#[test]
fn missing_model_file_is_one_line_naming_it() {
    let output = flapper(&["--model", "/no/such/robot.xml", "fly", "--seconds", "1"]);
    assert_one_line_error(&output, "/no/such/robot.xml");
}

#[test]
fn malformed_model_file_is_one_line_with_mujocos_message() {
    let dir = scratch("malformed");
    let model = dir.join("broken.xml");
    std::fs::write(&model, "<mujoco><worldbody><geom type='sphere'/></wrldbody></mujoco>").unwrap();
    let output = flapper(&["--model", model.to_str().unwrap(), "bench", "--blocks", "1"]);
    assert_one_line_error(&output, "broken.xml");
    assert_one_line_error(&output, "MuJoCo");
}

#[test]
fn a_model_that_is_not_the_robot_is_rejected() {
    let dir = scratch("other");
    let model = dir.join("ball.xml");
    std::fs::write(&model, "<mujoco><worldbody><body><freejoint/><geom size='0.1'/></body></worldbody></mujoco>")
        .unwrap();
    assert_one_line_error(&flapper(&["--model", model.to_str().unwrap(), "fly"]), "not the flapping-wing robot");
}

#[test]
fn bad_duration_is_rejected_and_existing_output_is_kept() {
    let out = scratch("keep");
    std::fs::write(out.join("flight.csv"), "precious").unwrap();
    for seconds in ["-3", "0", "nan", "1e9"] {
        let output = flapper(&["fly", "--seconds", seconds, "--out", out.to_str().unwrap()]);
        assert_one_line_error(&output, "--seconds");
    }
    assert_eq!(std::fs::read_to_string(out.join("flight.csv")).unwrap(), "precious");
}

#[test]
fn output_path_that_is_a_file_is_one_line() {
    let dir = scratch("file-out");
    let file = dir.join("occupied");
    std::fs::write(&file, "x").unwrap();
    assert_one_line_error(&flapper(&["fly", "--seconds", "1", "--out", file.to_str().unwrap()]), "occupied");
}

#[test]
fn bench_prints_microseconds_per_step() {
    assert_one_line_error(&flapper(&["bench", "--threads", "100000"]), "--threads at most 1024");
    assert_one_line_error(&flapper(&["bench", "--envs", "100000"]), "--envs must be at most 65536");
    let output = flapper(&["bench", "--blocks", "3", "--steps", "500", "--envs", "8", "--train-iterations", "1"]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("mj_step") && stdout.contains("control step"), "{stdout}");
    assert!(stdout.contains("PPO training end to end") && stdout.contains("update"), "{stdout}");
}

#[test]
fn reference_by_name_writes_csv_and_views() {
    let out = scratch("reference");
    let output = flapper(&["reference", "loop", "--out", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let csv = std::fs::read_to_string(out.join("reference.csv")).unwrap();
    assert_eq!(csv.lines().next(), Some("time_s,x_m,y_m,z_m"));
    assert_eq!(csv.lines().count(), 1 + 451, "9 s at 50 Hz plus the start");
    assert!(std::fs::read_to_string(out.join("reference.svg")).unwrap().contains("<svg"));
    let listed = flapper(&["reference", "--list"]);
    let stdout = String::from_utf8_lossy(&listed.stdout);
    for name in ["longitudinal", "lateral", "loop", "sharp-turn", "roll-off-the-bottom", "immelmann", "aerobatic"] {
        assert!(stdout.contains(name), "{name} not listed");
    }
}

#[test]
fn unknown_reference_and_bad_csv_are_one_line_errors() {
    assert_one_line_error(&flapper(&["reference", "barrel-roll"]), "barrel-roll");
    let dir = scratch("bad-reference");
    let file = dir.join("path.csv");
    std::fs::write(&file, "time_s,x_m,y_m,z_m\n0,0,0,0\n0.5,1,0,inf\n1,2,0,0\n").unwrap();
    assert_one_line_error(&flapper(&["reference", file.to_str().unwrap(), "--out", dir.to_str().unwrap()]), "line 3");
    assert!(!dir.join("reference.csv").exists(), "nothing written for a rejected file");
}

/// A config for a train run of seconds: 4 environments, 2 iterations of 8 steps, small networks.
fn tiny_train_config(dir: &std::path::Path) -> PathBuf {
    let path = dir.join("tiny.toml");
    std::fs::write(
        &path,
        "[runner]\nenvs = 4\niterations = 2\nthreads = 1\ncheckpoint_every = 1\n[ppo]\nsteps_per_env = 8\nactor_hidden = [8]\ncritic_hidden = [8]\n[task.episode]\nmax_steps = 30\n",
    )
    .unwrap();
    path
}

#[test]
fn train_writes_a_run_resumes_it_and_eval_flies_its_policy() {
    let dir = scratch("train");
    let config = tiny_train_config(&dir);
    let run = dir.join("run");
    let output = flapper(&["train", "--config", config.to_str().unwrap(), "--out", run.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    for file in [
        "config.toml",
        "training.csv",
        "learning_curves.svg",
        "policy.safetensors",
        "policy.safetensors.json",
        "checkpoints/iter_000002.safetensors",
    ] {
        assert!(run.join(file).exists(), "{file} missing");
    }
    let csv = std::fs::read_to_string(run.join("training.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    for column in
        ["mean_return", "end_too_far", "r_position", "value_loss", "kl", "learning_rate", "action_std", "update_time_s"]
    {
        assert!(csv.lines().next().unwrap().split(',').any(|h| h == column), "no column {column}");
    }

    // Starting again into the same folder is refused; --resume with more iterations extends it.
    let again = flapper(&["train", "--config", config.to_str().unwrap(), "--out", run.to_str().unwrap()]);
    assert_one_line_error(&again, "already holds a training run");
    // A resumed run keeps its environment count and seed; asking for others is an error, not a silent change.
    let csv_before = std::fs::read_to_string(run.join("training.csv")).unwrap();
    assert_one_line_error(
        &flapper(&["train", "--resume", "--iterations", "3", "--envs", "6", "--out", run.to_str().unwrap()]),
        "--envs 6 with --resume",
    );
    assert_usage_error(
        &flapper(&["train", "--resume", "--iterations", "3", "--seed", "99", "--out", run.to_str().unwrap()]),
        "cannot be used with",
    );
    assert_eq!(
        std::fs::read_to_string(run.join("training.csv")).unwrap(),
        csv_before,
        "a refused resume changes nothing"
    );
    let resumed = flapper(&["train", "--resume", "--iterations", "3", "--out", run.to_str().unwrap()]);
    assert!(resumed.status.success(), "{}", String::from_utf8_lossy(&resumed.stderr));
    assert_eq!(std::fs::read_to_string(run.join("training.csv")).unwrap().lines().count(), 4);

    // A checkpoint exported as a policy flies like one; an existing target is refused and kept.
    let exported = dir.join("iter2.safetensors");
    let checkpoint = run.join("checkpoints/iter_000002.safetensors");
    let output =
        flapper(&["export-policy", "--checkpoint", checkpoint.to_str().unwrap(), "--out", exported.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("iteration 2"));
    let sidecar = std::fs::read_to_string(dir.join("iter2.safetensors.json")).unwrap();
    assert!(sidecar.contains("\"kind\": \"policy\""), "{sidecar}");
    let before = std::fs::read(&exported).unwrap();
    let again =
        flapper(&["export-policy", "--checkpoint", checkpoint.to_str().unwrap(), "--out", exported.to_str().unwrap()]);
    assert_one_line_error(&again, "exists");
    assert_eq!(std::fs::read(&exported).unwrap(), before);
    // Several checkpoints of one run: the mean of their weights; a missing one is named.
    let averaged = dir.join("mean12.safetensors");
    let first = run.join("checkpoints/iter_000001.safetensors");
    let pair = [first.to_str().unwrap(), checkpoint.to_str().unwrap()];
    let output = flapper(&["export-policy", "--checkpoint", pair[0], pair[1], "--out", averaged.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(String::from_utf8_lossy(&output.stdout).contains("the mean of 2 checkpoints, newest iteration 2"));
    let missing = dir.join("iter_999.safetensors");
    let output = flapper(&[
        "export-policy",
        "--checkpoint",
        pair[0],
        missing.to_str().unwrap(),
        "--out",
        dir.join("never.safetensors").to_str().unwrap(),
    ]);
    assert_one_line_error(&output, "iter_999.safetensors");
    assert!(!dir.join("never.safetensors").exists());
    // A running training's checkpoint exports for a robot too, saying which iteration it is.
    let c_out = dir.join("iter2.c");
    let output = flapper(&[
        "export-policy",
        "--policy",
        checkpoint.to_str().unwrap(),
        "--format",
        "c",
        "--out",
        c_out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("a checkpoint of a training run, iteration 2"), "{stdout}");
    assert!(dir.join("iter2.h").exists());

    let eval_out = dir.join("eval");
    let policy = run.join("policy.safetensors");
    let output = flapper(&[
        "eval",
        "--policy",
        policy.to_str().unwrap(),
        "--reference",
        "cruise",
        "--episodes",
        "2",
        "--out",
        eval_out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(
        stdout.contains("completed") && stdout.contains("flap_left fundamental") && stdout.contains("scripted"),
        "{stdout}"
    );
    for file in [
        "summary.csv",
        "policy/steps.csv",
        "policy/path_3d.svg",
        "policy/path.svg",
        "policy/error.svg",
        "policy/joints.svg",
        "scripted/steps.csv",
    ] {
        assert!(eval_out.join(file).metadata().unwrap().len() > 100, "{file} missing or empty");
    }
    assert!(!eval_out.join("policy/segments.csv").exists(), "segments belong to the longitudinal reference");
    // summary.csv is the printed table: a row per metric (labels with commas stay one field), a column per controller.
    let mut summary = csv::Reader::from_path(eval_out.join("summary.csv")).unwrap();
    assert_eq!(summary.headers().unwrap().iter().collect::<Vec<_>>(), ["metric", "policy", "scripted"]);
    let rows: Vec<csv::StringRecord> = summary.records().map(|r| r.unwrap()).collect();
    assert!(rows.iter().all(|r| r.len() == 3));
    assert_eq!(&rows[0][0], "completed");
    assert!(rows.iter().any(|r| r[0].contains("mechanical power (W), net")), "a label with a comma is one field");
}

#[test]
fn train_rejects_bad_configs_and_checkpoints_with_one_line() {
    let dir = scratch("train-bad");
    let unknown = dir.join("unknown.toml");
    std::fs::write(&unknown, "[ppo]\nclip_range = 0.2\n").unwrap();
    let out = dir.join("run");
    assert_one_line_error(
        &flapper(&["train", "--config", unknown.to_str().unwrap(), "--out", out.to_str().unwrap()]),
        "clip_range",
    );
    let range = dir.join("range.toml");
    std::fs::write(&range, "[ppo]\nlambda = 2.0\n").unwrap();
    assert_one_line_error(
        &flapper(&["train", "--config", range.to_str().unwrap(), "--out", out.to_str().unwrap()]),
        "ppo.lambda",
    );
    let action = dir.join("action.toml");
    std::fs::write(&action, "[task.control]\naction_mode = \"flap_oscillator\"\nflap_amplitude_max = 9.0\n").unwrap();
    assert_one_line_error(
        &flapper(&["train", "--config", action.to_str().unwrap(), "--out", out.to_str().unwrap()]),
        "control.flap_amplitude_max = 9",
    );
    assert_one_line_error(
        &flapper(&["train", "--config", dir.join("absent.toml").to_str().unwrap(), "--out", out.to_str().unwrap()]),
        "absent.toml",
    );
    assert_one_line_error(
        &flapper(&["train", "--resume", "--out", dir.join("nothing").to_str().unwrap()]),
        "config.toml",
    );
    assert!(!out.exists(), "a refused run creates nothing");

    // A truncated checkpoint: the file is named, nothing is written.
    let config = tiny_train_config(&dir);
    let good = dir.join("good");
    assert!(
        flapper(&["train", "--config", config.to_str().unwrap(), "--out", good.to_str().unwrap()]).status.success()
    );
    let bytes = std::fs::read(good.join("policy.safetensors")).unwrap();
    let truncated = dir.join("truncated.safetensors");
    std::fs::write(&truncated, &bytes[..bytes.len() - 100]).unwrap();
    let chained = dir.join("chained");
    let output = flapper(&[
        "train",
        "--config",
        config.to_str().unwrap(),
        "--init-from",
        truncated.to_str().unwrap(),
        "--out",
        chained.to_str().unwrap(),
    ]);
    assert_one_line_error(&output, "truncated.safetensors");
    assert!(!chained.join("training.csv").exists());
    assert_one_line_error(
        &flapper(&["eval", "--policy", truncated.to_str().unwrap(), "--episodes", "1"]),
        "truncated.safetensors",
    );
    assert_one_line_error(
        &flapper(&["eval", "--baseline-only", "--reference", "nowhere", "--episodes", "1"]),
        "unknown reference 'nowhere'",
    );
}

#[test]
fn argument_errors_show_clap_s_whole_message_and_eval_needs_a_policy() {
    // A missing required flag is named, with the subcommand's usage.
    assert_usage_error(&flapper(&["sysid", "--out", "x"]), "--policy <FILE>");
    // An invalid value lists the valid ones and suggests the closest.
    let stderr = String::from_utf8_lossy(&flapper(&["fly", "--controller", "glid"]).stderr).to_string();
    assert!(stderr.contains("scripted, glide") && stderr.contains("'glide'"), "{stderr}");
    let stderr = String::from_utf8_lossy(&flapper(&["evl"]).stderr).to_string();
    assert!(stderr.contains("'eval'"), "did you mean: {stderr}");
    // No silent baseline-only evaluation.
    assert_one_line_error(&flapper(&["eval", "--episodes", "1"]), "--baseline-only");
}

/// Every numeric flag refuses a negative number naming the flag: a count or a seed as clap's invalid
/// value (clap would otherwise take `-1` for an unknown flag and name none), the others by their own
/// range check, before any work. Not here: `fly --tail-deg`, whose negative angles are valid.
#[test]
fn a_negative_number_is_refused_naming_its_flag() {
    let out = scratch("negative");
    let (o, policy) = (out.to_str().unwrap(), shipped_policy("final"));
    let p = policy.as_str();
    let flags: &[(&[&str], &[&str])] = &[
        (&["eval", "--policy", p, "--out", o], &["--episodes", "--seed"]),
        (&["train", "--out", o], &["--stage", "--iterations", "--seed", "--envs"]),
        (&["curriculum", "--out", o], &["--seed", "--until-stage"]),
        (&["bench"], &["--blocks", "--steps", "--envs", "--threads", "--train-iterations"]),
        (&["pendulum", "--out", o], &["--seeds", "--max-iterations"]),
        (&["fly", "--out", o], &["--seconds"]),
        (&["render", "--policy", p, "--out", o], &["--seed"]),
        (&["report", "--out", o], &["--episodes", "--robustness-episodes", "--seed"]),
        (&["robustness", "--policy", p, "--out", o], &["--episodes", "--seed", "--ranges"]),
        (&["sysid", "--policy", p, "--out", o], &["--seed", "--amplitude-m", "--input-lead-s", "--averaged-periods"]),
        (&["phase", "--policy", p, "--out", o], &["--speed-mps"]),
        (&["frontier", "--policy", p, "--out", o], &["--episodes", "--seed"]),
        (&["power-curve", "--out", o], &["--episodes", "--seed", "--speeds", "--frequencies", "--pitch-amplitudes"]),
    ];
    for (command, flags) in flags {
        for flag in *flags {
            let args = [command, &[*flag, "-1"][..]].concat();
            let output = flapper(&args);
            let stderr = String::from_utf8_lossy(&output.stderr);
            let first = stderr.lines().next().unwrap_or_default();
            assert!(!output.status.success() && !stderr.contains("panicked"), "{args:?}: {stderr}");
            assert!(first.starts_with("error: ") && first.contains("-1"), "{args:?}: {stderr}");
            assert!(first.contains(&format!("{flag} ")) || first.contains(&format!("{flag}:")), "{args:?}: {stderr}");
        }
    }
    assert!(std::fs::read_dir(&out).unwrap().next().is_none(), "a refused command writes nothing");
    let stage = flapper(&["train", "--stage", "7", "--out", o]);
    let stderr = String::from_utf8_lossy(&stage.stderr);
    assert!(stderr.starts_with("error: invalid value '7' for '--stage <STAGE>': 7 is not in 1..=4"), "{stderr}");
}

fn shipped_policy(folder: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../policies")
        .join(folder)
        .join("policy.safetensors")
        .display()
        .to_string()
}

#[test]
fn sysid_phase_and_modes_analyse_the_shipped_stage_2_policy() {
    let out = scratch("analysis");
    let policy = shipped_policy("history/stage2");
    let sysid = out.join("sysid");
    let output = flapper(&["sysid", "--policy", &policy, "--averaged-periods", "2", "--out", sysid.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(sysid.join("sysid.json")).unwrap()).unwrap();
    for axis in ["x", "y", "z"] {
        let m = &report[axis];
        assert_eq!(m["denominator"].as_array().unwrap().len(), 4, "{m}");
        assert_eq!(m["numerator"].as_array().unwrap().len(), 3);
        assert_eq!(m["poles"].as_array().unwrap().len(), 3);
        assert!(m["mse_validation"].as_f64().unwrap() > 0.0 && m["fit_percent"].as_f64().unwrap() > 0.0, "{m}");
        assert!(m["bibo_stable"].is_boolean() && m["minimum_phase"].is_boolean());
        let lead = m["input_lead_s"].as_f64().unwrap();
        assert!((0.0..=0.6).contains(&lead), "the lead is estimated within the policy's lookahead: {m}");
    }
    let io = std::fs::read_to_string(sysid.join("sysid_io.csv")).unwrap();
    assert!(io.starts_with("time_s,u_x,u_y,u_z,y_x,y_y,y_z,set,record\n"), "{}", &io[..80]);
    assert!(io.contains(",identification,0\n") && io.contains(",validation,0\n"));
    for file in ["pole_zero.svg", "validation.svg", "bode.svg"] {
        assert!(sysid.join(file).metadata().unwrap().len() > 1000, "{file}");
    }

    let phase = out.join("phase");
    let output = flapper(&["phase", "--policy", &policy, "--speed-mps", "3.5", "--out", phase.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("left turn skipped: the policy cannot turn"), "stage 2 never learned to turn: {stdout}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(phase.join("phase.json")).unwrap()).unwrap();
    assert!(report["claims"].as_array().unwrap().iter().all(|c| c["confirmed"].is_boolean()));

    let modes = out.join("modes");
    let output = flapper(&["modes", "--policy", &policy, "--out", modes.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(modes.join("modes.json")).unwrap()).unwrap();
    assert_eq!(report["segments"].as_array().unwrap().len(), 4);
}

#[test]
fn analysis_commands_reject_bad_input_with_one_line() {
    let out = scratch("analysis-bad");
    let o = out.to_str().unwrap();
    assert_one_line_error(
        &flapper(&["sysid", "--policy", "/no/such/policy.safetensors", "--out", o]),
        "/no/such/policy.safetensors",
    );
    let policy = shipped_policy("history/stage2");
    assert_one_line_error(&flapper(&["sysid", "--policy", &policy, "--amplitude-m", "5", "--out", o]), "--amplitude-m");
    assert_one_line_error(
        &flapper(&["sysid", "--policy", &policy, "--input-lead-s", "2", "--out", o]),
        "--input-lead-s",
    );
    assert_one_line_error(
        &flapper(&["sysid", "--policy", &policy, "--averaged-periods", "0", "--out", o]),
        "--averaged-periods",
    );
    assert_one_line_error(&flapper(&["phase", "--policy", &policy, "--speed-mps", "NaN", "--out", o]), "--speed-mps");
    // A perturbation the policy cannot follow is reported as such (after the progress line), not as a bad fit.
    let output = flapper(&["sysid", "--policy", &policy, "--amplitude-m", "1", "--averaged-periods", "1", "--out", o]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!output.status.success() && !stderr.contains("panicked"), "{stderr}");
    let last = stderr.trim_end().lines().last().unwrap();
    assert!(last.starts_with("error: the policy did not fly identification record"), "{stderr}");
}

#[test]
fn robustness_writes_the_sweeps_tables_and_rejects_bad_input() {
    let out = scratch("robustness");
    let o = out.to_str().unwrap();
    let policy = shipped_policy("history/stage3");
    let args = ["robustness", "--policy", &policy, "--reference", "sharp-turn", "--episodes", "2", "--seed", "5"];
    let output = flapper(&[&args[..], &["--sweeps", "fluid,wind", "--ranges", "0,0.5", "--out", o]].concat());
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let fluid = std::fs::read_to_string(out.join("robustness_fluid.csv")).unwrap();
    let mut lines = fluid.lines();
    assert_eq!(lines.next(), Some("coefficient,range,episodes,successes,success_rate"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 6 * 2, "six series at two ranges");
    for coefficient in ["blunt", "slender", "angular", "kutta", "magnus", "all"] {
        assert_eq!(rows.iter().filter(|r| r[0] == coefficient).count(), 2, "{coefficient}");
    }
    for row in &rows {
        let (episodes, successes, rate): (usize, usize, f64) =
            (row[2].parse().unwrap(), row[3].parse().unwrap(), row[4].parse().unwrap());
        assert_eq!(episodes, 2);
        assert!(successes <= episodes && rate == successes as f64 / episodes as f64, "{row:?}");
    }
    let wind = std::fs::read_to_string(out.join("robustness_wind.csv")).unwrap();
    assert!(wind.starts_with("wind_x_mps,wind_y_mps,wind_z_mps,episodes,successes,success_rate\n"), "{wind}");
    assert_eq!(wind.lines().count(), 1 + 21);
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("robustness.json")).unwrap()).unwrap();
    assert!(report["table_iii"].is_null() && report["envelope"].is_null(), "only the sweeps asked for");
    for file in ["robustness_fluid.svg", "robustness_wind.svg"] {
        assert!(out.join(file).metadata().unwrap().len() > 1000, "{file}");
    }

    for (bad, needle) in [
        (&["--sweeps", "fluid,gusts"][..], "gusts"),
        (&["--ranges", "0,1.5"][..], "1.5"),
        (&["--ranges", "NaN"][..], "NaN"),
        (&["--ranges", "-0.1,0.2"][..], "got -0.1"),
        (&["--reference", "no-such-manoeuvre"][..], "no-such-manoeuvre"),
    ] {
        let base = ["robustness", "--policy", &policy, "--episodes", "1", "--out", o];
        assert_one_line_error(&flapper(&[&base[..], bad].concat()), needle);
    }
    assert_one_line_error(&flapper(&["robustness", "--policy", &policy, "--episodes", "0", "--out", o]), "--episodes");
}

#[test]
fn a_folder_holding_files_flapper_did_not_write_is_refused_as_output() {
    let out = scratch("users-files");
    std::fs::write(out.join("summary.csv"), "my own table").unwrap();
    let o = out.to_str().unwrap();
    assert_one_line_error(&flapper(&["fly", "--seconds", "1", "--out", o]), "holds files flapper did not write");
    assert_one_line_error(&flapper(&["reference", "loop", "--out", o]), "new or empty folder");
    assert_eq!(std::fs::read_to_string(out.join("summary.csv")).unwrap(), "my own table");
    // A folder flapper made may be written again.
    let ours = out.join("ours");
    for _ in 0..2 {
        assert!(flapper(&["reference", "loop", "--out", ours.to_str().unwrap()]).status.success());
    }
    assert!(ours.join(".flapper-output").exists() && ours.join("reference.csv").exists());
}

#[test]
fn eval_on_the_longitudinal_reference_measures_each_segment_over_its_flights() {
    // The hand fine-tune that glides (`policies/experiments/smooth`): from randomized starts its wings are
    // held over most of the glide segment and never in the cruise, where the stroke costs more power.
    let out = scratch("segments");
    let policy = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies/experiments/smooth/policy.safetensors");
    let output = flapper(&[
        "eval",
        "--policy",
        policy.to_str().unwrap(),
        "--reference",
        "longitudinal",
        "--episodes",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("per segment of the longitudinal reference"), "{stdout}");
    let read = |pilot: &str| -> Vec<csv::StringRecord> {
        let mut reader = csv::Reader::from_path(out.join(pilot).join("segments.csv")).unwrap();
        assert_eq!(
            reader.headers().unwrap().iter().collect::<Vec<_>>(),
            [
                "segment",
                "start_s",
                "end_s",
                "flights",
                "episodes",
                "mean_absolute_power_w",
                "mean_error_m",
                "energy_per_metre_j",
                "glide_fraction"
            ]
        );
        reader.records().map(|r| r.unwrap()).collect()
    };
    let number = |row: &csv::StringRecord, k: usize| -> f64 { row[k].parse().unwrap() };
    let policy_rows = read("policy");
    let segments: Vec<&str> = policy_rows.iter().map(|r| &r[0]).collect();
    assert_eq!(segments, ["cruise", "climb", "glide", "dive"]);
    assert!(policy_rows.iter().all(|r| &r[3] == "3" && &r[4] == "3"), "every flight flies every segment");
    let (cruise, glide) = (&policy_rows[0], &policy_rows[2]);
    assert!(number(glide, 8) >= 0.5 && number(cruise, 8) < 0.1, "{glide:?} {cruise:?}");
    assert!(number(glide, 5) < 0.5 * number(cruise, 5), "{glide:?} {cruise:?}");
    // The scripted gait falls behind in the climb: no flight of it reaches the climb's end.
    let scripted = read("scripted");
    assert_eq!(&scripted[1][3], "0", "{:?}", scripted[1]);

    // A file of one's own that happens to be called `longitudinal` is flown, but has no such segments.
    let own = scratch("segments-own");
    let rows: String = (0..=50).map(|k| format!("{:.1},{:.1},0,10\n", 0.1 * k as f64, 0.4 * k as f64)).collect();
    std::fs::write(own.join("longitudinal"), format!("time_s,x_m,y_m,z_m\n{rows}")).unwrap();
    let output = Command::new(env!("CARGO_BIN_EXE_flapper"))
        .args(["eval", "--policy", policy.to_str().unwrap(), "--reference", "longitudinal", "--episodes", "1"])
        .args(["--no-baseline", "--out", "eval"])
        .current_dir(&own)
        .output()
        .unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(own.join("eval/policy/steps.csv").exists());
    assert!(!own.join("eval/policy/segments.csv").exists(), "{}", String::from_utf8_lossy(&output.stdout));
}

#[test]
fn eval_writes_what_the_policy_saw_and_did() {
    // --observations: episode 0's observations and actions, one row per control step. Each row's
    // action is the "previous action" of the next row's newest frame (clipped to [-1, 1]), and the
    // first row's previous action is the reset's (every joint at 0: action 0).
    let out = scratch("observations");
    let policy = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../policies/history/stage2/policy.safetensors");
    let output = flapper(&[
        "eval",
        "--policy",
        policy.to_str().unwrap(),
        "--reference",
        "cruise",
        "--episodes",
        "1",
        "--no-baseline",
        "--observations",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let mut reader = csv::Reader::from_path(out.join("policy/observations.csv")).unwrap();
    let header = reader.headers().unwrap().clone();
    assert_eq!(header.len(), 1 + 540 + 5);
    let column = |name: &str| header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"));
    let previous = column("t-0.action.flap_left");
    let action = column("action_q1");
    let rows: Vec<Vec<f64>> =
        reader.records().map(|r| r.unwrap().iter().map(|v| v.parse().unwrap()).collect()).collect();
    let steps = std::fs::read_to_string(out.join("policy/steps.csv")).unwrap().lines().count() - 1;
    assert_eq!(rows.len(), steps, "one row per control step of episode 0");
    assert_eq!(rows[0][previous], 0.0);
    // start.json: the state episode 0 began in, every number to the bit (docs/deploy.md flies from it).
    let start: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("policy/start.json")).unwrap()).unwrap();
    let quaternion: Vec<f64> =
        start["orientation_wxyz"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert!((quaternion.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-12, "{quaternion:?}");
    assert_eq!(rows[0][column("t-0.quat_w")] as f32, quaternion[0] as f32);
    assert_eq!(start["joint_positions_rad"], serde_json::json!([0.0, 0.0, 0.0, 0.0, 0.0]));
    for pair in rows.windows(2) {
        assert!(
            (pair[1][previous] - pair[0][action].clamp(-1.0, 1.0)).abs() < 1e-6,
            "{} vs {}",
            pair[1][previous],
            pair[0][action]
        );
    }
}

#[test]
fn export_policy_writes_c_with_its_size_and_latency_and_refuses_bad_input_with_one_line() {
    let dir = scratch("export-c");
    let policy = shipped_policy("history/stage1");
    let out = dir.join("stage1_policy.c");
    let output = flapper(&["export-policy", "--policy", &policy, "--format", "c", "--out", out.to_str().unwrap()]);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("(a policy file, iteration"), "{stdout}");
    assert!(stdout.contains("179520 multiply-adds") && stdout.contains("724212 bytes"), "{stdout}");
    assert!(stdout.contains("one call of the compiled C: ") && stdout.contains(" us on this CPU"), "{stdout}");
    let header = std::fs::read_to_string(dir.join("stage1_policy.h")).unwrap();
    assert!(header.contains("void flapper_policy_act(const float obs[540], float actions[5]);"), "{header}");
    let source = std::fs::read_to_string(&out).unwrap();
    assert!(!source.contains("malloc") && source.matches("#include <").collect::<Vec<_>>() == ["#include <"]);

    let before = std::fs::read(&out).unwrap();
    let again = flapper(&["export-policy", "--policy", &policy, "--format", "c", "--out", out.to_str().unwrap()]);
    assert_one_line_error(&again, "exists; choose another name");
    assert_eq!(std::fs::read(&out).unwrap(), before);
    let text = dir.join("notes.txt");
    std::fs::write(&text, "not a policy").unwrap();
    let not_policy = dir.join("never.c");
    let output = flapper(&[
        "export-policy",
        "--policy",
        text.to_str().unwrap(),
        "--format",
        "c",
        "--out",
        not_policy.to_str().unwrap(),
    ]);
    assert_one_line_error(&output, "is not a flapper policy or checkpoint");
    assert!(!not_policy.exists());
    let output = flapper(&["export-policy", "--policy", &policy, "--format", "tflite", "--out", "x.tflite"]);
    assert_one_line_error(&output, "unknown --format 'tflite' (the formats are safetensors, onnx, c)");
    let output =
        flapper(&["export-policy", "--policy", &policy, "--format", "c", "--out", dir.join("p.txt").to_str().unwrap()]);
    assert_one_line_error(&output, "NAME.c");
    let output = flapper(&["export-policy", "--policy", &policy, &policy, "--format", "onnx", "--out", "x.onnx"]);
    assert_one_line_error(&output, "--format onnx exports one policy, got 2 files");
}

/// A one-stage curriculum of two tiny environments that trains in a second: `max_iterations`, validated
/// every iteration on one cruise flight, its gate `completed_percent`.
fn tiny_curriculum(seed: u64, max_iterations: usize, completed_percent: u32) -> String {
    format!(
        "seed = {seed}\n[runner]\nenvs = 2\nthreads = 1\n[ppo]\nsteps_per_env = 8\nminibatches = 2\n\
         actor_hidden = [8]\ncritic_hidden = [8]\n[[stages]]\nname = \"cruise\"\nmax_iterations = {max_iterations}\n\
         validate_every = 1\nvalidation = {{ references = [\"cruise\"], episodes = 1 }}\n\
         gate = {{ completed_percent = {completed_percent} }}\ntask = {{ stage = 1 }}\n"
    )
}

/// `flapper curriculum --config DIR/curriculum.toml --out DIR/run` in a fresh scratch folder `name`, with
/// `text` as the config: the config's path, the run folder and what the command did.
fn curriculum_in(name: &str, text: &str) -> (PathBuf, PathBuf, Output) {
    let dir = scratch(name);
    let config = dir.join("curriculum.toml");
    std::fs::write(&config, text).unwrap();
    let out = dir.join("run");
    let output = flapper(&["curriculum", "--config", config.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    (config, out, output)
}

#[test]
fn curriculum_rejects_a_bad_stage_config_with_one_line_naming_the_stage_and_key() {
    let (_, out, output) = curriculum_in(
        "curriculum-bad",
        "[[stages]]\nname = \"cruise\"\nmax_iterations = 10\nvalidate_every = 5\n\
         validation = { references = [\"cruise\"], episodes = 2 }\ngate = { completed_percent = 90 }\n\
         [stages.task.control]\naction_mode = \"flap_oscillator\"\nflap_amplitud_max = 1.5\n",
    );
    assert_one_line_error(&output, "flap_amplitud_max");
    assert!(String::from_utf8_lossy(&output.stderr).contains("stage 1"));
    assert!(!out.join("stage1").exists(), "a refused run trains nothing");
}

/// A tiny curriculum through the command: it prints its closing line, and `summary.json` records the
/// command as a reader would retype it (`flapper ...`, whatever the binary's file is called).
#[test]
fn curriculum_records_the_command_as_typed_and_says_what_it_handed_over() {
    let (config, out, output) = curriculum_in("curriculum-tiny", &tiny_curriculum(3, 2, 0));
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.lines().any(|l| l.starts_with("done: 1 stages handed over")), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let expected = format!("flapper curriculum --config {} --out {}", config.display(), out.display());
    assert_eq!(summary["command"], expected.as_str());
    assert!(out.join("policy.safetensors").is_file());
}

/// A run from scratch on a robot of one's own that stops at a gate ends with one error line that spells out
/// the fine-tune of the shipped controller on that robot (what `--model` runs without `--from-scratch`); on
/// the shipped robot, given as `--model` or not, it does not.
#[test]
fn a_robot_s_run_stopped_at_a_gate_names_the_transfer_command() {
    let text = &tiny_curriculum(3, 2, 100);
    let (config, out, output) = curriculum_in("curriculum-robot-stopped", text);
    assert_one_line_error(&output, "missed its gate");
    assert!(!String::from_utf8_lossy(&output.stderr).contains("fine-tuned on it"), "the shipped robot");

    let repository = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let shipped = repository.join("models/flapper.xml").display().to_string();
    let heavy = repository.join("examples/robots/heavy.xml").display().to_string();
    for (model, hint) in [(&shipped, false), (&heavy, true)] {
        let robot_out = out.with_file_name(if hint { "heavy" } else { "shipped" });
        let args = ["curriculum", "--model", model, "--config", config.to_str().unwrap(), "--out"];
        let output = flapper(&[&args[..], &[robot_out.to_str().unwrap()]].concat());
        assert_one_line_error(&output, "missed its gate");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let transfer = format!(
            "fine-tuned on it may fly where training from scratch stopped (it trained heavy.xml, wide.xml, narrow.xml and nose-heavy.xml of examples/robots/): flapper curriculum --model {model} --out {}-transfer",
            robot_out.display()
        );
        assert_eq!(stderr.contains(&transfer), hint, "{stderr}");
    }
}

/// A robot of one's own given as `--model` alone fine-tunes the shipped controller; a folder a run from
/// scratch started on it (as `--model` did before 2026-11-29) is refused in one line that names
/// `--from-scratch`, and nothing in it changes.
#[test]
fn a_robot_s_folder_from_scratch_is_continued_with_from_scratch() {
    let text = &tiny_curriculum(1, 1, 0);
    let (_, out, output) = curriculum_in("curriculum-robot-folder", text);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let saved = std::fs::read(out.join("curriculum.toml")).unwrap();
    let heavy = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../examples/robots/heavy.xml");
    let output = flapper(&["curriculum", "--model", heavy.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert_one_line_error(&output, "has started stage 1 ('cruise') with other settings");
    assert!(String::from_utf8_lossy(&output.stderr).contains("continues with --from-scratch"));
    assert!(String::from_utf8_lossy(&output.stdout).contains("fine-tuning the shipped controller"));
    assert_eq!(std::fs::read(out.join("curriculum.toml")).unwrap(), saved, "the folder unchanged");
}

/// `flapper frontier --policy policies/final/... --episodes 2 --seed 11`: its longitudinal figures are
/// `flapper eval`'s (the same library calls on the same starts, at the file's decimals), its energy ratio
/// is the policy's energy per metre over the scripted gait's, and the scripted gait's own ratio is 1.
#[test]
fn frontier_writes_eval_s_figures_on_the_same_starts_and_the_scripted_gait_at_ratio_one() {
    use std::sync::Arc;

    use flapper_analysis::frontier::file::read_frontier_csv;
    use flapper_eval::tracking::{TrackingController, evaluate_tracking};
    use flapper_eval::tracking_report::TrackingSummary;
    use flapper_task::TaskConfig;

    let out = scratch("frontier");
    let policy = shipped_policy("final");
    let args = ["frontier", "--policy", &policy, "--episodes", "2", "--seed", "11", "--out", out.to_str().unwrap()];
    let output = flapper(&args);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.lines().any(|l| l.starts_with("final ") && l.contains("2/2")), "{stdout}");
    let rows = read_frontier_csv(&out.join("frontier.csv")).unwrap();
    let labels: Vec<&str> = rows.iter().map(|r| r.label.as_str()).collect();
    assert_eq!(labels, ["final", "scripted gait"]);
    let (final_row, scripted_row) = (&rows[0], &rows[1]);

    // `flapper eval --policy P --reference longitudinal --episodes 2 --seed 11`, as eval_command flies it.
    let robot = flapper_sim::RobotModel::flapper().unwrap();
    let (actor, task) = flapper_eval::load_flight_policy(std::path::Path::new(&policy)).unwrap();
    let actor = Arc::new(actor);
    let period_s = task.control_period_s(robot.timestep_s());
    let reference =
        Arc::new(flapper_task::reference::resolve("longitudinal", period_s, task.observation.lookahead_steps).unwrap());
    let eval = |controller: TrackingController, task: &TaskConfig| {
        let results = evaluate_tracking(&robot, &controller, task, reference.clone(), 2, 11).unwrap();
        let window = flapper_task::reference::named::manoeuvre_window_s(reference.name());
        TrackingSummary::of(&results, task.control_period_s(robot.timestep_s()), window)
    };
    let by_policy = eval(TrackingController::Policy(Arc::clone(&actor)), &task);
    let by_scripted = eval(TrackingController::Scripted(Default::default()), &TaskConfig::default());
    let at = |decimals: usize, x: f64| Some(format!("{x:.decimals$}").parse::<f64>().unwrap());
    assert_eq!(final_row.longitudinal_completed, Some(by_policy.completed));
    assert_eq!(final_row.longitudinal_episodes, Some(2));
    assert_eq!(final_row.longitudinal_rms_m, at(4, by_policy.mean_rms_error_m));
    assert_eq!(final_row.longitudinal_j_per_m, at(3, by_policy.energy_per_metre_j));
    assert_eq!(final_row.scripted_j_per_m, at(3, by_scripted.energy_per_metre_j));
    assert_eq!(final_row.energy_ratio, at(3, by_policy.energy_per_metre_j / by_scripted.energy_per_metre_j));
    assert_eq!(scripted_row.longitudinal_completed, Some(by_scripted.completed));
    assert_eq!(scripted_row.longitudinal_j_per_m, at(3, by_scripted.energy_per_metre_j));
    assert_eq!(scripted_row.energy_ratio, Some(1.0), "the scripted gait against itself");
    // The glide fraction is `flapper modes`' from the exact start (the final controller holds its wings
    // through 0.75 of the glide segment, its seventh stage's gate asks 0.5), the flap at the paper's 4-6 Hz in
    // the cruise (its fifth to seventh stages' gates ask it; 4.97 Hz over 100 episodes), and it flies the rest.
    let modes =
        flapper_analysis::modes::measure_controller_flight_modes(&robot, &TrackingController::Policy(actor), &task)
            .unwrap();
    assert_eq!(final_row.glide_fraction, at(3, modes.glide_segment_fraction()));
    assert!(final_row.glide_fraction.is_some_and(|share| share >= 0.5), "{final_row:?}");
    assert!(final_row.cruise_flap_hz.is_some_and(|hz| (4.0..=6.0).contains(&hz)), "{final_row:?}");
    assert_eq!(final_row.level3_episodes, Some(2));
    assert!(out.join("energy_vs_tracking.svg").metadata().unwrap().len() > 1000);
    let svg = std::fs::read_to_string(out.join("energy_vs_tracking.svg")).unwrap();
    for label in ["final", "scripted gait"] {
        assert!(svg.lines().any(|line| line.trim() == label), "no point labelled {label}");
    }
    // Against slow flight, only a controller that holds level 3 m/s in 95% of its episodes has a point: the
    // final one where it flew both episodes, never the scripted gait (0 of 2).
    let slow = std::fs::read_to_string(out.join("energy_vs_slow_flight.svg")).unwrap();
    assert!(!slow.lines().any(|line| line.trim() == "scripted gait"), "the scripted gait falls out of slow flight");
    let held = final_row.level3_completed == final_row.level3_episodes;
    assert_eq!(slow.lines().any(|line| line.trim() == "final"), held, "{final_row:?}");
}

#[test]
fn frontier_refuses_bad_input_with_one_line_naming_the_flag_or_file() {
    let out = scratch("frontier-bad");
    let o = out.to_str().unwrap();
    let policy = shipped_policy("final");
    let missing = "/no/such/policy.safetensors";
    assert_one_line_error(&flapper(&["frontier", "--policy", &policy, "--policy", missing, "--out", o]), missing);
    let points = out.join("points.csv");
    std::fs::write(&points, "label,longitudinal_rms_m,energy_ratio,source\nA,0.3,1.5,x\nB,0.2,seven,x\n").unwrap();
    let p = points.to_str().unwrap();
    assert_one_line_error(
        &flapper(&["frontier", "--policy", &policy, "--points", p, "--out", o]),
        &format!("'{p}' line 3: column 'energy_ratio'"),
    );
    assert_one_line_error(&flapper(&["frontier", "--policy", &policy, "--episodes", "0", "--out", o]), "--episodes");
    assert_one_line_error(
        &flapper(&["frontier", "--policy", &policy, "--label", "a", "--label", "b", "--out", o]),
        "--label given 2 times for 1 --policy",
    );
    assert_usage_error(&flapper(&["frontier", "--out", o]), "--policy <FILE>");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1, "a refused command writes nothing");
}

#[test]
fn power_curve_flies_the_family_asked_for_and_judges_a_policy_against_its_cheapest_gait() {
    let out = scratch("power-curve");
    let policy = shipped_policy("final");
    let family = [
        "--frequencies",
        "5.3",
        "--body-pitches",
        "10,20",
        "--pitch-amplitudes",
        "10",
        "--pitch-leads",
        "90",
        "--tail-trims",
        "-20,-10",
    ];
    let mut args = vec!["power-curve", "--policy", &policy, "--speeds", "3.5", "--episodes", "2", "--out"];
    args.push(out.to_str().unwrap());
    args.extend(family);
    let output = flapper(&args);
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert!(stdout.contains("of 4 gaits, 4 level"), "{stdout}");
    assert!(stdout.contains("the scripted gait (5.3 Hz, nose 20 deg) flies level at"), "{stdout}");
    for file in ["gaits.csv", "power_curve.csv", "policies_level.csv", "power_curve.svg"] {
        assert!(out.join(file).is_file(), "{file} written");
    }
    let read = |file: &str| {
        let mut reader = csv::Reader::from_path(out.join(file)).unwrap();
        let header = reader.headers().unwrap().clone();
        let rows: Vec<csv::StringRecord> = reader.records().map(Result::unwrap).collect();
        (header, rows)
    };
    let column = |header: &csv::StringRecord, row: &csv::StringRecord, name: &str| -> f64 {
        row[header.iter().position(|h| h == name).unwrap()].parse().unwrap()
    };
    let (gait_header, gaits) = read("gaits.csv");
    assert_eq!(gaits.len(), 4, "two trims by two tails, a list of negative numbers taken as values");
    let scripted = gaits.iter().find(|g| &g[gait_header.iter().position(|h| h == "scripted_gait").unwrap()] == "true");
    let scripted_j_per_m =
        column(&gait_header, scripted.expect("the scripted gait is in the family"), "energy_per_metre_j");
    // The nose held lower flies faster (the trim sets the speed).
    let speeds: Vec<f64> = gaits.iter().map(|g| column(&gait_header, g, "speed_mps")).collect();
    assert!(speeds[0] > speeds[2], "nose 10 deg flies faster than 20: {speeds:?}");
    let (header, policies) = read("policies_level.csv");
    assert_eq!(policies.len(), 1);
    let row = &policies[0];
    assert_eq!(column(&header, row, "completed"), 2.0);
    let j_per_m = column(&header, row, "energy_per_metre_j");
    let over_scripted = column(&header, row, "over_scripted_gait");
    assert!(
        (over_scripted - j_per_m / scripted_j_per_m).abs() < 1e-9,
        "{over_scripted} against {j_per_m} / {scripted_j_per_m}"
    );
}

#[test]
fn power_curve_refuses_bad_input_with_one_line_naming_the_flag_or_file() {
    let out = scratch("power-curve-bad");
    let o = out.to_str().unwrap();
    let missing = "/no/such/policy.safetensors";
    assert_one_line_error(&flapper(&["power-curve", "--policy", missing, "--out", o]), missing);
    assert_one_line_error(&flapper(&["power-curve", "--speeds", "3,0.5", "--out", o]), "--speeds");
    assert_one_line_error(&flapper(&["power-curve", "--frequencies", "0", "--out", o]), "--frequencies");
    assert_one_line_error(&flapper(&["power-curve", "--body-pitches", "nan", "--out", o]), "--body-pitches");
    assert_one_line_error(&flapper(&["power-curve", "--pitch-leads", "200", "--out", o]), "--pitch-leads");
    assert_one_line_error(&flapper(&["power-curve", "--episodes", "0", "--out", o]), "--episodes");
    assert_one_line_error(
        &flapper(&["power-curve", "--label", "a", "--out", o]),
        "--label given 1 times for 0 --policy",
    );
    let not_a_number = flapper(&["power-curve", "--tail-trims", "up", "--out", o]);
    let stderr = String::from_utf8_lossy(&not_a_number.stderr);
    assert_eq!(not_a_number.status.code(), Some(2), "{stderr}");
    assert!(stderr.starts_with("error: invalid value 'up' for '--tail-trims"), "{stderr}");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0, "a refused command writes nothing");
}
