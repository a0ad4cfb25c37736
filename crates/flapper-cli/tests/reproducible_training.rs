//! Training reproduces bit for bit whatever the thread count and whatever the CPU's vector width:
//! `flapper train` runs in child processes with 1, 2, 3 and 17 threads, and with the matrix products
//! forced onto the 8-lane (AVX2) and the one-lane (portable) paths, must write the same training.csv
//! (timing columns apart) and byte-identical checkpoints; and a golden hash pins the result, so that
//! CI on another CPU model checks that it computes what this repository's CPUs computed.

use std::path::{Path, PathBuf};
use std::process::Command;

use flapper_ppo::fixed_matmul::SIMD_VARIABLE;

/// The paper's networks (540-256-128-64) on a run of seconds: `envs` environments x 16 steps, 2 iterations,
/// 4 minibatches (12 environments: 48 samples, 12 per chunk, so every product's ragged edges are exercised).
fn config(threads: usize, envs: usize) -> String {
    format!(
        "[runner]\nenvs = {envs}\niterations = 2\ncheckpoint_every = 1\nseed = 5\nthreads = {threads}\n\
         [ppo]\nsteps_per_env = 16\n[task.episode]\nmax_steps = 40\n"
    )
}

/// FNV-1a over the final checkpoint's tensor bytes (networks, optimizer, normalizer, random stream), as `flapper train` writes them on the CPUs this
/// repository has been run on (Intel Xeon with AVX-512, AMD Zen 4). If this changes, the training
/// arithmetic changed: every shipped training run changes with it.
const GOLDEN_CHECKPOINT_HASH: u64 = 0xea0c_f503_4c91_0474;

fn train(dir: &Path, name: &str, threads: usize, simd: Option<&str>) -> PathBuf {
    train_envs(dir, name, threads, 12, simd)
}

fn train_envs(dir: &Path, name: &str, threads: usize, envs: usize, simd: Option<&str>) -> PathBuf {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, config(threads, envs)).unwrap();
    let run = dir.join(name);
    let mut command = Command::new(env!("CARGO_BIN_EXE_flapper"));
    command.args(["train", "--config", file.to_str().unwrap(), "--out", run.to_str().unwrap()]);
    match simd {
        Some(path) => command.env(SIMD_VARIABLE, path),
        None => command.env_remove(SIMD_VARIABLE),
    };
    let output = command.output().expect("run flapper train");
    assert!(output.status.success(), "{name}: {}", String::from_utf8_lossy(&output.stderr));
    run
}

/// training.csv without the columns that measure time.
fn learning_columns(run: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(run.join("training.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> =
        (0..header.len()).filter(|&i| !header[i].ends_with("time_s") && header[i] != "steps_per_s").collect();
    lines
        .map(|line| {
            let cells: Vec<&str> = line.split(',').collect();
            keep.iter().map(|&i| cells[i].to_owned()).collect()
        })
        .collect()
}

/// The final checkpoint as (its tensors' bytes, its description less the wall time and the thread count).
fn checkpoint(run: &Path) -> (Vec<u8>, serde_json::Value) {
    let bytes = std::fs::read(run.join("checkpoints/iter_000002.safetensors")).unwrap();
    let header_len = u64::from_le_bytes(bytes[..8].try_into().unwrap()) as usize;
    let header: serde_json::Value = serde_json::from_slice(&bytes[8..8 + header_len]).unwrap();
    let mut description: serde_json::Value =
        serde_json::from_str(header["__metadata__"]["flapper"].as_str().unwrap()).unwrap();
    description.as_object_mut().unwrap().remove("wall_time_s").expect("a wall time");
    let config = description["config_toml"].as_str().unwrap();
    let without_threads: String = config.lines().filter(|l| !l.starts_with("threads =")).collect();
    description["config_toml"] = without_threads.into();
    (bytes[8 + header_len..].to_vec(), description)
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |hash, &b| (hash ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

#[test]
fn a_vector_path_that_is_not_one_is_refused_naming_the_variable_and_the_value() {
    for value in ["avx3", "sse"] {
        let output = Command::new(env!("CARGO_BIN_EXE_flapper"))
            .args(["bench", "--blocks", "1", "--steps", "5", "--envs", "0", "--train-iterations", "0"])
            .env(SIMD_VARIABLE, value)
            .output()
            .expect("run flapper bench");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!output.status.success(), "{value}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
        assert!(stderr.contains(SIMD_VARIABLE) && stderr.contains(value), "{stderr}");
    }
}

#[test]
fn training_is_the_same_on_any_thread_count_and_any_vector_width() {
    let dir = std::env::temp_dir().join(format!("flapper-reproducible-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let reference = train(&dir, "threads1", 1, None);
    let (csv, (tensors, description)) = (learning_columns(&reference), checkpoint(&reference));
    assert_eq!(csv.len(), 2, "two iterations logged");
    let runs =
        [("threads2", 2, None), ("threads3", 3, None), ("avx2", 2, Some("avx2")), ("portable", 1, Some("portable"))];
    for (name, threads, simd) in runs {
        let run = train(&dir, name, threads, simd);
        assert_eq!(learning_columns(&run), csv, "{name}: training.csv differs from one thread's");
        let (run_tensors, run_description) = checkpoint(&run);
        assert!(run_tensors == tensors, "{name}: the checkpoint's tensors differ from one thread's");
        assert_eq!(run_description, description, "{name}: the checkpoint's description differs");
    }
    // 17 threads, more than twice CHUNKS, on 72 environments: the rollout's actor and critic forward passes
    // on 8 threads each share 72 rows, each chunk's actor and critic run side by side on 2 threads each and
    // share its 72 rows, and the minibatch of 288 samples is gathered in 5 pieces side by side.
    let (wide_one, wide_many) = (train_envs(&dir, "wide1", 1, 72, None), train_envs(&dir, "wide17", 17, 72, None));
    assert_eq!(learning_columns(&wide_many), learning_columns(&wide_one), "72 environments: 17 threads' training.csv");
    assert!(checkpoint(&wide_many) == checkpoint(&wide_one), "72 environments: 17 threads' checkpoint differs");
    let hash = fnv1a(&tensors);
    assert_eq!(
        hash, GOLDEN_CHECKPOINT_HASH,
        "the training arithmetic changed: the short run's checkpoint hashes to {hash:#018x}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
