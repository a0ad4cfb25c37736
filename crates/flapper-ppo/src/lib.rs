//! The learner: PPO (Schulman et al. 2017) on the CPU. It drives any vectorized environment and knows
//! nothing of wings. So far: the network maths, written by hand on `gemm` for throughput
//! (`matmul`, `fast_math`, `mlp`) and the Adam optimizer (`adam`), each checked against finite
//! differences.

pub mod adam;
pub mod benchmark;
pub mod fast_math;
pub mod matmul;
pub mod mlp;
