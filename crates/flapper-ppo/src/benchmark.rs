//! Throughput of the network maths on the PPO workload: actor and critic MLPs (540 -> 256, 128, 64 ->
//! 5 and -> 1), forward, backward and an Adam step per minibatch. Used by `flapper bench`.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::adam::Adam;
use crate::mlp::{Activation, Mlp, Workspace};

#[derive(Debug, Clone)]
pub struct NetworkThroughput {
    pub minibatch: usize,
    pub threads: usize,
    /// Median over repeats of samples per second through actor and critic, forward + backward + Adam.
    pub median_samples_per_s: f64,
    pub repeats: usize,
}

pub fn time_actor_critic_update(observation_size: usize, minibatch: usize, threads: usize, repeats: usize) -> NetworkThroughput {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut actor = Mlp::new(&[observation_size, 256, 128, 64, 5], Activation::Elu, 0.01, &mut rng);
    let mut critic = Mlp::new(&[observation_size, 256, 128, 64, 1], Activation::Elu, 1.0, &mut rng);
    let (mut actor_adam, mut critic_adam) = (Adam::new(actor.params().len(), 1e-3), Adam::new(critic.params().len(), 1e-3));
    let (mut actor_grads, mut critic_grads) = (vec![0.0; actor.params().len()], vec![0.0; critic.params().len()]);
    let input: Vec<f32> = (0..minibatch * observation_size).map(|_| rng.random_range(-1.0..1.0)).collect();
    let (d_actor, d_critic) = (vec![1e-3f32; minibatch * 5], vec![1e-3f32; minibatch]);
    let (mut actor_ws, mut critic_ws) = (Workspace::default(), Workspace::default());
    let mut rates = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) + 1 {
        let began = Instant::now();
        actor.forward(&input, minibatch, &mut actor_ws, threads);
        actor.backward(&mut actor_ws, &d_actor, &mut actor_grads, threads);
        actor_adam.step(actor.params_mut(), &actor_grads);
        critic.forward(&input, minibatch, &mut critic_ws, threads);
        critic.backward(&mut critic_ws, &d_critic, &mut critic_grads, threads);
        critic_adam.step(critic.params_mut(), &critic_grads);
        rates.push(minibatch as f64 / began.elapsed().as_secs_f64());
    }
    rates.remove(0); // warm-up: buffers allocated on the first pass
    rates.sort_by(f64::total_cmp);
    NetworkThroughput { minibatch, threads, median_samples_per_s: rates[rates.len() / 2], repeats: rates.len() }
}
