//! The curriculum end to end with tiny budgets: every stage, validation and selection, the summary; a
//! missed gate stops the run with a message naming it; a run interrupted between stages or inside one
//! continues to exactly the files of an uninterrupted run.

use std::path::{Path, PathBuf};

use flapper_curriculum::run::{Progress, stage_dir};
use flapper_curriculum::{CurriculumConfig, CurriculumRequest, run_curriculum};
use flapper_sim::RobotModel;

const TINY: &str = r#"
seed = 5
[runner]
envs = 4
threads = 1
[ppo]
steps_per_env = 8
minibatches = 2
actor_hidden = [16]
critic_hidden = [16]
[[stages]]
name = "cruise"
max_iterations = 4
validate_every = 2
validation = { references = ["cruise"], episodes = 2 }
gate = { completed_percent = 0 }
task = { stage = 1 }
[[stages]]
name = "climb and dive"
max_iterations = 4
validate_every = 1
start_noise_std = 0.8
validation = { references = ["longitudinal"], procedural = 1, episodes = 1, randomized = [{ name = "table3", references = ["cruise"], episodes = 1 }] }
gate = { completed_percent = 0, min_iterations = 4 }
task = { stage = 2 }
"#;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("flapper-curriculum-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn run(dir: &Path, text: &str, until_stage: Option<usize>) -> Result<usize, String> {
    run_from(dir, text, until_stage, None)
}

/// `run`, the first stage starting from the policy `init_from` where given.
fn run_from(dir: &Path, text: &str, until_stage: Option<usize>, init_from: Option<&Path>) -> Result<usize, String> {
    let robot = RobotModel::flapper().unwrap();
    let config = CurriculumConfig::from_toml(text, "tiny.toml").unwrap();
    let init_from = init_from.map(Path::to_path_buf);
    let request = CurriculumRequest { dir, config, until_stage, command: "test".into(), init_from };
    run_curriculum(&robot, request, &mut |_| {}).map(|stages| stages.len()).map_err(|e| e.to_string())
}

/// A file with the columns that measure time removed (training.csv, selection.csv), or as it is.
fn without_timing(path: &Path) -> Vec<Vec<String>> {
    let mut reader = csv::Reader::from_path(path).unwrap();
    let headers: Vec<String> = reader.headers().unwrap().iter().map(String::from).collect();
    let timing = ["wall_time_s", "steps_per_s", "env_time_s", "inference_time_s", "update_time_s", "validation_s"];
    let keep: Vec<usize> = (0..headers.len()).filter(|&k| !timing.contains(&headers[k].as_str())).collect();
    let mut rows = vec![keep.iter().map(|&k| headers[k].clone()).collect()];
    for record in reader.records() {
        let record = record.unwrap();
        rows.push(keep.iter().map(|&k| record[k].to_owned()).collect());
    }
    rows
}

fn same_run(a: &Path, b: &Path) {
    for stage in [1, 2] {
        for file in ["training.csv", "selection.csv"] {
            let (x, y) = (stage_dir(a, stage).join(file), stage_dir(b, stage).join(file));
            assert_eq!(without_timing(&x), without_timing(&y), "stage {stage} {file}");
        }
    }
    // The networks, noise and normalizer (the file's metadata also records wall time).
    let policy = |dir: &Path| flapper_ppo::checkpoint::load(&dir.join("policy.safetensors")).unwrap().policy;
    assert!(policy(a) == policy(b), "the final policies differ");
}

