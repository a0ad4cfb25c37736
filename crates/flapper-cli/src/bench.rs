//! `flapper bench`: the speed of the simulator, the environments, the network update and training end
//! to end, as medians over repeats.

use std::path::Path;

use anyhow::{Result, bail};
use flapper_sim::RobotModel;

use crate::flag_values::count;

pub fn bench_command(
    robot: &RobotModel,
    blocks: usize,
    steps: usize,
    envs: usize,
    threads: usize,
    train_iterations: usize,
) -> Result<()> {
    if blocks == 0 || steps < 5 || blocks > 1000 || steps > 10_000_000 {
        bail!("--blocks must be 1 to 1000 and --steps 5 to 10000000 (got {blocks} and {steps})");
    }
    if envs > 65_536 || threads > 1024 || train_iterations > 100_000 {
        bail!(
            "--envs must be at most 65536, --threads at most 1024 and --train-iterations at most 100000 (got {envs}, {threads} and {train_iterations})"
        );
    }
    let t = flapper_sim::benchmark::time_steps(robot, blocks, steps)?;
    println!(
        "model {} on one thread, {} blocks of {} steps (flapping at 3.8 m/s):",
        robot.origin(),
        t.blocks,
        t.steps_per_block
    );
    println!(
        "  mj_step        median {:.2} us  (min {:.2}, max {:.2})",
        t.median_us_per_mj_step, t.min_us_per_mj_step, t.max_us_per_mj_step
    );
    println!("  control step   median {:.2} us  (5 substeps = 20 ms simulated)", t.median_us_per_control_step);
    println!("  real-time factor {:.0}x", 20_000.0 / t.median_us_per_control_step);
    let mut environments_only_steps_per_s = None;
    if envs > 0 {
        let env_blocks = blocks.clamp(1, 7);
        let v = flapper_task::benchmark::time_vec_env(robot, envs, threads, env_blocks, 50)?;
        let raw = v.threads as f64 * 1e6 / t.median_us_per_control_step;
        println!(
            "{} environments on {} threads, {} blocks of 50 steps (observation, reward, resets included):",
            v.envs, v.threads, v.blocks
        );
        println!(
            "  environment steps/s  median {:.0}  (min {:.0}, max {:.0})",
            v.median_steps_per_s, v.min_steps_per_s, v.max_steps_per_s
        );
        println!("  raw MuJoCo bound     {raw:.0} control steps/s ({} threads x one-thread control step)", v.threads);
        println!("  efficiency           {:.0}% of the bound", 100.0 * v.median_steps_per_s / raw);
        environments_only_steps_per_s = Some(v.median_steps_per_s);
    }
    let threads = flapper_ppo::config::threads_or_all_cores(threads);
    // The paper's network update: its observation, its 256 environments x 24 steps, 5 epochs of 4
    // minibatches, on the path training takes.
    let task = flapper_task::TaskConfig::default();
    let observation_size = flapper_task::observation::ObservationLayout::of(&task.observation).size();
    let action_size = flapper_task::action::ACTION_SIZE;
    let ppo = flapper_ppo::PpoConfig::default();
    let envs_per_rollout = flapper_ppo::RunnerConfig::default().envs;
    let n = flapper_ppo::benchmark::time_ppo_update(
        observation_size,
        action_size,
        envs_per_rollout,
        &ppo,
        threads,
        blocks.clamp(3, 21),
    );
    let hidden = |h: &[usize]| h.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", ");
    println!(
        "PPO update (actor {observation_size} -> {} -> {action_size}, critic -> {} -> 1, side by side), {} epochs of minibatch {}, {} threads:",
        hidden(&ppo.actor_hidden),
        hidden(&ppo.critic_hidden),
        ppo.epochs,
        n.minibatch,
        n.threads
    );
    println!("  forward + backward + Adam  median {:.0} samples/s over {} updates", n.median_samples_per_s, n.repeats);
    let latency = flapper_ppo::benchmark::time_policy_latency(observation_size, action_size, &ppo, 20_000);
    println!(
        "policy latency, one observation -> {action_size} actions on one thread, median over {} calls:",
        latency.calls
    );
    println!("  CPU-independent path (evaluation, Python, on board)  {:.1} us", latency.exact_us);
    println!("  the same, actor only                                 {:.1} us", latency.exact_actor_us);
    println!(
        "  training path (fixed_matmul, {}, actor only)   {:.1} us",
        flapper_ppo::fixed_matmul::Simd::active().name(),
        latency.training_path_us
    );
    if train_iterations > 0 {
        let envs = if envs > 0 { envs } else { 256 };
        let t = flapper_train::benchmark::time_training(robot, envs, threads, train_iterations)?;
        println!(
            "PPO training end to end, stage 1 from scratch, {} environments x 24 steps, {} threads, {} iterations:",
            t.envs, t.threads, t.iterations
        );
        println!(
            "  environment steps/s  median {:.0}  (paper: 30 M steps in about 5 h on 8 cores = 1.7 k/s)",
            t.median_steps_per_s
        );
        println!(
            "  time split           environments {:.0}%, inference {:.0}%, update {:.0}%",
            100.0 * t.env_fraction,
            100.0 * t.inference_fraction,
            100.0 * t.update_fraction
        );
        if let Some(alone) = environments_only_steps_per_s {
            println!(
                "  training / environments alone  {:.2}  ({:.0} / {alone:.0} steps/s, this run)",
                t.median_steps_per_s / alone,
                t.median_steps_per_s
            );
        }
    }
    Ok(())
}

/// `flapper bench`'s options.
#[derive(clap::Args)]
pub struct BenchArgs {
    /// Number of timed blocks (the median over blocks is reported).
    #[arg(long, default_value_t = 21, value_parser = count, allow_negative_numbers = true)]
    pub blocks: usize,
    /// MuJoCo steps per block.
    #[arg(long, default_value_t = 5000, value_parser = count, allow_negative_numbers = true)]
    pub steps: usize,
    /// Also time this many vectorized environments (0 = skip).
    #[arg(long, default_value_t = 256, value_parser = count, allow_negative_numbers = true)]
    pub envs: usize,
    /// Worker threads for the environments (0 = one per core).
    #[arg(long, default_value_t = 0, value_parser = count, allow_negative_numbers = true)]
    pub threads: usize,
    /// Also time this many PPO iterations end to end on the flight task (0 = skip).
    #[arg(long, default_value_t = 10, value_parser = count, allow_negative_numbers = true)]
    pub train_iterations: usize,
}

pub fn run(args: BenchArgs, model: Option<&Path>) -> Result<()> {
    let robot = crate::robot::load(model)?;
    bench_command(&robot, args.blocks, args.steps, args.envs, args.threads, args.train_iterations)
}
