//! The policy's actions are the same bits on every CPU: the golden actions in `data/` (made once by
//! `examples/inference_golden.rs`, from real flights and saturating copies of them) must come out
//! exactly, for the whole batch at once and for each observation alone. A CPU-dependent kernel, a
//! reordered sum or a fused multiply-add in the inference path fails here on some machine.

use std::path::PathBuf;

use flapper_eval::load_flight_policy;
use flapper_ppo::InferenceScratch;
use safetensors::SafeTensors;

fn repository() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The golden file's policy path, observations [rows x observation size] and actions [rows x actions].
fn golden() -> (PathBuf, Vec<f32>, Vec<f32>) {
    let bytes =
        std::fs::read(repository().join("crates/flapper-eval/tests/data/inference_golden.safetensors")).unwrap();
    let (_, metadata) = SafeTensors::read_metadata(&bytes).unwrap();
    let policy = metadata.metadata().as_ref().and_then(|m| m.get("policy")).expect("the golden file names its policy");
    let file = SafeTensors::deserialize(&bytes).unwrap();
    let floats = |name: &str| -> Vec<f32> {
        let data = file.tensor(name).unwrap().data().to_vec();
        data.chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect()
    };
    (repository().join(policy), floats("observations"), floats("actions"))
}

fn bits(values: &[f32]) -> Vec<u32> {
    values.iter().map(|v| v.to_bits()).collect()
}

#[test]
fn golden_actions_come_out_bit_for_bit_batched_and_one_row_at_a_time() {
    let (policy_path, observations, expected) = golden();
    let (policy, _) = load_flight_policy(&policy_path).unwrap();
    let (o, a) = (policy.observation_size(), policy.action_size());
    let rows = observations.len() / o;
    assert!(rows >= 200 && expected.len() == rows * a, "{rows} golden rows");
    assert!(expected.iter().any(|x| x.abs() > 1.0), "the golden set includes saturating actions");

    let mut scratch = InferenceScratch::default();
    let mut batch = Vec::new();
    policy.act_deterministic(&observations, &mut scratch, &mut batch);
    let mismatched = bits(&batch).iter().zip(bits(&expected)).filter(|(x, y)| **x != *y).count();
    assert_eq!(
        mismatched,
        0,
        "{mismatched} of {} golden actions differ in their bits (batch of {rows})",
        expected.len()
    );

    let mut single = Vec::new();
    for (row, (observation, golden)) in observations.chunks_exact(o).zip(expected.chunks_exact(a)).enumerate() {
        policy.act_deterministic(observation, &mut InferenceScratch::default(), &mut single);
        assert_eq!(bits(&single), bits(golden), "row {row} alone");
    }
}