#[test]
fn trains_every_stage_selects_and_summarizes_and_resumes_exactly() {
    let whole = scratch("whole");
    assert_eq!(run(&whole, TINY, None).unwrap(), 2);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["seed"], 5);
    assert_eq!(summary["command"], "test");
    let stages = summary["stages"].as_array().unwrap();
    assert_eq!(stages.len(), 2);
    // Stage 1's gate (0%) is met at its first validation (iteration 2): it stops one iteration later.
    // Stage 2's gate is looked at from iteration 4 on: it spends its budget.
    for (k, (stage, iterations)) in stages.iter().zip([3, 4]).enumerate() {
        assert_eq!(stage["stage"], k + 1);
        assert_eq!(stage["iterations"], iterations);
        assert_eq!(stage["env_steps"], iterations * 4 * 8);
        assert!(stage["wall_time_s"].as_f64().unwrap() > 0.0);
        for key in ["selected_iteration", "validation_score"] {
            assert!(stage[key].is_number(), "{key}");
        }
    }
    assert_eq!(summary["total_env_steps"], (3 + 4) * 4 * 8);
    let selection = without_timing(&stage_dir(&whole, 2).join("selection.csv"));
    assert_eq!(selection.len(), 1 + 4, "stage 2 validated every iteration");
    for column in ["procedural-1_completed", "cruise~table3_completed", "cruise~table3_rms_m"] {
        assert!(selection[0].contains(&column.to_owned()), "{column}: {:?}", selection[0]);
    }
    let selected = stages[1]["selected_iteration"].as_u64().unwrap() as usize;
    assert!(stage_dir(&whole, 2).join(format!("checkpoints/iter_{selected:06}.safetensors")).exists());
    for file in ["policy.safetensors", "curriculum.svg", "curriculum.toml"] {
        assert!(whole.join(file).exists(), "{file}");
    }

    // Between stages: stage 1 alone, then the rest.
    let between = scratch("between");
    assert_eq!(run(&between, TINY, Some(1)).unwrap(), 1);
    assert!(!stage_dir(&between, 2).exists());
    assert_eq!(run(&between, TINY, None).unwrap(), 2);
    same_run(&whole, &between);

    // Inside a stage: what a kill after stage 2's second checkpoint leaves (later checkpoints, the final
    // policy and the stage's outcome not yet written; its training.csv and selection.csv a row ahead).
    let inside = scratch("inside");
    copy_dir(&whole, &inside);
    let stage2 = stage_dir(&inside, 2);
    for name in ["selected.json", "policy.safetensors", "policy.safetensors.json"] {
        std::fs::remove_file(stage2.join(name)).unwrap();
    }
    for iteration in [3, 4] {
        for suffix in ["", ".json"] {
            std::fs::remove_file(stage2.join(format!("checkpoints/iter_{iteration:06}.safetensors{suffix}"))).unwrap();
        }
    }
    std::fs::remove_file(inside.join("policy.safetensors")).unwrap();
    assert_eq!(run(&inside, TINY, None).unwrap(), 2);
    same_run(&whole, &inside);

    // Before a stage's first checkpoint: what a kill during stage 2's first iteration leaves (its
    // config.toml and a log row, no checkpoint; the outcome and the final policy not written). The stage
    // starts again and ends as the uninterrupted one.
    let early = scratch("early");
    copy_dir(&whole, &early);
    let stage2 = stage_dir(&early, 2);
    for name in ["selected.json", "policy.safetensors", "policy.safetensors.json"] {
        std::fs::remove_file(stage2.join(name)).unwrap();
    }
    std::fs::remove_dir_all(stage2.join("checkpoints")).unwrap();
    std::fs::create_dir_all(stage2.join("checkpoints")).unwrap();
    let log = std::fs::read_to_string(stage2.join("training.csv")).unwrap();
    std::fs::write(stage2.join("training.csv"), log.lines().take(2).map(|l| format!("{l}\n")).collect::<String>())
        .unwrap();
    std::fs::remove_file(early.join("policy.safetensors")).unwrap();
    assert_eq!(run(&early, TINY, None).unwrap(), 2);
    same_run(&whole, &early);

    // A second process on the same folder is refused while the first holds it.
    let held = flapper_files::lock_folder(&whole).unwrap().expect("nobody holds it now");
    let e = run(&whole, TINY, None).unwrap_err();
    assert!(e.contains("another process"), "{e}");
    drop(held);
    // Another seed on the same folder is refused; so is a folder holding someone else's files.
    let e = run(&whole, &TINY.replace("seed = 5", "seed = 6"), None).unwrap_err();
    assert!(e.contains("seed"), "{e}");
    let foreign = scratch("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "mine").unwrap();
    let e = run(&foreign, TINY, None).unwrap_err();
    assert!(e.contains("curriculum.toml"), "{e}");
    assert_eq!(std::fs::read_to_string(foreign.join("notes.txt")).unwrap(), "mine");
    for dir in [whole, between, inside, early, foreign] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

/// Every validation written to a stage's selection.csv is reported to the progress callback (the log's
/// "validation at iteration N" lines), the one of the stage's last checkpoint included, which is judged after
/// the stage's last iteration has been reported.
#[test]
fn every_validation_written_is_reported_the_last_checkpoints_included() {
    let dir = scratch("reported");
    let robot = RobotModel::flapper().unwrap();
    let config = CurriculumConfig::from_toml(TINY, "tiny.toml").unwrap();
    let request = CurriculumRequest { dir: &dir, config, until_stage: None, command: "test".into(), init_from: None };
    let mut reported = [Vec::new(), Vec::new()];
    run_curriculum(&robot, request, &mut |progress| {
        if let Progress::Validated { stage, row, .. } = progress {
            reported[stage - 1].push(row.iteration);
        }
    })
    .unwrap();
    for stage in [1, 2] {
        let written: Vec<usize> = csv::Reader::from_path(stage_dir(&dir, stage).join("selection.csv"))
            .unwrap()
            .deserialize::<std::collections::HashMap<String, String>>()
            .map(|row| row.unwrap()["iteration"].parse().unwrap())
            .collect();
        assert_eq!(reported[stage - 1], written, "stage {stage}");
    }
    assert_eq!(reported[1], [1, 2, 3, 4], "stage 2 validates every iteration, its last (4) too");
}

#[test]
fn a_missed_gate_stops_the_run_naming_the_gate_and_the_best_score() {
    let dir = scratch("gate");
    let text = TINY.replacen("gate = { completed_percent = 0 }", "gate = { completed_percent = 100 }", 1);
    let e = run(&dir, &text, None).unwrap_err();
    assert!(e.contains("stage 1 ('cruise') missed its gate"), "{e}");
    assert!(e.contains("at least 100%") && e.contains("best checkpoint") && e.contains("completed 0.0%"), "{e}");
    assert!(
        e.contains("what to try next") && e.contains("docs/training.md"),
        "the message points to the remedies: {e}"
    );
    assert!(!stage_dir(&dir, 2).exists(), "the run stopped at the missed gate");
    assert!(dir.join("curriculum.svg").exists(), "the figure shows the stage that stopped the run");
    // The summary counts the stage that stopped the run: its steps are in the totals.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["stages"].as_array().unwrap().len(), 0, "{summary}");
    let stopped = &summary["stopped"];
    assert_eq!(stopped["stage"], 1, "{summary}");
    assert!(stopped["gate"].as_str().unwrap().contains("at least 100%"), "{summary}");
    assert_eq!(stopped["best_validation_score"], 0.0, "{summary}");
    let spent = stopped["env_steps"].as_u64().unwrap();
    assert!(spent > 0 && summary["total_env_steps"] == spent, "{summary}");
    assert!(summary["total_wall_time_s"].as_f64().unwrap() > 0.0, "{summary}");
    let again = run(&dir, &text, None).unwrap_err();
    assert_eq!(again, e, "running again reports the same, without training more");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_missed_optional_stage_ends_the_run_with_the_previous_stages_controller() {
    let dir = scratch("optional");
    let missed = "gate = { completed_percent = 100, min_iterations = 4 }";
    let text = TINY.replacen("start_noise_std = 0.8", "start_noise_std = 0.8\noptional = true", 1).replacen(
        "gate = { completed_percent = 0, min_iterations = 4 }",
        missed,
        1,
    );
    assert_eq!(run(&dir, &text, None), Ok(1), "one stage handed over a controller, and the run succeeds");
    let recorded = summary(&dir);
    assert_eq!(recorded["stages"].as_array().unwrap().len(), 1, "{recorded}");
    assert!(recorded.get("stopped").is_none(), "{recorded}");
    let missed_stage = &recorded["optional_stage_missed"];
    assert_eq!(missed_stage["stage"], 2, "{recorded}");
    assert!(missed_stage["gate"].as_str().unwrap().contains("at least 100%"), "{recorded}");
    // Its steps are in the totals; the final policy is stage 1's handed-over checkpoint.
    let steps = |v: &serde_json::Value| v["env_steps"].as_u64().unwrap();
    assert_eq!(recorded["total_env_steps"].as_u64().unwrap(), steps(&recorded["stages"][0]) + steps(missed_stage));
    let policy = |path: &Path| flapper_ppo::checkpoint::load(path).unwrap().policy;
    let handed_over = dir.join(recorded["stages"][0]["checkpoint"].as_str().unwrap());
    assert!(policy(&dir.join("policy.safetensors")) == policy(&handed_over), "the final policy is stage 1's");
    assert_eq!(run(&dir, &text, None), Ok(1), "running again ends the same way");
    assert_eq!(
        summary(&dir)["optional_stage_missed"]["iterations"],
        missed_stage["iterations"],
        "without training more"
    );
    // The same stage, not optional, stops the run; the key alone changes nothing it trained.
    let e = run(&dir, &text.replacen("\noptional = true", "", 1), None).unwrap_err();
    assert!(e.contains("stage 2 ('climb and dive') missed its gate"), "{e}");
    std::fs::remove_dir_all(dir).unwrap();

    // A trailing run of optional stages: the first one missed ends the run there, the later ones never
    // start (a refinement of a controller the run did not keep).
    let dir = scratch("optional-trailing");
    let third = "[[stages]]\nname = \"glide\"\nmax_iterations = 2\nvalidate_every = 1\noptional = true\n\
                 validation = { references = [\"cruise\"], episodes = 1 }\ngate = { completed_percent = 0 }\n\
                 task = { stage = 2 }\n";
    let trailing = format!("{text}{third}");
    assert_eq!(run(&dir, &trailing, None), Ok(1), "stage 1's controller again");
    assert_eq!(summary(&dir)["optional_stage_missed"]["stage"], 2);
    assert!(!dir.join("stage3").exists(), "the stage after the missed one never started");
    std::fs::remove_dir_all(dir).unwrap();

    // Only the last stages, after a required one, may be optional.
    let first = TINY.replacen("validate_every = 2", "validate_every = 2\noptional = true", 1);
    let e = CurriculumConfig::from_toml(&first, "tiny.toml").unwrap_err().to_string();
    assert!(
        e.contains("stage 1 ('cruise')") && e.contains("optional = true is allowed on the last stages only"),
        "{e}"
    );
    let required_after = format!("{}{}", text, third.replacen("optional = true\n", "", 1));
    let e = CurriculumConfig::from_toml(&required_after, "tiny.toml").unwrap_err().to_string();
    assert!(e.contains("stage 2 ('climb and dive')") && e.contains("no required stage after it"), "{e}");
}

#[test]
fn a_curriculum_started_from_a_policy_fine_tunes_it_with_the_first_stages_noise() {
    let source = scratch("init-source");
    assert_eq!(run(&source, TINY, Some(1)), Ok(1));
    let source_policy = source.join("policy.safetensors");
    // TINY's stage 2 alone, with a learning rate too small to move a weight.
    let stage2 = &TINY[TINY.rfind("[[stages]]").unwrap()..];
    let header = &TINY[..TINY.find("[[stages]]").unwrap()];
    let text =
        format!("{}{stage2}", header.replacen("[ppo]\n", "[ppo]\nschedule = \"fixed\"\nlearning_rate = 1e-30\n", 1));
    let policy = |path: &Path| flapper_ppo::checkpoint::load(path).unwrap().policy;
    let tuned = scratch("init-tuned");
    assert_eq!(run_from(&tuned, &text, None, Some(&source_policy)), Ok(1));
    let (from, after) = (policy(&source_policy), policy(&tuned.join("policy.safetensors")));
    assert!(after.actor == from.actor, "the networks it started from, unmoved");
    let noise: Vec<f32> = after.log_std.iter().map(|l| l.exp()).collect();
    assert!(noise.iter().all(|std| (std - 0.8).abs() < 1e-4), "the stage's start_noise_std 0.8: {noise:?}");
    // From scratch, the same stage trains other networks.
    let fresh = scratch("init-fresh");
    assert_eq!(run(&fresh, &text, None), Ok(1));
    assert!(policy(&fresh.join("policy.safetensors")).actor != from.actor);
    for dir in [source, tuned, fresh] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

#[test]
fn a_stage_still_improving_when_its_budget_runs_out_is_extended_and_the_summary_says_why() {
    let dir = scratch("extended");
    let text = TINY
        .replacen("max_iterations = 4\nvalidate_every = 2", "max_iterations = 8\nvalidate_every = 1", 1)
        .replacen("gate = { completed_percent = 0 }", "gate = { completed_percent = 100 }", 1);
    let first = run(&dir, &text, None).unwrap_err();
    assert!(first.contains("missed its gate"), "{first}");
    // Its validations as they were, then the last four made better than the first four: a stage still
    // learning when its budget ran out.
    let path = stage_dir(&dir, 1).join("selection.csv");
    let mut reader = csv::Reader::from_path(&path).unwrap();
    let headers = reader.headers().unwrap().clone();
    let mut rows: Vec<csv::StringRecord> = reader.records().map(|r| r.unwrap()).collect();
    assert_eq!(rows.len(), 8, "one validation per iteration");
    let column = |name: &str| headers.iter().position(|h| h == name).unwrap();
    let (percent, completed) = (column("completed_percent"), column("cruise_completed"));
    assert!(rows.iter().all(|r| r[percent].parse::<f64>().unwrap() < 100.0), "the test needs the gate unmet");
    for (k, row) in rows.iter_mut().enumerate() {
        let (p, c) = if k < 4 { ("0", "0") } else { ("50", "1") };
        *row = row
            .iter()
            .enumerate()
            .map(|(i, v)| {
                if i == percent {
                    p
                } else if i == completed {
                    c
                } else {
                    v
                }
            })
            .collect();
    }
    let mut writer = csv::Writer::from_path(&path).unwrap();
    writer.write_record(&headers).unwrap();
    rows.iter().for_each(|r| writer.write_record(r).unwrap());
    writer.flush().unwrap();

    let second = run(&dir, &text, None).unwrap_err();
    assert!(second.contains("missed its gate"), "nothing completes every episode: {second}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let stopped = &summary["stopped"];
    let extensions = stopped["extensions"].as_array().expect("the extension is recorded");
    assert!((1..=2).contains(&extensions.len()), "{summary}");
    assert_eq!(extensions[0]["at_iteration"], 8, "{summary}");
    assert_eq!(extensions[0]["added_iterations"], 4, "half the stage's budget: {summary}");
    let reason = extensions[0]["reason"].as_str().unwrap();
    assert!(reason.contains("still improving") && reason.contains("50.0%"), "{reason}");
    let trained = stopped["iterations"].as_u64().unwrap();
    assert_eq!(trained, 8 + extensions.iter().map(|e| e["added_iterations"].as_u64().unwrap()).sum::<u64>());
    assert!(stage_dir(&dir, 1).join(format!("checkpoints/iter_{trained:06}.safetensors")).exists());
    let third = run(&dir, &text, None).unwrap_err();
    assert_eq!(third, second, "running again reports the same, without training more");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Stage 1 of TINY made to stall: a gate nothing meets, a learning rate too small to move a weight (every
/// validation flies the same policy, so the trend is flat), a validation every iteration.
fn stalled_stage(restart: &str) -> String {
    TINY.replacen(
        "max_iterations = 4\nvalidate_every = 2",
        &format!("max_iterations = 8\nvalidate_every = 1{restart}"),
        1,
    )
    .replacen("gate = { completed_percent = 0 }", "gate = { completed_percent = 100 }", 1)
    .replacen("[ppo]\n", "[ppo]\nschedule = \"fixed\"\nlearning_rate = 1e-30\n", 1)
}

fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

#[test]
fn a_stalled_stage_restarts_its_exploration_once_where_asked_and_else_stops_saying_why() {
    // Without restart_noise_std: the stall stops the run, and the message and the summary say why.
    let plain = scratch("stalled");
    let e = run(&plain, &stalled_stage(""), None).unwrap_err();
    assert!(e.contains("missed its gate") && e.contains("No more iterations: stalled"), "{e}");
    assert!(e.contains("restart_noise_std is not set"), "{e}");
    let stopped = &summary(&plain)["stopped"];
    assert_eq!(stopped["iterations"], 8, "{stopped}");
    assert!(stopped.get("extensions").is_none(), "{stopped}");
    assert!(stopped["stopped_because"].as_str().unwrap().starts_with("stalled"), "{stopped}");
    // The stopped stage given a restart continues in its folder (the key changes nothing it trained).
    let e = run(&plain, &stalled_stage("\nrestart_noise_std = 3.0"), None).unwrap_err();
    assert!(e.contains("after its exploration had been restarted once already"), "{e}");
    assert_eq!(summary(&plain)["stopped"]["iterations"], 12);
    std::fs::remove_dir_all(plain).unwrap();

    // With it: one restart from the last checkpoint, the noise reset, half the budget more; stalled again,
    // the run stops, saying that the restart was spent.
    let dir = scratch("restarted");
    let text = stalled_stage("\nrestart_noise_std = 3.0");
    let e = run(&dir, &text, None).unwrap_err();
    assert!(e.contains("after its exploration had been restarted once already"), "{e}");
    let stopped = &summary(&dir)["stopped"];
    let extensions = stopped["extensions"].as_array().expect("the restart is recorded");
    assert_eq!(extensions.len(), 1, "{stopped}");
    assert_eq!(
        (extensions[0]["at_iteration"].as_u64(), extensions[0]["added_iterations"].as_u64()),
        (Some(8), Some(4))
    );
    assert_eq!(extensions[0]["restart_noise_std"], 3.0, "{stopped}");
    let reason = extensions[0]["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("stalled")
            && reason.contains("restarted from the checkpoint of iteration 8 with action noise 3"),
        "{reason}"
    );
    assert_eq!(stopped["iterations"], 12, "{stopped}");
    let log = without_timing(&stage_dir(&dir, 1).join("training.csv"));
    let std_column = log[0].iter().position(|c| c == "action_std").unwrap();
    let std_at = |iteration: usize| log[iteration][std_column].parse::<f64>().unwrap();
    // (TINY's noise starts at 1, and a learning rate of 1e-30 moves no weight.)
    assert!(
        (std_at(8) - 1.0).abs() < 1e-3 && (std_at(9) - 3.0).abs() < 1e-3,
        "noise {} before the restart, {} after",
        std_at(8),
        std_at(9)
    );
    assert_eq!(run(&dir, &text, None).unwrap_err(), e, "running again reports the same, without training more");

    // A budget with no room for the restart after the later stage's (4 iterations of 32 steps): the stall
    // stops the run, saying so; raised, the same folder restarts (stage 1's own budget is 8 either way); a
    // budget that would have cut stage 1 is refused.
    let tight = scratch("restart-budget");
    let budgeted = |steps: u64| text.replacen("seed = 5\n", &format!("seed = 5\nmax_env_steps = {steps}\n"), 1);
    let no_room = run(&tight, &budgeted(384), None).unwrap_err();
    assert!(
        no_room.contains("leaves no room for another 1 iterations after the fewest the later stages need"),
        "{no_room}"
    );
    let refused = run(&tight, &budgeted(200), None).unwrap_err();
    assert!(refused.contains("max_env_steps, which would change the budget of a stage it has started"), "{refused}");
    let raised = run(&tight, &budgeted(512), None).unwrap_err();
    assert!(raised.contains("after its exploration had been restarted once already"), "{raised}");
    assert_eq!(summary(&tight)["stopped"]["extensions"][0]["added_iterations"], 4);
    // Lowered so far that the recorded restart would not have been given (no room at 400): refused.
    let lowered = run(&tight, &budgeted(400), None).unwrap_err();
    assert!(lowered.contains("max_env_steps, which would change the budget"), "{lowered}");
    std::fs::remove_dir_all(tight).unwrap();

    // Interrupted after the restart was decided and before its first checkpoint: it restarts again.
    let interrupted = scratch("restart-interrupted");
    copy_dir(&dir, &interrupted);
    let stage1 = stage_dir(&interrupted, 1);
    for iteration in 9..=12 {
        for suffix in ["", ".json"] {
            std::fs::remove_file(stage1.join(format!("checkpoints/iter_{iteration:06}.safetensors{suffix}"))).unwrap();
        }
    }
    assert_eq!(run(&interrupted, &text, None).unwrap_err().replace("restart-interrupted", "restarted"), e);
    assert_eq!(without_timing(&stage1.join("training.csv")), log, "the same iterations after the restart");

    // From the stage's best checkpoint instead (`restart_from_best`): the same eight iterations, then the
    // restart takes the learner of the best validation's checkpoint (its weights, normalizer, optimizer
    // and random state), so the iterations after it differ from a restart from the last; it is recorded.
    let best_dir = scratch("restarted-best");
    let from_best = stalled_stage("\nrestart_noise_std = 3.0\nrestart_from_best = true");
    let e_best = run(&best_dir, &from_best, None).unwrap_err();
    assert!(e_best.contains("after its exploration had been restarted once already"), "{e_best}");
    let validations = without_timing(&stage_dir(&best_dir, 1).join("selection.csv"));
    let column = |name: &str| validations[0].iter().position(|c| c == name).unwrap();
    let (completed, rms) = (column("completed_percent"), column("mean_rms_m"));
    let score = |row: &Vec<String>| (row[completed].parse::<f64>().unwrap(), row[rms].parse::<f64>().unwrap());
    // The best of the first eight: most completed, then the smallest RMS, the earliest on a tie.
    let best = (1..=8)
        .reduce(|b, i| {
            let ((bc, br), (c, r)) = (score(&validations[b]), score(&validations[i]));
            if c > bc || (c == bc && r < br) { i } else { b }
        })
        .unwrap();
    assert!(best < 8, "the validations of this stage peak before its last checkpoint (best {best})");
    let extension = &summary(&best_dir)["stopped"]["extensions"][0];
    assert_eq!(extension["restart_from_iteration"], best, "{extension}");
    let reason = extension["reason"].as_str().unwrap();
    let named = format!(
        "restarted from its best checkpoint, iteration {best}, with action noise 3 (the iterations go on from 8)"
    );
    assert!(reason.contains(&named), "{reason}");
    let best_log = without_timing(&stage_dir(&best_dir, 1).join("training.csv"));
    assert_eq!(best_log[..=8], log[..=8], "the same run up to the restart");
    assert_ne!(best_log[9], log[9], "another learner after it");
    assert!(
        (best_log[9][std_column].parse::<f64>().unwrap() - 3.0).abs() < 1e-3,
        "the noise reset on the best checkpoint's learner"
    );
    for dir in [dir, interrupted, best_dir] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

#[test]
fn an_identification_bar_is_checked_only_where_the_rest_of_the_gate_is_met_and_sought_not_required() {
    let dir = scratch("identification");
    let gate = "gate = { completed_percent = 0, min_iterations = 4, identification_fit_percent = 80 }";
    let text = TINY.replacen("gate = { completed_percent = 0 }", gate, 1);
    // Four iterations of training cannot cruise through the identification's 340 s records: no
    // checkpoint meets the identification, so the stage trains its whole budget and hands over the best
    // checkpoint that meets the other bars, saying that the identification was not met.
    assert_eq!(run(&dir, &text, Some(1)).unwrap(), 1);
    let selected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(stage_dir(&dir, 1).join("selected.json")).unwrap()).unwrap();
    assert_eq!(selected["selected_iteration"], 4, "{selected}");
    assert_eq!(selected["identification_met"], false, "{selected}");
    assert!(selected.get("glide_fraction").is_none(), "no glide bar, no glide recorded: {selected}");
    if cfg!(target_arch = "x86_64") {
        let cpu = selected["cpu"].as_str().unwrap_or_default();
        assert!(
            cpu.contains("(family ") && cpu.contains("avx512f"),
            "the stage names the CPU that trained it: {selected}"
        );
    }
    let table = std::fs::read_to_string(stage_dir(&dir, 1).join("selection.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert!(
        rows[0].ends_with("identification_x_fit_percent,identification_y_fit_percent,identification_z_fit_percent")
    );
    assert!(rows[1].starts_with("2,") && rows[1].ends_with(",,,"), "before min_iterations: not identified: {table}");
    assert!(rows[2].starts_with("4,") && rows[2].ends_with(",NaN,NaN,NaN"), "{table}");
    std::fs::remove_dir_all(&dir).unwrap();

    // Required, the same bar stops the run where it was handed over above, naming the identified fits.
    let required = gate.replacen(
        "identification_fit_percent = 80",
        "identification_fit_percent = 80, identification_required = true",
        1,
    );
    let text = TINY.replacen("gate = { completed_percent = 0 }", &required, 1);
    let e = run(&dir, &text, Some(1)).unwrap_err();
    assert!(e.contains("stage 1 ('cruise') missed its gate") && e.contains("every axis of the identified"), "{e}");
    assert!(!e.contains("budget lasts"), "required, not sought: {e}");
    assert!(e.contains("identified (iteration: fit per axis): 4: x NaN%"), "{e}");
    assert!(!stage_dir(&dir, 1).join("selected.json").exists(), "nothing handed over");
    std::fs::remove_dir_all(&dir).unwrap();

    // Where no checkpoint meets the other bars, nothing is identified and the gate is missed.
    let gate = "gate = { completed_percent = 100, identification_fit_percent = 80 }";
    let text = TINY.replacen("gate = { completed_percent = 0 }", gate, 1);
    let e = run(&dir, &text, None).unwrap_err();
    assert!(e.contains("stage 1 ('cruise') missed its gate") && e.contains("identified closed loop"), "{e}");
    assert!(e.contains("no checkpoint met the other bars, none was identified"), "{e}");
    assert_eq!(run(&dir, &text, None).unwrap_err(), e, "read back, the table gives the same verdict");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn sought_rms_bars_hand_over_the_best_completing_checkpoint_and_required_ones_stop_the_run() {
    let dir = scratch("rms-sought");
    // No checkpoint of four iterations cruises within 1 mm: required (the default), the run stops.
    let gate = "gate = { completed_percent = 0, max_rms_m = 0.001 }";
    let text = TINY.replacen("gate = { completed_percent = 0 }", gate, 1);
    let e = run(&dir, &text, Some(1)).unwrap_err();
    assert!(e.contains("stage 1 ('cruise') missed its gate") && e.contains("mean RMS error at most 0.001 m"), "{e}");
    assert!(!e.contains("budget lasts"), "required, not sought: {e}");
    assert!(!stage_dir(&dir, 1).join("selected.json").exists(), "nothing handed over");
    std::fs::remove_dir_all(&dir).unwrap();
    // Sought: the stage spends its budget seeking the bar and hands over its best completing checkpoint.
    let sought = TINY.replacen(
        "gate = { completed_percent = 0 }",
        "gate = { completed_percent = 0, max_rms_m = 0.001, rms_sought = true }",
        1,
    );
    assert_eq!(run(&dir, &sought, Some(1)).unwrap(), 1);
    let selected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(stage_dir(&dir, 1).join("selected.json")).unwrap()).unwrap();
    assert_eq!(selected["rms_met"], false, "{selected}");
    assert!(selected["validation_rms_m"].as_f64().unwrap() > 0.001, "{selected}");
    assert_eq!(selected["iterations"], 4, "the whole budget sought the bar: {selected}");
    assert!(selected.get("flight_modes_met").is_none() && selected.get("identification_met").is_none());
    // The same folder continues with the bar required again: rms_sought decides only at the end of the
    // budget, so the finished stage is kept as it is.
    assert_eq!(run(&dir, &text, Some(1)).unwrap(), 1);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn flight_mode_bars_measure_every_checkpoint_and_stop_a_stage_that_never_glides() {
    let dir = scratch("glide");
    let bars = "glide_fraction = 0.5, max_energy_ratio = 1.5, cruise_flap_hz = [4.0, 6.0]";
    // Sought (the default): the stage tracks (0% asked) and hands over its most efficient checkpoint,
    // marked as not meeting the flight modes.
    let sought =
        TINY.replacen("gate = { completed_percent = 0 }", &format!("gate = {{ completed_percent = 0, {bars} }}"), 1);
    assert_eq!(run(&dir, &sought, Some(1)).unwrap(), 1);
    let selected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(stage_dir(&dir, 1).join("selected.json")).unwrap()).unwrap();
    assert_eq!(selected["flight_modes_met"], false, "{selected}");
    assert_eq!(selected["iterations"], 4, "the whole budget sought the flight modes: {selected}");
    std::fs::remove_dir_all(&dir).unwrap();
    // Required: four iterations cannot fly the longitudinal reference, no checkpoint glides, the stage stops.
    let gate = format!("gate = {{ completed_percent = 0, {bars}, flight_modes_required = true }}");
    let text = TINY.replacen("gate = { completed_percent = 0 }", &gate, 1);
    let e = run(&dir, &text, None).unwrap_err();
    assert!(e.contains("stage 1 ('cruise') missed its gate") && e.contains("glide segment (flapper modes)"), "{e}");
    assert!(e.contains("no checkpoint flew the longitudinal reference to its end for its glide (bar 0.5)"), "{e}");
    assert!(e.contains("for its energy (bar 1.5 x)") && e.contains("for its flap frequency (bar 4-6 Hz)"), "{e}");
    assert!(e.contains("at most 1.5 x the scripted gait's") && e.contains("within 4-6 Hz"), "the gate in words: {e}");
    let table = std::fs::read_to_string(stage_dir(&dir, 1).join("selection.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert!(rows[0].ends_with(",cruise_rms_m,glide_fraction,energy_ratio,cruise_flap_hz"), "{table}");
    assert_eq!(rows.len(), 3, "a row per validated checkpoint: {table}");
    assert!(rows[1..].iter().all(|row| row.ends_with(",NaN,NaN,NaN")), "not flown to its end: NaN: {table}");
    assert_eq!(run(&dir, &text, None).unwrap_err(), e, "read back, the table gives the same verdict");
    std::fs::remove_dir_all(&dir).unwrap();
    // A bar of 0 is met by any flight that ends, not by one that fails: it still stops.
    let gate = "gate = { completed_percent = 0, glide_fraction = 0, flight_modes_required = true }";
    let text = TINY.replacen("gate = { completed_percent = 0 }", gate, 1);
    assert!(run(&dir, &text, None).unwrap_err().contains("missed its gate"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_reference_held_to_its_own_rms_bar_holds_the_gate_shut_and_the_message_says_by_how_much() {
    let dir = scratch("rms-bar");
    let validation = "validation = { references = [\"cruise\"], episodes = 2 }";
    let own = "validation = { references = [\"cruise\", \"longitudinal\"], episodes = 2, reference_episodes = { cruise = 3 } }";
    let gate = "gate = { completed_percent = 0, reference_max_rms_m = { longitudinal = 0.001 } }";
    let text = TINY.replacen(validation, own, 1).replacen("gate = { completed_percent = 0 }", gate, 1);
    let e = run(&dir, &text, None).unwrap_err();
    assert!(
        e.contains("stage 1 ('cruise') missed its gate") && e.contains("mean RMS error of longitudinal 0.001 m"),
        "{e}"
    );
    assert!(e.contains("longitudinal") && e.contains("m at best (iteration ") && e.contains("bar 0.001 m"), "{e}");
    let table = std::fs::read_to_string(stage_dir(&dir, 1).join("selection.csv")).unwrap();
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for row in table.lines().skip(1) {
        let cells: Vec<&str> = row.split(',').collect();
        assert_eq!(cells[column("cruise_episodes")], "3", "cruise from its own 3 starts: {table}");
        assert_eq!(cells[column("longitudinal_episodes")], "2", "{table}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_averaging_stage_judges_and_hands_over_the_mean_of_its_last_checkpoints() {
    let dir = scratch("averaged");
    let text = TINY.replacen("start_noise_std = 0.8", "start_noise_std = 0.8\naverage_checkpoints = 3", 1);
    assert_eq!(run(&dir, &text, None).unwrap(), 2);
    let stage2 = stage_dir(&dir, 2);
    let load = |path: PathBuf| flapper_ppo::checkpoint::load(&path).unwrap();
    let checkpoint = |iteration: usize| load(stage2.join(format!("checkpoints/iter_{iteration:06}.safetensors")));
    for iteration in 1..=4usize {
        let averaged = load(stage2.join(format!("averaged/iter_{iteration:06}.safetensors")));
        let window: Vec<_> = (iteration.saturating_sub(2).max(1)..=iteration).map(checkpoint).collect();
        let newest = &window[window.len() - 1].policy;
        for k in [0, newest.actor.params().len() / 2, newest.actor.params().len() - 1] {
            let mean = window.iter().map(|c| c.policy.actor.params()[k] as f64).sum::<f64>() / window.len() as f64;
            assert!(
                (averaged.policy.actor.params()[k] as f64 - mean).abs() < 1e-6,
                "iteration {iteration}, weight {k}"
            );
        }
        if window.len() > 1 {
            assert!(averaged.policy.actor != newest.actor, "iteration {iteration}: the mean differs from the newest");
        }
        assert!(averaged.policy.normalizer == newest.normalizer, "the newest checkpoint's normalizer");
    }
    // Stage 1 does not average: it hands over a checkpoint, and stage 2 one of its averages.
    assert!(!stage_dir(&dir, 1).join("averaged").exists());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let handed = summary["stages"][1]["checkpoint"].as_str().unwrap();
    assert!(handed.starts_with("stage2/averaged/iter_"), "{summary}");
    let exported = load(dir.join("policy.safetensors"));
    assert!(exported.policy.actor == load(dir.join(handed)).policy.actor, "the run's policy is the handed-over mean");
    // Read back after an interruption between the stage's end and its outcome: the same choice.
    std::fs::remove_file(stage2.join("selected.json")).unwrap();
    std::fs::remove_file(dir.join("policy.safetensors")).unwrap();
    assert_eq!(run(&dir, &text, None).unwrap(), 2);
    let again: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(again["stages"][1]["checkpoint"], summary["stages"][1]["checkpoint"]);
    std::fs::remove_dir_all(dir).unwrap();
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for entry in std::fs::read_dir(from).unwrap() {
        let entry = entry.unwrap();
        let target = to.join(entry.file_name());
        if entry.file_type().unwrap().is_dir() {
            copy_dir(&entry.path(), &target);
        } else {
            std::fs::copy(entry.path(), target).unwrap();
        }
    }
}

#[test]
fn the_runs_step_budget_shortens_a_stage_and_stops_one_it_leaves_too_little() {
    // 64 steps = 2 iterations of 4 x 8: stage 1 (max_iterations 4) is cut to its first validation
    // interval and hands over; stage 2 (at least 4 iterations, its min_iterations) is not started.
    let dir = scratch("budget");
    let text = TINY.replacen("seed = 5", "seed = 5\nmax_env_steps = 64", 1);
    let e = run(&dir, &text, None).unwrap_err();
    assert!(
        e.contains("stage 2 ('climb and dive') cannot start")
            && e.contains("max_env_steps (64)")
            && e.contains("leaves 0 environment steps")
            && e.contains("at least 4"),
        "{e}"
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let stages = summary["stages"].as_array().unwrap();
    assert_eq!(stages.len(), 1, "{summary}");
    assert!(stages[0]["iterations"].as_u64().unwrap() <= 2, "{summary}");
    assert!(summary["total_env_steps"].as_u64().unwrap() <= 64, "{summary}");
    assert!(!stage_dir(&dir, 2).exists(), "stage 2 was not started");
    assert_eq!(run(&dir, &text, None).unwrap_err(), e, "running again reports the same");
    // An optional stage 2 left too little to start ends the run with stage 1's controller, and says why.
    let optional = text.replacen("start_noise_std = 0.8", "start_noise_std = 0.8\noptional = true", 1);
    assert_eq!(run(&dir, &optional, None), Ok(1));
    let recorded: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    let missed = &recorded["optional_stage_missed"];
    assert_eq!((missed["stage"].as_u64(), missed["iterations"].as_u64()), (Some(2), Some(0)), "{missed}");
    assert!(missed["stopped_because"].as_str().unwrap().contains("cannot start"), "{missed}");
    assert!(dir.join("policy.safetensors").exists() && !stage_dir(&dir, 2).exists());
    // A budget the stages fit in changes nothing: the same files as a run without one.
    let roomy = scratch("budget-roomy");
    let whole = scratch("budget-none");
    assert_eq!(run(&roomy, &TINY.replacen("seed = 5", "seed = 5\nmax_env_steps = 1000", 1), None).unwrap(), 2);
    assert_eq!(run(&whole, TINY, None).unwrap(), 2);
    same_run(&whole, &roomy);
    for dir in [dir, roomy, whole] {
        std::fs::remove_dir_all(dir).unwrap();
    }
}

#[test]
fn a_folder_continues_with_changed_later_stages_and_refuses_a_changed_started_one() {
    // Stage 1 alone, then the curriculum with stage 2 changed (not started): it continues, and stage 1
    // is what it was.
    let dir = scratch("changed-later");
    assert_eq!(run(&dir, TINY, Some(1)).unwrap(), 1);
    let stage1_before = without_timing(&stage_dir(&dir, 1).join("selection.csv"));
    let changed = TINY.replace("start_noise_std = 0.8", "start_noise_std = 0.6");
    assert_eq!(run(&dir, &changed, None).unwrap(), 2);
    assert_eq!(without_timing(&stage_dir(&dir, 1).join("selection.csv")), stage1_before);
    let saved = CurriculumConfig::load(&dir.join("curriculum.toml")).unwrap();
    assert_eq!(saved.stages[1].start_noise_std, Some(0.6), "the new curriculum is saved");
    let replaced = CurriculumConfig::load(&dir.join("curriculum.replaced-1.toml")).unwrap();
    assert_eq!(replaced.stages[1].start_noise_std, Some(0.8), "the old one is kept");

    // A third stage appended: trained from stage 2's hand-over; stages 1 and 2 read back.
    let third = format!(
        "{changed}\n[[stages]]\nname = \"more\"\nmax_iterations = 2\nvalidate_every = 1\nvalidation = {{ references = [\"cruise\"], episodes = 1 }}\ngate = {{ completed_percent = 0 }}\ntask = {{ stage = 2 }}\n"
    );
    let stage2_before = without_timing(&stage_dir(&dir, 2).join("training.csv"));
    assert_eq!(run(&dir, &third, None).unwrap(), 3);
    assert_eq!(without_timing(&stage_dir(&dir, 2).join("training.csv")), stage2_before);
    assert!(dir.join("curriculum.replaced-2.toml").exists());

    // A started stage changed (here stage 2, and a shared [ppo] key that every stage trains with) is
    // refused naming the stage, and the saved curriculum stays.
    let saved_text = std::fs::read_to_string(dir.join("curriculum.toml")).unwrap();
    let e = run(&dir, &third.replace("start_noise_std = 0.6", "start_noise_std = 0.7"), None).unwrap_err();
    assert!(e.contains("stage 2 ('climb and dive')"), "{e}");
    let e = run(&dir, &third.replace("minibatches = 2", "minibatches = 4"), None).unwrap_err();
    assert!(e.contains("stage 1 ('cruise')"), "{e}");
    assert_eq!(std::fs::read_to_string(dir.join("curriculum.toml")).unwrap(), saved_text);
    std::fs::remove_dir_all(dir).unwrap();
}
